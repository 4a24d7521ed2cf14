//! Floor response spectra of one case (`floor_spectra:` in a case file): each floor's
//! pseudo-acceleration spectrum of its absolute acceleration history, the input a
//! nonstructural designer reads (docs/model.md, "Floor response spectra").
//!
//! The floor's history is not linear between record samples (the structure's response is smooth
//! within them, and a stack's switch makes a floor's acceleration jump), so the spectrum of its
//! record-rate samples is not the spectrum of the floor. The case is run again on its record
//! linearly interpolated to `1/REFINEMENT` of the step: the same ground motion (the record is
//! linear between samples), so the same response, its history now `REFINEMENT` times denser;
//! the spectrum of that history (exact for a history linear between its samples,
//! [`crate::spectrum::response_spectrum`]) differs from the floor's by the history's departure
//! from linear over `dt/REFINEMENT`, measured in tests/floor_spectra.rs against a history four
//! times denser still and, where the floor's spectrum is known exactly (one storey whose stack
//! cannot slide), against the cascade of the structure and the oscillator.

use super::{Simulation, SimulationError};
use crate::dynamics::Watch;
use crate::ground_motion::Record;
use crate::limits::{DT_RANGE_S, MAX_SAMPLES};
use crate::spectrum::{parse_periods, periods_from_list, response_spectrum};
use serde::{Deserialize, Serialize};

/// Samples of the refined record per record step.
pub const REFINEMENT: usize = 64;

/// The periods when the case file gives none (the `--periods` syntax: 0.05 to 4 s by 0.01 s).
pub const DEFAULT_PERIODS: &str = "0.05:4:0.01";

/// The damping ratios when the case file gives none.
pub const DEFAULT_DAMPING: [f64; 1] = [0.05];

/// Periods as a case file writes them: the `--periods` syntax or a list of seconds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Periods {
    Spec(String),
    List(Vec<f64>),
}

/// The `floor_spectra:` key of a case file.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FloorSpectraSettings {
    /// Oscillator periods, s [default: 0.05:4:0.01].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub periods: Option<Periods>,
    /// Oscillator damping ratios [default: [0.05]].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<Vec<f64>>,
}

/// The checked request: periods and damping ratios.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorSpectraSpec {
    pub periods_s: Vec<f64>,
    pub damping: Vec<f64>,
}

impl FloorSpectraSettings {
    /// The periods parsed and every damping ratio checked (`0 ≤ ζ < 1`); a message naming the
    /// key otherwise.
    pub fn resolve(&self) -> Result<FloorSpectraSpec, String> {
        let periods_s = match &self.periods {
            None => parse_periods(DEFAULT_PERIODS),
            Some(Periods::Spec(s)) => parse_periods(s),
            Some(Periods::List(v)) => periods_from_list(v),
        }
        .map_err(|e| format!("`floor_spectra.periods`: {e}"))?;
        let damping = self.damping.clone().unwrap_or(DEFAULT_DAMPING.to_vec());
        if damping.is_empty() {
            return Err("`floor_spectra.damping` is empty: give at least one ratio".into());
        }
        if let Some(z) = damping
            .iter()
            .find(|z| !(z.is_finite() && (0.0..1.0).contains(*z)))
        {
            return Err(format!("`floor_spectra.damping` {z} must be in [0, 1)"));
        }
        Ok(FloorSpectraSpec { periods_s, damping })
    }
}

/// A case's floor response spectra (`simulate --json`'s `floor_spectra`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FloorSpectra {
    pub periods_s: Vec<f64>,
    pub damping: Vec<f64>,
    /// Pseudo-acceleration `ω²·Sd`, g: `[damping][floor][period]`, floor 1 first (one storey:
    /// the structure).
    pub psa_g: Vec<Vec<Vec<f64>>>,
    /// Samples of the history per record step ([`REFINEMENT`]).
    pub refinement: usize,
}

/// Refuses a record whose refined history the spectrum cannot take (too many samples, too short
/// a step: [`crate::limits`]), before any run.
pub fn check_record(record: &Record, refinement: usize) -> Result<(), String> {
    let samples = (record.accel_g.len().saturating_sub(1)).saturating_mul(refinement) + 1;
    let dt_s = record.dt_s / refinement as f64;
    if samples > MAX_SAMPLES || dt_s < DT_RANGE_S.0 {
        return Err(format!(
            "`floor_spectra`: the record refined {refinement} times has {samples} samples {dt_s:e} s \
             apart; the spectrum takes at most {MAX_SAMPLES} samples at least {:e} s apart",
            DT_RANGE_S.0
        ));
    }
    Ok(())
}

/// `record` linearly interpolated to `1/refinement` of its step: the same piecewise-linear
/// ground motion, sampled `refinement` times as densely.
pub fn refined(record: &Record, refinement: usize) -> Record {
    let a = &record.accel_g;
    let mut fine = Vec::with_capacity((a.len().saturating_sub(1)) * refinement + 1);
    for w in a.windows(2) {
        for i in 0..refinement {
            fine.push(w[0] + (w[1] - w[0]) * (i as f64 / refinement as f64));
        }
    }
    fine.extend(a.last());
    Record {
        name: record.name.clone(),
        dt_s: record.dt_s / refinement as f64,
        accel_g: fine,
    }
}

/// The floor response spectra of `sim` as `spec` asks, from its run on the record refined
/// [`REFINEMENT`] times, under `watch`.
pub fn floor_spectra(
    sim: &Simulation,
    spec: &FloorSpectraSpec,
    refinement: usize,
    watch: &dyn Watch,
) -> Result<FloorSpectra, SimulationError> {
    let mut fine = sim.with_record(refined(&sim.record, refinement))?;
    fine.floor_spectra = None;
    fine.history = None;
    let accel = fine.accel_mps2();
    let (_, history) = fine.run_watched(&accel, true, watch)?;
    let h = history.expect("a run asked for its history keeps it");
    let floors = match &sim.model {
        super::Model::OneStorey { .. } => 1,
        super::Model::Building { building, .. } => building.storeys(),
    };
    let rows = h.rows();
    let mut psa_g = vec![Vec::with_capacity(floors); spec.damping.len()];
    for floor in 0..floors {
        let series: Vec<f64> = (0..rows)
            .map(|r| h.abs_accel_mps2[r * h.bodies + floor])
            .collect();
        for (z, &zeta) in spec.damping.iter().enumerate() {
            let s = response_spectrum(&series, fine.record.dt_s, &spec.periods_s, zeta)
                .map_err(|e| SimulationError::Invalid(format!("floor_spectra: {e}")))?;
            psa_g[z].push(s.psa_g());
        }
    }
    Ok(FloorSpectra {
        periods_s: spec.periods_s.clone(),
        damping: spec.damping.clone(),
        psa_g,
        refinement,
    })
}
