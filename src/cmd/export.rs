//! `slidestack export edp`: a building case's FEMA P-58 demands under a set of motions, written
//! in pelicun's demand-sample format (docs/building.md, "FEMA P-58 demands through pelicun").

use super::RecordArgs;
use anyhow::Result;
use slidestack::simulation::edp::{self, Stacks};
use std::path::PathBuf;

#[derive(Debug, clap::Subcommand)]
pub enum What {
    /// A building case's peak floor accelerations and velocities and peak and residual drift
    /// ratios, one row per record, as pelicun's demand sample (CSV with a `Units` row).
    Edp(EdpArgs),
}

#[derive(Debug, clap::Args)]
pub struct EdpArgs {
    /// The building case (YAML, as `simulate --config`; its `record` is replaced by each
    /// `--record`, its `scale` applied to each).
    #[arg(long)]
    config: PathBuf,
    #[command(flatten)]
    records: RecordArgs,
    /// The stacks rigidly attached to their floors instead of sliding.
    #[arg(long)]
    attached: bool,
    /// The CSV file to write.
    #[arg(long)]
    out: PathBuf,
}

pub fn run(what: What) -> Result<()> {
    let What::Edp(args) = what;
    let records = args.records.read()?;
    let stacks = if args.attached {
        Stacks::Attached
    } else {
        Stacks::Sliding
    };
    let rows = edp::export(&args.config, &records, stacks, &args.out)?;
    println!(
        "export edp: {} motions, {} storeys, stacks {} → {}",
        rows.len(),
        rows.first().map_or(0, |r| r.pid_rad.len()),
        if args.attached { "attached" } else { "sliding" },
        args.out.display()
    );
    Ok(())
}
