//! The motions stage: seed motions (stochastic or records), matched to each zone's target, and
//! the checks on the set.
//!
//! A seed that does not meet the matching acceptance is an [`Unmatched`] result naming it, its
//! worst check period and ratio and the iterations spent, unless the config says
//! `allow_unmatched: true`: then it is kept with its misfit and flagged (`converged` false in
//! its report). Stochastic seeds are matched in order until `count` are accepted, spares
//! replacing the seeds that are not; only when the spares run out is that unmatched.
//!
//! The set's mean spectrum must not fall below `set_mean_min` of the target on the check grid:
//! when it does, the kept motions are scaled up together by the smallest factor `s` that lifts
//! it there. When that pushes a motion above the upper bound, every motion not yet within half
//! the tolerance is matched again, from its matched form, with half the tolerance (a tighter set
//! needs a smaller scale), those pushed out to the target over `s` so that after the scale they
//! lie around the target; the scale is then computed anew, and motions still pushed out are
//! matched again likewise, at most [`SET_SCALE_ROUNDS`] rounds in all. A motion still outside
//! the band after that (seen with sets of two motions, whose mean can need more scale than any
//! re-match leaves room for) is kept and flagged: listed in `unmatched`, `all_within_band`
//! false.

use super::config::{MotionsConfig, Seeds, StudyConfig};
use crate::ground_motion::matching::{
    MatchError, MatchSettings, Matched, match_record, match_record_scaled,
};
use crate::ground_motion::record::{parse_record, read_record_file};
pub use crate::ground_motion::set::{UnmatchedRecord, ZoneMotions};
use crate::ground_motion::stochastic::StochasticError;
use crate::ground_motion::{Record, RecordError};
use crate::spectrum::TargetSpectrum;
use crate::store::fingerprint::sha256_hex;
use rayon::prelude::*;
use std::fmt;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum SeedError {
    #[error(transparent)]
    Record(#[from] RecordError),
    #[error("stochastic seeds: {0}")]
    Stochastic(#[from] StochasticError),
}

/// Rounds of re-matching motions that the set scale pushed out of the band.
pub const SET_SCALE_ROUNDS: usize = 3;

/// Motions of a zone that do not meet the acceptance `[lower, upper]`, and the config does not
/// allow them.
#[derive(Debug, Clone, PartialEq, Error)]
pub struct Unmatched {
    pub zone: String,
    pub lower: f64,
    pub upper: f64,
    pub records: Vec<UnmatchedRecord>,
}

impl fmt::Display for Unmatched {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "zone {}: {} motion(s) not within [{}, {}] of the target at every check period \
             (set `motions.allow_unmatched: true` to keep them, flagged): ",
            self.zone,
            self.records.len(),
            self.lower,
            self.upper
        )?;
        for (i, r) in self.records.iter().enumerate() {
            write!(f, "{}{r}", if i > 0 { "; " } else { "" })?;
        }
        Ok(())
    }
}

