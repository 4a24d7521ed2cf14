//! The motions stage: seed motions (the built-in stochastic model or record files) matched to
//! every zone's target, with the set checks → `motions.h5` (layout in
//! [`crate::store::motions`]).
//!
//! Fingerprint: the tool version, the `zones` and `motions` sections, and the SHA-256 of every
//! record file and target table (not its path, which differs between machines), hashed from the
//! bytes the config loaded; the stage refuses a record whose bytes changed since. Each zone's
//! target spectrum is stored in `motions.h5`, so later stages never read a table file again.

use super::{PipelineError, Session, StageId, StageOutcome};
use crate::ground_motion::matching::MatchError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::motions::{StageMeta, write_motions};
use crate::study::config::{Seeds, StudyConfig};
use crate::study::motions::{
    MotionsError as StudyMotionsError, SeedError, Unmatched, match_zone_until, seed_records,
};
use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum MotionsError {
    #[error("cannot make the seed motions: {0}")]
    Seeds(#[from] SeedError),
    #[error("zone {zone}: matching failed: {source}")]
    Matching { zone: String, source: MatchError },
    /// Motions outside the matching band that the config does not allow (exit code 2).
    #[error(transparent)]
    Unmatched(Unmatched),
    #[error("zone {zone}: no seed met the matching acceptance")]
    NothingMatched { zone: String },
    /// A record file's bytes differ from those the config loaded (and the fingerprint hashed).
    #[error(
        "{}: changed after the study was loaded, while the stage ran: run it again",
        file.display()
    )]
    Changed { file: PathBuf },
}

/// The JSON list of the files the stage reads, each named by its file name with the SHA-256 of
/// the bytes the config loaded: the record files, then the target tables (`zone`, `table`).
fn inputs(cfg: &StudyConfig) -> String {
    let name = |f: &Path| {
        f.file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    };
    let mut inputs = Vec::new();
    if let Seeds::Records(r) = cfg.motions.seeds.kind() {
        for (f, h) in r.files.iter().zip(&cfg.loaded.record_sha256) {
            inputs.push(serde_json::json!({ "file": name(f), "sha256": h }));
        }
    }
    for (z, t) in cfg.zones.iter().zip(&cfg.loaded.targets) {
        if let Some((f, h)) = &t.table {
            inputs.push(serde_json::json!({ "zone": z.name, "table": name(f), "sha256": h }));
        }
    }
    serde_json::to_string(&inputs).expect("JSON of strings")
}

/// The fingerprint `motions.h5` must carry for `cfg`.
pub fn fingerprint(cfg: &StudyConfig) -> String {
    let section = serde_json::json!({
        "zones": cfg.zones,
        "motions": match cfg.motions.seeds.kind() {
            // Record paths differ between machines; their contents are in `inputs`.
            Seeds::Records(r) => serde_json::json!({
                "units": r.units, "dt_s": r.dt_s,
                "matching": cfg.motions.matching, "set_mean_min": cfg.motions.set_mean_min,
            }),
            Seeds::Stochastic(_) => serde_json::to_value(&cfg.motions).expect("serialisable"),
        },
    });
    StageId::Motions.fingerprint(&hash_parts(&[&section.to_string(), &inputs(cfg)]))
}

/// Builds `motions.h5`.
pub fn build(s: &Session) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let cfg = &study.cfg;
    let me = StageId::Motions;
    let (seeds, sha256) = seed_records(&cfg.motions).map_err(MotionsError::from)?;
    if let Seeds::Records(r) = cfg.motions.seeds.kind()
        && let Some(i) = (0..r.files.len()).find(|&i| sha256[i] != cfg.loaded.record_sha256[i])
    {
        return Err(MotionsError::Changed {
            file: r.files[i].clone(),
        }
        .into());
    }
    let mut zones = Vec::new();
    for (i, z) in cfg.zones.iter().enumerate() {
        s.check_cancelled(me)?;
        let target = cfg.target(i);
        let start = std::time::Instant::now();
        let keep_going = || s.pass("motions.record", me).is_ok();
        let zm =
            match_zone_until(&z.name, target, &seeds, &cfg.motions, &keep_going).map_err(|e| {
                match e {
                    StudyMotionsError::Stopped => PipelineError::Cancelled(me),
                    StudyMotionsError::Unmatched(u) => MotionsError::Unmatched(u).into(),
                    StudyMotionsError::Match(source) => MotionsError::Matching {
                        zone: z.name.clone(),
                        source,
                    }
                    .into(),
                }
            })?;
        let met = |b: bool| if b { "met" } else { "NOT met" };
        s.reporter.info(
            me,
            &format!(
                "zone {}: {} motions kept of {} seeds tried, matched to {} in {:.1} s; set scale \
                 {:.4}, mean/target ≥ {:.3} (set_mean_min {}: {}; ASCE 7 90 %: {})",
                z.name,
                zm.kept.len(),
                zm.seeds.len(),
                target,
                start.elapsed().as_secs_f64(),
                zm.set_scale,
                zm.mean_ratio_min,
                cfg.motions.set_mean_min,
                met(zm.set_mean_ok),
                met(zm.asce7_ok),
            ),
        );
        for (i, (seed, r)) in zm.seeds.iter().zip(&zm.reports).enumerate() {
            if !r.converged && !zm.kept.contains(&i) {
                s.reporter.warn(
                    me,
                    &format!(
                        "zone {}: {seed} left out: worst misfit {:.3} after {} iterations",
                        z.name, r.worst_misfit, r.iterations
                    ),
                );
            }
        }
        for u in &zm.unmatched {
            s.reporter
                .warn(me, &format!("zone {}: kept, flagged: {u}", z.name));
        }
        if zm.kept.is_empty() {
            return Err(MotionsError::NothingMatched {
                zone: z.name.clone(),
            }
            .into());
        }
        let zone_fp = hash_parts(&[study.fingerprint(me)?, &z.name]);
        zones.push((zm, zone_fp));
    }
    let meta = StageMeta {
        fingerprint: study.fingerprint(me)?.to_string(),
        config_sha256: study.config_sha256.clone(),
        inputs: inputs(cfg),
    };
    let path = study.path(me.output());
    write_motions(&path, &meta, &seeds, &zones)?;
    Ok(StageOutcome::Wrote(vec![path]))
}
