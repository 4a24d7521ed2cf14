//! The study's stages from Python: `run`, each stage by name, `merge` and `status`, as the CLI's
//! subcommands run them ([`slidestack::pipeline`]).
//!
//! A stage runs on a thread of its own while the calling thread, GIL released, waits for it in
//! short slices and between them lets Python run its signal handlers: Ctrl-C raises
//! `KeyboardInterrupt` there, and the reporter then tells the stage to stop at its next work
//! unit ([`Reporter::cancelled`]), which leaves the output directory as a killed run does.

use crate::convert::{to_yaml_value, warn};
use crate::errors::{internal, to_py_err};
use crate::interrupt::on_worker;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use slidestack::pipeline::lock::LockMode;
use slidestack::pipeline::{
    PipelineError, Progress, Reporter, Session, StageId, StageOptions, StageOutcome, StageState,
    Study, execute, execute_shard, run_all, status as study_status, sweep, terminal_progress,
};
use slidestack::study::config::{ConfigError, StudyConfig};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The name a config given as a mapping has in messages.
const DICT_CONFIG: &str = "<config dict>";

/// A study file, or a mapping with its keys (paths in it relative to the working directory).
enum ConfigArg {
    Path(PathBuf),
    Yaml(String),
}

impl ConfigArg {
    fn from_py(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        if obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")? {
            return Ok(ConfigArg::Path(obj.extract()?));
        }
        if obj.is_instance_of::<PyDict>() {
            let value = to_yaml_value(obj, "config")?;
            let text = serde_yaml::to_string(&value)
                .map_err(|e| PyValueError::new_err(format!("`config`: {e}")))?;
            return Ok(ConfigArg::Yaml(text));
        }
        Err(PyValueError::new_err(
            "`config` must be a path to a study file or a dict with its keys",
        ))
    }

    fn study(&self, out: Option<PathBuf>) -> Result<Study, PipelineError> {
        match self {
            ConfigArg::Path(p) => Study::load(p, out),
            ConfigArg::Yaml(text) => {
                let name = Path::new(DICT_CONFIG);
                // The lines are of the YAML made from the dict: not the caller's.
                let cfg = StudyConfig::parse(text.as_bytes(), name, Path::new("."))
                    .map_err(ConfigError::without_line)?;
                Study::with_config(cfg, name, out)
            }
        }
    }
}

/// Progress as the CLI shows it when standard error is a terminal, nothing otherwise; warnings
/// kept for Python's `warnings`; the Ctrl-C flag.
struct PyReporter {
    terminal: bool,
    cancel: Arc<AtomicBool>,
    /// The output directory is locked (the stage checks `cancel` from here on).
    opened: AtomicBool,
    warnings: Mutex<Vec<String>>,
}

impl Reporter for PyReporter {
    fn info(&self, stage: StageId, message: &str) {
        if self.terminal {
            eprintln!("{stage}: {message}");
        }
    }
    fn warn(&self, stage: StageId, message: &str) {
        if let Ok(mut w) = self.warnings.lock() {
            w.push(format!("{stage}: {message}"));
        }
    }
    fn progress(&self, _stage: StageId, total: u64) -> Box<dyn Progress + '_> {
        terminal_progress(total)
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// Runs `work` in a session on the study of `config` (module doc: its thread, Ctrl-C).
fn in_session<T: Send + 'static>(
    py: Python<'_>,
    config: ConfigArg,
    out: Option<PathBuf>,
    mode: LockMode,
    wait: bool,
    work: impl FnOnce(&Session) -> Result<T, PipelineError> + Send + 'static,
) -> PyResult<T> {
    let reporter = Arc::new(PyReporter {
        terminal: std::io::stderr().is_terminal(),
        cancel: Arc::new(AtomicBool::new(false)),
        opened: AtomicBool::new(false),
        warnings: Mutex::new(Vec::new()),
    });
    let worker = Arc::clone(&reporter);
    let waited = on_worker(
        py,
        Arc::clone(&reporter.cancel),
        // Still waiting for another run's lock: the thread stops at its first check.
        || reporter.opened.load(Ordering::Relaxed),
        move || {
            let study = config.study(out)?;
            let session = Session::open(study, mode, wait, &*worker)?;
            worker.opened.store(true, Ordering::Relaxed);
            work(&session)
        },
    )?;
    let (result, interrupt) = (waited.result, waited.interrupt);
    let warnings = reporter
        .warnings
        .lock()
        .map(|w| w.clone())
        .unwrap_or_default();
    warn(py, &warnings)?;
    if let Some(e) = interrupt {
        // The stage's own word on what it kept, where it stopped for the interrupt.
        return Err(match result {
            Ok(Err(stopped @ PipelineError::Cancelled(_))) => to_py_err(&stopped),
            _ => e,
        });
    }
    match result {
        Ok(r) => r.map_err(|e| to_py_err(&e)),
        Err(why) => Err(internal(&why)),
    }
}

