//! `slidestack match`: spectral matching of records to a target spectrum.
//!
//! Reads the records (`--record`, see [`super::RecordArgs`]), the target (`--target SPEC`, e.g.
//! `is1893:zone=V,soil=I`, `asce7:sds=1.0,sd1=0.6,tl=8` or `table:FILE`) and optional matching
//! settings (`--settings YAML`, the keys of `MatchSettings`, unknown keys refused). Writes into
//! `--out DIR` each matched motion that meets the acceptance as a PEER `.AT2` file (values in g,
//! the record's base name), and `summary.csv` with one row per record: iterations, worst misfit,
//! PGA before and after, final velocity and displacement (drift) and the Arias intensity ratio.
//! A record that does not meet the acceptance is listed in the summary and not written; the
//! command then fails after writing the others.

use super::RecordArgs;
use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use slidestack::motion::matching::{MatchSettings, match_record};
use slidestack::motion::{Record, checked_at2};
use slidestack::spectrum::TargetSpectrum;
use slidestack::store::atomic::write_bytes;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    records: RecordArgs,
    /// Target spectrum: is1893:zone=V,soil=I | asce7:sds=1.0,sd1=0.6,tl=8 | table:FILE.
    #[arg(long)]
    target: String,
    /// Output directory (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// YAML file with matching settings (damping, check_range_s, check_periods, lower, upper,
    /// passes, max_iterations, tolerance, gain, regularisation, prescale).
    #[arg(long)]
    settings: Option<PathBuf>,
}

/// Reads matching settings from YAML, refusing unknown keys and impossible values.
pub fn read_settings(path: &Path) -> Result<MatchSettings> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read settings {}", path.display()))?;
    let s: MatchSettings = serde_yaml::from_str(&text)
        .with_context(|| format!("invalid settings {}", path.display()))?;
    s.validate()
        .with_context(|| format!("invalid settings {}", path.display()))?;
    Ok(s)
}

/// `NAME.AT2` for a record read from `NAME.ext`.
pub fn at2_name(record: &Record) -> String {
    let stem = Path::new(&record.name)
        .file_stem()
        .map_or_else(|| record.name.clone(), |s| s.to_string_lossy().into_owned());
    format!("{stem}.AT2")
}

pub fn run(args: Args) -> Result<()> {
    let target: TargetSpectrum = args
        .target
        .parse()
        .with_context(|| format!("invalid --target `{}`", args.target))?;
    let settings = match &args.settings {
        Some(p) => read_settings(p)?,
        None => MatchSettings::default(),
    };
    settings.validate()?;
    target
        .check_covers(settings.check_range_s.0, settings.check_range_s.1)
        .context("the target does not cover the matching range")?;
    let records = args.records.read()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;

    let results = records
        .par_iter()
        .map(|rec| {
            match_record(&rec.accel_g, rec.dt_s, &target, &settings)
                .with_context(|| format!("{}: matching failed", rec.name))
        })
        .collect::<Result<Vec<_>>>()?;

    let mut summary = String::from(
        "record,converged,iterations,worst_misfit,scale,pga_before_g,pga_after_g,\
         final_velocity_mps,final_displacement_m,arias_ratio,output\n",
    );
    let mut left_out = Vec::new();
    println!(
        "{:<32} {:>9} {:>5} {:>8} {:>15} {:>11} {:>11} {:>7}",
        "record",
        "converged",
        "iter",
        "misfit",
        "PGA g (before→after)",
        "v_end m/s",
        "d_end m",
        "Arias"
    );
    for (rec, m) in records.iter().zip(&results) {
        let r = &m.report;
        let out = if r.converged {
            let name = at2_name(rec);
            let matched = Record {
                name: name.clone(),
                dt_s: rec.dt_s,
                accel_g: m.accel_g.clone(),
            };
            let desc = format!(
                "{} matched to {target} by slidestack {} (wavelet adjustment)",
                rec.name,
                env!("CARGO_PKG_VERSION")
            );
            let path = args.out.join(&name);
            let text = checked_at2(&matched, &desc, &path.display().to_string())?;
            write_bytes(&path, text.as_bytes())?;
            name
        } else {
            left_out.push(rec.name.clone());
            String::new()
        };
        writeln!(
            summary,
            "{},{},{},{},{},{},{},{},{},{},{}",
            rec.name,
            r.converged,
            r.iterations,
            r.worst_misfit,
            r.scale,
            r.pga_before_g,
            r.pga_after_g,
            r.final_velocity_mps,
            r.final_displacement_m,
            r.arias_ratio,
            out
        )?;
        println!(
            "{:<32} {:>9} {:>5} {:>8.4} {:>7.3} → {:>6.3} {:>11.2e} {:>11.2e} {:>7.3}",
            rec.name,
            r.converged,
            r.iterations,
            r.worst_misfit,
            r.pga_before_g,
            r.pga_after_g,
            r.final_velocity_mps,
            r.final_displacement_m,
            r.arias_ratio
        );
    }
    let summary_path = args.out.join("summary.csv");
    slidestack::store::atomic::write_bytes(&summary_path, summary.as_bytes())?;
    if !left_out.is_empty() {
        bail!(
            "{} of {} records did not meet the acceptance (every check period within [{}, {}] of \
             the target) and were left out: {}",
            left_out.len(),
            records.len(),
            settings.lower,
            settings.upper,
            left_out.join(", ")
        );
    }
    Ok(())
}
