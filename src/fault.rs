//! What went wrong, classified once: every error the library returns has a [`FaultKind`] (bad
//! input, a missing or damaged file, I/O, an interruption, a failed run) and, where it names
//! them, the file, the key and the line at fault. The command line maps the kind to its exit code
//! ([`FaultKind::exit_code`]) and the Python module to its exception class, both from
//! [`classify`]: neither keeps a list of its own.

use crate::dynamics::building::BuildingError;
use crate::dynamics::{ModelError, SimError};
use crate::frame_edp::FrameEdpError;
use crate::ground_motion::RecordError;
use crate::ground_motion::matching::MatchError;
use crate::ground_motion::spectra::SpectraError;
use crate::match_files::MatchFilesError;
use crate::one_case::SimulationError;
use crate::one_case::batch::BatchError;
use crate::pipeline::floors::FloorsStageError;
use crate::pipeline::ida::IdaStageError;
use crate::pipeline::lock::LockError;
use crate::pipeline::motions::MotionsError;
use crate::pipeline::sweep::SweepStageError;
use crate::pipeline::{PipelineError, StageState};
use crate::spectrum::PeriodsError;
use crate::spectrum::ductility::DuctilityError;
use crate::store::StoreError;
use crate::store::atomic::OutputPathError;
use crate::study::config::ConfigError;
use crate::study::design::DesignError;
use crate::study::motions::SeedError;
use std::error::Error;
use std::io::ErrorKind;

/// The kinds of fault, each with one exit code and one Python exception class.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    /// The input is at fault: a config, case file, record, table or argument (exit 2,
    /// `ValueError`).
    BadInput,
    /// A file the input names, or that an earlier stage must write first, is not there (or
    /// was made from other inputs) (exit 2, `FileNotFoundError`).
    MissingFile,
    /// A stored file fails its checksum, identity or layout (exit 1, `slidestack.Error`).
    DamagedFile,
    /// Reading, writing or locking failed (exit 1, `OSError`).
    Io,
    /// Ctrl-C (exit 130, `KeyboardInterrupt`).
    Interrupted,
    /// The run could not produce its result: a numerical failure, an acceptance not met, a
    /// defect (exit 1, `slidestack.Error`).
    Failed,
}

impl FaultKind {
    /// The command line's exit code: 2 when the input is at fault, 130 when interrupted (the
    /// shell's 128 + SIGINT), 1 otherwise.
    pub fn exit_code(self) -> u8 {
        match self {
            FaultKind::BadInput | FaultKind::MissingFile => 2,
            FaultKind::Interrupted => 130,
            FaultKind::DamagedFile | FaultKind::Io | FaultKind::Failed => 1,
        }
    }

    /// The kind's name, as the Python exceptions' `kind` attribute gives it.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::BadInput => "bad_input",
            FaultKind::MissingFile => "missing_file",
            FaultKind::DamagedFile => "damaged_file",
            FaultKind::Io => "io",
            FaultKind::Interrupted => "interrupted",
            FaultKind::Failed => "failed",
        }
    }
}

/// A fault's kind and where it lies, as far as the error says.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fault {
    pub kind: FaultKind,
    /// The file at fault.
    pub file: Option<String>,
    /// The key of a config or case file (`grid.period_s`), or the setting of a call.
    pub key: Option<String>,
    /// The line of the file, 1 the first.
    pub line: Option<usize>,
}

impl Fault {
    fn of(kind: FaultKind) -> Self {
        Self {
            kind,
            file: None,
            key: None,
            line: None,
        }
    }
    fn file(mut self, file: impl std::fmt::Display) -> Self {
        self.file = Some(file.to_string());
        self
    }
    fn key(mut self, key: impl Into<String>) -> Self {
        self.key = Some(key.into());
        self
    }
    fn io(e: &std::io::Error) -> Self {
        Self::of(match e.kind() {
            ErrorKind::NotFound => FaultKind::MissingFile,
            ErrorKind::IsADirectory | ErrorKind::NotADirectory | ErrorKind::InvalidData => {
                FaultKind::BadInput
            }
            ErrorKind::Interrupted => FaultKind::Interrupted,
            _ => FaultKind::Io,
        })
    }
}

