//! `slidestack sweep CONFIG [--shard K/N]` and `slidestack merge CONFIG`: the study's second
//! stage ([`slidestack::pipeline::sweep`]). A shard computes its work units only (side by side
//! with the other shards: it takes the output directory's lock shared); `merge` assembles
//! `sweep.h5` when every shard is done.

use super::{BadInput, CliReporter, StudyArgs, print_outcome};
use anyhow::Result;
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::{StageId, execute, sweep};

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub study: StudyArgs,
    /// Compute only shard K of N (1 ≤ K ≤ N ≤ work units) and leave the assembly to `merge`.
    #[arg(long, value_parser = super::parse_shard)]
    pub shard: Option<(usize, usize)>,
}

pub fn run(args: Args) -> Result<()> {
    let stage = StageId::Sweep;
    let outcome = match args.shard {
        Some((k, n)) => {
            let s = args.study.session(LockMode::Shared, &CliReporter)?;
            sweep::run_shard(&s, k, n, args.study.options())?
        }
        None => {
            let s = args.study.session(LockMode::Exclusive, &CliReporter)?;
            execute(&s, stage, args.study.options())?
        }
    };
    print_outcome(stage, &outcome, &args.study.config);
    Ok(())
}

pub fn merge(args: StudyArgs) -> Result<()> {
    if args.force {
        return Err(
            BadInput("merge takes no --force: rerun the shards with --force".into()).into(),
        );
    }
    let s = args.session(LockMode::Exclusive, &CliReporter)?;
    let outcome = sweep::merge(&s)?;
    print_outcome(StageId::Sweep, &outcome, &args.config);
    Ok(())
}
