"""What the command line reports without a traceback."""


class StudyError(Exception):
    """An error the user can act on: printed as `error: ...`, exit status 2."""


class Interrupted(Exception):
    """Ctrl-C during a run: what was kept and how to go on, printed as one line, exit status
    130 (the shell's code for SIGINT)."""
