//! `slidestack merge CONFIG`: assembles `sweep.h5` ([`slidestack::pipeline::sweep`]) when every
//! shard of the sweep is done (`slidestack sweep CONFIG --shard K/N`, [`super::stage`]).

use super::{BadInput, CliReporter, StudyArgs, print_outcome};
use anyhow::Result;
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::{StageId, sweep};

pub fn run(args: StudyArgs) -> Result<()> {
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
