//! `slidestack run CONFIG`: every stage the config configures in order (motions → sweep → tnew
//! → fit with a grid → ida with an `ida:` section → report; `Study::configured`), each skipped
//! when its output is up to date, under one lock of the output directory; prints the stages,
//! the time of each and ends with the report's path.

use super::{CliReporter, StudyArgs, print_outcome};
use anyhow::Result;
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::{StageId, run_all};

pub fn run(args: StudyArgs) -> Result<()> {
    let session = args.session(LockMode::Exclusive, &CliReporter)?;
    let study = &session.study;
    let stages: Vec<&str> = study.stages().iter().map(|s| s.name()).collect();
    println!("run: stages {}", stages.join(", "));
    if study.configured(StageId::Tnew)
        && let Some(why) = study.not_configured_why(StageId::Fit)
    {
        println!("run: no fit: {why}");
    }
    let mut times = Vec::new();
    run_all(&session, args.options(), |stage, outcome, secs| {
        print_outcome(stage, outcome, &args.config);
        times.push((stage, secs));
    })?;
    let total: f64 = times.iter().map(|t| t.1).sum();
    let line: Vec<String> = times.iter().map(|(s, t)| format!("{s} {t:.1} s")).collect();
    println!("run: {} (total {total:.1} s)", line.join(", "));
    println!("{}", session.study.path("report/index.html").display());
    Ok(())
}
