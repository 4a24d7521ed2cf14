//! `slidestack design --study OUT_DIR --zone III --period 0.7 --alpha 1,1 --mu 0.3,0.1 [--json]`:
//! `T_new` and the design spectral accelerations of one structure from a finished study
//! ([`slidestack::design`]); in a building study also `--storeys 3 --floor roof`.

use anyhow::Result;
use slidestack::design::design;
use slidestack::grid::StackFloor;
use slidestack::study::design::{Answer, Query};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Output directory of a finished study (holding tnew.h5 and fit.yaml).
    #[arg(long)]
    study: PathBuf,
    /// Zone (hazard level) of the study, e.g. III.
    #[arg(long)]
    zone: String,
    /// Period of the bare structure T_p, s.
    #[arg(long = "period")]
    period_s: f64,
    /// Block mass ratios α_i = m_i/m_p, bottom block first.
    #[arg(long, value_delimiter = ',', num_args = 1.., required = true)]
    alpha: Vec<f64>,
    /// Kinetic friction coefficients μ_i, interface 1 (structure–block 1) first.
    #[arg(long, value_delimiter = ',', num_args = 1.., required = true)]
    mu: Vec<f64>,
    /// Outside the study's grid, answer from the fitted form instead of refusing.
    #[arg(long)]
    extrapolate: bool,
    /// A building study's storey count N (with --floor; --period is then its bare first-mode
    /// period T_1).
    #[arg(long, requires = "floor")]
    storeys: Option<usize>,
    /// A building study's floor carrying the stack: a number (1 the lowest), roof or all.
    #[arg(long, requires = "storeys")]
    floor: Option<StackFloor>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let q = Query {
        zone: args.zone,
        period_s: args.period_s,
        alpha: args.alpha,
        mu: args.mu,
        extrapolate: args.extrapolate,
        building: args.storeys.zip(args.floor),
    };
    let a = design(&args.study, &q)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&a)?);
    } else {
        print_table(&a);
    }
    Ok(())
}

fn print_table(a: &Answer) {
    let t = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.3} s"));
    let g = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.3} g"));
    println!(
        "zone {} ({}): T_p {} s, α {:?}, μ {:?}",
        a.zone, a.target, a.period_s, a.alpha, a.mu
    );
    if let Some(b) = &a.building {
        println!("building: {b} (T_p is its bare first-mode period T_1)");
    }
    println!("{:<34}{:>10}{:>12}", "", "period", "Sa");
    println!(
        "{:<34}{:>10}{:>12}",
        "bare structure, T_p",
        format!("{:.3} s", a.period_s),
        format!("{:.3} g", a.sa_tp_g)
    );
    println!(
        "{:<34}{:>10}",
        "stack rigidly attached, T_rigid",
        format!("{:.3} s", a.t_rigid_s)
    );
    println!(
        "{:<34}{:>10}{:>12}",
        "T_new, the study's grid",
        t(a.t_new_grid_s),
        g(a.sa_new_grid_g)
    );
    println!(
        "{:<34}{:>10}{:>12}",
        format!("T_new, fitted ({} form)", a.fit_form),
        t(a.t_new_fit_s),
        g(a.sa_new_fit_g)
    );
    println!(
        "{:<34}{:>10}{:>12}",
        "T_new, the paper's Eqs. 16–17",
        t(a.t_new_paper_s),
        g(a.sa_new_paper_g)
    );
    if a.lambda_grid.is_some() || a.lambda_fit.is_some() {
        let f = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.3}"));
        println!(
            "effective live-load fraction λ: {} (the study's grid), {} (fitted)",
            f(a.lambda_grid),
            f(a.lambda_fit)
        );
        println!(
            "code-format fraction λ_code (the share of the live load to count as seismic \
             weight): {} (the study's grid)",
            f(a.lambda_code_grid)
        );
    }
    for n in &a.notes {
        println!("note: {n}");
    }
}
