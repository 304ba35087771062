//! A progress line for long commands (`bench`, `sweep`, `fuzz`): while a phase runs, a
//! background thread prints `  … PHASE: 45 s[, DETAIL]` to stderr every [`INTERVAL`], so a
//! user (or a CI log) can tell a long phase from a hung one. The line stops when the
//! [`Ticker`] is dropped.

use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Time between two progress lines.
pub const INTERVAL: Duration = Duration::from_secs(15);

/// Prints a progress line every [`INTERVAL`] until dropped.
pub struct Ticker {
    stop: Arc<(Mutex<bool>, Condvar)>,
    thread: Option<JoinHandle<()>>,
}

/// Starts a progress line for `phase`; `detail` is called for each line (say, the cases done
/// so far) and may return an empty string.
pub fn ticker(phase: impl Into<String>, detail: impl Fn() -> String + Send + 'static) -> Ticker {
    ticker_every(INTERVAL, phase, detail)
}

/// [`ticker`] with a line every `interval`.
fn ticker_every(
    interval: Duration,
    phase: impl Into<String>,
    detail: impl Fn() -> String + Send + 'static,
) -> Ticker {
    let phase = phase.into();
    let stop = Arc::new((Mutex::new(false), Condvar::new()));
    let signal = stop.clone();
    let start = Instant::now();
    let thread = std::thread::spawn(move || {
        let (lock, wake) = &*signal;
        let mut stopped = lock.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            // Checked before waiting too: the drop may come before this thread first waits.
            if *stopped {
                return;
            }
            let (guard, timeout) =
                wake.wait_timeout(stopped, interval).unwrap_or_else(|e| e.into_inner());
            stopped = guard;
            if *stopped {
                return;
            }
            if timeout.timed_out() {
                let detail = detail();
                let sep = if detail.is_empty() { "" } else { ", " };
                eprintln!("  … {phase}: {:.0} s{sep}{detail}", start.elapsed().as_secs_f64());
            }
        }
    });
    Ticker { stop, thread: Some(thread) }
}

impl Drop for Ticker {
    fn drop(&mut self) {
        let (lock, wake) = &*self.stop;
        *lock.lock().unwrap_or_else(|e| e.into_inner()) = true;
        wake.notify_all();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dropping the ticker wakes its thread and joins it, rather than waiting out the
    /// interval: with an interval of a year, a drop that did not wake the thread would hang
    /// the test (no clock is read, so a loaded machine cannot fail it).
    #[test]
    fn drop_wakes_and_stops_the_thread() {
        let year = Duration::from_secs(365 * 24 * 3600);
        drop(ticker_every(year, "test", || unreachable!("no line within a year")));
    }
}
