//! `slidestack bench stress`: the numerical stress suite (`slidestack::stress`).
//!
//! Reads nothing: every case's system and ground motion are built in code. Runs every case with
//! the exact integrator and its checks, and the survey of the integrator's known limit, then
//! prints the Markdown report (how to regenerate it, the tolerances, the table of cases and
//! outcomes, the survey) on stdout or, with `--out FILE.md`, writes it there and prints the
//! path. Exits non-zero, after the report, if any case or checked survey point fails.

use anyhow::{Context, Result, bail};
use slidestack::stress::{cases, limit_survey, markdown_report, run_all};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Write the Markdown report to this file instead of stdout.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let outcomes = run_all(&cases());
    let survey = limit_survey();
    let report = markdown_report(&outcomes, &survey);
    match &args.out {
        Some(path) => {
            std::fs::write(path, &report)
                .with_context(|| format!("cannot write {}", path.display()))?;
            println!("{}", path.display());
        }
        None => print!("{report}"),
    }
    let mut failed: Vec<&str> = outcomes
        .iter()
        .filter(|o| !o.passed())
        .map(|o| o.name.as_str())
        .collect();
    let survey_failed = survey
        .iter()
        .filter(|p| p.checked && !p.outcome.passed())
        .count();
    if survey_failed > 0 {
        failed.push("the known-limit survey");
    }
    if !failed.is_empty() {
        bail!(
            "stress suite: {} failed: {} (see the report)",
            failed.len(),
            failed.join(", ")
        );
    }
    Ok(())
}
