//! `slidestack motions|tnew|fit|report CONFIG`: one stage of the study
//! ([`slidestack::pipeline`]: what each reads and writes, and when it does nothing).

use super::{CliReporter, StudyArgs, print_outcome};
use anyhow::Result;
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::{StageId, execute};

pub fn run(args: StudyArgs, stage: StageId) -> Result<()> {
    let session = args.session(LockMode::Exclusive, &CliReporter)?;
    let outcome = execute(&session, stage, args.options())?;
    print_outcome(stage, &outcome, &args.config);
    Ok(())
}
