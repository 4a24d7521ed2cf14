//! The structure-and-stack model and its integrators.
//!
//! * [`model`]: the validated system (docs/model.md, "The physical system").
//! * [`contact`]: the Coulomb-consistent stick/slip pattern at an instant.
//! * [`exact`]: the default event-driven integrator, exact for piecewise-linear ground motion.
//! * [`rk4`]: the paper's fixed-step RK4 with its top-down cluster rule, kept as a reference.
//!
//! Nothing here reads files or configurations: inputs are slices and small structs.
//!
//! # A yielding structure
//!
//! [`System::with_yielding`] turns the linear structure into an elastic–perfectly-plastic or
//! bilinear one ([`Yielding`]; docs/model.md, "Yielding structure"). Both integrators take it;
//! the [`Response`] then carries [`Response::ductility`] (`u_m/u_y`),
//! [`Response::residual_displacement_m`] and [`Energy::hysteretic`]. A study stage (incremental
//! dynamic analysis) builds the system once per case and scales the record per intensity into a
//! reused buffer:
//!
//! ```
//! use slidestack::dynamics::{ExactOptions, Ground, System, SystemSpec, Yielding, simulate_exact};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let spec = SystemSpec::new(1.0, &[0.5, 0.5], &[0.2, 0.1]);
//! let sys = System::new(&spec)?.with_yielding(Yielding::bilinear(0.15, 0.05))?;
//! let opts = ExactOptions { energy_balance: false, ..ExactOptions::default() };
//! let record: Vec<f64> = (0..2000).map(|k| (0.02 * k as f64).sin()).collect(); // m/s²
//! let mut accel = Vec::with_capacity(record.len());
//! for lambda in [0.5, 1.0, 2.0] {
//!     accel.clear();
//!     accel.extend(record.iter().map(|a| lambda * a));
//!     let r = simulate_exact(&sys, &Ground { dt_s: 0.01, accel_mps2: &accel }, &opts)?;
//!     let (mu, drift) = (r.ductility.unwrap(), r.residual_displacement_m);
//!     assert!(mu > 0.0 && drift.is_finite() && r.peak_slip_m.len() == 2);
//! }
//! # Ok(())
//! # }
//! ```
//!
//! The residual drift is the displacement at the record's end (pad the record with zeros to
//! read it at rest); `yield_events == 0` means the structure stayed elastic. Neither model has
//! negative stiffness, so a collapse criterion must be a ductility or drift cap.

pub mod building;
pub mod closed_form;
pub mod contact;
pub(crate) mod deferred;
pub mod exact;
pub mod model;
pub mod response;
pub mod rk4;
pub mod rocking;
pub(crate) mod search;

pub use contact::{Contact, ContactSelector};
pub use exact::{ExactOptions, simulate_exact, simulate_exact_watched};
pub use model::{DampingBasis, G, Hysteresis, ModelError, System, SystemSpec, Yielding};
pub use response::{Energy, History, Response};
pub use rk4::{simulate_rk4, simulate_rk4_watched};
pub use rocking::{Rocking, RockingOnset};
pub use search::SearchError;

use crate::limits::{
    DT_RANGE_S, MAX_PEAK_ACCEL_G, MAX_RK4_SUBSTEPS, MAX_SAMPLES, RK4_MAX_OMEGA_STEP,
};
use thiserror::Error;

/// A ground acceleration sampled at a constant step, linear between samples.
#[derive(Debug, Clone, Copy)]
pub struct Ground<'a> {
    /// Sample interval, s.
    pub dt_s: f64,
    /// Ground acceleration at `t = k·dt`, m/s².
    pub accel_mps2: &'a [f64],
}

impl<'a> Ground<'a> {
    /// `accel_mps2` (m/s²) sampled every `dt_s` (s).
    pub fn new(dt_s: f64, accel_mps2: &'a [f64]) -> Self {
        Self { dt_s, accel_mps2 }
    }
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum SimError {
    #[error(
        "time step dt must be within {lo} … {hi} s, got {0:?} s",
        lo = DT_RANGE_S.0,
        hi = DT_RANGE_S.1
    )]
    TimeStep(f64),
    #[error("a ground motion may have at most {MAX_SAMPLES} samples, got {0}")]
    TooLong(usize),
    #[error("ground motion needs at least 2 samples, got {0}")]
    TooShort(usize),
    #[error("ground acceleration sample {index} is not finite ({value})")]
    NonFinite { index: usize, value: f64 },
    #[error(
        "ground acceleration sample {index} is {value_g:.3e} g, beyond the {MAX_PEAK_ACCEL_G:e} g a \
         simulation takes (its results would be round-off; a unit or scale mistake?)"
    )]
    PeakAccel { index: usize, value_g: f64 },
    #[error(
        "switches accumulate (Zeno behaviour): more than {limit} stick/slip switches within the \
         sample interval starting at t = {time_s} s; the case is refused rather than run forever"
    )]
    Zeno { time_s: f64, limit: usize },
    #[error("rk4 sub-steps per sample must be 1 … {MAX_RK4_SUBSTEPS}, got {0}")]
    Substeps(usize),
    #[error(
        "rk4 with {substeps} sub-steps of dt = {dt_s} s is unstable for T_p = {period_s} s \
         (ω·h = {omega_step:.2} > {RK4_MAX_OMEGA_STEP}); use at least {needed} sub-steps, or the \
         exact integrator"
    )]
    Rk4Unstable {
        period_s: f64,
        dt_s: f64,
        substeps: usize,
        omega_step: f64,
        needed: usize,
    },
    #[error("the response is not finite (the integration diverged)")]
    Diverged,
    /// The run's [`Watch`] said stop (Ctrl-C).
    #[error("stopped at sample {sample} of {samples}")]
    Stopped { sample: usize, samples: usize },
    /// A certified search for a switch or a peak that could not proceed.
    #[error("in the sample interval starting at t = {time_s} s: {source}")]
    Search {
        time_s: f64,
        #[source]
        source: SearchError,
    },
    /// A building's contact and yield state that the modal solution cannot represent.
    #[error("{0}")]
    Modal(String),
    #[error(transparent)]
    Contact(#[from] contact::ContactError),
}

