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
//! `R_y = C_e/C_y`.

use super::{BadInput, RecordArgs};
use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use serde::Serialize;
use slidestack::spectrum::ductility::{
    DuctilityError, DuctilityOptions, DuctilityPoint, constant_ductility_spectrum,
};
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
    /// Target ductilities (comma-separated, each ≥ 1): constant-ductility spectra instead of
    /// elastic ones (the largest strength with each ductility, Chopra Section 7.5).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    ductility: Vec<f64>,
    /// Post-yield stiffness ratio r of the --ductility oscillators [default: 0, elastic–perfectly
    /// plastic].
    #[arg(long, requires = "ductility")]
    post_yield_ratio: Option<f64>,
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
    if !args.ductility.is_empty() {
        return run_ductility(&args, &periods);
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
    write_out(args.out.as_deref(), &text)
}

/// One record, damping ratio and target ductility (the `--ductility --json` contract).
#[derive(Debug, Serialize)]
struct DuctilityJson {
    record: String,
    damping: f64,
    ductility: f64,
    post_yield_ratio: f64,
    periods_s: Vec<f64>,
    /// `C_y = F_y/(m·g) = A_y/g`.
    strength_ratio: Vec<f64>,
    yield_displacement_m: Vec<f64>,
    peak_displacement_m: Vec<f64>,
    /// `u_m/u_y` at `strength_ratio` (the target to the bisection's tolerance).
    ductility_reached: Vec<f64>,
    /// `C_e = PSA/g` of the elastic oscillator.
    elastic_strength_ratio: Vec<f64>,
    /// `R_y = C_e/C_y`.
    reduction_factor: Vec<f64>,
}

fn run_ductility(args: &Args, periods: &[f64]) -> Result<()> {
    let r = args.post_yield_ratio.unwrap_or(0.0);
    let records = args.records.read()?;
    let jobs: Vec<(usize, f64, f64)> = (0..records.len())
        .flat_map(|i| {
            args.damping
                .iter()
                .flat_map(move |&z| args.ductility.iter().map(move |&mu| (i, z, mu)))
        })
        .collect();
    let spectra = jobs
        .par_iter()
        .map(|&(i, z, mu)| {
            let rec = &records[i];
            let opts = DuctilityOptions {
                damping: z,
                post_yield_ratio: r,
            };
            let pts =
                constant_ductility_spectrum(&rec.accel_mps2(1.0), rec.dt_s, periods, mu, opts)
                    .map_err(|e| ductility_error(e, &rec.name))?;
            let col = |f: fn(&DuctilityPoint) -> f64| pts.iter().map(f).collect::<Vec<f64>>();
            Ok(DuctilityJson {
                record: rec.name.clone(),
                damping: z,
                ductility: mu,
                post_yield_ratio: r,
                periods_s: periods.to_vec(),
                strength_ratio: col(|p| p.strength_ratio),
                yield_displacement_m: col(|p| p.yield_displacement_m),
                peak_displacement_m: col(|p| p.peak_displacement_m),
                ductility_reached: col(|p| p.ductility),
                elastic_strength_ratio: col(|p| p.elastic_strength_ratio),
                reduction_factor: col(|p| p.reduction_factor),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let mut text = String::new();
    if args.json {
        text = serde_json::to_string_pretty(&spectra)? + "\n";
    } else {
        text += if args.csv {
            "record,damping,ductility,post_yield_ratio,period_s,strength_ratio,\
             yield_displacement_m,peak_displacement_m,ductility_reached,elastic_strength_ratio,\
             reduction_factor\n"
        } else {
            "record                          damping  ductility  period_s    C_y (g)   D_y (m)      \
             u_m (m)      C_e (g)    R_y\n"
        };
        for s in &spectra {
            for i in 0..s.periods_s.len() {
                text += &if args.csv {
                    format!(
                        "{},{},{},{},{},{},{},{},{},{},{}\n",
                        s.record,
                        s.damping,
                        s.ductility,
                        s.post_yield_ratio,
                        s.periods_s[i],
                        s.strength_ratio[i],
                        s.yield_displacement_m[i],
                        s.peak_displacement_m[i],
                        s.ductility_reached[i],
                        s.elastic_strength_ratio[i],
                        s.reduction_factor[i]
                    )
                } else {
                    format!(
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
                    )
                };
            }
        }
    }
    write_out(args.out.as_deref(), &text)
}

/// A refused target, period or oscillator is the user's (exit code 2); a failed run is not.
fn ductility_error(e: DuctilityError, record: &str) -> anyhow::Error {
    let bad = match &e {
        DuctilityError::Simulation { source, .. } => source.is_bad_input(),
        DuctilityError::NoResponse { .. } | DuctilityError::NotReached { .. } => false,
        _ => true,
    };
    if bad {
        BadInput(format!("{record}: {e}")).into()
    } else {
        anyhow::Error::from(e).context(format!("{record}: constant-ductility spectrum failed"))
    }
}

/// `text` to `out` (written atomically and checked, `store::atomic`), or to standard output.
fn write_out(out: Option<&std::path::Path>, text: &str) -> Result<()> {
    match out {
        Some(path) => slidestack::store::atomic::write_bytes(path, text.as_bytes())?,
        None => std::io::stdout().lock().write_all(text.as_bytes())?,
    }
    Ok(())
}
