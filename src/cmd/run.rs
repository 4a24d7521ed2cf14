//! `slidestack run CONFIG`: every stage in order (motions → sweep → tnew → fit → report), each
//! skipped when its file is up to date, with the time of each; ends with the report's path.

use anyhow::Result;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file (YAML).
    config: PathBuf,
    /// Output directory [default: the config's output_dir].
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let (config, out) = (args.config, args.out);
    let mut times = Vec::new();
    let mut time = |name: &'static str, f: &mut dyn FnMut() -> Result<()>| -> Result<()> {
        let start = Instant::now();
        f()?;
        times.push((name, start.elapsed().as_secs_f64()));
        Ok(())
    };
    time("motions", &mut || {
        super::motions::run(super::motions::Args {
            config: config.clone(),
            out: out.clone(),
            force: false,
        })
    })?;
    time("sweep", &mut || {
        super::sweep::run(super::sweep::Args {
            config: config.clone(),
            out: out.clone(),
            shard: None,
        })
    })?;
    time("tnew", &mut || {
        super::tnew::run(super::tnew::Args {
            config: config.clone(),
            out: out.clone(),
        })
    })?;
    time("fit", &mut || {
        super::fit::run(super::fit::Args {
            config: config.clone(),
            out: out.clone(),
        })
    })?;
    time("report", &mut || {
        super::report::run(super::report::Args {
            config: config.clone(),
            out: out.clone(),
        })
    })?;
    let total: f64 = times.iter().map(|t| t.1).sum();
    let line: Vec<String> = times.iter().map(|(n, t)| format!("{n} {t:.1} s")).collect();
    println!("run: {} (total {total:.1} s)", line.join(", "));
    let dir = match out {
        Some(o) => o,
        None => slidestack::study::config::StudyConfig::load(&config)?.output_dir,
    };
    println!("{}", dir.join("report/index.html").display());
    Ok(())
}