/// What a stage did, as a dict: `stage`, `outcome` (`up_to_date`, `wrote`, `shard_done`),
/// `files` and, from `run`, `seconds`.
fn outcome_dict<'py>(
    py: Python<'py>,
    stage: StageId,
    outcome: &StageOutcome,
    seconds: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("stage", stage.name())?;
    let (word, files): (&str, Vec<String>) = match outcome {
        StageOutcome::UpToDate(p) => ("up_to_date", vec![p.display().to_string()]),
        StageOutcome::Wrote(ps) => (
            "wrote",
            ps.iter().map(|p| p.display().to_string()).collect(),
        ),
        StageOutcome::ShardDone { k, n } => {
            d.set_item("shard", (k, n))?;
            ("shard_done", Vec::new())
        }
    };
    d.set_item("outcome", word)?;
    d.set_item("files", PyList::new(py, files)?)?;
    if let Some(s) = seconds {
        d.set_item("seconds", s)?;
    }
    Ok(d)
}

/// Every stage in order (`slidestack run`): a dict of what each did, by stage name.
#[pyfunction]
#[pyo3(signature = (config, out=None, force=false, wait=true))]
fn run<'py>(
    py: Python<'py>,
    config: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    force: bool,
    wait: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let config = ConfigArg::from_py(config)?;
    let done = in_session(py, config, out, LockMode::Exclusive, wait, move |s| {
        let mut done = Vec::new();
        run_all(s, StageOptions { force }, |stage, outcome, secs| {
            done.push((stage, outcome.clone(), secs));
        })?;
        Ok(done)
    })?;
    let d = PyDict::new(py);
    for (stage, outcome, secs) in &done {
        d.set_item(
            stage.name(),
            outcome_dict(py, *stage, outcome, Some(*secs))?,
        )?;
    }
    Ok(d)
}

fn one_stage<'py>(
    py: Python<'py>,
    stage: StageId,
    config: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    force: bool,
    wait: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let config = ConfigArg::from_py(config)?;
    let outcome = in_session(py, config, out, LockMode::Exclusive, wait, move |s| {
        execute(s, stage, StageOptions { force })
    })?;
    outcome_dict(py, stage, &outcome, None)
}

macro_rules! stage_fn {
    ($name:ident, $id:expr, $doc:literal) => {
        #[doc = $doc]
        #[pyfunction]
        #[pyo3(signature = (config, out=None, force=false, wait=true))]
        fn $name<'py>(
            py: Python<'py>,
            config: &Bound<'py, PyAny>,
            out: Option<PathBuf>,
            force: bool,
            wait: bool,
        ) -> PyResult<Bound<'py, PyDict>> {
            one_stage(py, $id, config, out, force, wait)
        }
    };
}

stage_fn!(
    motions,
    StageId::Motions,
    "The motions stage (`slidestack motions`)."
);
stage_fn!(fit, StageId::Fit, "The fit stage (`slidestack fit`).");
stage_fn!(
    floors,
    StageId::Floors,
    "The floors stage (`slidestack floors`): floor response spectra."
);
stage_fn!(
    report,
    StageId::Report,
    "The report stage (`slidestack report`)."
);

