//! `slidestack floors CONFIG`: the floor response spectra stage
//! ([`slidestack::pipeline::floors`]), then each floor's measured amplifications beside the
//! codes' (the report's table).

use super::{CliReporter, StudyArgs, print_outcome};
use anyhow::Result;
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::{StageId, execute, report};

pub fn run(args: StudyArgs) -> Result<()> {
    let session = args.session(LockMode::Exclusive, &CliReporter)?;
    let outcome = execute(&session, StageId::Floors, args.options())?;
    print_outcome(StageId::Floors, &outcome, &args.config);
    println!(
        "{:<5} {:>4} {:>5} {:>5} {:>14} {:>14} {:>10} {:>10} {:>14} {:>14}  building",
        "zone",
        "case",
        "floor",
        "z/h",
        "PFA/PGA slide",
        "PFA/PGA attach",
        "ASCE7-16",
        "ASCE7-22",
        "PSA/PFA slide",
        "PSA/PFA attach"
    );
    for r in report::floors::amplification_table(&session.study)? {
        println!(
            "{:<5} {:>4} {:>5} {:>5.2} {:>14.3} {:>14.3} {:>10.3} {:>10.3} {:>14.3} {:>14.3}  {}",
            r.zone,
            r.case,
            r.floor,
            r.z_over_h,
            r.pfa_ratio_stack,
            r.pfa_ratio_rigid,
            r.asce7_16,
            r.asce7_22,
            r.psa_peak_ratio_stack,
            r.psa_peak_ratio_rigid,
            r.frame.as_deref().unwrap_or("one storey")
        );
    }
    Ok(())
}
