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
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Simulate(args) => cmd::simulate::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
