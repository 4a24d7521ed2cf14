//! Library errors as Python exceptions, with the CLI's message (the error and its causes, each
//! once): `FileNotFoundError` and `OSError` where a file could not be read or written,
//! `ValueError` where the input is at fault, `RuntimeError` where the run failed,
//! `KeyboardInterrupt` for a stage stopped by Ctrl-C.

use pyo3::PyErr;
use pyo3::exceptions::{
    PyFileNotFoundError, PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError,
};
use slidestack::design::DesignError;
use slidestack::ground_motion::matching::MatchError;
use slidestack::pipeline::PipelineError;
use slidestack::simulation::SimulationError;
use slidestack::spectrum::batch::BatchError;
use std::error::Error;

/// Whose fault an error is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    Input,
    Run,
    Interrupted,
}

impl Fault {
    pub fn of_simulation(e: &SimulationError) -> Self {
        Self::input_if(e.is_bad_input())
    }
    pub fn of_batch(e: &BatchError) -> Self {
        Self::input_if(e.is_bad_input())
    }
    pub fn of_design(e: &DesignError) -> Self {
        Self::input_if(e.is_bad_input())
    }
    pub fn of_match(e: &MatchError) -> Self {
        Self::input_if(matches!(
            e,
            MatchError::Setting { .. } | MatchError::Spectrum(_)
        ))
    }
    pub fn of_pipeline(e: &PipelineError) -> Self {
        match e {
            PipelineError::Cancelled(_) => Fault::Interrupted,
            _ => Self::input_if(e.is_bad_input()),
        }
    }
    fn input_if(bad: bool) -> Self {
        if bad { Fault::Input } else { Fault::Run }
    }
}

/// The message the CLI prints after `error: `: the error and each cause whose text it does not
/// already hold.
pub fn message(e: &(dyn Error + 'static)) -> String {
    let mut text = String::new();
    let mut cause: Option<&(dyn Error + 'static)> = Some(e);
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

/// The Python exception for `e`: an I/O error anywhere in its chain decides the class (a missing
/// file is `FileNotFoundError`), else `fault` does.
pub fn to_py_err(e: &(dyn Error + 'static), fault: Fault) -> PyErr {
    let msg = message(e);
    if fault == Fault::Interrupted {
        return PyKeyboardInterrupt::new_err(msg);
    }
    let mut cause: Option<&(dyn Error + 'static)> = Some(e);
    while let Some(c) = cause {
        if let Some(io) = c.downcast_ref::<std::io::Error>() {
            return match io.kind() {
                std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
                _ => PyOSError::new_err(msg),
            };
        }
        if let Some(DesignError::Missing { .. }) = c.downcast_ref::<DesignError>() {
            return PyFileNotFoundError::new_err(msg);
        }
        cause = c.source();
    }
    match fault {
        Fault::Input => PyValueError::new_err(msg),
        _ => PyRuntimeError::new_err(msg),
    }
}
