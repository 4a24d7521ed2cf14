//! `slidestack spectrum`: response spectra of records.
//!
//! Reads the records (`--record`, see [`super::RecordArgs`]) and computes, at the periods of
//! `--periods` and every damping ratio of `--damping`, the exact peak relative displacement
//! `Sd` (m), pseudo-velocity `PSV = ω·Sd` (m/s) and pseudo-acceleration `PSA = ω²·Sd` (g), with
//! the time of the peak. Prints a table, or CSV (`--csv`) or JSON (`--json`), one row per record,
//! damping and period; `--out FILE` writes it to a file instead of stdout.

use super::RecordArgs;
use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use serde::Serialize;
use slidestack::spectrum::parse_periods;
use slidestack::spectrum::response_spectrum;
use std::io::Write;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
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
}

/// One record at one damping ratio (the `--json` contract).
#[derive(Debug, Serialize)]
struct SpectrumJson {
    record: String,
    damping: f64,
    periods_s: Vec<f64>,
    sd_m: Vec<f64>,
    psv_mps: Vec<f64>,
    psa_g: Vec<f64>,
    peak_time_s: Vec<f64>,
}

pub fn run(args: Args) -> Result<()> {
    let periods = parse_periods(&args.periods)?;
    if let Some(z) = args
        .damping
        .iter()
        .find(|z| !(z.is_finite() && (0.0..1.0).contains(*z)))
    {
        bail!("--damping {z} must be in [0, 1)");
    }
    let records = args.records.read()?;
    let jobs: Vec<(usize, f64)> = (0..records.len())
        .flat_map(|r| args.damping.iter().map(move |&z| (r, z)))
        .collect();
    let spectra = jobs
        .par_iter()
        .map(|&(r, z)| {
            let rec = &records[r];
            let s = response_spectrum(&rec.accel_mps2(1.0), rec.dt_s, &periods, z)
                .with_context(|| format!("{}: cannot compute its spectrum", rec.name))?;
            Ok(SpectrumJson {
                record: rec.name.clone(),
                damping: z,
                periods_s: periods.clone(),
                sd_m: s.sd_m(),
                psv_mps: s.psv_mps(),
                psa_g: s.psa_g(),
                peak_time_s: s.peaks.iter().map(|p| p.time_s).collect(),
            })
        })
        .collect::<Result<Vec<_>>>()?;

    let mut text = String::new();
    if args.json {
        text = serde_json::to_string_pretty(&spectra)? + "\n";
    } else {
        let csv = args.csv;
        text += if csv {
            "record,damping,period_s,sd_m,psv_mps,psa_g,peak_time_s\n"
        } else {
            "record                          damping  period_s         sd_m      psv_mps        psa_g  peak_time_s\n"
        };
        for s in &spectra {
            for i in 0..s.periods_s.len() {
                let row = (
                    s.periods_s[i],
                    s.sd_m[i],
                    s.psv_mps[i],
                    s.psa_g[i],
                    s.peak_time_s[i],
                );
                text += &if csv {
                    format!(
                        "{},{},{},{},{},{},{}\n",
                        s.record, s.damping, row.0, row.1, row.2, row.3, row.4
                    )
                } else {
                    format!(
                        "{:<30} {:>8.4} {:>9.4} {:>12.6e} {:>12.6e} {:>12.6} {:>12.4}\n",
                        s.record, s.damping, row.0, row.1, row.2, row.3, row.4
                    )
                };
            }
        }
    }
    match &args.out {
        Some(path) => std::fs::write(path, text)
            .with_context(|| format!("cannot write {}", path.display()))?,
        None => std::io::stdout().lock().write_all(text.as_bytes())?,
    }
    Ok(())
}
