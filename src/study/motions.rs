//! The motions stage: seed motions (stochastic or records), matched to each zone's target, and
//! the checks on the set.
//!
//! A seed that does not meet the matching acceptance is reported and left out of the zone. The
//! set's mean spectrum must not fall below `set_mean_min` of the target on the check grid: when
//! it does, the kept motions are scaled up together by the smallest factor that lifts it there,
//! and `all_within_band` says whether every motion still meets the upper bound afterwards.

use super::config::{MotionsConfig, Seeds, StudyConfig};
use crate::motion::matching::{MatchError, MatchReport, match_record};
use crate::motion::stochastic::StochasticError;
use crate::motion::{Record, RecordError, read_record_with};
use crate::spectrum::TargetSpectrum;
use rayon::prelude::*;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum SeedError {
    #[error(transparent)]
    Record(#[from] RecordError),
    #[error("stochastic seeds: {0}")]
    Stochastic(#[from] StochasticError),
}

/// The seed motions of a study, in configuration order.
pub fn seed_records(cfg: &MotionsConfig) -> Result<Vec<Record>, SeedError> {
    match cfg.seeds.kind() {
        Seeds::Stochastic(s) => {
            Ok(s.model
                .simulate_set(s.seed, s.count + s.spare, "stochastic")?)
        }
        Seeds::Records(r) => {
            let opts = StudyConfig::read_options(r);
            r.files
                .iter()
                .map(|f| read_record_with(f, &opts).map_err(SeedError::from))
                .collect()
        }
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
    /// Indices (into `seeds`) of the motions kept.
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
}

/// Matches every seed to `target` (in parallel; the result does not depend on the thread count)
/// and applies the set checks.
pub fn match_zone(
    name: &str,
    target: &TargetSpectrum,
    seeds: &[Record],
    cfg: &MotionsConfig,
) -> Result<ZoneMotions, MatchError> {
    let settings = &cfg.matching;
    let periods_s = settings.check_grid_s();
    let target_psa_g: Vec<f64> = periods_s.iter().map(|&t| target.sa_g(t)).collect();
    let wanted = match cfg.seeds.kind() {
        Seeds::Stochastic(s) => s.count,
        Seeds::Records(_) => seeds.len(),
    };
    // Seeds are matched in order, a batch at a time, until `wanted` are accepted: spares are
    // only matched when needed, and which seeds are tried does not depend on the thread count.
    let mut matched = Vec::new();
    loop {
        let accepted = matched
            .iter()
            .filter(|m: &&crate::motion::matching::Matched| m.report.converged)
            .count();
        if accepted >= wanted || matched.len() == seeds.len() {
            break;
        }
        let from = matched.len();
        let to = (from + wanted - accepted).min(seeds.len());
        let batch = seeds[from..to]
            .par_iter()
            .map(|s| match_record(&s.accel_g, s.dt_s, target, settings))
            .collect::<Result<Vec<_>, _>>()?;
        matched.extend(batch);
    }
    let seeds = &seeds[..matched.len()];
    let kept: Vec<usize> = (0..seeds.len())
        .filter(|&i| matched[i].report.converged)
        .take(wanted)
        .collect();
    let n = periods_s.len();
    let mean = |psa: &[Vec<f64>]| -> Vec<f64> {
        (0..n)
            .map(|p| psa.iter().map(|s| s[p]).sum::<f64>() / psa.len().max(1) as f64)
            .collect()
    };
    let mut psa_g: Vec<Vec<f64>> = kept
        .iter()
        .map(|&i| matched[i].check_psa_g.clone())
        .collect();
    let ratio_min = |m: &[f64]| {
        m.iter()
            .zip(&target_psa_g)
            .map(|(a, q)| a / q)
            .fold(f64::INFINITY, f64::min)
    };
    let before = ratio_min(&mean(&psa_g));
    let set_scale = if kept.is_empty() {
        1.0
    } else {
        (cfg.set_mean_min / before).max(1.0)
    };
    psa_g
        .iter_mut()
        .for_each(|s| s.iter_mut().for_each(|v| *v *= set_scale));
    let mean_psa_g = mean(&psa_g);
    let mean_ratio_min = ratio_min(&mean_psa_g);
    let all_within_band = psa_g.iter().all(|s| {
        s.iter()
            .zip(&target_psa_g)
            .all(|(a, q)| a / q >= settings.lower && a / q <= settings.upper * (1.0 + 1e-12))
    });
    let motions = kept
        .iter()
        .map(|&i| Record {
            name: seeds[i].name.clone(),
            dt_s: seeds[i].dt_s,
            accel_g: matched[i].accel_g.iter().map(|a| a * set_scale).collect(),
        })
        .collect();
    Ok(ZoneMotions {
        name: name.to_string(),
        target: target.clone(),
        target_psa_g,
        seeds: seeds.iter().map(|s| s.name.clone()).collect(),
        reports: matched.into_iter().map(|m| m.report).collect(),
        kept,
        motions,
        psa_g,
        mean_psa_g,
        set_scale,
        mean_ratio_min,
        set_mean_ok: mean_ratio_min >= cfg.set_mean_min * (1.0 - 1e-12),
        asce7_ok: mean_ratio_min >= 0.9,
        all_within_band,
        periods_s,
    })
}