#[derive(Debug, Error)]
pub enum MotionsError {
    #[error(transparent)]
    Match(#[from] MatchError),
    #[error(transparent)]
    Unmatched(#[from] Unmatched),
    /// `keep_going` said stop ([`match_zone_until`]).
    #[error("the matching was stopped")]
    Stopped,
}

/// The seed motions of a study, in configuration order. Each record file is read once: the
/// second vector holds the SHA-256 of the bytes each seed was parsed from (empty for
/// stochastic seeds).
pub fn seed_records(cfg: &MotionsConfig) -> Result<(Vec<Record>, Vec<String>), SeedError> {
    match cfg.seeds.kind() {
        Seeds::Stochastic(s) => Ok((
            s.model
                .simulate_set(s.seed, s.count + s.spare, "stochastic")?,
            Vec::new(),
        )),
        Seeds::Records(r) => {
            let opts = StudyConfig::read_options(r);
            let mut seeds = Vec::new();
            let mut sha256 = Vec::new();
            for f in &r.files {
                let bytes = read_record_file(f)?;
                sha256.push(sha256_hex(&bytes));
                seeds.push(parse_record(&bytes, f, &opts)?);
            }
            Ok((seeds, sha256))
        }
    }
}

/// The mean over `psa` (motions × periods) per period.
fn mean(psa: &[Vec<f64>], periods: usize) -> Vec<f64> {
    (0..periods)
        .map(|p| psa.iter().map(|s| s[p]).sum::<f64>() / psa.len().max(1) as f64)
        .collect()
}

/// `(index, ratio)` of the largest `|ratio − 1|` of `psa·scale` against `target`.
fn worst(psa: &[f64], scale: f64, target: &[f64]) -> (usize, f64) {
    psa.iter()
        .zip(target)
        .map(|(a, q)| a * scale / q)
        .enumerate()
        .fold((0, 1.0), |w, (i, r)| {
            if (r - 1.0).abs() > (w.1 - 1.0f64).abs() {
                (i, r)
            } else {
                w
            }
        })
}

/// Matches every seed to `target` (in parallel; the result does not depend on the thread count)
/// and applies the set checks.
pub fn match_zone(
    name: &str,
    target: &TargetSpectrum,
    seeds: &[Record],
    cfg: &MotionsConfig,
) -> Result<ZoneMotions, MotionsError> {
    match_zone_until(name, target, seeds, cfg, &|| true)
}

/// [`match_zone`], asking `keep_going` before each record is matched (or matched again) and
/// stopping with [`MotionsError::Stopped`] when it says no: the Ctrl-C of a stage, within one
/// record.
pub fn match_zone_until(
    name: &str,
    target: &TargetSpectrum,
    seeds: &[Record],
    cfg: &MotionsConfig,
    keep_going: &(dyn Fn() -> bool + Sync),
) -> Result<ZoneMotions, MotionsError> {
    let settings = &cfg.matching;
    let periods_s = settings.check_grid_s();
    let target_psa_g: Vec<f64> = periods_s.iter().map(|&t| target.sa_g(t)).collect();
    let wanted = match cfg.seeds.kind() {
        Seeds::Stochastic(s) => s.count,
        Seeds::Records(_) => seeds.len(),
    };
    let mut matched = match_in_order(seeds, wanted, target, settings, keep_going)?;
    let seeds = &seeds[..matched.len()];
    let (kept, mut unmatched) = keep(name, seeds, &matched, wanted, cfg)?;
    let set = SetChecks {
        target_psa_g: &target_psa_g,
        kept: &kept,
        upper: settings.upper,
        set_mean_min: cfg.set_mean_min,
    };
    let set_scale = set.scale_and_rematch(&mut matched, seeds, target, settings, keep_going)?;
    let psa_g: Vec<Vec<f64>> = kept
        .iter()
        .map(|&i| {
            matched[i]
                .check_psa_g
                .iter()
                .map(|v| v * set_scale)
                .collect()
        })
        .collect();
    let mean_psa_g = mean(&psa_g, periods_s.len());
    let mean_ratio_min = set.ratio_min(&mean_psa_g);
    for (k, &i) in kept.iter().enumerate() {
        let in_band = psa_g[k].iter().zip(&target_psa_g).all(|(a, q)| {
            a / q >= settings.lower * (1.0 - 1e-12) && a / q <= settings.upper * (1.0 + 1e-12)
        });
        if !in_band && matched[i].report.converged {
            let (w, r) = worst(&matched[i].check_psa_g, set_scale, &target_psa_g);
            unmatched.push(UnmatchedRecord {
                name: seeds[i].name.clone(),
                worst_period_s: periods_s[w],
                worst_ratio: r,
                iterations: matched[i].report.iterations,
                after_set_scale: true,
            });
        }
    }
    let all_within_band = unmatched.is_empty();
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
        unmatched,
        periods_s,
    })
}

/// The seeds matched in order, a batch at a time, until `wanted` are accepted: spares are only
/// matched when needed, and which seeds are tried does not depend on the thread count.
fn match_in_order(
    seeds: &[Record],
    wanted: usize,
    target: &TargetSpectrum,
    settings: &MatchSettings,
    keep_going: &(dyn Fn() -> bool + Sync),
) -> Result<Vec<Matched>, MotionsError> {
    let mut matched: Vec<Matched> = Vec::new();
    loop {
        let accepted = matched.iter().filter(|m| m.report.converged).count();
        if accepted >= wanted || matched.len() == seeds.len() {
            return Ok(matched);
        }
        let from = matched.len();
        let to = (from + wanted - accepted).min(seeds.len());
        let batch = seeds[from..to]
            .par_iter()
            .map(|s| {
                if !keep_going() {
                    return Err(MotionsError::Stopped);
                }
                Ok(match_record(&s.accel_g, s.dt_s, target, settings)?)
            })
            .collect::<Result<Vec<_>, _>>()?;
        matched.extend(batch);
    }
}

