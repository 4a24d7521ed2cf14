//! Floor response spectra of one case (`floor_spectra:` in a case file): each floor's
//! pseudo-acceleration spectrum of its absolute acceleration history, the input a
//! nonstructural designer reads (docs/model.md, "Floor response spectra"; the request, the
//! refinement and the spectra of a history in [`crate::spectrum::floor`]).

use super::{Simulation, SimulationError};
use crate::dynamics::Watch;
use serde::Serialize;

pub use crate::spectrum::floor::{
    DEFAULT_DAMPING, DEFAULT_PERIODS, FloorSpectraSettings, FloorSpectraSpec, Periods, REFINEMENT,
};

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

/// The floor response spectra of `sim` as `spec` asks, from its run on the record refined
/// `refinement` times, under `watch`.
pub fn floor_spectra(
    sim: &Simulation,
    spec: &FloorSpectraSpec,
    refinement: usize,
    watch: &dyn Watch,
) -> Result<FloorSpectra, SimulationError> {
    let mut fine = sim.with_record(sim.record.refined(refinement))?;
    fine.floor_spectra = None;
    fine.history = None;
    let accel = fine.accel_mps2();
    let (_, history) = fine.run_watched(&accel, true, watch)?;
    let h = history.expect("a run asked for its history keeps it");
    let floors = match &sim.model {
        super::Model::OneStorey { .. } => 1,
        super::Model::Building { building, .. } => building.storeys(),
    };
    let psa_g = crate::spectrum::floor::floor_psa_g(&h, floors, fine.record.dt_s, spec)
        .map_err(|e| SimulationError::Invalid(format!("floor_spectra: {e}")))?;
    Ok(FloorSpectra {
        periods_s: spec.periods_s.clone(),
        damping: spec.damping.clone(),
        psa_g,
        refinement,
    })
}
