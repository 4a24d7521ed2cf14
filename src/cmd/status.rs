//! `slidestack status CONFIG [--out DIR] [--format text|env|make]`: what is on disk for every
//! stage the config configures and the sweep's work units, without changing anything (no lock
//! is taken). `--format env` prints `KEY=value` lines for shell scripts (`eval "$(slidestack
//! status … --format env)"`), `STAGES=motions,sweep,…` among them; `--format make` only the
//! configured stages, as the make variable `STAGES` (pipelines/paper.mk includes it).

use super::StudyArgs;
use anyhow::Result;
use clap::ValueEnum;
use slidestack::pipeline::{StageState, status};

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    Text,
    Env,
    Make,
}

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub study: StudyArgs,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    pub format: Format,
}

pub fn run(args: Args) -> Result<()> {
    let study = args.study.study()?;
    let stages: Vec<&str> = study.stages().iter().map(|s| s.name()).collect();
    if args.format == Format::Make {
        println!("# The stages {} configures.", args.study.config.display());
        println!("STAGES := {}", stages.join(" "));
        return Ok(());
    }
    let st = status(&study)?;
    match args.format {
        Format::Make => unreachable!("printed above"),
        Format::Env => {
            println!("STAGES={}", stages.join(","));
            for (stage, state) in &st.stages {
                println!("{}={}", stage.name().to_uppercase(), state.word());
            }
            println!("SWEEP_UNITS={}", st.sweep_units);
            println!("SWEEP_UNITS_DONE={}", st.sweep_units_done);
            println!("SWEEP_CASES_PER_UNIT={}", st.cases_per_unit);
            println!("SWEEP_SAMPLES_PER_MOTION={}", st.samples_per_motion);
            println!("SWEEP_SAMPLES_PER_UNIT={}", st.samples_per_unit);
            println!("SWEEP_NS_PER_SAMPLE={:.0}", st.ns_per_sample);
            println!("TNEW_UNITS={}", st.tnew_units);
            println!("TNEW_UNITS_DONE={}", st.tnew_units_done);
            println!("IDA_UNITS={}", st.ida_units);
            println!("IDA_UNITS_DONE={}", st.ida_units_done);
        }
        Format::Text => {
            println!("output directory {}", study.out.display());
            for (stage, state) in &st.stages {
                let detail = match state {
                    StageState::Damaged(why) => format!("damaged: {why}"),
                    other => other.word().replace('_', " "),
                };
                let detail = match st.made_with.iter().find(|m| m.0 == *stage) {
                    Some((_, made, now)) => {
                        format!("{detail} (made with methods {made}; this binary's are {now})")
                    }
                    None => detail,
                };
                println!("{:<8} {:<20} {detail}", stage.name(), stage.output());
            }
            if st.sweep_units > 0 {
                println!(
                    "sweep units: {} of {} stored ({} cases each)",
                    st.sweep_units_done, st.sweep_units, st.cases_per_unit
                );
            }
            if st.tnew_units > 0 {
                println!(
                    "tnew units: {} of {} stored (the attached fractions' scans)",
                    st.tnew_units_done, st.tnew_units
                );
            }
        }
    }
    Ok(())
}
