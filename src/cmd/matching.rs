//! `slidestack match`: spectral matching of records to a target spectrum.
//!
//! Reads the records (`--record`, see [`super::RecordArgs`]), the target (`--target SPEC`, e.g.
//! `is1893:zone=V,soil=I`, `asce7:sds=1.0,sd1=0.6,tl=8` or `table:FILE`) and optional matching
//! settings (`--settings YAML`, the keys of `MatchSettings`, unknown keys refused), matches and
//! writes them into `--out DIR` ([`slidestack::match_files`]) and prints a row per record. A
//! record that does not meet the acceptance is listed in the summary and not written; the
//! command then fails after writing the others.

use super::{BadInput, RecordArgs};
use anyhow::Result;
use slidestack::ground_motion::matching::MatchSettings;
use slidestack::match_files::{MatchedFile, all_accepted, match_files, read_settings};
use slidestack::spectrum::TargetSpectrum;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
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

pub fn run(args: Args) -> Result<()> {
    let target: TargetSpectrum = args
        .target
        .parse()
        .map_err(|e| BadInput(format!("invalid --target `{}`: {e}", args.target)))?;
    let settings = match &args.settings {
        Some(p) => read_settings(p)?,
        None => MatchSettings::default(),
    };
    let records = args.records.read()?;
    let files = match_files(&records, &target, &settings, &args.out)?;
    print_table(&files);
    all_accepted(&files, &settings)?;
    Ok(())
}

fn print_table(files: &[MatchedFile]) {
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
    for f in files {
        let r = &f.report;
        println!(
            "{:<32} {:>9} {:>5} {:>8.4} {:>7.3} → {:>6.3} {:>11.2e} {:>11.2e} {:>7.3}",
            f.record,
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
}
