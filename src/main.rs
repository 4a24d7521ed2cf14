//! The `slidestack` command line: one subcommand per file under `src/cmd/`.

mod cmd;

use clap::{Parser, Subcommand};

/// Seismic response of a structure carrying stacks of sliding rigid blocks.
#[derive(Debug, Parser)]
#[command(name = "slidestack", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate one case: a structure and its stack under one ground motion.
    Simulate(cmd::simulate::Args),
    /// Response spectra (Sd, PSV, PSA) of records, exact between samples.
    Spectrum(cmd::spectrum::Args),
    /// Match records to a target spectrum (wavelet adjustment) and write them as .AT2 files.
    Match(cmd::matching::Args),
    /// Study stage 1: seed motions matched to every zone's target → motions.h5.
    Motions(cmd::motions::Args),
    /// Study stage 2: every case of the grid under every motion → sweep.h5 (resumable, shards).
    Sweep(cmd::sweep::Args),
    /// Join the units of a sharded sweep into sweep.h5.
    Merge(cmd::sweep::MergeArgs),
    /// Study stage 3: T_new and the displacement response ratios → tnew.h5.
    Tnew(cmd::tnew::Args),
    /// Study stage 4: fit the design equation for T_new (argmin) → fit.h5, fit.yaml.
    Fit(cmd::fit::Args),
    /// Study stage 5: figures and tables → report/index.html.
    Report(cmd::report::Args),
    /// The whole study: motions, sweep, tnew, fit, report (each skipped when up to date).
    Run(cmd::run::Args),
    /// Evidence: work-precision of the integrators and the numerical stress suite.
    #[command(subcommand)]
    Bench(cmd::bench::BenchCommand),
}

fn main() -> std::process::ExitCode {
    // Piped into `head` and the like, stop quietly when the reader goes away, as shell tools do,
    // instead of panicking on the failed write.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Simulate(args) => cmd::simulate::run(args),
        Command::Spectrum(args) => cmd::spectrum::run(args),
        Command::Match(args) => cmd::matching::run(args),
        Command::Motions(args) => cmd::motions::run(args),
        Command::Sweep(args) => cmd::sweep::run(args),
        Command::Merge(args) => cmd::sweep::merge(args),
        Command::Tnew(args) => cmd::tnew::run(args),
        Command::Fit(args) => cmd::fit::run(args),
        Command::Report(args) => cmd::report::run(args),
        Command::Run(args) => cmd::run::run(args),
        Command::Bench(command) => cmd::bench::run(command),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            // Motions outside the matching band that the config does not allow: a result, not
            // a failure of the tool.
            if e.downcast_ref::<slidestack::study::motions::Unmatched>()
                .is_some()
            {
                std::process::ExitCode::from(2)
            } else {
                std::process::ExitCode::FAILURE
            }
        }
    }
}
