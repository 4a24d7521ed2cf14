//! Floor response spectra: what a case or a study asks for (`floor_spectra:` periods and
//! damping ratios), the refinement of the record that makes a floor's history linear enough
//! between samples, and each floor's pseudo-acceleration spectrum of its absolute acceleration
//! history (docs/model.md, "Floor response spectra").
//!
//! The floor's history is not linear between record samples (the structure's response is smooth
//! within them, and a stack's switch makes a floor's acceleration jump), so the spectrum of its
//! record-rate samples is not the spectrum of the floor. The case is run again on its record
//! linearly interpolated to `1/REFINEMENT` of the step ([`crate::ground_motion::Record::refined`]):
//! the same ground motion (the record is linear between samples), so the same response, its
//! history now `REFINEMENT` times denser; the spectrum of that history (exact for a history linear
//! between its samples, [`super::response_spectrum`]) differs from the floor's by the history's
//! departure from linear over `dt/REFINEMENT`, measured in tests/floor_spectra.rs against a
//! history four times denser still and, where the floor's spectrum is known exactly (one storey
//! whose stack cannot slide), against the cascade of the structure and the oscillator.

use super::{SpectrumError, parse_periods, periods_from_list, response_spectrum};
use crate::dynamics::History;
use serde::{Deserialize, Serialize};

/// Samples of the refined record per record step.
pub const REFINEMENT: usize = 64;

/// The periods when none are given (the `--periods` syntax: 0.05 to 4 s by 0.01 s).
pub const DEFAULT_PERIODS: &str = "0.05:4:0.01";

/// The damping ratios when none are given.
pub const DEFAULT_DAMPING: [f64; 1] = [0.05];

/// Periods as a file writes them: the `--periods` syntax or a list of seconds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Periods {
    Spec(String),
    List(Vec<f64>),
}

/// The `floor_spectra:` key of a case file (a study's section adds its cases).
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
        self.checked().map_err(|(key, why)| match key {
            "periods" => format!("`floor_spectra.periods`: {why}"),
            _ => format!("`floor_spectra.{key}` {why}"),
        })
    }

    /// [`Self::resolve`], a refusal as the key under `floor_spectra.` (`periods`, `damping`)
    /// and why.
    pub fn checked(&self) -> Result<FloorSpectraSpec, (&'static str, String)> {
        let periods_s = match &self.periods {
            None => parse_periods(DEFAULT_PERIODS),
            Some(Periods::Spec(s)) => parse_periods(s),
            Some(Periods::List(v)) => periods_from_list(v),
        }
        .map_err(|e| ("periods", e.to_string()))?;
        let damping = self.damping.clone().unwrap_or(DEFAULT_DAMPING.to_vec());
        if damping.is_empty() {
            return Err(("damping", "is empty: give at least one ratio".into()));
        }
        if let Some(z) = damping
            .iter()
            .find(|z| !(z.is_finite() && (0.0..1.0).contains(*z)))
        {
            return Err(("damping", format!("{z} must be in [0, 1)")));
        }
        Ok(FloorSpectraSpec { periods_s, damping })
    }
}

/// Each of the first `floors` bodies' pseudo-acceleration spectra `ω²·Sd`, g, of its absolute
/// acceleration in `history` (rows `dt_s` apart), as `spec` asks: `[damping][floor][period]`.
pub fn floor_psa_g(
    history: &History,
    floors: usize,
    dt_s: f64,
    spec: &FloorSpectraSpec,
) -> Result<Vec<Vec<Vec<f64>>>, SpectrumError> {
    let rows = history.rows();
    let mut psa_g = vec![Vec::with_capacity(floors); spec.damping.len()];
    for floor in 0..floors {
        let series: Vec<f64> = (0..rows)
            .map(|r| history.abs_accel_mps2[r * history.bodies + floor])
            .collect();
        for (z, &zeta) in spec.damping.iter().enumerate() {
            psa_g[z].push(response_spectrum(&series, dt_s, &spec.periods_s, zeta)?.psa_g());
        }
    }
    Ok(psa_g)
}
