//! `beam-body`: the standalone solver. Runs the model without FMI: `simulate`, `modes`,
//! `residual` (for the oracle) and `study`. `beam-body --help` and `beam-body COMMAND --help`
//! say the rest; the help is generated from the settings table.
//!
//! Every error is one line, `error: …`, with exit status 2. Nothing panics on I/O: a closed
//! stderr is ignored, and a closed stdout (`| head`) stops the work at the first failed
//! write, quietly, with status 141, as a tool that SIGPIPE ended reports in a shell.

mod args;
mod interrupt;
mod location;
mod modes;
mod output;
mod progress;
mod residual;
mod simulate;
mod study;

use std::io::{self, Write};
use std::process::ExitCode;

/// How a command ends when it does not succeed.
pub enum Failure {
    /// A usage or input error: printed as `error: …`, exit status 2.
    Usage(String),
    /// Standard output was closed by its reader: no message, exit status 141.
    ClosedStdout,
    /// Ctrl-C, SIGTERM or SIGHUP: what was kept, and where; exit status 130.
    Interrupted(String),
}

impl From<String> for Failure {
    fn from(message: String) -> Self {
        Failure::Usage(message)
    }
}

pub type CmdResult = Result<(), Failure>;

/// A failed write to standard output: its reader went away (quietly), or another error.
pub fn stdout_failed(e: io::Error) -> Failure {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Failure::ClosedStdout
    } else {
        Failure::Usage(format!("writing to standard output failed: {e}"))
    }
}

/// Writes a line to standard error; a closed or failing stderr is ignored (there is nowhere
/// else to say it, and the results on stdout are still worth writing).
pub fn note(message: std::fmt::Arguments<'_>) {
    let _ = writeln!(io::stderr().lock(), "{message}");
}

/// Writes `text` to standard output.
pub fn print(text: &str) -> CmdResult {
    let mut out = io::stdout().lock();
    out.write_all(text.as_bytes()).and_then(|()| out.flush()).map_err(stdout_failed)
}

fn main() -> ExitCode {
    let mut argv = std::env::args_os().skip(1);
    let command = argv.next().map(|c| c.to_string_lossy().into_owned());
    let rest: Vec<_> = argv.collect();
    let result = match command.as_deref() {
        Some("simulate") => simulate::run(rest),
        Some("modes") => modes::run(rest),
        Some("residual") => residual::run(rest),
        Some("study") => study::run(rest),
        Some("help" | "--help" | "-h") => match rest.first().map(|c| c.to_string_lossy()) {
            Some(c) => args::command_help(&c).map_or_else(
                || Err(Failure::Usage(format!("unknown command `{c}`: {}", args::COMMANDS))),
                |text| print(&text),
            ),
            None => print(&args::main_help()),
        },
        Some("--version" | "-V") => print(&args::version()),
        Some(other) => Err(Failure::Usage(format!(
            "unknown command `{other}`: {} (beam-body --help)",
            args::COMMANDS
        ))),
        None => Err(Failure::Usage(format!(
            "a command is missing: {} (beam-body --help)",
            args::COMMANDS
        ))),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Usage(message)) => {
            note(format_args!("error: {message}"));
            ExitCode::from(2)
        }
        Err(Failure::ClosedStdout) => ExitCode::from(141),
        Err(Failure::Interrupted(message)) => {
            note(format_args!("{message}"));
            ExitCode::from(interrupt::STATUS)
        }
    }
}