/// The fault of an error and its causes: the first in the chain of a type the library knows
/// decides (each delegates to the cause it wraps where that cause says more); a chain of none
/// of them (a message of the caller's own) is [`FaultKind::Failed`].
pub fn classify(e: &(dyn Error + 'static)) -> Fault {
    let mut cause: Option<&(dyn Error + 'static)> = Some(e);
    while let Some(c) = cause {
        if let Some(f) = known(c) {
            return f;
        }
        cause = c.source();
    }
    Fault::of(FaultKind::Failed)
}

/// The classification of `e` when it is one of the library's error types.
fn known(e: &(dyn Error + 'static)) -> Option<Fault> {
    macro_rules! first_of {
        ($($t:ty),* $(,)?) => {
            $(if let Some(x) = e.downcast_ref::<$t>() {
                return Some(x.fault());
            })*
        };
    }
    first_of!(
        PipelineError,
        SimulationError,
        BatchError,
        DesignError,
        FrameEdpError,
        MatchFilesError,
        SpectraError,
        ConfigError,
        StoreError,
        OutputPathError,
        LockError,
        RecordError,
        SeedError,
        MatchError,
        SimError,
        ModelError,
        BuildingError,
        PeriodsError,
        DuctilityError,
        BadInput,
        std::io::Error,
    );
    None
}

/// An input the caller got wrong that no library type describes (a flag combination).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// An error type's own classification.
trait Classify {
    fn fault(&self) -> Fault;
}

impl Classify for BadInput {
    fn fault(&self) -> Fault {
        Fault::of(FaultKind::BadInput)
    }
}

impl Classify for std::io::Error {
    fn fault(&self) -> Fault {
        Fault::io(self)
    }
}

impl Classify for PipelineError {
    fn fault(&self) -> Fault {
        use FaultKind::*;
        match self {
            PipelineError::Config(e) => e.fault(),
            PipelineError::BadInput { file, .. } => Fault::of(BadInput).file(file.display()),
            PipelineError::Setting { setting, .. } => Fault::of(BadInput).key(*setting),
            PipelineError::NoGrid { config, .. } | PipelineError::TooFewToFit { config, .. } => {
                Fault::of(BadInput).file(config.display()).key("grid")
            }
            PipelineError::Lock(e) => e.fault(),
            PipelineError::Store(e) => e.fault(),
            // A stage run before the one whose file it needs (or after its inputs changed).
            PipelineError::Upstream { file, state, .. } => match state {
                StageState::Damaged(_) => Fault::of(DamagedFile),
                _ => Fault::of(MissingFile),
            }
            .file(file.display()),
            PipelineError::Motions(e) => match e {
                MotionsError::Seeds(e) => e.fault(),
                MotionsError::Unmatched(_) => Fault::of(BadInput).key("motions.allow_unmatched"),
                MotionsError::Matching { .. }
                | MotionsError::NothingMatched { .. }
                | MotionsError::Changed { .. } => Fault::of(Failed),
            },
            PipelineError::Sweep(e) => match e {
                SweepStageError::MissingUnits { dir, .. } => {
                    Fault::of(MissingFile).file(dir.display())
                }
                SweepStageError::BadUnits { dir, .. } => Fault::of(DamagedFile).file(dir.display()),
                SweepStageError::Verify { file, .. } => Fault::of(DamagedFile).file(file.display()),
                SweepStageError::Simulation { .. } => Fault::of(Failed),
            },
            PipelineError::Ida(e) => match e {
                IdaStageError::NoSection { config } => {
                    Fault::of(BadInput).file(config.display()).key("ida")
                }
                IdaStageError::Simulation { .. } => Fault::of(Failed),
            },
            PipelineError::Floors(e) => match e {
                FloorsStageError::NoSection { config } => Fault::of(BadInput)
                    .file(config.display())
                    .key("floor_spectra"),
                FloorsStageError::Record { .. } => Fault::of(BadInput).key("floor_spectra"),
                FloorsStageError::Unit { .. } => Fault::of(Failed),
            },
            PipelineError::Report(crate::pipeline::report::ReportError::Design(e)) => e.fault(),
            PipelineError::Tnew(_) | PipelineError::Fit(_) | PipelineError::Report(_) => {
                Fault::of(Failed)
            }
            PipelineError::Shard { .. } => Fault::of(BadInput).key("shard"),
            PipelineError::Cancelled(_) => Fault::of(Interrupted),
        }
    }
}

impl Classify for ConfigError {
    fn fault(&self) -> Fault {
        match self {
            ConfigError::Io { file, source } => Fault::io(source).file(file),
            ConfigError::Yaml { file, .. } => Fault::of(FaultKind::BadInput).file(file),
            ConfigError::Invalid { file, key, .. } => {
                Fault::of(FaultKind::BadInput).file(file).key(key.as_str())
            }
        }
    }
}

impl Classify for StoreError {
    fn fault(&self) -> Fault {
        match self {
            StoreError::Io { file, source, .. } => match source.kind() {
                ErrorKind::NotFound => Fault::of(FaultKind::MissingFile),
                _ => Fault::of(FaultKind::Io),
            }
            .file(file.display()),
            StoreError::Hdf5 { file, .. } => Fault::of(FaultKind::Io).file(file.display()),
            StoreError::Corrupt { file, .. } | StoreError::Shape { file, .. } => {
                Fault::of(FaultKind::DamagedFile).file(file.display())
            }
            StoreError::Format(file) => Fault::of(FaultKind::BadInput).file(file.display()),
        }
    }
}

impl Classify for LockError {
    fn fault(&self) -> Fault {
        let dir = match self {
            LockError::CreateDir { dir, .. }
            | LockError::Open { dir, .. }
            | LockError::Busy { dir, .. }
            | LockError::Lock { dir, .. } => dir,
        };
        Fault::of(FaultKind::Io).file(dir.display())
    }
}

impl Classify for RecordError {
    fn fault(&self) -> Fault {
        let mut f = match self {
            RecordError::Io { file, source } => Fault::io(source).file(file),
            RecordError::TooLarge { file, .. } | RecordError::Empty { file } => {
                Fault::of(FaultKind::BadInput).file(file)
            }
            RecordError::Located { file, .. } => Fault::of(FaultKind::BadInput).file(file),
            RecordError::Samples { name, .. } => Fault::of(FaultKind::BadInput).file(name),
            RecordError::Setting { setting, .. } => Fault::of(FaultKind::BadInput).key(*setting),
        };
        if let RecordError::Located { line, .. } = self {
            f.line = Some(*line);
        }
        f
    }
}

impl Classify for OutputPathError {
    fn fault(&self) -> Fault {
        let path = match self {
            OutputPathError::NoDirectory { path, .. }
            | OutputPathError::NotADirectory { path, .. }
            | OutputPathError::IsADirectory { path }
            | OutputPathError::Extension { path, .. } => path,
        };
        Fault::of(FaultKind::BadInput).file(path.display())
    }
}

impl Classify for SeedError {
    fn fault(&self) -> Fault {
        match self {
            SeedError::Record(e) => e.fault(),
            SeedError::Stochastic(_) => Fault::of(FaultKind::BadInput).key("motions.seeds"),
        }
    }
}

impl Classify for SimulationError {
    fn fault(&self) -> Fault {
        match self {
            SimulationError::Config(e) => e.fault(),
            SimulationError::Record(e) => e.fault(),
            SimulationError::Yaml { file, .. } | SimulationError::Key { file, .. } => {
                Fault::of(FaultKind::BadInput).file(file)
            }
            SimulationError::Invalid(_) => Fault::of(FaultKind::BadInput),
            SimulationError::Setting { key, .. } => Fault::of(FaultKind::BadInput).key(key),
            SimulationError::Output(e) => e.fault(),
            SimulationError::Store(e) => e.fault(),
            SimulationError::Simulation { record, source } => source.fault().file(record),
        }
    }
}

impl Classify for BatchError {
    fn fault(&self) -> Fault {
        let case_key = |case: &usize, key: Option<&str>| match key {
            Some(k) => format!("cases[{case}].{k}"),
            None => format!("cases[{case}]"),
        };
        match self {
            BatchError::NoCase => Fault::of(FaultKind::BadInput).key("cases"),
            BatchError::NoRecord => Fault::of(FaultKind::BadInput).key("record"),
            BatchError::Case { case, source } => {
                let f = source.fault();
                let key = case_key(case, f.key.as_deref());
                Fault {
                    key: Some(key),
                    ..f
                }
            }
            BatchError::Mixed { case, .. } => {
                Fault::of(FaultKind::BadInput).key(case_key(case, None))
            }
            BatchError::Run { source, .. } => source.fault(),
            BatchError::Stopped { .. } => Fault::of(FaultKind::Interrupted),
            BatchError::Pool { .. } => Fault::of(FaultKind::Failed),
        }
    }
}

impl Classify for SimError {
    fn fault(&self) -> Fault {
        Fault::of(match self {
            SimError::Stopped { .. } => FaultKind::Interrupted,
            SimError::Zeno { .. }
            | SimError::Contact(_)
            | SimError::Diverged
            | SimError::Search { .. } => FaultKind::Failed,
            _ => FaultKind::BadInput,
        })
    }
}

impl Classify for ModelError {
    fn fault(&self) -> Fault {
        Fault::of(FaultKind::BadInput)
    }
}

impl Classify for BuildingError {
    fn fault(&self) -> Fault {
        Fault::of(FaultKind::BadInput)
    }
}

impl Classify for PeriodsError {
    fn fault(&self) -> Fault {
        Fault::of(FaultKind::BadInput).key("periods")
    }
}

impl Classify for DesignError {
    fn fault(&self) -> Fault {
        use FaultKind::*;
        match self {
            DesignError::Missing { dir, file } => {
                Fault::of(MissingFile).file(dir.join(file).display())
            }
            DesignError::Store(e) => e.fault(),
            // Files of one study that do not belong together: an earlier stage was rerun.
            DesignError::Mismatch { file } | DesignError::OtherMotions { file, .. } => {
                Fault::of(MissingFile).file(file.display())
            }
            DesignError::Building { file } | DesignError::NotBuilding { file } => {
                Fault::of(BadInput).file(file.display())
            }
            _ => Fault::of(BadInput),
        }
    }
}

impl Classify for FrameEdpError {
    fn fault(&self) -> Fault {
        use FaultKind::*;
        match self {
            FrameEdpError::Store(e) => e.fault(),
            FrameEdpError::Output(e) => e.fault(),
            FrameEdpError::Missing { dir, file } => {
                Fault::of(MissingFile).file(dir.join(file).display())
            }
            // Files of one study that do not belong together: an earlier stage was rerun.
            FrameEdpError::OtherMotions { file } => Fault::of(MissingFile).file(file.display()),
            FrameEdpError::NotBuilding { file } => Fault::of(BadInput).file(file.display()),
            FrameEdpError::NotHeld { file, key, .. } | FrameEdpError::Blocks { file, key, .. } => {
                Fault::of(BadInput).file(file.display()).key(key)
            }
        }
    }
}

impl Classify for MatchError {
    fn fault(&self) -> Fault {
        Fault::of(match self {
            MatchError::Setting { .. } | MatchError::Spectrum(_) => FaultKind::BadInput,
            _ => FaultKind::Failed,
        })
    }
}

impl Classify for MatchFilesError {
    fn fault(&self) -> Fault {
        use FaultKind::*;
        match self {
            MatchFilesError::Config(e) => e.fault(),
            MatchFilesError::Settings { file, .. } => Fault::of(BadInput).file(file.display()),
            MatchFilesError::Target(_) => Fault::of(BadInput).key("target"),
            MatchFilesError::CreateDir { dir, source } => Fault::io(source).file(dir.display()),
            MatchFilesError::Match { record, source } => source.fault().file(record),
            MatchFilesError::Record(e) => e.fault(),
            MatchFilesError::Store(e) => e.fault(),
            MatchFilesError::LeftOut { .. } => Fault::of(Failed),
        }
    }
}

impl Classify for DuctilityError {
    fn fault(&self) -> Fault {
        match self {
            DuctilityError::Simulation { source, .. } => source.fault(),
            DuctilityError::NoResponse { .. } | DuctilityError::NotReached { .. } => {
                Fault::of(FaultKind::Failed)
            }
            _ => Fault::of(FaultKind::BadInput),
        }
    }
}

impl Classify for SpectraError {
    fn fault(&self) -> Fault {
        match self {
            SpectraError::Damping(_) => Fault::of(FaultKind::BadInput).key("damping"),
            SpectraError::Spectrum { record, .. } => Fault::of(FaultKind::BadInput).file(record),
            SpectraError::Ductility { record, source } => source.fault().file(record),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes_follow_the_kinds() {
        assert_eq!(FaultKind::BadInput.exit_code(), 2);
        assert_eq!(FaultKind::MissingFile.exit_code(), 2);
        assert_eq!(FaultKind::Interrupted.exit_code(), 130);
        for k in [FaultKind::DamagedFile, FaultKind::Io, FaultKind::Failed] {
            assert_eq!(k.exit_code(), 1);
        }
    }

    #[test]
    fn the_first_known_error_in_a_chain_decides_and_keeps_its_place() {
        let e = ConfigError::Invalid {
            file: "c.yaml".into(),
            key: "grid.period_s".into(),
            why: "must be > 0".into(),
        };
        let p = PipelineError::from(e);
        let f = classify(&p);
        assert_eq!(f.kind, FaultKind::BadInput);
        assert_eq!(f.file.as_deref(), Some("c.yaml"));
        assert_eq!(f.key.as_deref(), Some("grid.period_s"));
        let io = std::io::Error::new(ErrorKind::NotFound, "gone");
        assert_eq!(classify(&io).kind, FaultKind::MissingFile);
    }
}
