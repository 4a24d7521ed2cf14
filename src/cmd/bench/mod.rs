//! `slidestack bench …`: checks and measurements of the numerics, one file per kind.

pub mod stress;

use anyhow::Result;

/// What `bench` runs.
#[derive(Debug, clap::Subcommand)]
pub enum BenchCommand {
    /// Numerical stress suite: extreme but legal cases and their checks → a Markdown report
    /// (docs/stress.md).
    Stress(stress::Args),
}

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub command: BenchCommand,
}

pub fn run(args: Args) -> Result<()> {
    match args.command {
        BenchCommand::Stress(a) => stress::run(a),
    }
}
