//! The structure-and-stack model and its integrators.
//!
//! * [`model`]: the validated system (NOTES.md, "The physical system").
//! * [`contact`]: the Coulomb-consistent stick/slip pattern at an instant.
//! * [`exact`]: the default event-driven integrator, exact for piecewise-linear ground motion.
//! * [`rk4`]: the paper's fixed-step RK4 with its top-down cluster rule, kept as a reference.
//!
//! Nothing here reads files or configurations: inputs are slices and small structs.

pub mod closed_form;
pub mod contact;
pub mod exact;
pub mod model;
pub mod response;
pub mod rk4;

pub use contact::{Contact, ContactSelector};
pub use exact::{ExactOptions, simulate_exact};
pub use model::{G, ModelError, System, SystemSpec};
pub use response::{Energy, History, Response};
pub use rk4::simulate_rk4;

use thiserror::Error;

/// A ground acceleration sampled at a constant step, linear between samples.
#[derive(Debug, Clone, Copy)]
pub struct Ground<'a> {
    /// Sample interval, s.
    pub dt_s: f64,
    /// Ground acceleration at `t = k·dt`, m/s².
    pub accel_mps2: &'a [f64],
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum SimError {
    #[error("time step dt must be finite and > 0, got {0} s")]
    TimeStep(f64),
    #[error("ground motion needs at least 2 samples, got {0}")]
    TooShort(usize),
    #[error("ground acceleration sample {index} is not finite ({value})")]
    NonFinite { index: usize, value: f64 },
    #[error(
        "switches accumulate (Zeno behaviour): more than {limit} stick/slip switches within the \
         sample interval starting at t = {time_s} s; the case is refused rather than run forever"
    )]
    Zeno { time_s: f64, limit: usize },
    #[error("rk4 sub-steps per sample must be >= 1, got {0}")]
    Substeps(usize),
    #[error(transparent)]
    Contact(#[from] contact::ContactError),
}

impl Ground<'_> {
    pub fn validate(&self) -> Result<(), SimError> {
        if !(self.dt_s.is_finite() && self.dt_s > 0.0) {
            return Err(SimError::TimeStep(self.dt_s));
        }
        if self.accel_mps2.len() < 2 {
            return Err(SimError::TooShort(self.accel_mps2.len()));
        }
        if let Some((index, &value)) = self
            .accel_mps2
            .iter()
            .enumerate()
            .find(|(_, a)| !a.is_finite())
        {
            return Err(SimError::NonFinite { index, value });
        }
        Ok(())
    }

    /// Duration covered, s.
    pub fn duration_s(&self) -> f64 {
        (self.accel_mps2.len() - 1) as f64 * self.dt_s
    }
}
