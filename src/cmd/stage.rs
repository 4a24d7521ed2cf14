//! `slidestack motions|tnew|fit|report CONFIG`: one stage of the study
//! ([`slidestack::pipeline`]: what each reads and writes, and when it does nothing); the stages
//! that can be split (`sweep`, `tnew`) with `--shard K/N`.

use super::{CliReporter, StudyArgs, print_outcome};
use anyhow::Result;
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::{StageId, execute, execute_shard};

pub fn run(args: StudyArgs, stage: StageId) -> Result<()> {
    let session = args.session(LockMode::Exclusive, &CliReporter)?;
    let outcome = execute(&session, stage, args.options())?;
    print_outcome(stage, &outcome, &args.config);
    Ok(())
}

/// A stage that can be split over a cluster.
#[derive(Debug, clap::Args)]
pub struct ShardArgs {
    #[command(flatten)]
    pub study: StudyArgs,
    /// Compute only shard K of N of the stage's work units (1 ≤ K ≤ N ≤ units) into their unit
    /// files, side by side with the other shards; `merge` (the sweep) or the stage without
    /// `--shard` (tnew) assembles them.
    #[arg(long, value_parser = super::parse_shard)]
    pub shard: Option<(usize, usize)>,
}

/// The whole stage, or with `--shard` that shard (sharing the output directory's lock with
/// the other shards).
pub fn run_sharded(args: ShardArgs, stage: StageId) -> Result<()> {
    let outcome = match args.shard {
        Some(shard) => {
            let s = args.study.session(LockMode::Shared, &CliReporter)?;
            execute_shard(&s, stage, shard, args.study.options())?
        }
        None => {
            let s = args.study.session(LockMode::Exclusive, &CliReporter)?;
            execute(&s, stage, args.study.options())?
        }
    };
    print_outcome(stage, &outcome, &args.study.config);
    Ok(())
}
