"""docs/cli.md's synopsis against the CLI's own `--help` (issue 43: the synopsis lacked --elements,
--beam, --columns and modes --count). `cargo xtask gen` writes the synopsis from the settings table and
a list of each command's own flags; this test holds that list to the binary: every option a command's
help offers is in its synopsis, and every option of the synopsis is one the command takes.
"""

from __future__ import annotations

import re
import subprocess

import pytest

from conftest import REPO

COMMANDS = ["simulate", "modes", "residual", "study"]


def synopsis_options() -> dict[str, set[str]]:
    """The long options in docs/cli.md's generated synopsis, by command (the lines of a command
    continue until the next `beam-body COMMAND`)."""
    text = (REPO / "docs" / "cli.md").read_text(encoding="utf-8")
    block = text.split("<!-- synopsis: generated", 1)[1].split("<!-- end of the generated synopsis -->", 1)[0]
    options: dict[str, set[str]] = {}
    command = None
    for line in block.splitlines():
        m = re.match(r"beam-body (\w+)", line)
        if m:
            command = m.group(1)
        if command:
            options.setdefault(command, set()).update(re.findall(r"\[(-[-\w]+)", line))
            options[command].update(re.findall(r"^beam-body \w+ \S+ (--\w[-\w]*)", line))
    return options


def help_options(beam_body, command: str) -> set[str]:
    """The options in the `options:` section of `beam-body COMMAND --help` (long names, and `-o`
    where that is how the synopsis writes it)."""
    proc = subprocess.run([str(beam_body), command, "--help"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    section = proc.stdout.split("\noptions:\n", 1)[1].split("\n\n", 1)[0]
    found = set()
    for line in section.splitlines():
        names = re.findall(r"(?:^|, )\s*(--?[\w][-\w]*)", line)
        if not names:
            continue
        long = [n for n in names if n.startswith("--")]
        found.add("-o" if "-o" in names else long[0] if long else names[0])
    found -= {"--help", "-h"}
    return found


@pytest.mark.parametrize("command", COMMANDS)
def test_the_synopsis_offers_exactly_the_options_of_the_command(beam_body, command):
    documented = synopsis_options()[command]
    offered = help_options(beam_body, command)
    assert offered, command
    assert offered <= documented, f"{command}: --help offers {sorted(offered - documented)}, docs/cli.md does not"
    assert documented <= offered, f"{command}: docs/cli.md offers {sorted(documented - offered)}, --help does not"
