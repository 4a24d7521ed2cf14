//! `slidestack-verify`: regenerates the evidence (`scripts/evidence` runs every part).

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use slidestack_verify::stress::{cases, limit_survey, markdown_report, run_all};
use slidestack_verify::work_precision;
use std::path::PathBuf;

/// The evidence that slidestack is fast and accurate.
#[derive(Debug, Parser)]
#[command(name = "slidestack-verify", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Work-precision: error against time of the exact integrator, the paper's RK4 at 1–1000
    /// sub-steps and (optionally) OpenSees, on real records → accuracy.{md,csv,svg,html}.
    Accuracy(work_precision::Args),
    /// Numerical stress suite: extreme but legal cases and their checks → a Markdown report
    /// (docs/stress.md); fails, after the report, if a case fails.
    Stress {
        /// Write the Markdown report to this file instead of stdout.
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

fn stress(out: Option<PathBuf>) -> Result<()> {
    let outcomes = run_all(&cases());
    let survey = limit_survey();
    let report = markdown_report(&outcomes, &survey);
    match &out {
        Some(path) => {
            slidestack::store::atomic::write_bytes(path, report.as_bytes())
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
    if survey.iter().any(|p| p.checked && !p.outcome.passed()) {
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

fn main() -> std::process::ExitCode {
    let result = match Cli::parse().command {
        Command::Accuracy(args) => work_precision::run(&args),
        Command::Stress { out } => stress(out),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
