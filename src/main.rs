//! The `slidestack` command line: one subcommand per file under `src/cmd/`.

mod cmd;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use slidestack::pipeline::StageId;

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
    Simulate(Box<cmd::simulate::Args>),
    /// Response spectra (Sd, PSV, PSA) of records, exact between samples.
    Spectrum(cmd::spectrum::Args),
    /// Match records to a target spectrum (wavelet adjustment) and write them as .AT2 files.
    Match(cmd::matching::Args),
    /// Study stage 1: seed motions matched to every zone's target → motions.h5.
    Motions(cmd::StudyArgs),
    /// Study stage 2: every case of the grid under every motion → sweep.h5 (resumable, shards).
    Sweep(cmd::stage::ShardArgs),
    /// Join the units of a sharded sweep into sweep.h5.
    Merge(cmd::StudyArgs),
    /// Study stage 3: T_new and the displacement response ratios → tnew.h5 (resumable; in a
    /// building study shards of the attached fractions).
    Tnew(cmd::stage::ShardArgs),
    /// Study stage 4: fit the design equation for T_new (argmin) → fit.h5, fit.yaml.
    Fit(cmd::StudyArgs),
    /// Study stage 5: figures and tables → report/index.html.
    Report(cmd::StudyArgs),
    /// Incremental dynamic analysis of a yielding structure (the `ida:` section) → ida.h5.
    Ida(cmd::ida::Args),
    /// Floor response spectra of listed cases (the `floor_spectra:` section) → floors.h5.
    Floors(cmd::StudyArgs),
    /// The whole study: motions, sweep, tnew, fit, report, ida with an `ida:` section and
    /// floors with a `floor_spectra:` section (each skipped when up to date).
    Run(cmd::StudyArgs),
    /// What is on disk for every stage of a study (for people and job scripts).
    Status(cmd::status::Args),
    /// T_new and the design spectral accelerations of one structure, from a finished study.
    Design(cmd::design::Args),
    /// Demands in other tools' formats.
    #[command(subcommand)]
    Export(cmd::export::What),
}

fn main() -> std::process::ExitCode {
    // Piped into `head` and the like, stop quietly when the reader goes away, as shell tools do,
    // instead of panicking on the failed write.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let args = cmd::join_negative_values(std::env::args_os().collect(), &Cli::command());
    let matches = Cli::command().get_matches_from(args);
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    // The study's stages check for Ctrl-C between work units, `simulate` every few samples;
    // the other commands end at once.
    let checked = !matches!(
        cli.command,
        Command::Spectrum(_) | Command::Match(_) | Command::Design(_) | Command::Export(_)
    );
    cmd::interrupt::install(checked);
    let result = match cli.command {
        Command::Simulate(args) => cmd::simulate::run(*args),
        Command::Spectrum(args) => cmd::spectrum::run(args),
        Command::Match(args) => cmd::matching::run(args),
        Command::Motions(args) => cmd::stage::run(args, StageId::Motions),
        Command::Sweep(args) => cmd::stage::run_sharded(args, StageId::Sweep),
        Command::Merge(args) => cmd::merge::run(args),
        Command::Tnew(args) => cmd::stage::run_sharded(args, StageId::Tnew),
        Command::Fit(args) => cmd::stage::run(args, StageId::Fit),
        Command::Report(args) => cmd::stage::run(args, StageId::Report),
        Command::Ida(args) => cmd::ida::run(args),
        Command::Floors(args) => cmd::floors::run(args),
        Command::Run(args) => cmd::run::run(args),
        Command::Status(args) => cmd::status::run(args),
        Command::Design(args) => cmd::design::run(args),
        Command::Export(what) => cmd::export::run(what),
    };
    match result {
        // A Ctrl-C that came after the work was done is still reported.
        Ok(()) if cmd::interrupt::interrupted() => {
            eprintln!("error: interrupted after the work was done; what it wrote is complete");
            std::process::ExitCode::from(cmd::interrupt::EXIT_CODE)
        }
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            let root = Cli::command();
            let command = matches
                .subcommand_name()
                .and_then(|name| root.find_subcommand(name))
                .unwrap_or(&root);
            eprintln!("error: {}", cmd::message(&e, command));
            std::process::ExitCode::from(cmd::exit_code(&e))
        }
    }
}
