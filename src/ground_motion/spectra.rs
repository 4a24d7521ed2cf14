//! Spectra of several records at several damping ratios (and, for constant-ductility spectra,
//! several target ductilities), computed in parallel: the work of `slidestack spectrum` and of
//! the Python module's `spectrum`, in one place. Each job is independent and its result lands
//! in the job's slot, so the output is the same whatever the number of threads.

use super::Record;
use crate::spectrum::SpectrumError;
use crate::spectrum::ductility::{
    DuctilityError, DuctilityOptions, DuctilityPoint, constant_ductility_spectrum,
};
use crate::spectrum::response_spectrum;
use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;

/// One record at one damping ratio (the `spectrum --json` contract).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordSpectrum {
    pub record: String,
    pub damping: f64,
    pub periods_s: Vec<f64>,
    /// Peak relative displacement, m.
    pub sd_m: Vec<f64>,
    /// Pseudo-velocity `ω·Sd`, m/s.
    pub psv_mps: Vec<f64>,
    /// Pseudo-acceleration `ω²·Sd`, g.
    pub psa_g: Vec<f64>,
    /// Time of the displacement peak, s.
    pub peak_time_s: Vec<f64>,
}

/// One record, damping ratio and target ductility (the `spectrum --ductility --json` contract).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DuctilitySpectrum {
    pub record: String,
    pub damping: f64,
    pub ductility: f64,
    pub post_yield_ratio: f64,
    pub periods_s: Vec<f64>,
    /// `C_y = F_y/(m·g) = A_y/g`.
    pub strength_ratio: Vec<f64>,
    pub yield_displacement_m: Vec<f64>,
    pub peak_displacement_m: Vec<f64>,
    /// `u_m/u_y` at `strength_ratio` (the target to the bisection's tolerance).
    pub ductility_reached: Vec<f64>,
    /// `C_e = PSA/g` of the elastic oscillator.
    pub elastic_strength_ratio: Vec<f64>,
    /// `R_y = C_e/C_y`.
    pub reduction_factor: Vec<f64>,
}

#[derive(Debug, Error)]
pub enum SpectraError {
    #[error("`damping` {0} must be in [0, 1)")]
    Damping(f64),
    #[error("{record}: cannot compute its spectrum: {source}")]
    Spectrum {
        record: String,
        source: SpectrumError,
    },
    #[error("{record}: {source}")]
    Ductility {
        record: String,
        source: DuctilityError,
    },
}

/// Refuses a damping ratio outside `[0, 1)` before any work.
fn check_dampings(dampings: &[f64]) -> Result<(), SpectraError> {
    match dampings
        .iter()
        .find(|z| !(z.is_finite() && (0.0..1.0).contains(*z)))
    {
        Some(&z) => Err(SpectraError::Damping(z)),
        None => Ok(()),
    }
}

/// The elastic spectrum of every record at every damping ratio, record-major.
pub fn response_spectra(
    records: &[Record],
    periods_s: &[f64],
    dampings: &[f64],
) -> Result<Vec<RecordSpectrum>, SpectraError> {
    check_dampings(dampings)?;
    let jobs: Vec<(&Record, f64)> = records
        .iter()
        .flat_map(|r| dampings.iter().map(move |&z| (r, z)))
        .collect();
    jobs.par_iter()
        .map(|&(rec, z)| {
            let s = response_spectrum(&rec.accel_mps2(1.0), rec.dt_s, periods_s, z).map_err(
                |source| SpectraError::Spectrum {
                    record: rec.name.clone(),
                    source,
                },
            )?;
            Ok(RecordSpectrum {
                record: rec.name.clone(),
                damping: z,
                periods_s: periods_s.to_vec(),
                sd_m: s.sd_m(),
                psv_mps: s.psv_mps(),
                psa_g: s.psa_g(),
                peak_time_s: s.peaks.iter().map(|p| p.time_s).collect(),
            })
        })
        .collect()
}

/// The constant-ductility spectrum of every record at every damping ratio and target
/// ductility (record-major, then damping), for oscillators of post-yield ratio
/// `post_yield_ratio`.
pub fn ductility_spectra(
    records: &[Record],
    periods_s: &[f64],
    dampings: &[f64],
    ductilities: &[f64],
    post_yield_ratio: f64,
) -> Result<Vec<DuctilitySpectrum>, SpectraError> {
    check_dampings(dampings)?;
    let jobs: Vec<(&Record, f64, f64)> = records
        .iter()
        .flat_map(|r| {
            dampings
                .iter()
                .flat_map(move |&z| ductilities.iter().map(move |&mu| (r, z, mu)))
        })
        .collect();
    jobs.par_iter()
        .map(|&(rec, z, mu)| {
            let opts = DuctilityOptions {
                damping: z,
                post_yield_ratio,
            };
            let pts =
                constant_ductility_spectrum(&rec.accel_mps2(1.0), rec.dt_s, periods_s, mu, opts)
                    .map_err(|source| SpectraError::Ductility {
                        record: rec.name.clone(),
                        source,
                    })?;
            let col = |f: fn(&DuctilityPoint) -> f64| pts.iter().map(f).collect::<Vec<f64>>();
            Ok(DuctilitySpectrum {
                record: rec.name.clone(),
                damping: z,
                ductility: mu,
                post_yield_ratio,
                periods_s: periods_s.to_vec(),
                strength_ratio: col(|p| p.strength_ratio),
                yield_displacement_m: col(|p| p.yield_displacement_m),
                peak_displacement_m: col(|p| p.peak_displacement_m),
                ductility_reached: col(|p| p.ductility),
                elastic_strength_ratio: col(|p| p.elastic_strength_ratio),
                reduction_factor: col(|p| p.reduction_factor),
            })
        })
        .collect()
}
