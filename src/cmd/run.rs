//! `slidestack run CONFIG`: every stage in order (motions → sweep → tnew → fit → ida with an
//! `ida:` section → report), each skipped when its output is up to date, under one lock of the
//! output directory; prints the time of each and ends with the report's path.

use super::{CliReporter, StudyArgs, print_outcome};
use anyhow::Result;
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::run_all;

pub fn run(args: StudyArgs) -> Result<()> {
    let session = args.session(LockMode::Exclusive, &CliReporter)?;
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
