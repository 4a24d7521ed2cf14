//! `slidestack sweep CONFIG [--shard K/N]` and `slidestack merge CONFIG`: the study's second stage.
//!
//! Reads the study file (`zones`, `grid`) and `OUT/motions.h5` (which must be up to date with
//! the config). Every work unit (one zone, one motion, one `T_p`: all block and friction
//! combinations) is computed in parallel and written as its own file under `OUT/sweep.units/`
//! the moment it is done; units already there with the same fingerprint are not redone, so an
//! interrupted run resumes where it stopped. Then `OUT/sweep.h5` is assembled from the units
//! (layout in `slidestack::store::sweep`) and the units are removed. With `--shard K/N` only the
//! units `i` with `i mod N = K−1` are computed and nothing is assembled: run `merge` when every
//! shard is done (cluster job arrays, `pipelines/`). Up to date (same fingerprint in
//! `sweep.h5`): nothing is done.

use super::motions::stage_fingerprint as motions_fingerprint;
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use slidestack::dynamics::Ground;
use slidestack::store::fingerprint::{fingerprint, sha256_hex};
use slidestack::store::motions::{read_fingerprint as read_motions_fp, read_zone_motions};
use slidestack::store::sweep::{
    SweepMeta, ZoneUnits, read_fingerprint, read_unit, unit_path, write_sweep, write_unit,
};
use slidestack::study::config::StudyConfig;
use slidestack::study::sweep::{Grid, UnitOptions, run_unit};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file (YAML).
    pub config: PathBuf,
    /// Output directory [default: the config's output_dir].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Compute only shard K of N (1 ≤ K ≤ N) and leave the assembly to `merge`.
    #[arg(long, value_parser = parse_shard)]
    pub shard: Option<(usize, usize)>,
}

#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// Study file (YAML).
    pub config: PathBuf,
    /// Output directory [default: the config's output_dir].
    #[arg(long)]
    pub out: Option<PathBuf>,
}

fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s.split_once('/').ok_or("expected K/N, e.g. 2/8")?;
    let k: usize = k
        .trim()
        .parse()
        .map_err(|_| format!("K in `{s}` is not a whole number"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("N in `{s}` is not a whole number"))?;
    if k == 0 || k > n {
        return Err(format!("shard `{s}`: needs 1 ≤ K ≤ N"));
    }
    Ok((k, n))
}

/// Everything the stage needs, checked before any work.
pub struct Stage {
    pub cfg: StudyConfig,
    pub grid: Grid,
    pub out: PathBuf,
    units_dir: PathBuf,
    /// The fingerprint `sweep.h5` must carry to be up to date.
    pub fingerprint: String,
    motions_fingerprint: String,
    config_sha256: String,
}

/// Loads the config and checks that `motions.h5` is up to date with it.
pub fn prepare(config: &Path, out: Option<PathBuf>) -> Result<Stage> {
    let cfg = StudyConfig::load(config)?;
    let grid = Grid::from_config(cfg.grid()?);
    let out = out.unwrap_or_else(|| cfg.output_dir.clone());
    let motions = out.join("motions.h5");
    let (expected, _) = motions_fingerprint(&cfg)?;
    let stored = read_motions_fp(&motions);
    if stored.as_deref() != Some(expected.as_str()) {
        bail!(
            "{} is missing or out of date with {}: run `slidestack motions {}` first",
            motions.display(),
            config.display(),
            config.display()
        );
    }
    let section = serde_json::to_string(&serde_json::json!({
        "zones": cfg.zones, "grid": cfg.grid, "solver": "exact",
    }))?;
    let fingerprint = fingerprint(&[&section, &expected]);
    Ok(Stage {
        units_dir: out.join("sweep.units"),
        config_sha256: sha256_hex(&std::fs::read(config)?),
        cfg,
        grid,
        out,
        fingerprint,
        motions_fingerprint: expected,
    })
}

/// Every unit `(zone, motion, period)` in the fixed order shards count in.
fn all_units(
    stage: &Stage,
    motions: &[Vec<slidestack::motion::Record>],
) -> Vec<(usize, usize, usize)> {
    let mut v = Vec::new();
    for (z, ms) in motions.iter().enumerate() {
        for m in 0..ms.len() {
            for p in 0..stage.grid.periods_s.len() {
                v.push((z, m, p));
            }
        }
    }
    v
}

pub fn load_motions(stage: &Stage) -> Result<Vec<Vec<slidestack::motion::Record>>> {
    let path = stage.out.join("motions.h5");
    stage
        .cfg
        .zones
        .iter()
        .map(|z| {
            read_zone_motions(&path, &z.name)
                .with_context(|| format!("cannot read zone {} from {}", z.name, path.display()))
        })
        .collect()
}