/// The indices of the motions kept: the first `wanted` accepted ones, completed, when the config
/// allows it, by the first that were not (returned flagged); `Unmatched` when it does not.
fn keep(
    name: &str,
    seeds: &[Record],
    matched: &[Matched],
    wanted: usize,
    cfg: &MotionsConfig,
) -> Result<(Vec<usize>, Vec<UnmatchedRecord>), Unmatched> {
    let mut kept: Vec<usize> = (0..seeds.len())
        .filter(|&i| matched[i].report.converged)
        .take(wanted)
        .collect();
    if kept.len() >= wanted {
        return Ok((kept, Vec::new()));
    }
    let short: Vec<usize> = (0..seeds.len())
        .filter(|&i| !matched[i].report.converged)
        .take(wanted - kept.len())
        .collect();
    let unmatched: Vec<UnmatchedRecord> = short
        .iter()
        .map(|&i| UnmatchedRecord {
            name: seeds[i].name.clone(),
            worst_period_s: matched[i].report.worst_period_s,
            worst_ratio: matched[i].report.worst_ratio,
            iterations: matched[i].report.iterations,
            after_set_scale: false,
        })
        .collect();
    if !cfg.allow_unmatched {
        return Err(Unmatched {
            zone: name.to_string(),
            lower: cfg.matching.lower,
            upper: cfg.matching.upper,
            records: unmatched,
        });
    }
    kept.extend(short);
    kept.sort_unstable();
    Ok((kept, unmatched))
}

/// The set checks of a zone's kept motions against its target on the check grid (module doc).
struct SetChecks<'a> {
    target_psa_g: &'a [f64],
    kept: &'a [usize],
    upper: f64,
    set_mean_min: f64,
}

impl SetChecks<'_> {
    /// `min_T spectrum/target`.
    fn ratio_min(&self, psa_g: &[f64]) -> f64 {
        psa_g
            .iter()
            .zip(self.target_psa_g)
            .map(|(a, q)| a / q)
            .fold(f64::INFINITY, f64::min)
    }

    /// The smallest factor (≥ 1) that lifts the kept motions' mean to `set_mean_min` of the
    /// target.
    fn scale(&self, matched: &[Matched]) -> f64 {
        if self.kept.is_empty() {
            return 1.0;
        }
        let psa: Vec<Vec<f64>> = self
            .kept
            .iter()
            .map(|&i| matched[i].check_psa_g.clone())
            .collect();
        (self.set_mean_min / self.ratio_min(&mean(&psa, self.target_psa_g.len()))).max(1.0)
    }

    /// Whether `m`, times `scale`, lies above the band somewhere.
    fn above(&self, m: &Matched, scale: f64) -> bool {
        m.check_psa_g
            .iter()
            .zip(self.target_psa_g)
            .any(|(a, q)| a * scale / q > self.upper * (1.0 + 1e-12))
    }

    /// The set scale, after matching again (at most [`SET_SCALE_ROUNDS`] rounds) the kept
    /// motions it pushes above the band; each such motion replaces its match in `matched` when
    /// it still meets the band.
    fn scale_and_rematch(
        &self,
        matched: &mut [Matched],
        seeds: &[Record],
        target: &TargetSpectrum,
        settings: &MatchSettings,
        keep_going: &(dyn Fn() -> bool + Sync),
    ) -> Result<f64, MotionsError> {
        // A motion matched again is aimed at the target after the scale, with half the
        // tolerance (and fallbacks above half the room to the bound): what the scale may still
        // add when the set is scaled anew stays inside the band.
        let tight = MatchSettings {
            tolerance: 0.5 * settings.tolerance,
            retry_misfit: 0.5 * settings.tolerance + 0.25 * (settings.upper - 1.0),
            ..settings.clone()
        };
        let mut set_scale = self.scale(matched);
        for round in 0..SET_SCALE_ROUNDS {
            if !self
                .kept
                .iter()
                .any(|&i| matched[i].report.converged && self.above(&matched[i], set_scale))
            {
                break;
            }
            // The first round tightens every motion not yet within half the tolerance (what
            // lowers the mean and so raises the scale), later ones the motions still pushed out.
            let first = round == 0;
            let out: Vec<usize> = self
                .kept
                .iter()
                .copied()
                .filter(|&i| {
                    let m = &matched[i];
                    m.report.converged
                        && if first {
                            m.report.worst_misfit > tight.tolerance || self.above(m, set_scale)
                        } else {
                            self.above(m, set_scale)
                        }
                })
                .collect();
            let again = out
                .par_iter()
                .map(|&i| {
                    if !keep_going() {
                        return Err(MotionsError::Stopped);
                    }
                    let m = &matched[i];
                    let factor = m.report.target_factor / set_scale;
                    Ok(match_record_scaled(
                        &m.accel_g,
                        seeds[i].dt_s,
                        target,
                        factor,
                        &tight,
                    )?)
                })
                .collect::<Result<Vec<_>, _>>()?;
            for (&i, mut m) in out.iter().zip(again) {
                let old = &matched[i].report;
                m.report.scale *= old.scale;
                m.report.iterations += old.iterations;
                m.report.attempts += old.attempts;
                m.report.stalls += old.stalls;
                m.report.pga_before_g = old.pga_before_g;
                m.report.arias_ratio *= old.arias_ratio;
                // Kept only if it still meets the band against its own (scaled) target.
                if m.report.converged {
                    matched[i] = m;
                }
            }
            set_scale = self.scale(matched);
        }
        Ok(set_scale)
    }
}
