//! Library errors as Python exceptions, with the CLI's message (the error and its causes, each
//! once). The class comes from the library's one classification ([`slidestack::fault`]):
//! `ValueError` where the input is at fault, `FileNotFoundError` where a file is missing,
//! `OSError` where reading, writing or locking failed, `KeyboardInterrupt` for Ctrl-C, and
//! `slidestack.Error` (a `RuntimeError`) for a damaged file or a failed run. Each exception
//! carries `kind` (the fault's name) and `file`, `key` and `line` (`None` where the error names
//! none).

use pyo3::exceptions::{
    PyFileNotFoundError, PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError,
};
use pyo3::prelude::*;
use slidestack::fault::{FaultKind, classify};
use std::error::Error as StdError;

pyo3::create_exception!(
    slidestack,
    Error,
    PyRuntimeError,
    "A stored file that fails its checks, or a run that could not produce its result."
);

/// The message the CLI prints after `error: `: the error and each cause whose text it does not
/// already hold.
pub fn message(e: &(dyn StdError + 'static)) -> String {
    let mut text = String::new();
    let mut cause: Option<&(dyn StdError + 'static)> = Some(e);
    while let Some(c) = cause {
        let s = c.to_string();
        if !text.contains(&s) {
            if !text.is_empty() {
                text += ": ";
            }
            text += &s;
        }
        cause = c.source();
    }
    text
}

/// The Python exception for `e` (module doc).
pub fn to_py_err(e: &(dyn StdError + 'static)) -> PyErr {
    let fault = classify(e);
    let msg = message(e);
    let err = match fault.kind {
        FaultKind::BadInput => PyValueError::new_err(msg),
        FaultKind::MissingFile => PyFileNotFoundError::new_err(msg),
        FaultKind::Io => PyOSError::new_err(msg),
        FaultKind::Interrupted => PyKeyboardInterrupt::new_err(msg),
        FaultKind::DamagedFile | FaultKind::Failed => Error::new_err(msg),
    };
    Python::attach(|py| {
        let value = err.value(py);
        // Attributes on a fresh exception object cannot fail but for lack of memory, in which
        // case the exception goes without them.
        let _ = value.setattr("kind", fault.kind.name());
        let _ = value.setattr("file", fault.file);
        let _ = value.setattr("key", fault.key);
        let _ = value.setattr("line", fault.line);
    });
    err
}

/// A panic's message as the exception of a defect.
pub fn internal(why: &str) -> PyErr {
    Error::new_err(format!("internal error: {why}"))
}
