//! Ctrl-C during a long call: the work runs on a thread of its own while the calling
//! thread, taking the GIL between waits, lets Python check its signals.

use std::sync::mpsc;
use std::time::Duration;

use pyo3::prelude::*;

use crate::rust_err;

/// How often the waiting thread looks for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// What to do with the work when a signal's handler raises (Ctrl-C: `KeyboardInterrupt`).
pub(crate) enum OnSignal<'a> {
    /// Call this (it tells the work to stop, e.g. raises a flag the work checks) and wait
    /// for the work to return before raising.
    Stop(&'a dyn Fn()),
    /// Raise at once; the work, which cannot be stopped, finishes on its thread and its
    /// result is dropped.
    Abandon,
}

/// Runs `work` on a new thread and returns its result; raises the exception of a Python
/// signal handler (Ctrl-C) that fires meanwhile, after dealing with the work as
/// `on_signal` says. The GIL is released while waiting.
pub(crate) fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    on_signal: OnSignal<'_>,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    let (tx, rx) = mpsc::channel();
    std::thread::Builder::new()
        .name("partisim-work".into())
        .spawn(move || {
            // The receiver is gone only if the caller was interrupted and abandoned us.
            let _ = tx.send(work());
        })
        .map_err(|e| rust_err(format!("could not start a worker thread: {e}")))?;
    let mut rx = rx;
    loop {
        // The receiver goes with each wait and comes back (it may be sent to another
        // thread, not shared).
        let (received, back) = py.detach(move || (rx.recv_timeout(SIGNAL_POLL), rx));
        rx = back;
        match received {
            Ok(result) => return Ok(result),
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    if let OnSignal::Stop(stop) = &on_signal {
                        stop();
                        let _ = py.detach(move || rx.recv());
                    }
                    return Err(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(rust_err("the worker thread stopped without a result"));
            }
        }
    }
}
