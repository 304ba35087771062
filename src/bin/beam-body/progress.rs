//! Progress of a long command on standard error (the `indicatif` crate): on a terminal, a
//! bar with a line of its own, drawn once the command has taken `delay`; elsewhere, if asked,
//! a line every 10 s. Nothing when quiet.

use crate::note;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{self, IsTerminal};
use std::time::{Duration, Instant};

/// The progress of work measured in `total` units (simulated seconds, cases).
pub struct Progress {
    total: f64,
    /// The line for `done` units at `rate` units a second, and the time left.
    line: Box<dyn Fn(f64, f64) -> String>,
    start: Instant,
    delay: Duration,
    bar: Option<ProgressBar>,
    terminal: bool,
    /// Off a terminal: a line this often (`None`: none).
    log: Option<Duration>,
    last_log: Instant,
}

impl Progress {
    /// Progress over `total` units, shown after `delay` (on a terminal), every 10 s in a log
    /// with `log_lines`, never when `quiet`.
    pub fn new(
        total: f64,
        delay: Duration,
        log_lines: bool,
        quiet: bool,
        line: impl Fn(f64, f64) -> String + 'static,
    ) -> Self {
        let terminal = !quiet && io::stderr().is_terminal();
        let log = (!quiet && !terminal && log_lines).then_some(Duration::from_secs(10));
        let start = Instant::now();
        Self {
            total,
            line: Box::new(line),
            start,
            delay,
            bar: None,
            terminal,
            log,
            last_log: start,
        }
    }

    /// The time left at `rate` units a second, in words.
    pub fn left(&self, done: f64, rate: f64) -> String {
        if done > 0.0 && rate > 0.0 {
            let secs = (self.total - done).max(0.0) / rate;
            format!("{} left", indicatif::HumanDuration(Duration::from_secs_f64(secs)))
        } else {
            "time left unknown".into()
        }
    }

    /// `done` units of the total are done.
    pub fn update(&mut self, done: f64) {
        let now = Instant::now();
        let elapsed = now.duration_since(self.start);
        if !self.terminal && self.log.is_none_or(|every| now.duration_since(self.last_log) < every)
        {
            return;
        }
        let rate = done / elapsed.as_secs_f64().max(1e-9);
        if !self.terminal {
            self.last_log = now;
            note(format_args!("{}, {}", (self.line)(done, rate), self.left(done, rate)));
            return;
        }
        if elapsed < self.delay {
            return;
        }
        let message = format!("{}, {}", (self.line)(done, rate), self.left(done, rate));
        let bar = self.bar.get_or_insert_with(|| {
            let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
            let style = ProgressStyle::with_template("[{bar:30}] {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
            bar.set_style(style);
            bar
        });
        bar.set_position((1000.0 * done / self.total.max(f64::MIN_POSITIVE)) as u64);
        bar.set_message(message);
    }

    /// Clears the bar (the summary comes next).
    pub fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}
