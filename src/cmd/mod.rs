//! One module per subcommand: each parses its arguments, calls the library and prints. The
//! study's stages share [`StudyArgs`], [`CliReporter`] and [`print_outcome`].

pub mod design;
pub mod export;
pub mod floors;
pub mod ida;
pub mod interrupt;
pub mod matching;
pub mod merge;
pub mod run;
pub mod simulate;
pub mod spectrum;
pub mod stage;
pub mod status;

use anyhow::{Context, Result};
pub use slidestack::fault::BadInput;
use slidestack::ground_motion::{ReadOptions, Record, Units, read_record_with};
use slidestack::pipeline::lock::{LockError, LockMode};
use slidestack::pipeline::{
    PipelineError, Progress, Reporter, Session, StageId, StageOptions, StageOutcome, Study,
};
use std::ffi::OsString;
use std::path::PathBuf;

/// What every study stage takes.
#[derive(Debug, Clone, clap::Args)]
pub struct StudyArgs {
    /// Study file (YAML).
    pub config: PathBuf,
    /// Output directory [default: the config's output_dir].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Rebuild even when the stored fingerprint says the output is up to date.
    #[arg(long)]
    pub force: bool,
    /// Refuse instead of waiting when another run holds the output directory.
    #[arg(long)]
    pub no_wait: bool,
}

impl StudyArgs {
    pub fn study(&self) -> Result<Study, PipelineError> {
        Study::load(&self.config, self.out.clone())
    }

    /// The study with its output directory locked.
    pub fn session<'r>(
        &self,
        mode: LockMode,
        reporter: &'r CliReporter,
    ) -> Result<Session<'r>, PipelineError> {
        Session::open(self.study()?, mode, !self.no_wait, reporter)
    }

    pub fn options(&self) -> StageOptions {
        StageOptions { force: self.force }
    }
}

/// Progress on stdout (`stage: …`), warnings on stderr, a bar on a terminal.
pub struct CliReporter;

impl Reporter for CliReporter {
    fn info(&self, stage: StageId, message: &str) {
        println!("{stage}: {message}");
    }
    fn warn(&self, stage: StageId, message: &str) {
        eprintln!("{stage}: warning: {message}");
    }
    fn progress(&self, _stage: StageId, total: u64) -> Box<dyn Progress + '_> {
        slidestack::pipeline::terminal_progress(total)
    }
    fn cancelled(&self) -> bool {
        interrupt::interrupted()
    }
}

/// `--shard K/N` of a stage that can be split: `1 ≤ K ≤ N` (the stage checks `N` against its
/// work units).
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s.split_once('/').ok_or("expected K/N, e.g. 2/8")?;
    let num = |x: &str, what: &str| {
        x.trim()
            .parse::<usize>()
            .map_err(|_| format!("{what} in `{s}` is not a whole number"))
    };
    let (k, n) = (num(k, "K")?, num(n, "N")?);
    if k == 0 || k > n {
        return Err(format!("shard `{s}`: needs 1 ≤ K ≤ N"));
    }
    Ok((k, n))
}

/// One line saying what a stage did.
pub fn print_outcome(stage: StageId, outcome: &StageOutcome, config: &std::path::Path) {
    match outcome {
        StageOutcome::UpToDate(p) => println!("{stage}: {} is up to date", p.display()),
        StageOutcome::Wrote(paths) => {
            let list: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            println!("{stage}: wrote {}", list.join(" and "));
        }
        StageOutcome::ShardDone { k, n } => {
            let assemble = match stage {
                StageId::Sweep => "merge",
                _ => stage.name(),
            };
            println!(
                "{stage}: shard {k}/{n} done; run `slidestack {assemble} {}` when every shard is \
                 done",
                config.display()
            )
        }
    }
}

/// The process exit code for an error: its kind's ([`slidestack::fault`]).
pub fn exit_code(e: &anyhow::Error) -> u8 {
    slidestack::fault::classify(e.as_ref()).kind.exit_code()
}

/// `Err` unless an SVG figure (`--figure`) can be written at `path`, checked before any work.
pub fn check_figure(path: &std::path::Path) -> Result<(), BadInput> {
    slidestack::store::atomic::check_output_extension(path, "a figure (SVG)", &["svg"])
        .map_err(|e| BadInput(e.to_string()))
}

/// The message of an error and its causes, each cause once (a cause whose text the message
/// already holds, from error types that repeat their source, is not printed again), with the
/// settings it names as `command`'s flags ([`with_flags`]), but for a YAML file's message,
/// which names the file's keys.
pub fn message(e: &anyhow::Error, command: &clap::Command) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = if names_file_keys(cause) {
            cause.to_string()
        } else {
            with_flags(&cause.to_string(), command)
        };
        if !text.contains(&c) {
            if !text.is_empty() {
                text += ": ";
            }
            text += &c;
        }
    }
    if e.chain()
        .any(|c| matches!(c.downcast_ref::<LockError>(), Some(LockError::Busy { .. })))
    {
        text += " (or run without --no-wait to wait)";
    }
    text
}

