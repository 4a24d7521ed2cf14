//! `slidestack spectrum`: response spectra of records.
//!
//! Reads the records (`--record`, see [`super::RecordArgs`]) and computes, at the periods of
//! `--periods` and every damping ratio of `--damping`, the exact peak relative displacement
//! `Sd` (m), pseudo-velocity `PSV = ω·Sd` (m/s) and pseudo-acceleration `PSA = ω²·Sd` (g), with
//! the time of the peak. Prints a table, or CSV (`--csv`) or JSON (`--json`), one row per record,
//! damping and period; `--out FILE` writes it to a file instead of stdout.
//!
//! With `--ductility μ,…` it computes constant-ductility spectra instead
//! ([`slidestack::spectrum::ductility`]): per period the yield strength ratio `C_y` of an
//! elastic–perfectly-plastic (or, with `--post-yield-ratio`, bilinear) oscillator whose peak
//! displacement is `μ` times its yield displacement, with `D_y`, `u_m`, the elastic `C_e` and
//! `R_y = C_e/C_y`. The spectra themselves: [`slidestack::ground_motion::spectra`].

use super::RecordArgs;
use anyhow::Result;
use slidestack::ground_motion::spectra::{ductility_spectra, response_spectra};
use slidestack::spectrum::parse_periods;
use slidestack::store::atomic::check_output_file;
use std::io::Write;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    #[command(flatten)]
    records: RecordArgs,
    /// Periods, s: START:STOP:STEP, log:START:STOP:COUNT or a list such as 0.1,0.5,1.
    #[arg(long, default_value = "0.05:4:0.01")]
    periods: String,
    /// Damping ratios (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "0.05")]
    damping: Vec<f64>,
    /// Write CSV.
    #[arg(long, conflicts_with = "json")]
    csv: bool,
    /// Write JSON: an array with one object per record and damping ratio.
    #[arg(long)]
    json: bool,
    /// Write to this file instead of stdout.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Target ductilities (comma-separated, each ≥ 1): constant-ductility spectra instead of
    /// elastic ones (the largest strength with each ductility, Chopra Section 7.5).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    ductility: Vec<f64>,
    /// Post-yield stiffness ratio r of the --ductility oscillators [default: 0, elastic–perfectly
    /// plastic].
    #[arg(long, requires = "ductility")]
    post_yield_ratio: Option<f64>,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(path) = &args.out {
        check_output_file(path).map_err(|e| super::BadInput(e.to_string()))?;
    }
    let periods = parse_periods(&args.periods)?;
    if !args.ductility.is_empty() {
        return run_ductility(&args, &periods);
    }
    let records = args.records.read()?;
    let spectra = response_spectra(&records, &periods, &args.damping)?;
    let text = if args.json {
        serde_json::to_string_pretty(&spectra)? + "\n"
    } else if args.csv {
        let mut w = csv_writer();
        w.write_record([
            "record",
            "damping",
            "period_s",
            "sd_m",
            "psv_mps",
            "psa_g",
            "peak_time_s",
        ])?;
        for s in &spectra {
            for i in 0..s.periods_s.len() {
                w.write_record([
                    s.record.clone(),
                    s.damping.to_string(),
                    s.periods_s[i].to_string(),
                    s.sd_m[i].to_string(),
                    s.psv_mps[i].to_string(),
                    s.psa_g[i].to_string(),
                    s.peak_time_s[i].to_string(),
                ])?;
            }
        }
        csv_text(w)?
    } else {
        let mut text = String::from(
            "record                          damping  period_s         sd_m      psv_mps        psa_g  peak_time_s\n",
        );
        for s in &spectra {
            for i in 0..s.periods_s.len() {
                text += &format!(
                    "{:<30} {:>8.4} {:>9.4} {:>12.6e} {:>12.6e} {:>12.6} {:>12.4}\n",
                    s.record,
                    s.damping,
                    s.periods_s[i],
                    s.sd_m[i],
                    s.psv_mps[i],
                    s.psa_g[i],
                    s.peak_time_s[i]
                );
            }
        }
        text
    };
    write_out(args.out.as_deref(), &text)
}

/// A CSV writer into memory (the `csv` crate: a field is quoted where it holds a comma, a quote
/// or a line break, as a record's name may).
fn csv_writer() -> csv::Writer<Vec<u8>> {
    csv::Writer::from_writer(Vec::new())
}

/// The text `w` wrote.
fn csv_text(w: csv::Writer<Vec<u8>>) -> Result<String> {
    let bytes = w
        .into_inner()
        .map_err(|e| anyhow::anyhow!("{}", e.error()))?;
    Ok(String::from_utf8(bytes)?)
}

fn run_ductility(args: &Args, periods: &[f64]) -> Result<()> {
    let r = args.post_yield_ratio.unwrap_or(0.0);
    let records = args.records.read()?;
    let spectra = ductility_spectra(&records, periods, &args.damping, &args.ductility, r)?;
    let text = if args.json {
        serde_json::to_string_pretty(&spectra)? + "\n"
    } else if args.csv {
        let mut w = csv_writer();
        w.write_record([
            "record",
            "damping",
            "ductility",
            "post_yield_ratio",
            "period_s",
            "strength_ratio",
            "yield_displacement_m",
            "peak_displacement_m",
            "ductility_reached",
            "elastic_strength_ratio",
            "reduction_factor",
        ])?;
        for s in &spectra {
            for i in 0..s.periods_s.len() {
                w.write_record([
                    s.record.clone(),
                    s.damping.to_string(),
                    s.ductility.to_string(),
                    s.post_yield_ratio.to_string(),
                    s.periods_s[i].to_string(),
                    s.strength_ratio[i].to_string(),
                    s.yield_displacement_m[i].to_string(),
                    s.peak_displacement_m[i].to_string(),
                    s.ductility_reached[i].to_string(),
                    s.elastic_strength_ratio[i].to_string(),
                    s.reduction_factor[i].to_string(),
                ])?;
            }
        }
        csv_text(w)?
    } else {
        let mut text = String::from(
            "record                          damping  ductility  period_s    C_y (g)   D_y (m)      \
             u_m (m)      C_e (g)    R_y\n",
        );
        for s in &spectra {
            for i in 0..s.periods_s.len() {
                text += &format!(
                    "{:<30} {:>8.4} {:>10.3} {:>9.4} {:>10.5} {:>12.5e} {:>12.5e} {:>10.5} \
                     {:>6.3}\n",
                    s.record,
                    s.damping,
                    s.ductility,
                    s.periods_s[i],
                    s.strength_ratio[i],
                    s.yield_displacement_m[i],
                    s.peak_displacement_m[i],
                    s.elastic_strength_ratio[i],
                    s.reduction_factor[i]
                );
            }
        }
        text
    };
    write_out(args.out.as_deref(), &text)
}

/// `text` to `out` (written atomically and checked, `store::atomic`), or to standard output.
fn write_out(out: Option<&std::path::Path>, text: &str) -> Result<()> {
    match out {
        Some(path) => slidestack::store::atomic::write_bytes(path, text.as_bytes())?,
        None => std::io::stdout().lock().write_all(text.as_bytes())?,
    }
    Ok(())
}
