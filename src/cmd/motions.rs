//! `slidestack motions CONFIG`: the study's first stage.
//!
//! Reads the study file (`zones`, `motions`; see `slidestack::study::config`) and the record
//! seeds it names, or generates the stochastic seeds. Matches every seed to every zone's target,
//! applies the set checks and writes `OUT/motions.h5` (layout in `slidestack::store::motions`),
//! where `OUT` is `--out` or the config's `output_dir`. The file carries the fingerprint of its
//! inputs (tool version, the `zones` and `motions` sections, the SHA-256 of every record file):
//! when it matches, the stage does nothing; otherwise the file is rebuilt as a whole.

use anyhow::{Context, Result, bail};
use slidestack::store::fingerprint::{file_sha256, fingerprint, sha256_hex};
use slidestack::store::motions::{StageMeta, read_fingerprint, write_motions};
use slidestack::study::config::{Seeds, StudyConfig};
use slidestack::study::motions::{MotionsError, match_zone, seed_records};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file (YAML).
    pub config: PathBuf,
    /// Output directory [default: the config's output_dir].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Rebuild even when the stored fingerprint says the file is up to date.
    #[arg(long)]
    pub force: bool,
}

/// The fingerprint of the motions stage for `cfg` and the JSON list of its input files.
pub fn stage_fingerprint(cfg: &StudyConfig) -> Result<(String, String)> {
    let mut inputs = Vec::new();
    if let Seeds::Records(r) = cfg.motions.seeds.kind() {
        for f in &r.files {
            let h = file_sha256(f).with_context(|| format!("cannot read {}", f.display()))?;
            let name = f
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            inputs.push(serde_json::json!({ "file": name, "sha256": h }));
        }
    }
    let inputs = serde_json::to_string(&inputs)?;
    let section = serde_json::to_string(&serde_json::json!({
        "zones": cfg.zones,
        "motions": match cfg.motions.seeds.kind() {
            // Record paths differ between machines; their contents are in `inputs`.
            Seeds::Records(r) => serde_json::json!({
                "units": r.units, "dt_s": r.dt_s,
                "matching": cfg.motions.matching, "set_mean_min": cfg.motions.set_mean_min,
            }),
            Seeds::Stochastic(_) => serde_json::to_value(&cfg.motions)?,
        },
    }))?;
    Ok((fingerprint(&[&section, &inputs]), inputs))
}

pub fn run(args: Args) -> Result<()> {
    let cfg = StudyConfig::load(&args.config)?;
    let out = args.out.clone().unwrap_or_else(|| cfg.output_dir.clone());
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let path = out.join("motions.h5");
    let (fp, inputs) = stage_fingerprint(&cfg)?;
    if !args.force && read_fingerprint(&path).as_deref() == Some(fp.as_str()) {
        println!("motions: {} is up to date", path.display());
        return Ok(());
    }
    let config_text = std::fs::read(&args.config)?;
    let seeds = seed_records(&cfg.motions).context("cannot make the seed motions")?;
    let mut zones = Vec::new();
    for (i, z) in cfg.zones.iter().enumerate() {
        let target = cfg.target(i)?;
        let start = std::time::Instant::now();
        // Unmatched motions stay their own error: `main` maps it to exit code 2.
        let zm = match_zone(&z.name, &target, &seeds, &cfg.motions).map_err(|e| match e {
            MotionsError::Unmatched(u) => anyhow::Error::new(u),
            e => anyhow::Error::new(e).context(format!("zone {}: matching failed", z.name)),
        })?;
        println!(
            "motions: zone {}: {} motions kept of {} seeds tried, matched to {} in {:.1} s; set scale {:.4}, \
             mean/target ≥ {:.3} (set_mean_min {}: {}; ASCE 7 90 %: {})",
            z.name,
            zm.kept.len(),
            zm.seeds.len(),
            target,
            start.elapsed().as_secs_f64(),
            zm.set_scale,
            zm.mean_ratio_min,
            cfg.motions.set_mean_min,
            if zm.set_mean_ok { "met" } else { "NOT met" },
            if zm.asce7_ok { "met" } else { "NOT met" },
        );
        for (i, (s, r)) in zm.seeds.iter().zip(&zm.reports).enumerate() {
            if !r.converged && !zm.kept.contains(&i) {
                eprintln!(
                    "motions: zone {}: {s} left out: worst misfit {:.3} after {} iterations",
                    z.name, r.worst_misfit, r.iterations
                );
            }
        }
        for u in &zm.unmatched {
            eprintln!("motions: zone {}: kept, flagged: {u}", z.name);
        }
        if zm.kept.is_empty() {
            bail!("zone {}: no seed met the matching acceptance", z.name);
        }
        let zone_fp = fingerprint(&[&fp, &z.name]);
        zones.push((zm, zone_fp));
    }
    let meta = StageMeta {
        fingerprint: fp,
        config_sha256: sha256_hex(&config_text),
        inputs,
    };
    write_motions(&path, &meta, &seeds, &zones)
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!("motions: wrote {}", path.display());
    Ok(())
}