pub fn run(args: Args) -> Result<()> {
    let stage = prepare(&args.config, args.out)?;
    let sweep_path = stage.out.join("sweep.h5");
    if args.shard.is_none() && read_fingerprint(&sweep_path).as_deref() == Some(&stage.fingerprint)
    {
        println!("sweep: {} is up to date", sweep_path.display());
        return Ok(());
    }
    let motions = load_motions(&stage)?;
    std::fs::create_dir_all(&stage.units_dir)
        .with_context(|| format!("cannot create {}", stage.units_dir.display()))?;
    let units = all_units(&stage, &motions);
    let mine: Vec<(usize, usize, usize)> = units
        .iter()
        .enumerate()
        .filter(|(i, _)| args.shard.is_none_or(|(k, n)| i % n == k - 1))
        .map(|(_, u)| *u)
        .collect();
    let path_of = |&(z, m, p): &(usize, usize, usize)| {
        unit_path(&stage.units_dir, &stage.cfg.zones[z].name, m, p)
    };
    let todo: Vec<(usize, usize, usize)> = mine
        .iter()
        .filter(|u| read_unit(&path_of(u), &stage.fingerprint).is_none())
        .copied()
        .collect();
    let cases = todo.len() * stage.grid.cases_per_unit();
    println!(
        "sweep: {} of {} units to compute ({} cases; {} already done)",
        todo.len(),
        mine.len(),
        cases,
        mine.len() - todo.len()
    );
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(todo.len() as u64).with_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} units, {per_sec}, ETA {eta}")
                .expect("valid template"),
        )
    } else {
        ProgressBar::hidden()
    };
    let start = std::time::Instant::now();
    let sims = std::sync::atomic::AtomicUsize::new(0);
    // Record samples crossed by all simulations together.
    let samples = std::sync::atomic::AtomicUsize::new(0);
    todo.par_iter().try_for_each(|u| -> Result<()> {
        let (z, m, p) = *u;
        let rec = &motions[z][m];
        let accel = rec.accel_mps2(1.0);
        let ground = Ground {
            dt_s: rec.dt_s,
            accel_mps2: &accel,
        };
        let r = run_unit(&stage.grid, &ground, p, UnitOptions { skip: true })
            .with_context(|| format!("zone {}, motion {}", stage.cfg.zones[z].name, rec.name))?;
        sims.fetch_add(r.simulations, std::sync::atomic::Ordering::Relaxed);
        samples.fetch_add(
            r.simulations * accel.len(),
            std::sync::atomic::Ordering::Relaxed,
        );
        let path = path_of(u);
        write_unit(&path, &stage.fingerprint, &r)
            .with_context(|| format!("cannot write {}", path.display()))?;
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    if !todo.is_empty() {
        let sims = sims.into_inner();
        let threads = rayon::current_num_threads();
        println!(
            "sweep: {} cases in {:.1} s ({:.0} cases/s); {} simulations ({:.0}/s; the skip rules \
             saved {:.0} %); {:.0} ns per simulated record sample per thread ({threads} threads)",
            cases,
            secs,
            cases as f64 / secs.max(1e-9),
            sims,
            sims as f64 / secs.max(1e-9),
            100.0 * (1.0 - sims as f64 / (3 * cases) as f64),
            secs * 1e9 * threads as f64 / samples.into_inner().max(1) as f64
        );
    }
    if let Some((k, n)) = args.shard {
        println!(
            "sweep: shard {k}/{n} done; run `slidestack merge {}` when every shard is done",
            args.config.display()
        );
        return Ok(());
    }
    assemble(&stage, &motions, &units)
}

pub fn merge(args: MergeArgs) -> Result<()> {
    let stage = prepare(&args.config, args.out)?;
    let motions = load_motions(&stage)?;
    let units = all_units(&stage, &motions);
    assemble(&stage, &motions, &units)
}

fn assemble(
    stage: &Stage,
    motions: &[Vec<slidestack::motion::Record>],
    units: &[(usize, usize, usize)],
) -> Result<()> {
    let mut zones = Vec::new();
    let names: Vec<Vec<String>> = motions
        .iter()
        .map(|ms| ms.iter().map(|m| m.name.clone()).collect())
        .collect();
    let mut missing = 0;
    for (z, zc) in stage.cfg.zones.iter().enumerate() {
        let mut per_motion = Vec::new();
        for m in 0..motions[z].len() {
            let mut per_period = Vec::new();
            for p in 0..stage.grid.periods_s.len() {
                match read_unit(
                    &unit_path(&stage.units_dir, &zc.name, m, p),
                    &stage.fingerprint,
                ) {
                    Some(u) => per_period.push(u),
                    None => missing += 1,
                }
            }
            per_motion.push(per_period);
        }
        zones.push(per_motion);
    }
    if missing > 0 {
        bail!(
            "{missing} of {} units are missing from {}: run the remaining shards (or `slidestack sweep` without --shard)",
            units.len(),
            stage.units_dir.display()
        );
    }
    let zone_units: Vec<ZoneUnits> = stage
        .cfg
        .zones
        .iter()
        .zip(zones)
        .zip(&names)
        .map(|((zc, units), names)| ZoneUnits {
            name: &zc.name,
            target: &zc.target,
            motions: names,
            units,
        })
        .collect();
    let meta = SweepMeta {
        fingerprint: stage.fingerprint.clone(),
        config_sha256: stage.config_sha256.clone(),
        motions_fingerprint: stage.motions_fingerprint.clone(),
    };
    let path = stage.out.join("sweep.h5");
    write_sweep(&path, &meta, &stage.grid, &zone_units)
        .with_context(|| format!("cannot write {}", path.display()))?;
    std::fs::remove_dir_all(&stage.units_dir)
        .with_context(|| format!("cannot remove {}", stage.units_dir.display()))?;
    println!("sweep: wrote {}", path.display());
    Ok(())
}
