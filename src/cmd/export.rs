//! `slidestack export edp`: a building case's FEMA P-58 demands under a set of records, or one
//! case of a finished building study's under its motions, written in pelicun's demand-sample
//! format (docs/building.md, "FEMA P-58 demands through pelicun").

use super::{BadInput, RecordArgs};
use anyhow::Result;
use slidestack::frame_edp::{self, FrameQuery};
use slidestack::grid::StackFloor;
use slidestack::ground_motion::Units;
use slidestack::one_case::edp::{self, Stacks};
use std::path::PathBuf;

#[derive(Debug, clap::Subcommand)]
pub enum What {
    /// A building's peak floor accelerations and velocities and peak and residual drift ratios,
    /// one row per motion, as pelicun's demand sample (CSV with a `Units` row): a case file
    /// under `--record`s, or one case of a finished building study (`--study`) under its zone's
    /// motions.
    Edp(EdpArgs),
}

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("source").required(true).args(["config", "study"])))]
pub struct EdpArgs {
    /// The building case (YAML, as `simulate --config`; its `record` is replaced by each
    /// `--record`, its `scale` applied to each).
    #[arg(long, requires = "records")]
    config: Option<PathBuf>,
    /// With `--config`: ground-motion files, one row each (as `spectrum --record`).
    #[arg(long = "record", num_args = 1.., requires = "config")]
    records: Vec<PathBuf>,
    /// Units of the records' values when a file does not declare them: g, m/s2 or cm/s2
    /// [default: g].
    #[arg(long, requires = "config")]
    units: Option<Units>,
    /// Time step, s, for single-column record files that do not declare `# dt:`.
    #[arg(long, requires = "config")]
    dt: Option<f64>,
    /// A finished building study's output directory (its `sweep.h5` and `motions.h5`), with
    /// `--zone`, `--storeys`, `--stack-floor`, `--period`, `--alpha` and `--mu` naming the case.
    #[arg(long, requires_all = ["zone", "storeys", "stack_floor", "period", "alpha", "mu"])]
    study: Option<PathBuf>,
    #[arg(long, requires = "study")]
    zone: Option<String>,
    /// The building's storeys.
    #[arg(long, requires = "study")]
    storeys: Option<usize>,
    /// The floor the stacks stand on: a number, `roof`, `mid` or `all`.
    #[arg(long, requires = "study")]
    stack_floor: Option<StackFloor>,
    /// The bare building's first-mode period, s.
    #[arg(long, requires = "study")]
    period: Option<f64>,
    /// Block mass ratios, bottom first.
    #[arg(long, value_delimiter = ',', requires = "study")]
    alpha: Option<Vec<f64>>,
    /// Kinetic friction coefficients, interface 1 first.
    #[arg(long, value_delimiter = ',', requires = "study")]
    mu: Option<Vec<f64>>,
    /// The stacks rigidly attached to their floors instead of sliding.
    #[arg(long)]
    attached: bool,
    /// The CSV file to write.
    #[arg(long)]
    out: PathBuf,
}

pub fn run(what: What) -> Result<()> {
    let What::Edp(args) = what;
    let stacks = if args.attached {
        Stacks::Attached
    } else {
        Stacks::Sliding
    };
    let rows = match (&args.config, &args.study) {
        (Some(config), None) => {
            let records = RecordArgs {
                records: args.records.clone(),
                units: args.units,
                dt: args.dt,
            };
            edp::export(config, &records.read()?, stacks, &args.out)?
        }
        (None, Some(study)) => {
            let q = FrameQuery {
                zone: args.zone.clone().unwrap_or_default(),
                storeys: args.storeys.unwrap_or_default(),
                stack_floor: args.stack_floor.unwrap_or(StackFloor::Roof),
                period_s: args.period.unwrap_or_default(),
                alpha: args.alpha.clone().unwrap_or_default(),
                mu: args.mu.clone().unwrap_or_default(),
            };
            frame_edp::export_frame(study, &q, stacks, &args.out)?
        }
        _ => {
            return Err(BadInput(
                "export edp takes a case (`--config` with `--record`) or a study's case \
                 (`--study` with `--zone` …), not both"
                    .into(),
            )
            .into());
        }
    };
    println!(
        "export edp: {} motions, {} storeys, stacks {} → {}",
        rows.len(),
        rows.first().map_or(0, |r| r.pid_rad.len()),
        if args.attached { "attached" } else { "sliding" },
        args.out.display()
    );
    Ok(())
}