/// Someone watching a long run: told every [`WATCH_EVERY`] samples how far it is, and asked
/// whether to go on (a progress bar, Ctrl-C). The integrators' `*_watched` entry points take
/// one; the others run [`Unwatched`].
pub trait Watch: Sync {
    /// `sample` of `samples` done; `false` stops the run ([`SimError::Stopped`]).
    fn going_on(&self, sample: usize, samples: usize) -> bool;
}

/// A run nobody watches.
pub struct Unwatched;

impl Watch for Unwatched {
    fn going_on(&self, _: usize, _: usize) -> bool {
        true
    }
}

/// Samples between two calls of [`Watch::going_on`]: a small share of a sample interval's
/// work for the largest building, often enough for a bar and for Ctrl-C.
pub const WATCH_EVERY: usize = 64;

/// Asks `watch` at sample `k` of `steps` whether to go on.
pub(crate) fn watched(watch: &dyn Watch, k: usize, steps: usize) -> Result<(), SimError> {
    if k.is_multiple_of(WATCH_EVERY) && !watch.going_on(k, steps) {
        return Err(SimError::Stopped {
            sample: k,
            samples: steps,
        });
    }
    Ok(())
}

impl Ground<'_> {
    pub fn validate(&self) -> Result<(), SimError> {
        if !(DT_RANGE_S.0..=DT_RANGE_S.1).contains(&self.dt_s) {
            return Err(SimError::TimeStep(self.dt_s));
        }
        if self.accel_mps2.len() < 2 {
            return Err(SimError::TooShort(self.accel_mps2.len()));
        }
        if self.accel_mps2.len() > MAX_SAMPLES {
            return Err(SimError::TooLong(self.accel_mps2.len()));
        }
        let most = MAX_PEAK_ACCEL_G * G;
        // One pass without a branch per sample (the compiler vectorises it: kernels validate
        // their record at every run); the offending sample is looked for only when there is one.
        let within = (self.accel_mps2.iter()).fold(true, |ok, a| ok & (a.abs() <= most));
        if within {
            return Ok(());
        }
        if let Some((index, &value)) = self
            .accel_mps2
            .iter()
            .enumerate()
            .find(|(_, a)| !a.is_finite())
        {
            return Err(SimError::NonFinite { index, value });
        }
        if let Some((index, &value)) = self
            .accel_mps2
            .iter()
            .enumerate()
            .find(|(_, a)| a.abs() > most)
        {
            return Err(SimError::PeakAccel {
                index,
                value_g: value / G,
            });
        }
        Ok(())
    }

    /// Duration covered, s.
    pub fn duration_s(&self) -> f64 {
        (self.accel_mps2.len() - 1) as f64 * self.dt_s
    }
}

/// What a user should know before trusting a run that is allowed but near the edge of what the
/// record and the integrator resolve.
pub fn accuracy_warnings(sys: &System, ground: &Ground) -> Vec<String> {
    let t_rigid_s = sys.period_rigid_s();
    let mut out = Vec::new();
    let duration = ground.duration_s();
    if t_rigid_s > 10.0 * duration {
        out.push(format!(
            "T_rigid = {t_rigid_s} s is more than ten times the record's {duration} s: the \
             structure barely responds dynamically and its displacement follows the ground's, \
             which depends on the record's baseline correction"
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one-pass check finds what a sample-by-sample search finds: the first sample that is
    /// not finite before any that is too large, each at its index, and nothing in a record
    /// within the limit (its largest sample exactly at it).
    #[test]
    fn validate_names_the_first_offending_sample() {
        let most = MAX_PEAK_ACCEL_G * G;
        let check = |accel: &[f64]| {
            Ground {
                dt_s: 0.01,
                accel_mps2: accel,
            }
            .validate()
        };
        let mut a = vec![0.5; 37];
        a[20] = -most;
        assert_eq!(check(&a), Ok(()));
        a[30] = f64::NAN;
        a[25] = 2.0 * most;
        assert!(matches!(
            check(&a),
            Err(SimError::NonFinite { index: 30, .. })
        ));
        a[30] = 0.0;
        assert!(matches!(
            check(&a),
            Err(SimError::PeakAccel { index: 25, .. })
        ));
        a[3] = f64::NEG_INFINITY;
        assert!(matches!(
            check(&a),
            Err(SimError::NonFinite { index: 3, .. })
        ));
    }
}
