//! Ctrl-C during a long call: the work runs on a thread of its own while the calling
//! thread, taking the GIL between waits, lets Python check its signals.

use std::sync::mpsc;
use std::time::Duration;

use pyo3::prelude::*;

use crate::rust_err;

/// How often the waiting thread looks for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` on a new thread and returns its result; when a Python signal handler
/// raises meanwhile (Ctrl-C: `KeyboardInterrupt`), calls `stop` (which tells the work to
/// stop, e.g. raises a flag the work checks), waits for the work to return, and raises.
/// The GIL is released while waiting.
pub(crate) fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    stop: &dyn Fn(),
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    let (tx, rx) = mpsc::channel();
    std::thread::Builder::new()
        .name("partisim-work".into())
        .spawn(move || {
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
                    stop();
                    let _ = py.detach(move || rx.recv());
                    return Err(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(rust_err("the worker thread stopped without a result"));
            }
        }
    }
}
