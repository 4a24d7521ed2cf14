//! The study as library code: its stages, one shape for all of them, and what they promise about
//! the files they leave.
//!
//! ```text
//! config ─► motions ─► motions.h5 ─► sweep ─► sweep.h5 ─► tnew ─► tnew.h5 ─► fit ─► fit.h5, fit.yaml
//!                          │                                  ▲                       │
//!                          └──────────────────────────────────┴──────── report ◄──────┘
//!                          │                                                           ▲
//!                          └─► ida ─► ida.h5 ──────────────────────────────────────────┘
//!                              (with an `ida:` section: a yielding structure; the report then
//!                               shows it and requires it)
//! ```
//!
//! Every stage ([`StageId`]) has the same shape: the upstream stages it reads, the fingerprint
//! its output must carry (computed from the config and the record files alone, so every stage
//! knows what each upstream file should be without trusting it), the files it writes, and its
//! `build`. [`execute`] runs any stage the same way:
//! 1. every upstream file must verify (checksum sidecar) and carry the fingerprint the config
//!    gives it, else the stage refuses and names the stage to rerun;
//! 2. when its own output verifies and carries the expected fingerprint, nothing is done (unless
//!    forced); a damaged output is rebuilt;
//! 3. `build` writes every file checked and atomically ([`crate::store`]).
//!
//! A [`Session`] holds the output directory's lock ([`lock`]) for its life, so two runs into one
//! directory never interleave; `run`, `make`, Slurm and a future Python binding all go through
//! [`Study::load`], [`Session::open`] and [`execute`]. Nothing here prints: progress goes to a
//! [`Reporter`].

pub mod files;
pub mod fit;
pub mod floors;
pub mod ida;
pub mod lock;
pub mod motions;
pub mod pause;
pub mod report;
pub mod sweep;
pub mod tnew;

use crate::grid::{BuildingAxes, Grid};
use crate::methods::Method;
use crate::store::{StoreError, atomic};
use crate::study::building::Frame;
use crate::study::config::{ConfigError, Seeds, StudyConfig};
use crate::study::floors::FloorsConfig;
use crate::study::ida::IdaConfig;
use crate::study::physics::{Physics, SystemKind};
use crate::study::shape::StudyShape;
use lock::{LockError, LockMode, OutputLock};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A stage of the study, in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StageId {
    Motions,
    Sweep,
    Tnew,
    Fit,
    /// Incremental dynamic analysis of a yielding structure (only with an `ida:` section).
    Ida,
    /// Floor response spectra of listed cases (only with a `floor_spectra:` section).
    Floors,
    Report,
}

impl StageId {
    pub const ALL: [StageId; 7] = [
        StageId::Motions,
        StageId::Sweep,
        StageId::Tnew,
        StageId::Fit,
        StageId::Ida,
        StageId::Floors,
        StageId::Report,
    ];

    /// The subcommand's name.
    pub fn name(self) -> &'static str {
        match self {
            StageId::Motions => "motions",
            StageId::Sweep => "sweep",
            StageId::Tnew => "tnew",
            StageId::Fit => "fit",
            StageId::Report => "report",
            StageId::Ida => "ida",
            StageId::Floors => "floors",
        }
    }

    /// The file whose stored fingerprint says whether the stage is up to date, relative to the
    /// output directory.
    pub fn output(self) -> &'static str {
        match self {
            StageId::Motions => "motions.h5",
            StageId::Sweep => "sweep.h5",
            StageId::Tnew => "tnew.h5",
            StageId::Fit => "fit.h5",
            StageId::Report => "report/index.html",
            StageId::Ida => "ida.h5",
            StageId::Floors => "floors.h5",
        }
    }

    /// The stages whose files this one reads (the report also reads `ida.h5` when the config
    /// has an `ida:` section; [`execute`] requires it then).
    pub fn upstream(self) -> &'static [StageId] {
        match self {
            StageId::Motions => &[],
            StageId::Sweep => &[StageId::Motions],
            StageId::Tnew => &[StageId::Motions, StageId::Sweep],
            StageId::Fit => &[StageId::Tnew],
            StageId::Report => &[StageId::Motions, StageId::Tnew, StageId::Fit],
            StageId::Ida | StageId::Floors => &[StageId::Motions],
        }
    }
}