/// A `shard=(k, n)` keyword: `None` when absent, else `1 ≤ k ≤ n` (the stage checks `n`
/// against its work units).
fn shard_pair(shard: Option<&Bound<'_, PyAny>>) -> PyResult<Option<(usize, usize)>> {
    let Some(shard) = shard.filter(|s| !s.is_none()) else {
        return Ok(None);
    };
    let pair: Vec<Bound<'_, PyAny>> = (shard.extract().ok())
        .filter(|p: &Vec<Bound<'_, PyAny>>| p.len() == 2)
        .ok_or_else(|| PyValueError::new_err("`shard` must be a pair (k, n) of whole numbers"))?;
    let (k, n) = (
        crate::convert::whole(&pair[0], "shard", 1)?,
        crate::convert::whole(&pair[1], "shard", 1)?,
    );
    if k == 0 || k > n {
        return Err(PyValueError::new_err(format!(
            "`shard` ({k}, {n}): needs 1 ≤ k ≤ n"
        )));
    }
    Ok(Some((k, n)))
}

/// A stage that can be split: the whole stage, or with `shard=(k, n)` only that shard's units
/// (`execute_shard`), in a session shared with the other shards.
fn sharded_stage<'py>(
    py: Python<'py>,
    stage: StageId,
    (config, out, force, wait): (&Bound<'py, PyAny>, Option<PathBuf>, bool, bool),
    shard: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let Some((k, n)) = shard_pair(shard)? else {
        return one_stage(py, stage, config, out, force, wait);
    };
    let config = ConfigArg::from_py(config)?;
    let outcome = in_session(py, config, out, LockMode::Shared, wait, move |s| {
        execute_shard(s, stage, (k, n), StageOptions { force })
    })?;
    outcome_dict(py, stage, &outcome, None)
}

/// A stage that can be split (`slidestack STAGE [--shard K/N]`): its function with the
/// `shard=(k, n)` keyword ([`sharded_stage`]).
macro_rules! sharded_fn {
    ($name:ident, $py_name:literal, $id:expr, $doc:literal) => {
        #[doc = $doc]
        #[pyfunction]
        #[pyo3(name = $py_name, signature = (config, out=None, force=false, wait=true, shard=None))]
        fn $name<'py>(
            py: Python<'py>,
            config: &Bound<'py, PyAny>,
            out: Option<PathBuf>,
            force: bool,
            wait: bool,
            shard: Option<&Bound<'py, PyAny>>,
        ) -> PyResult<Bound<'py, PyDict>> {
            sharded_stage(py, $id, (config, out, force, wait), shard)
        }
    };
}

sharded_fn!(
    sweep_,
    "sweep",
    StageId::Sweep,
    "The sweep stage (`slidestack sweep`); with `shard=(k, n)` only that shard's units."
);
sharded_fn!(
    tnew_,
    "tnew",
    StageId::Tnew,
    "The tnew stage (`slidestack tnew`); with `shard=(k, n)` only that shard's units of a \
     building study's attached fractions, which a later call without it assembles."
);
sharded_fn!(
    ida_,
    "ida",
    StageId::Ida,
    "The ida stage (`slidestack ida`); with `shard=(k, n)` only that shard's units, which a \
     later call without it assembles."
);

/// Assembles `sweep.h5` when every shard is done (`slidestack merge`).
#[pyfunction]
#[pyo3(signature = (config, out=None, wait=true))]
fn merge<'py>(
    py: Python<'py>,
    config: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    wait: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let config = ConfigArg::from_py(config)?;
    let outcome = in_session(py, config, out, LockMode::Exclusive, wait, sweep::merge)?;
    outcome_dict(py, StageId::Sweep, &outcome, None)
}

/// What is on disk for every stage (`slidestack status --format env`, as a dict); takes no lock.
#[pyfunction]
#[pyo3(signature = (config, out=None))]
fn status<'py>(
    py: Python<'py>,
    config: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let config = ConfigArg::from_py(config)?;
    let (dir, st) = py
        .detach(|| {
            let study = config.study(out)?;
            study_status(&study).map(|st| (study.out.clone(), st))
        })
        .map_err(|e| to_py_err(&e))?;
    let d = PyDict::new(py);
    d.set_item("output_dir", dir.display().to_string())?;
    let stages = PyDict::new(py);
    let damaged = PyDict::new(py);
    for (stage, state) in &st.stages {
        stages.set_item(stage.name(), state.word())?;
        if let StageState::Damaged(why) = state {
            damaged.set_item(stage.name(), why)?;
        }
    }
    d.set_item("stages", stages)?;
    d.set_item("damaged", damaged)?;
    let made_with = PyDict::new(py);
    for (stage, made, now) in &st.made_with {
        made_with.set_item(stage.name(), (made, now))?;
    }
    d.set_item("made_with", made_with)?;
    d.set_item("sweep_units", st.sweep_units)?;
    d.set_item("sweep_units_done", st.sweep_units_done)?;
    d.set_item("tnew_units", st.tnew_units)?;
    d.set_item("tnew_units_done", st.tnew_units_done)?;
    d.set_item("ida_units", st.ida_units)?;
    d.set_item("ida_units_done", st.ida_units_done)?;
    d.set_item("sweep_cases_per_unit", st.cases_per_unit)?;
    d.set_item("sweep_samples_per_motion", st.samples_per_motion)?;
    d.set_item("sweep_samples_per_unit", st.samples_per_unit)?;
    d.set_item("sweep_ns_per_sample", st.ns_per_sample)?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(motions, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_, m)?)?;
    m.add_function(wrap_pyfunction!(tnew_, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(ida_, m)?)?;
    m.add_function(wrap_pyfunction!(floors, m)?)?;
    m.add_function(wrap_pyfunction!(report, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(status, m)?)?;
    Ok(())
}
