//! Ctrl-C during long work: the work runs on a thread of its own while the calling thread, the
//! GIL released, waits for it in short slices and between them lets Python run its signal
//! handlers. Ctrl-C sets the work's cancel flag, which the library checks (a stage between work
//! units, a simulation every few samples), and is raised as `KeyboardInterrupt` once the work
//! has stopped, however late in the work it came.

use crate::errors::internal;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How often the waiting thread looks for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// The work's result (or its panic's message) and the interrupt, if Ctrl-C came meanwhile.
pub struct Waited<T> {
    pub result: Result<T, String>,
    pub interrupt: Option<PyErr>,
}

/// Runs `work` as the module doc says; `cancel` is the flag the work checks. Ctrl-C before
/// `started()` says the work has begun anything that must finish returns at once (the work
/// stops at its first check).
pub fn on_worker<T: Send + 'static>(
    py: Python<'_>,
    cancel: Arc<AtomicBool>,
    started: impl Fn() -> bool,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<Waited<T>> {
    let (tx, rx) = channel();
    let rx = Mutex::new(rx);
    std::thread::spawn(move || {
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(work));
        let _ = tx.send(result);
    });
    let mut interrupt: Option<PyErr> = None;
    let joined = loop {
        let next = py.detach(|| match rx.lock() {
            Ok(rx) => rx.recv_timeout(SIGNAL_POLL),
            Err(_) => Err(RecvTimeoutError::Disconnected),
        });
        match next {
            Ok(r) => {
                // A Ctrl-C of the last slice is reported even though the work has finished.
                if interrupt.is_none()
                    && let Err(e) = py.check_signals()
                {
                    interrupt = Some(e);
                }
                break r;
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(internal("the work's thread ended without a result"));
            }
            Err(RecvTimeoutError::Timeout) => {}
        }
        if interrupt.is_none()
            && let Err(e) = py.check_signals()
        {
            cancel.store(true, Ordering::Relaxed);
            if !started() {
                return Err(e);
            }
            interrupt = Some(e);
        }
    };
    let result = joined.map_err(|panic| {
        panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default()
    });
    Ok(Waited { result, interrupt })
}
