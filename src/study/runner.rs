//! Runs a range of a study's cases on several threads, handing the rows over in case order.

use super::{Row, Status, Study};
use std::collections::BTreeMap;
use std::ops::{ControlFlow, Range};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// How often `progress` is called while no row arrives.
const TICK: Duration = Duration::from_millis(250);

/// Runs `cases` of `study` on `threads` threads (at least 1). `on_row` gets every row, in
/// case order, on the calling thread; its first error stops the run (the threads finish the
/// case in hand) and is returned. `progress` gets the number of cases done, as they finish
/// (in any order) and at least every 250 ms; when it breaks (an interrupt), no case starts
/// any more, and the cases running finish and hand over their rows, so that the rows handed
/// over are always those of the cases from `cases.start` up to some case, with no gap.
///
/// The cases are independent and take about the same time, so each thread takes the next
/// case number from a shared counter: no work-stealing pool is needed. A case that panics
/// (a bug) is a failed row, not the end of the study.
pub fn run_cases<E>(
    study: &Study,
    cases: Range<u64>,
    threads: usize,
    mut progress: impl FnMut(u64) -> ControlFlow<()>,
    mut on_row: impl FnMut(Row) -> Result<(), E>,
) -> Result<(), E> {
    let next = AtomicU64::new(cases.start);
    let stop = AtomicBool::new(false);
    let (tx, rx) = mpsc::sync_channel::<Row>(threads.max(1) * 64);
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            let tx = tx.clone();
            let (next, stop) = (&next, &stop);
            scope.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let case = next.fetch_add(1, Ordering::Relaxed);
                    if case >= cases.end {
                        break;
                    }
                    let row = catch_unwind(AssertUnwindSafe(|| study.run_case(case)))
                        .unwrap_or_else(|panic| panicked(study, case, &*panic));
                    if tx.send(row).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        // The rows that came early, until the ones before them arrive.
        let mut early = BTreeMap::new();
        let (mut expected, mut done) = (cases.start, 0);
        let result = loop {
            let row = match rx.recv_timeout(TICK) {
                Ok(row) => Some(row),
                Err(mpsc::RecvTimeoutError::Timeout) => None,
                Err(mpsc::RecvTimeoutError::Disconnected) => break Ok(()),
            };
            done += u64::from(row.is_some());
            if progress(done).is_break() {
                stop.store(true, Ordering::Relaxed);
            }
            let Some(row) = row else { continue };
            early.insert(row.case, row);
            let mut failed = None;
            while let Some(row) = early.remove(&expected) {
                expected += 1;
                if let Err(e) = on_row(row) {
                    failed = Some(e);
                    break;
                }
            }
            if let Some(e) = failed {
                break Err(e);
            }
        };
        // On error, let the threads see the flag and the closed channel, and end.
        stop.store(true, Ordering::Relaxed);
        drop(rx);
        result
    })
}

/// The row of a case whose run panicked.
fn panicked(study: &Study, case: u64, panic: &(dyn std::any::Any + Send)) -> Row {
    let what = panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into());
    Row {
        case,
        values: study.values(case),
        metrics: vec![None; study.metrics().len()],
        status: Status::Failed,
        message: format!("internal error: {what}"),
        steps: 0,
    }
}