/// Whether `cause` is a YAML file's parser error, whose backticked names are the file's keys.
fn names_file_keys(cause: &(dyn std::error::Error + 'static)) -> bool {
    matches!(
        cause.downcast_ref::<slidestack::one_case::SimulationError>(),
        Some(slidestack::one_case::SimulationError::Yaml { .. })
    ) || matches!(
        cause.downcast_ref::<slidestack::study::config::ConfigError>(),
        Some(slidestack::study::config::ConfigError::Yaml { .. })
    )
}

/// The command line `args` (the program's name first) with the values of a flag given each as
/// `--flag=VALUE` where one of them is a negative number or list: `--mu -0.1,0.05` becomes
/// `--mu=-0.1,0.05`, `--alpha -0.5 0.5` becomes `--alpha=-0.5 --alpha=0.5`. Clap takes a
/// token that starts with `-` for short flags (`-0`) unless it is a lone number of the form
/// it knows (`allow_negative_numbers`): not a list, `-.5`, `-1e-3` or `-inf`; so a negative
/// value then reaches the library, which says what is wrong with it.
pub fn join_negative_values(args: Vec<OsString>, root: &clap::Command) -> Vec<OsString> {
    let mut root = root.clone();
    root.build();
    let sub = (args.iter().skip(1))
        .find_map(|a| a.to_str().filter(|a| !a.starts_with('-')))
        .and_then(|name| root.find_subcommand(name));
    let Some(sub) = sub else { return args };
    // The most values `--long` takes at once; `None` for a flag taking none.
    let most_values = |long: &str| {
        (sub.get_arguments())
            .find(|a| a.get_long() == Some(long) && a.get_action().takes_values())
            .map(|a| a.get_num_args().map_or(1, |n| n.max_values()))
    };
    let negative = |v: &str| {
        v.starts_with('-')
            && v.split(',')
                .next()
                .is_some_and(|x| x.parse::<f64>().is_ok())
    };
    let mut out = Vec::with_capacity(args.len());
    let mut i = 0;
    while i < args.len() {
        let flag = (args[i].to_str())
            .and_then(|s| s.strip_prefix("--"))
            .filter(|f| !f.contains('='));
        if let Some((flag, most)) = flag.and_then(|f| Some((f, most_values(f)?))) {
            let values: Vec<&str> = (args[i + 1..].iter())
                .take(most)
                .map_while(|v| v.to_str().filter(|v| !v.starts_with('-') || negative(v)))
                .collect();
            if values.iter().any(|v| negative(v)) {
                out.extend(values.iter().map(|v| format!("--{flag}={v}").into()));
                i += 1 + values.len();
                continue;
            }
        }
        out.push(args[i].clone());
        i += 1;
    }
    out
}

/// The library names a setting in backticks, with its value where that matters
/// (`` `period_s` ``, `` `structure: epp` ``); on the command line a setting is the flag of the
/// argument whose id it is (`--period`, `--structure epp`). A setting `command` has no flag for
/// is left as it is.
pub fn with_flags(text: &str, command: &clap::Command) -> String {
    let flag = |id: &str| {
        command
            .get_arguments()
            .find(|a| a.get_id() == id)
            .and_then(|a| a.get_long())
    };
    let parts: Vec<&str> = text.split('`').collect();
    let mut out = String::new();
    for (i, part) in parts.iter().enumerate() {
        // Odd parts lie between backticks; an unmatched last backtick is text.
        if i % 2 == 0 || i == parts.len() - 1 {
            if i % 2 == 1 {
                out.push('`');
            }
            out += part;
            continue;
        }
        let (id, value) = match part.split_once(": ") {
            Some((id, value)) => (id, Some(value)),
            None => (*part, None),
        };
        match (flag(id), value) {
            (Some(long), Some(value)) => out += &format!("--{long} {value}"),
            (Some(long), None) => out += &format!("--{long}"),
            (None, _) => out += &format!("`{part}`"),
        }
    }
    out
}

/// Ground-motion files and how to read them, shared by the commands that take records.
#[derive(Debug, clap::Args)]
pub struct RecordArgs {
    /// Ground-motion files: PEER .AT2, two-column time/acceleration or single-column text.
    #[arg(long = "record", required = true, num_args = 1..)]
    pub records: Vec<PathBuf>,
    /// Units of the values when a file does not declare them: g, m/s2 or cm/s2 [default: g].
    #[arg(long)]
    pub units: Option<Units>,
    /// Time step, s, for single-column files that do not declare `# dt:`.
    #[arg(long)]
    pub dt: Option<f64>,
}

impl RecordArgs {
    /// Reads every record, refusing the whole call on the first bad file (names file and line).
    pub fn read(&self) -> Result<Vec<Record>> {
        let opts = ReadOptions {
            units: self.units,
            dt_s: self.dt,
        };
        self.records
            .iter()
            .map(|p| read_record_with(p, &opts).map_err(anyhow::Error::from))
            .collect::<Result<Vec<_>>>()
            .context("cannot read the ground motions")
    }
}
