//! Where a command's CSV goes, and what a failure or an interrupt leaves there.
//!
//! Standard output, checked to be open (a closed one would swallow every row); a file that
//! exists and is not a regular file (a device, a
//! pipe) is written in place; a regular file is written as `FILE.partial-PID` beside it and
//! renamed to FILE once every row is written, so that FILE keeps what it held until then.
//! A command that fails or is interrupted renames what it wrote to `FILE.partial` and says so.

use crate::{interrupt, stdout_failed, Failure};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

enum Target {
    Stdout,
    InPlace(String),
    /// FILE as the user named it, the temporary and the file FILE's name resolves to.
    File {
        path: String,
        temp: PathBuf,
        real: PathBuf,
    },
}

/// An open output ([module docs](self)).
pub struct Output {
    target: Target,
    writer: BufWriter<Box<dyn Write>>,
}

/// Whether standard output was closed when the process started. Rust's runtime then opens
/// /dev/null in its place, read-write, and every row would vanish; a shell's `> /dev/null`
/// opens it write-only. Linux only (/proc); elsewhere taken as open.
fn stdout_was_closed() -> bool {
    let is_null = std::fs::read_link("/proc/self/fd/1").is_ok_and(|p| p == Path::new("/dev/null"));
    if !is_null {
        return false;
    }
    let info = std::fs::read_to_string("/proc/self/fdinfo/1").unwrap_or_default();
    let flags = info.lines().find_map(|l| l.strip_prefix("flags:"));
    // O_ACCMODE is 3, O_RDWR 2 (Linux's fcntl.h).
    flags.and_then(|f| u32::from_str_radix(f.trim(), 8).ok()).is_some_and(|f| f & 3 == 2)
}

/// `path` with `suffix` appended to its file name.
fn suffixed(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(suffix);
    PathBuf::from(name)
}

impl Output {
    /// Where the rows go: `path`, or standard output (no path, or `-` as Unix tools read it).
    pub fn open(path: Option<&str>) -> Result<Output, Failure> {
        let path = path.filter(|p| *p != "-");
        let create = |p: &Path, shown: &str| {
            File::create(p).map_err(|e| Failure::Usage(format!("cannot create {shown}: {e}")))
        };
        let (target, sink): (Target, Box<dyn Write>) =
            match path {
                None if stdout_was_closed() => return Err(Failure::Usage(
                    "standard output is closed: the rows would go nowhere; write them to a file \
                     with -o FILE"
                        .into(),
                )),
                None => (Target::Stdout, Box::new(io::stdout().lock())),
                Some(p) if std::fs::metadata(p).is_ok_and(|m| !m.is_file()) => {
                    (Target::InPlace(p.to_string()), Box::new(create(Path::new(p), p)?))
                }
                Some(p) => {
                    // Beside the file a symbolic link names, so that the rename replaces the file.
                    let real = std::fs::canonicalize(p).unwrap_or_else(|_| PathBuf::from(p));
                    let temp = suffixed(&real, &format!(".partial-{}", std::process::id()));
                    let file = create(&temp, &temp.display().to_string())?;
                    interrupt::keep_on_exit(Some((temp.clone(), suffixed(&real, ".partial"))));
                    (Target::File { path: p.to_string(), temp, real }, Box::new(file))
                }
            };
        // 64 KiB: a system call per 200 rows of `simulate` instead of 25 (8 KiB).
        Ok(Output { target, writer: BufWriter::with_capacity(1 << 16, sink) })
    }

    pub fn writer(&mut self) -> &mut impl Write {
        &mut self.writer
    }

    /// A failed write as the command's failure: a closed standard output (quietly), or an
    /// error naming the file.
    pub fn failed(&self, e: io::Error) -> Failure {
        match &self.target {
            Target::Stdout => stdout_failed(e),
            Target::InPlace(path) | Target::File { path, .. } => {
                Failure::Usage(format!("writing {path} failed: {e}"))
            }
        }
    }

    /// Every row is written: flushed, and the file takes FILE's place.
    pub fn finish(mut self) -> Result<(), Failure> {
        if let Err(e) = self.writer.flush() {
            let failure = self.failed(e);
            self.abandon();
            return Err(failure);
        }
        interrupt::keep_on_exit(None);
        if let Target::File { temp, real, .. } = &self.target {
            std::fs::rename(temp, real).map_err(|e| {
                Failure::Usage(format!(
                    "cannot rename {} to {}: {e}",
                    temp.display(),
                    real.display()
                ))
            })?;
        }
        Ok(())
    }

    /// The command ends early: what was written is flushed, and a file's rows move to
    /// `FILE.partial`. Returns where the rows are, for the message: "standard output",
    /// "FILE.partial (FILE is unchanged)".
    pub fn abandon(mut self) -> String {
        let _ = self.writer.flush();
        interrupt::keep_on_exit(None);
        match &self.target {
            Target::Stdout => "standard output".into(),
            Target::InPlace(path) => path.clone(),
            Target::File { path, temp, real } => {
                let partial = suffixed(real, ".partial");
                match std::fs::rename(temp, &partial) {
                    Ok(()) => format!("{} ({path} is unchanged)", partial.display()),
                    Err(_) => format!("{} ({path} is unchanged)", temp.display()),
                }
            }
        }
    }
}
