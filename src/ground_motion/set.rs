//! A matched set of motions: what matching a zone's seeds to its target gave, and the checks on
//! the set (the content of one zone of `motions.h5`; the stage that makes it is
//! [`crate::study::motions::match_zone`]).

use super::Record;
use super::matching::MatchReport;
use crate::spectrum::TargetSpectrum;
use std::fmt;

/// One motion that does not meet the acceptance.
#[derive(Debug, Clone, PartialEq)]
pub struct UnmatchedRecord {
    pub name: String,
    /// Check period of the largest misfit, s, and spectrum/target there (after the set scale
    /// when `after_set_scale`).
    pub worst_period_s: f64,
    pub worst_ratio: f64,
    pub iterations: usize,
    /// Outside the band only once the set scale was applied.
    pub after_set_scale: bool,
}

impl fmt::Display for UnmatchedRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: PSA/target {:.3} at {:.3} s{} after {} iterations",
            self.name,
            self.worst_ratio,
            self.worst_period_s,
            if self.after_set_scale {
                " once the set is scaled"
            } else {
                ""
            },
            self.iterations
        )
    }
}

/// The matched motions of one zone and the checks on them.
#[derive(Debug, Clone)]
pub struct ZoneMotions {
    pub name: String,
    pub target: TargetSpectrum,
    /// The check grid, s.
    pub periods_s: Vec<f64>,
    pub target_psa_g: Vec<f64>,
    /// Names of the seeds tried (spares that were not needed are not), and what matching did to
    /// each.
    pub seeds: Vec<String>,
    pub reports: Vec<MatchReport>,
    /// Indices (into `seeds`) of the motions kept: the accepted ones, and with
    /// `allow_unmatched` the others needed (their reports say `converged: false`).
    pub kept: Vec<usize>,
    /// The kept motions, after the set scale.
    pub motions: Vec<Record>,
    /// PSA of each kept motion on the check grid, g.
    pub psa_g: Vec<Vec<f64>>,
    pub mean_psa_g: Vec<f64>,
    /// Factor applied to all kept motions to lift the set mean (1 when not needed).
    pub set_scale: f64,
    /// `min_T mean/target` after the set scale.
    pub mean_ratio_min: f64,
    pub set_mean_ok: bool,
    /// The ASCE 7-16 rule: the mean does not fall below 90 % of the target.
    pub asce7_ok: bool,
    /// Every kept motion within `[lower, upper]` after the set scale.
    pub all_within_band: bool,
    /// The kept motions that are not (flagged; empty unless `allow_unmatched`).
    pub unmatched: Vec<UnmatchedRecord>,
}