impl StageId {
    /// The methods whose numbers the stage stores ([`crate::methods`]); their versions are in
    /// its fingerprint.
    pub fn methods(self) -> &'static [Method] {
        use crate::methods::*;
        match self {
            StageId::Motions => &[MOTIONS, SPECTRUM],
            StageId::Sweep => &[INTEGRATOR],
            StageId::Tnew => &[SPECTRUM, TNEW, LAMBDA, INTEGRATOR],
            StageId::Fit => &[FIT],
            // The report simulates the paper's named cases.
            StageId::Report => &[REPORT, INTEGRATOR],
            StageId::Ida => &[INTEGRATOR, SPECTRUM, IDA],
            StageId::Floors => &[INTEGRATOR, SPECTRUM, FLOORS],
        }
    }

    /// The stage's fingerprint from the hash of its inputs: that hash and its methods' versions.
    pub fn fingerprint(self, inputs_hash: &str) -> String {
        crate::methods::fingerprint(inputs_hash, self.methods())
    }
}

impl std::fmt::Display for StageId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[derive(Debug, Error)]
pub enum PipelineError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error("{}: {why}", file.display())]
    BadInput { file: PathBuf, why: String },
    /// A setting of the call (not of the config), named as the library names it.
    #[error("`{setting}` {why}")]
    Setting { setting: &'static str, why: String },
    #[error(transparent)]
    Lock(#[from] LockError),
    #[error(transparent)]
    Store(#[from] StoreError),
    /// An upstream file is missing, stale or damaged; `why` names it.
    #[error("{why}: run `slidestack {stage} {}` first", config.display())]
    Upstream {
        why: String,
        file: PathBuf,
        /// What was found of it (never up to date).
        state: StageState,
        stage: StageId,
        config: PathBuf,
    },
    #[error("{}: the `{stage}` stage needs a `grid` section", config.display())]
    NoGrid { config: PathBuf, stage: StageId },
    /// The grid has fewer cases than any design equation needs ([`crate::study::equations::case_count`]).
    #[error(
        "{}: the `fit` stage needs at least {needed} cases (over the distinct frames) to fit \
         and cross-validate a design equation; the grid gives {cases}",
        config.display()
    )]
    TooFewToFit {
        config: PathBuf,
        cases: usize,
        needed: usize,
    },
    #[error(transparent)]
    Motions(#[from] motions::MotionsError),
    #[error(transparent)]
    Sweep(#[from] sweep::SweepStageError),
    #[error(transparent)]
    Tnew(#[from] crate::study::tnew::TnewError),
    #[error(transparent)]
    Fit(#[from] crate::study::equations::EquationError),
    #[error(transparent)]
    Report(#[from] report::ReportError),
    #[error(transparent)]
    Ida(#[from] ida::IdaStageError),
    #[error(transparent)]
    Floors(#[from] floors::FloorsStageError),
    #[error("shard {k}/{n}: needs 1 ≤ K ≤ N ≤ {units} (the {stage} stage has {units} work units)")]
    Shard {
        stage: StageId,
        k: usize,
        n: usize,
        units: usize,
    },
    /// The reporter asked the run to stop ([`Reporter::cancelled`]).
    #[error("{0}: interrupted; what it stored is kept and the next run resumes from there")]
    Cancelled(StageId),
}

/// What a stage found on disk.
#[derive(Debug, Clone, PartialEq)]
pub enum StageState {
    UpToDate,
    Missing,
    /// Made from other inputs.
    Stale,
    /// Fails its checksum or cannot be read.
    Damaged(String),
}

impl StageState {
    /// The word `status --format env` prints.
    pub fn word(&self) -> &'static str {
        match self {
            StageState::UpToDate => "up_to_date",
            StageState::Missing => "missing",
            StageState::Stale => "stale",
            StageState::Damaged(_) => "damaged",
        }
    }
}

/// Where progress goes; the CLI prints it, tests and bindings may collect or drop it.
pub trait Reporter: Sync {
    /// A line of progress from `stage`.
    fn info(&self, stage: StageId, message: &str);
    /// Something the user should know that does not stop the stage.
    fn warn(&self, stage: StageId, message: &str);
    /// A counter of `total` steps (work units); the default shows nothing.
    fn progress(&self, _stage: StageId, _total: u64) -> Box<dyn Progress + '_> {
        Box::new(NoProgress)
    }
    /// Whether the caller wants the run stopped (the Python module's Ctrl-C). Stages ask between
    /// work units and stop with [`PipelineError::Cancelled`], leaving the output directory as a
    /// killed run does: every unit stored so far kept, the next run resuming from them.
    fn cancelled(&self) -> bool {
        false
    }
}

/// A counter on standard error when it is a terminal (`{bar} {pos}/{len} units, {per_sec}, ETA
/// {eta}`), nothing otherwise: the progress the CLI and the Python module show.
pub fn terminal_progress(total: u64) -> Box<dyn Progress> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return Box::new(NoProgress);
    }
    let style =
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} units, {per_sec}, ETA {eta}")
            .expect("valid template");
    Box::new(TerminalBar(
        indicatif::ProgressBar::new(total).with_style(style),
    ))
}

struct TerminalBar(indicatif::ProgressBar);

impl Progress for TerminalBar {
    fn inc(&self) {
        self.0.inc(1);
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}

/// A counter handed out by [`Reporter::progress`].
pub trait Progress: Sync {
    fn inc(&self);
    fn finish(&self) {}
}

struct NoProgress;

impl Progress for NoProgress {
    fn inc(&self) {}
}

/// A reporter that drops everything.
pub struct Quiet;

impl Reporter for Quiet {
    fn info(&self, _: StageId, _: &str) {}
    fn warn(&self, _: StageId, _: &str) {}
}

/// The expected fingerprint of every stage's output, from the config (and record files) alone;
/// a stage the config does not configure has none ([`Study::configured`]).
#[derive(Debug, Clone)]
struct Fingerprints {
    motions: String,
    /// `None` without a `grid` section.
    sweep: Option<String>,
    tnew: Option<String>,
    /// `None` without a grid, or with one too small to fit a design equation to
    /// ([`crate::study::equations::case_count`]).
    fit: Option<String>,
    /// `None` without an `ida` section.
    ida: Option<String>,
    /// `None` without a `floor_spectra` section.
    floors: Option<String>,
    report: String,
}

/// A loaded, validated study: its config, output directory, grid and expected fingerprints.
#[derive(Debug, Clone)]
pub struct Study {
    pub config_path: PathBuf,
    pub cfg: StudyConfig,
    /// The output directory (`--out`, else the config's `output_dir`).
    pub out: PathBuf,
    /// SHA-256 of the config file's bytes.
    pub config_sha256: String,
    /// Its grid and frames.
    pub shape: StudyShape,
    /// The cases a fit would have and the least it needs ([`crate::study::equations::case_count`]); `None`
    /// without a grid.
    fit_cases: Option<(usize, usize)>,
    fingerprints: Fingerprints,
    /// The study `report.compare_with` names (its own `report:` section ignored: no chains).
    pub compare: Option<Box<Study>>,
}

/// Refuses output directories that are surely mistakes: empty, the file-system root, an
/// unexpanded `~`; `Err(why)`.
pub fn check_output_dir(out: &Path) -> Result<(), String> {
    let text = out.to_string_lossy();
    let why = if text.trim().is_empty() {
        Some("is empty".to_string())
    } else if text.starts_with('~') {
        Some(format!(
            "`{text}`: `~` is not expanded here; write the full path"
        ))
    } else if out.parent().is_none() {
        Some(format!("`{text}` is the root of the file system"))
    } else if out.is_file() {
        Some(format!("`{text}` is a file, not a directory"))
    } else {
        None
    };
    why.map_or(Ok(()), Err)
}

/// The physics settings every stage file after the motions' stores as file attributes.
pub fn physics_attrs(p: &Physics) -> [(&'static str, crate::store::h5::Attr<'static>); 2] {
    use crate::store::h5::Attr;
    [
        ("damping", Attr::F64(p.damping)),
        ("damping_basis", Attr::Str(p.basis.name())),
    ]
}

impl Study {
    /// Reads and validates the config (every limit is checked here, before any work) and
    /// computes every stage's expected fingerprint.
    pub fn load(config: &Path, out: Option<PathBuf>) -> Result<Self, PipelineError> {
        Self::with_config(StudyConfig::load(config)?, config, out)
    }

    /// The study of a config already read ([`StudyConfig::parse`]); `config` names it in
    /// messages.
    pub fn with_config(
        cfg: StudyConfig,
        config: &Path,
        out: Option<PathBuf>,
    ) -> Result<Self, PipelineError> {
        let out = match out {
            Some(o) => {
                check_output_dir(&o).map_err(|why| PipelineError::Setting {
                    setting: "out",
                    why,
                })?;
                o
            }
            None => {
                check_output_dir(&cfg.output_dir).map_err(|why| PipelineError::BadInput {
                    file: config.to_path_buf(),
                    why: format!("`output_dir` {why}"),
                })?;
                cfg.output_dir.clone()
            }
        };
        let shape = StudyShape::of(&cfg);
        let compare = match cfg.report.as_ref().and_then(|r| r.compare_with.as_ref()) {
            Some(path) => {
                let mut other = StudyConfig::load(path)?;
                other.report = None;
                Some(Box::new(Study::with_config(other, path, None)?))
            }
            None => None,
        };
        // The compared study's results enter the report (its `T_new`, `λ` and fit).
        let compared = (compare.as_deref()).and_then(|c| c.fingerprints.fit.clone());
        let motions_fp = motions::fingerprint(&cfg);
        let ida = ida::fingerprint(&cfg, &motions_fp);
        let floors = floors::fingerprint(&cfg, &motions_fp);
        let sweep = (shape.grid()).map(|_| sweep::fingerprint(&cfg, &motions_fp));
        let tnew = sweep.as_deref().map(tnew::fingerprint);
        let fit_cases =
            (shape.grid()).map(|g| crate::study::equations::case_count(g, shape.frames()));
        let fit = match (&tnew, fit_cases) {
            (Some(t), Some((cases, needed))) if cases >= needed => {
                Some(fit::fingerprint(t, shape.is_building()))
            }
            _ => None,
        };
        // The report reads the fit's results, else the `T_new` of a grid too small to fit.
        let report = report::fingerprint(
            fit.as_deref().or(tnew.as_deref()),
            &motions_fp,
            ida.as_deref(),
            floors.as_deref(),
            compared.as_deref(),
        );
        Ok(Self {
            config_path: config.to_path_buf(),
            config_sha256: cfg.loaded.config_sha256.clone(),
            cfg,
            out,
            shape,
            fit_cases,
            fingerprints: Fingerprints {
                motions: motions_fp,
                sweep,
                tnew,
                fit,
                ida,
                floors,
                report,
            },
            compare,
        })
    }

    /// Whether the config configures `stage`: motions and the report always; sweep and `tnew`
    /// with a `grid` section; the fit with a grid of enough cases to fit a design equation to
    /// ([`crate::study::equations::case_count`]); the IDA with an `ida:` section. `run`, make and Slurm run exactly
    /// these stages.
    pub fn configured(&self, stage: StageId) -> bool {
        let f = &self.fingerprints;
        match stage {
            StageId::Motions | StageId::Report => true,
            StageId::Sweep => f.sweep.is_some(),
            StageId::Tnew => f.tnew.is_some(),
            StageId::Fit => f.fit.is_some(),
            StageId::Ida => f.ida.is_some(),
            StageId::Floors => f.floors.is_some(),
        }
    }

    /// The configured stages, in the order they run.
    pub fn stages(&self) -> Vec<StageId> {
        (StageId::ALL.into_iter())
            .filter(|&s| self.configured(s))
            .collect()
    }

    /// Why `stage` is not configured, in a sentence; `None` when it is.
    pub fn not_configured_why(&self, stage: StageId) -> Option<String> {
        self.fingerprint(stage).err().map(|e| e.to_string())
    }

    /// The configured stages whose files `stage` reads.
    pub fn upstream(&self, stage: StageId) -> Vec<StageId> {
        let mut up: Vec<StageId> = (stage.upstream().iter().copied())
            .filter(|&s| self.configured(s))
            .collect();
        if stage == StageId::Report {
            up.extend(
                [StageId::Ida, StageId::Floors]
                    .into_iter()
                    .filter(|&s| self.configured(s)),
            );
        }
        up
    }

    /// The grid, or an error naming the stage that needs it.
    pub fn grid(&self, stage: StageId) -> Result<&Grid, PipelineError> {
        self.shape.grid().ok_or_else(|| PipelineError::NoGrid {
            config: self.config_path.clone(),
            stage,
        })
    }

    /// A building study's `building:` section as JSON (the file attribute `building` of every
    /// stage file after the motions').
    pub fn building_attr(&self) -> Option<String> {
        let b = self.cfg.building.as_ref()?;
        Some(serde_json::to_string(b).expect("the building section serialises"))
    }

    /// Each zone's motion count as the config gives it, before the motions stage ran (the
    /// seeds' count or the record files'; the stage may keep fewer).
    pub fn motions_per_zone(&self) -> Vec<usize> {
        let per_zone = match self.cfg.motions.seeds.kind() {
            Seeds::Stochastic(s) => s.count,
            Seeds::Records(r) => r.files.len(),
        };
        vec![per_zone; self.cfg.zones.len()]
    }

    /// The config's `ida:` section, which the `ida` stage and what reads `ida.h5` need.
    pub fn ida_config(&self) -> Result<&IdaConfig, PipelineError> {
        (self.cfg.ida.as_ref()).ok_or_else(|| {
            ida::IdaStageError::NoSection {
                config: self.config_path.clone(),
            }
            .into()
        })
    }

    /// The config's `floor_spectra:` section, which the `floors` stage and what reads
    /// `floors.h5` need.
    pub fn floors_config(&self) -> Result<&FloorsConfig, PipelineError> {
        (self.cfg.floor_spectra.as_ref()).ok_or_else(|| {
            floors::FloorsStageError::NoSection {
                config: self.config_path.clone(),
            }
            .into()
        })
    }

    /// The blocks' width-to-height ratios (`grid.aspect`), when the rocking check is asked for.
    pub fn aspect(&self) -> Option<&[f64]> {
        self.cfg.grid.as_ref().and_then(|g| g.aspect.as_deref())
    }

    /// The building axes of a building study (`None` on one storey).
    pub fn building(&self) -> Option<&BuildingAxes> {
        self.shape.building()
    }

    /// The frames in stored order ([`StudyShape::frames`]; one on one storey).
    pub fn frames(&self) -> &[Frame] {
        self.shape.frames()
    }

    /// The physics of every case (`grid.damping`, `grid.mu_static_ratio`).
    pub fn physics(&self) -> Physics {
        self.cfg.physics()
    }

    /// A file of the output directory.
    pub fn path(&self, name: &str) -> PathBuf {
        self.out.join(name)
    }

    /// The fingerprint the stage's output must carry; an error saying what the config lacks
    /// for a stage it does not configure.
    pub fn fingerprint(&self, stage: StageId) -> Result<&str, PipelineError> {
        let f = &self.fingerprints;
        let no_grid = || PipelineError::NoGrid {
            config: self.config_path.clone(),
            stage,
        };
        match stage {
            StageId::Motions => Ok(&f.motions),
            StageId::Report => Ok(&f.report),
            StageId::Sweep => f.sweep.as_deref().ok_or_else(no_grid),
            StageId::Tnew => f.tnew.as_deref().ok_or_else(no_grid),
            StageId::Fit => f.fit.as_deref().ok_or_else(|| match self.fit_cases {
                Some((cases, needed)) => PipelineError::TooFewToFit {
                    config: self.config_path.clone(),
                    cases,
                    needed,
                },
                None => no_grid(),
            }),
            StageId::Ida => f.ida.as_deref().ok_or_else(|| {
                ida::IdaStageError::NoSection {
                    config: self.config_path.clone(),
                }
                .into()
            }),
            StageId::Floors => f.floors.as_deref().ok_or_else(|| {
                floors::FloorsStageError::NoSection {
                    config: self.config_path.clone(),
                }
                .into()
            }),
        }
    }

    /// The verified fingerprint stored in the stage's output, `None` when it is missing.
    pub fn stored(&self, stage: StageId) -> Result<Option<String>, StoreError> {
        let path = self.path(stage.output());
        match stage {
            StageId::Fit => crate::store::fit::stored_fingerprint(&path, &self.path("fit.yaml")),
            StageId::Report => crate::store::report::stored_fingerprint(&self.path("report")),
            _ => crate::store::h5::stored_fingerprint(&path),
        }
    }

    /// What is on disk for `stage`.
    pub fn state(&self, stage: StageId) -> Result<StageState, PipelineError> {
        let want = self.fingerprint(stage)?;
        Ok(match self.stored(stage) {
            Ok(None) => StageState::Missing,
            Ok(Some(fp)) if fp == want => StageState::UpToDate,
            Ok(Some(_)) => StageState::Stale,
            Err(e) => StageState::Damaged(e.to_string()),
        })
    }

    /// Refuses unless `stage`'s output is on disk, whole and made from this config; the error
    /// names the file and the earliest stage that must run again.
    pub fn require(&self, stage: StageId) -> Result<(), PipelineError> {
        let file = self.path(stage.output());
        let state = self.state(stage)?;
        if state == StageState::UpToDate {
            return Ok(());
        }
        let mut first = stage;
        for earlier in StageId::ALL
            .into_iter()
            .take_while(|&s| s != stage)
            .filter(|&s| self.configured(s))
        {
            if self.state(earlier)? != StageState::UpToDate {
                first = earlier;
                break;
            }
        }
        let why = match &state {
            StageState::UpToDate => unreachable!("returned above"),
            StageState::Missing => format!("{} is missing", file.display()),
            StageState::Stale => format!(
                "{} was made from other inputs than {}",
                file.display(),
                self.config_path.display()
            ),
            StageState::Damaged(e) => e.clone(),
        };
        Err(PipelineError::Upstream {
            why,
            file,
            state,
            stage: first,
            config: self.config_path.clone(),
        })
    }
}

/// A study with its output directory locked; stages run inside one.
pub struct Session<'r> {
    pub study: Study,
    pub reporter: &'r dyn Reporter,
    mode: LockMode,
    _lock: OutputLock,
}

impl<'r> Session<'r> {
    /// Locks the study's output directory (creating it): exclusively for every stage but a
    /// sweep shard. With `wait`, waits for another holder (telling the reporter); without,
    /// refuses naming it. An exclusive session first removes temporaries left by killed runs.
    pub fn open(
        study: Study,
        mode: LockMode,
        wait: bool,
        reporter: &'r dyn Reporter,
    ) -> Result<Self, PipelineError> {
        let first = StageId::Motions;
        let lock = OutputLock::acquire(&study.out, mode, wait, |holder| {
            reporter.info(
                first,
                &format!(
                    "waiting for {holder}, which holds {}",
                    study.out.join(lock::LOCK_FILE).display()
                ),
            )
        })?;
        if lock.unsupported {
            reporter.warn(
                first,
                &format!(
                    "the file system of {} does not support locks: nothing stops another run from \
                     writing into it at the same time",
                    study.out.display()
                ),
            );
        }
        if mode == LockMode::Exclusive {
            let units = [sweep::UNITS_DIR, ida::UNITS_DIR].map(|d| study.path(d));
            for dir in [study.out.clone()].iter().chain(&units) {
                atomic::remove_stale_temps(dir)?;
            }
        }
        let session = Self {
            study,
            reporter,
            mode,
            _lock: lock,
        };
        session.pass("session.locked", first)?;
        Ok(session)
    }

    pub fn exclusive(&self) -> bool {
        self.mode == LockMode::Exclusive
    }

    /// `Err(Cancelled)` when the reporter asks the run to stop.
    pub fn check_cancelled(&self, stage: StageId) -> Result<(), PipelineError> {
        if self.reporter.cancelled() {
            return Err(PipelineError::Cancelled(stage));
        }
        Ok(())
    }

    /// Passes the test hook's `point` ([`pause`]), then `Err(Cancelled)` when the run was
    /// cancelled meanwhile.
    pub fn pass(&self, point: &str, stage: StageId) -> Result<(), PipelineError> {
        pause::point(point, &|| self.reporter.cancelled());
        self.check_cancelled(stage)
    }
}

/// How a stage runs.
#[derive(Debug, Clone, Copy, Default)]
pub struct StageOptions {
    /// Rebuild even when the output is up to date.
    pub force: bool,
}

/// What a stage did.
#[derive(Debug, Clone, PartialEq)]
pub enum StageOutcome {
    /// The output was already up to date.
    UpToDate(PathBuf),
    /// These files were written.
    Wrote(Vec<PathBuf>),
    /// A shard of the sweep, `tnew` or the IDA stored its units; `merge` (the sweep) or the
    /// unsharded stage (`tnew`, the IDA) assembles them.
    ShardDone { k: usize, n: usize },
}

/// Which of a stage's `units` work units `--shard K/N` computes (`i mod N = K − 1`; every unit
/// without a shard): refused unless `1 ≤ K ≤ N ≤ units`.
pub fn shard_filter(
    stage: StageId,
    shard: Option<(usize, usize)>,
    units: usize,
) -> Result<impl Fn(usize) -> bool, PipelineError> {
    if let Some((k, n)) = shard
        && !(1 <= k && k <= n && n <= units)
    {
        return Err(PipelineError::Shard { stage, k, n, units });
    }
    Ok(move |i: usize| shard.is_none_or(|(k, n)| i % n == k - 1))
}

/// A stage's stored work units, read back: what each of `units` holds (in order; only when
/// `keep`, else `None`), and `(index, unit)` of those to compute again: missing, stale, or
/// damaged (with a warning naming the file). The sweep, `tnew` and the IDA resume through it.
pub(crate) fn scan_units<U: Copy, T, E: std::fmt::Display>(
    s: &Session,
    stage: StageId,
    units: &[U],
    keep: bool,
    read: impl Fn(U) -> Result<Option<T>, E>,
) -> (Vec<Option<T>>, Vec<(usize, U)>) {
    let mut held = Vec::with_capacity(units.len());
    let mut todo = Vec::new();
    for (i, &u) in units.iter().enumerate() {
        let stored = read(u).unwrap_or_else(|e| {
            s.reporter.warn(stage, &format!("{e}: computing it again"));
            None
        });
        if stored.is_none() {
            todo.push((i, u));
        }
        held.push(if keep { stored } else { None });
    }
    (held, todo)
}

/// Runs shard `K/N` of a stage that can be split (the sweep, `tnew`, the IDA): checks its
/// inputs, does nothing when its output is up to date (unless forced), else computes and stores
/// that shard's units; the unsharded stage (`merge` for the sweep) assembles them.
pub fn execute_shard(
    s: &Session,
    stage: StageId,
    (k, n): (usize, usize),
    opts: StageOptions,
) -> Result<StageOutcome, PipelineError> {
    check_inputs(s, stage)?;
    if !opts.force && s.study.state(stage)? == StageState::UpToDate {
        return Ok(StageOutcome::UpToDate(s.study.path(stage.output())));
    }
    let shard = Some((k, n));
    match stage {
        StageId::Sweep => sweep::build(s, shard),
        StageId::Tnew => tnew::build(s, shard),
        StageId::Ida => ida::build(s, shard),
        _ => Err(PipelineError::Setting {
            setting: "shard",
            why: format!("is not an option of the {stage} stage: it has no work units to split"),
        }),
    }
}

/// `Err` unless `stage` can run: not cancelled, configured, every upstream file up to date.
fn check_inputs(s: &Session, stage: StageId) -> Result<(), PipelineError> {
    s.check_cancelled(stage)?;
    s.study.fingerprint(stage)?;
    for up in s.study.upstream(stage) {
        s.study.require(up)?;
    }
    Ok(())
}

/// Runs one stage (module doc): checks its inputs, skips it when up to date, else builds it.
pub fn execute(
    s: &Session,
    stage: StageId,
    opts: StageOptions,
) -> Result<StageOutcome, PipelineError> {
    check_inputs(s, stage)?;
    let path = s.study.path(stage.output());
    if !opts.force {
        match s.study.state(stage)? {
            StageState::UpToDate => {
                if s.exclusive() {
                    match stage {
                        StageId::Sweep => sweep::remove_units(&s.study)?,
                        StageId::Tnew => tnew::remove_units(&s.study)?,
                        StageId::Ida => ida::remove_units(&s.study)?,
                        _ => {}
                    }
                }
                return Ok(StageOutcome::UpToDate(path));
            }
            StageState::Damaged(why) => s.reporter.warn(stage, &format!("{why}: rebuilding it")),
            StageState::Missing | StageState::Stale => {}
        }
    }
    let outcome = match stage {
        StageId::Motions => motions::build(s),
        StageId::Sweep => sweep::build(s, None),
        StageId::Tnew => tnew::build(s, None),
        StageId::Fit => fit::build(s),
        StageId::Report => report::build(s),
        StageId::Ida => ida::build(s, None),
        StageId::Floors => floors::build(s),
    }?;
    // A Ctrl-C that came while the output was being finished is reported, the output kept.
    s.pass("stage.done", stage)?;
    Ok(outcome)
}

/// Every configured stage in order ([`Study::configured`]), each skipped when up to date,
/// telling `done` what each did and how long it took, s.
pub fn run_all(
    s: &Session,
    opts: StageOptions,
    mut done: impl FnMut(StageId, &StageOutcome, f64),
) -> Result<(), PipelineError> {
    for stage in s.study.stages() {
        let start = std::time::Instant::now();
        let outcome = execute(s, stage, opts)?;
        done(stage, &outcome, start.elapsed().as_secs_f64());
    }
    Ok(())
}

/// The state of every stage and of the sweep's work units (for job schedulers).
#[derive(Debug, Clone, PartialEq)]
pub struct Status {
    pub stages: Vec<(StageId, StageState)>,
    /// The stale stages whose file was made with other method versions than this binary's:
    /// `(stage, the file's methods, this binary's)`.
    pub made_with: Vec<(StageId, String, String)>,
    /// Work units of the sweep (zones × motions × periods).
    pub sweep_units: usize,
    /// Units already stored for the current sweep.
    pub sweep_units_done: usize,
    /// Work units the IDA traces (zones × motions × cases × distinct buildings; 0 without an
    /// `ida:` section) and those already stored for the current IDA.
    pub ida_units: usize,
    pub ida_units_done: usize,
    /// `tnew`'s work units (the attached fractions' of a building study; 0 on one storey) and
    /// those stored for the current `tnew`.
    pub tnew_units: usize,
    pub tnew_units_done: usize,
    pub cases_per_unit: usize,
    /// Record samples per motion, the mean over the stored motions (0 before `motions` ran).
    pub samples_per_motion: usize,
    /// Record samples a unit simulates at most (every system of every case simulated): the work
    /// bound job scripts size their tasks with.
    pub samples_per_unit: usize,
    /// CPU nanoseconds per sample of that bound ([`crate::study::cost::ns_per_sample`]).
    pub ns_per_sample: f64,
}

/// What is on disk for every stage; reads only, takes no lock.
pub fn status(study: &Study) -> Result<Status, PipelineError> {
    let mut stages = Vec::new();
    let mut made_with = Vec::new();
    for stage in StageId::ALL {
        if !study.configured(stage) {
            continue;
        }
        let state = study.state(stage)?;
        if state == StageState::Stale {
            let want = crate::methods::tag(stage.methods());
            let stored = study.stored(stage).ok().flatten();
            let made = stored.as_deref().and_then(crate::methods::methods_of);
            if made != Some(want.as_str()) {
                let made = made.unwrap_or("a version that did not record them");
                made_with.push((stage, made.to_string(), want));
            }
        }
        stages.push((stage, state));
    }
    let (sweep_units, sweep_units_done, samples_per_motion) = match study.shape.grid() {
        Some(_) => sweep::unit_status(study)?,
        None => (0, 0, 0),
    };
    let cases_per_unit = study.shape.grid().map_or(0, Grid::cases_per_unit);
    let (tnew_units, tnew_units_done) = match study.configured(StageId::Tnew) {
        true => tnew::unit_status(study)?,
        false => (0, 0),
    };
    let (ida_units, ida_units_done) = match study.configured(StageId::Ida) {
        true => ida::unit_status(study)?,
        false => (0, 0),
    };
    Ok(Status {
        ida_units,
        ida_units_done,
        tnew_units,
        tnew_units_done,
        stages,
        made_with,
        sweep_units,
        sweep_units_done,
        cases_per_unit,
        samples_per_motion,
        samples_per_unit: SystemKind::ALL.len() * cases_per_unit * samples_per_motion,
        ns_per_sample: crate::study::cost::ns_per_sample(&study.shape),
    })
}
