//! Ctrl-C, SIGTERM and SIGHUP (the `ctrlc` crate, feature `termination`). The first asks the
//! command to stop where it is and keep what it has computed ([`interrupted`]); a second
//! stops the process at once, after moving the rows written so far where the first would
//! have put them ([`keep_on_exit`]).

use crate::note;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
/// A temporary file of rows and where a second interrupt moves it.
static KEEP: Mutex<Option<(PathBuf, PathBuf)>> = Mutex::new(None);

/// The exit status of an interrupted command: 128 + SIGINT, as a shell reports it.
pub const STATUS: u8 = 130;

/// Installs the handler (once; a second call changes nothing).
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        if !INTERRUPTED.swap(true, Ordering::SeqCst) {
            return;
        }
        let keep = KEEP.lock().ok().and_then(|k| k.clone());
        match keep.map(|(from, to)| std::fs::rename(&from, &to).map(|()| to)) {
            Some(Ok(to)) => note(format_args!(
                "interrupted again: stopped at once; the rows written so far are in {}",
                to.display()
            )),
            _ => note(format_args!("interrupted again: stopped at once")),
        }
        std::process::exit(i32::from(STATUS));
    });
}

/// Whether an interrupt has asked the command to stop.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// What a second interrupt does with the rows written so far: move `from` to `to`
/// (`None`: nothing, the rows have their place).
pub fn keep_on_exit(files: Option<(PathBuf, PathBuf)>) {
    if let Ok(mut k) = KEEP.lock() {
        *k = files;
    }
}
