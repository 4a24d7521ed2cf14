//! `slidestack._native`: the Python module's compiled half (python/slidestack/ is the rest).
//!
//! Every function here converts its arguments, calls the library function the CLI calls, and
//! converts the answer: a result the CLI prints as JSON comes back as that JSON parsed by
//! Python's `json` (so the keys and the shortest round-trip digits are the CLI's, bit for bit),
//! with numpy arrays where the CLI prints lists of samples. The work runs with the GIL released;
//! the study's stages run on a thread of their own so that Ctrl-C stops them
//! ([`slidestack::pipeline::Reporter::cancelled`]).
//!
//! Errors: the library's classification as Python's exception classes, with the CLI's message
//! ([`errors`]).

mod batch;
mod convert;
mod errors;
mod interrupt;
mod pipeline;

use convert::{json_to_py, to_yaml_value};
use errors::to_py_err;
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};
use slidestack::design::design as design_query;
use slidestack::dynamics::History;
use slidestack::dynamics::Watch;
use slidestack::frame_edp::{FrameQuery, export_frame};
use slidestack::grid::StackFloor;
use slidestack::ground_motion::matching::{MatchSettings, match_record};
use slidestack::ground_motion::spectra::{ductility_spectra, response_spectra};
use slidestack::ground_motion::{ReadOptions, Record, Units, read_record_with};
use slidestack::one_case::building::history_layout;
use slidestack::one_case::edp::{self, Stacks};
use slidestack::one_case::{Model, Settings, SimulationError};
use slidestack::spectrum::{TargetSpectrum, parse_periods, periods_from_list};
use slidestack::store::HistoryLayout;
use slidestack::study::design::Query;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A simulation's watch: it goes on until Ctrl-C sets the flag.
struct Cancel(Arc<AtomicBool>);

impl Watch for Cancel {
    fn going_on(&self, _: usize, _: usize) -> bool {
        let cancelled = || self.0.load(Ordering::Relaxed);
        slidestack::pipeline::pause::point("simulate.samples", &cancelled);
        !cancelled()
    }
}

/// The label of a record given as samples (its `record` in the results).
const ARRAY_RECORD: &str = "array";

/// `slidestack spectrum --periods`'s default.
const DEFAULT_PERIODS: &str = "0.05:4:0.01";

/// A record argument: a path (str or os.PathLike) or an `(accel_g, dt)` pair.
enum RecordArg {
    Path(PathBuf),
    Samples(Record),
}

fn record_arg(obj: &Bound<'_, PyAny>) -> PyResult<RecordArg> {
    if obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")? {
        return Ok(RecordArg::Path(obj.extract()?));
    }
    let pair: Vec<Bound<'_, PyAny>> = obj
        .extract()
        .map_err(|_| PyValueError::new_err("`record` must be a path or an (accel_g, dt) pair"))?;
    let [accel, dt] = pair.as_slice() else {
        return Err(PyValueError::new_err(format!(
            "`record` must be a path or an (accel_g, dt) pair, got a sequence of {}",
            pair.len()
        )));
    };
    let accel_g = convert::float_vec(accel, "record[0] (accel_g)")?;
    let dt_s: f64 = dt
        .extract()
        .map_err(|_| PyValueError::new_err("`record[1]` (dt, s) must be a number"))?;
    Record::from_samples(ARRAY_RECORD, dt_s, accel_g)
        .map(RecordArg::Samples)
        .map_err(|e| to_py_err(&e))
}

/// A record argument as a record: a path read (as `simulate` reads its `record`), or the samples.
fn record_of(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Record> {
    match record_arg(obj)? {
        RecordArg::Path(p) => py
            .detach(|| read_record_with(&p, &ReadOptions::default()))
            .map_err(|e| to_py_err(&e)),
        RecordArg::Samples(r) => Ok(r),
    }
}

/// One case under one ground motion: the dict `slidestack simulate --json` prints.
#[pyfunction]
#[pyo3(signature = (
    record=None, period=None, alpha=None, mu=None, mu_static=None, damping=None,
    damping_basis=None, scale=None, structure=None, yield_strength_ratio=None,
    post_yield_ratio=None, aspect=None, integrator=None, rk4_substeps=None, building=None,
    stacks=None, floor_spectra=None, history=false, config=None
))]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    record: Option<&Bound<'py, PyAny>>,
    period: Option<&Bound<'py, PyAny>>,
    alpha: Option<&Bound<'py, PyAny>>,
    mu: Option<&Bound<'py, PyAny>>,
    mu_static: Option<&Bound<'py, PyAny>>,
    damping: Option<&Bound<'py, PyAny>>,
    damping_basis: Option<&Bound<'py, PyAny>>,
    scale: Option<&Bound<'py, PyAny>>,
    structure: Option<&Bound<'py, PyAny>>,
    yield_strength_ratio: Option<&Bound<'py, PyAny>>,
    post_yield_ratio: Option<&Bound<'py, PyAny>>,
    aspect: Option<&Bound<'py, PyAny>>,
    integrator: Option<&Bound<'py, PyAny>>,
    rk4_substeps: Option<&Bound<'py, PyAny>>,
    building: Option<&Bound<'py, PyAny>>,
    stacks: Option<&Bound<'py, PyAny>>,
    floor_spectra: Option<&Bound<'py, PyAny>>,
    history: bool,
    config: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    // In the order of CASE_KEYS.
    let values = [
        period,
        alpha,
        mu,
        mu_static,
        damping,
        damping_basis,
        scale,
        structure,
        yield_strength_ratio,
        post_yield_ratio,
        aspect,
        integrator,
        rk4_substeps,
        building,
        stacks,
        floor_spectra,
    ];
    let given = CASE_KEYS.into_iter().zip(values);
    let mut mapping = case_mapping(given.filter_map(|(k, v)| Some((k, v?))))?;
    let samples = match record
        .filter(|r| !r.is_none())
        .map(record_arg)
        .transpose()?
    {
        Some(RecordArg::Path(p)) => {
            mapping.insert("record".into(), p.to_string_lossy().into_owned().into());
            None
        }
        Some(RecordArg::Samples(r)) => Some(r),
        None => None,
    };
    let input = |e: SimulationError| to_py_err(&e);
    let given = Settings::from_mapping(mapping).map_err(input)?;
    let settings = given
        .over(base_settings(config.as_deref())?)
        .map_err(input)?;
    let sim = match samples {
        Some(r) => settings.resolve_with(r),
        None => settings.resolve(),
    }
    .map_err(input)?;
    // The run on a thread of its own, so that Ctrl-C stops it within a few samples' work.
    let cancel = Arc::new(AtomicBool::new(false));
    let watch = Cancel(Arc::clone(&cancel));
    let waited = interrupt::on_worker(
        py,
        cancel,
        || true,
        move || {
            let accel = sim.accel_mps2();
            let warnings = sim.warnings(&accel);
            let layout = |h: &History| match &sim.model {
                Model::OneStorey { .. } => HistoryLayout::one_storey(h.interfaces),
                Model::Building { building, .. } => history_layout(building),
            };
            sim.run_watched(&accel, history, &watch).map(|(o, h)| {
                let h = h.map(|h| (layout(&h), h));
                (o, h, warnings)
            })
        },
    )?;
    let (outcome, hist, warnings) = match (waited.result, waited.interrupt) {
        (Ok(Err(e)), Some(_)) if matches!(e, SimulationError::Simulation { .. }) => {
            return Err(input(e));
        }
        (_, Some(interrupt)) => return Err(interrupt),
        (Ok(r), None) => r.map_err(input)?,
        (Err(why), None) => return Err(errors::internal(&why)),
    };
    convert::warn(py, &warnings)?;
    let text = serde_json::to_string(&outcome).expect("a summary serialises");
    let dict = json_to_py(py, &text)?;
    if let Some((layout, h)) = hist {
        dict.set_item("history", history_dict(py, h, &layout)?)?;
    }
    Ok(dict)
}

/// The keywords of `simulate` that are a case's keys (`record`, `history` and `config` are not).
const CASE_KEYS: [&str; 16] = [
    "period",
    "alpha",
    "mu",
    "mu_static",
    "damping",
    "damping_basis",
    "scale",
    "structure",
    "yield_strength_ratio",
    "post_yield_ratio",
    "aspect",
    "integrator",
    "rk4_substeps",
    "building",
    "stacks",
    "floor_spectra",
];

/// A case's keywords (None values left out: the default applies) as the mapping of a case file.
fn case_mapping<'a, 'py: 'a>(
    keys: impl IntoIterator<Item = (&'a str, &'a Bound<'py, PyAny>)>,
) -> PyResult<serde_yaml::Mapping> {
    let mut mapping = serde_yaml::Mapping::new();
    for (key, value) in keys {
        if value.is_none() {
            continue;
        }
        if key == "rk4_substeps" {
            convert::whole(value, key, 1)?;
        }
        mapping.insert(key.into(), to_yaml_value(value, key)?);
    }
    Ok(mapping)
}

/// The case file `config` names (its keys under the call's), or no keys.
fn base_settings(config: Option<&std::path::Path>) -> PyResult<Settings> {
    match config {
        Some(path) => Settings::read(path).map_err(|e| to_py_err(&e)),
        None => Ok(Settings::default()),
    }
}

/// The time history as numpy arrays: rows in time, a column per body or interface.
fn history_dict<'py>(
    py: Python<'py>,
    h: History,
    layout: &HistoryLayout,
) -> PyResult<Bound<'py, PyDict>> {
    let rows = h.time_s.len();
    let d = PyDict::new(py);
    d.set_item("time_s", h.time_s.into_pyarray(py))?;
    d.set_item("ground_accel_mps2", h.ground_accel_mps2.into_pyarray(py))?;
    for (key, v) in [
        ("displacement_m", h.displacement_m),
        ("velocity_mps", h.velocity_mps),
        ("abs_accel_mps2", h.abs_accel_mps2),
    ] {
        d.set_item(key, v.into_pyarray(py).reshape([rows, h.bodies])?)?;
    }
    d.set_item(
        "contact",
        h.contact.into_pyarray(py).reshape([rows, h.interfaces])?,
    )?;
    d.set_item("bodies", PyList::new(py, &layout.bodies)?)?;
    d.set_item("interfaces", PyList::new(py, &layout.interfaces)?)?;
    Ok(d)
}

/// A record file as `(accel_g, dt_s)`.
#[pyfunction]
#[pyo3(signature = (path, units=None, dt=None))]
fn read_record<'py>(
    py: Python<'py>,
    path: PathBuf,
    units: Option<&str>,
    dt: Option<f64>,
) -> PyResult<Bound<'py, PyTuple>> {
    let units = units
        .map(|u| {
            u.parse::<Units>()
                .map_err(|e| PyValueError::new_err(format!("`units` {u}: {e}")))
        })
        .transpose()?;
    let opts = ReadOptions { units, dt_s: dt };
    let r = py
        .detach(|| read_record_with(&path, &opts))
        .map_err(|e| to_py_err(&e))?;
    PyTuple::new(
        py,
        [
            r.accel_g.into_pyarray(py).into_any(),
            r.dt_s.into_pyobject(py)?.into_any(),
        ],
    )
}

/// Periods as `parse_periods` reads them: a SPEC string, or numbers written back in shortest
/// round-trip form (so the same checks apply and the values are the given ones).
fn periods_arg(obj: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    match obj.extract::<String>() {
        Ok(s) => parse_periods(&s),
        Err(_) => periods_from_list(&convert::float_vec(obj, "periods")?),
    }
    .map_err(|e| to_py_err(&e))
}

/// Floats from a number or a sequence, and whether it was one number.
fn one_or_many(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<f64>, bool)> {
    match obj.extract::<f64>() {
        Ok(x) => Ok((vec![x], true)),
        Err(_) => Ok((convert::float_vec(obj, what)?, false)),
    }
}

/// Response spectra of one record (`slidestack spectrum --json`'s objects, numpy arrays for
/// the lists); constant-ductility spectra with `ductility`.
#[pyfunction]
#[pyo3(signature = (accel_g, dt, periods=None, damping=None, ductility=None, post_yield_ratio=None))]
fn spectrum<'py>(
    py: Python<'py>,
    accel_g: &Bound<'py, PyAny>,
    dt: f64,
    periods: Option<&Bound<'py, PyAny>>,
    damping: Option<&Bound<'py, PyAny>>,
    ductility: Option<&Bound<'py, PyAny>>,
    post_yield_ratio: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let rec = Record::from_samples(ARRAY_RECORD, dt, convert::float_vec(accel_g, "accel_g")?)
        .map_err(|e| to_py_err(&e))?;
    let periods = match periods {
        Some(p) => periods_arg(p)?,
        None => parse_periods(DEFAULT_PERIODS).map_err(|e| to_py_err(&e))?,
    };
    let (dampings, one_damping) = match damping {
        Some(d) => one_or_many(d, "damping")?,
        None => (vec![0.05], true),
    };
    let records = [rec];
    let text = match ductility {
        None => {
            if post_yield_ratio.is_some() {
                return Err(PyValueError::new_err(
                    "`post_yield_ratio` needs `ductility` (a constant-ductility spectrum)",
                ));
            }
            let s = py
                .detach(|| response_spectra(&records, &periods, &dampings))
                .map_err(|e| to_py_err(&e))?;
            serde_json::to_string(&s)
        }
        Some(mu) => {
            let (mus, _) = one_or_many(mu, "ductility")?;
            let r = post_yield_ratio.unwrap_or(0.0);
            let s = py
                .detach(|| ductility_spectra(&records, &periods, &dampings, &mus, r))
                .map_err(|e| to_py_err(&e))?;
            serde_json::to_string(&s)
        }
    }
    .expect("spectra serialise");
    let list = json_to_py(py, &text)?;
    let np = py.import("numpy")?;
    let out = PyList::empty(py);
    for item in list.try_iter()? {
        let item = item?.cast_into::<PyDict>()?;
        for (k, v) in item.clone().iter() {
            if v.is_instance_of::<PyList>() {
                item.set_item(k, np.call_method1("asarray", (v, "float64"))?)?;
            }
        }
        out.append(item)?;
    }
    if one_damping && ductility.is_none() {
        return out.get_item(0);
    }
    Ok(out.into_any())
}

/// Elastic response spectra of many records at many damping ratios (`slidestack spectrum
/// --json`'s objects, record-major: every damping ratio of the first record, then the next);
/// slidestack.spectra labels them as an xarray Dataset.
#[pyfunction]
#[pyo3(signature = (records, periods=None, damping=None))]
fn spectra<'py>(
    py: Python<'py>,
    records: &Bound<'py, PyList>,
    periods: Option<&Bound<'py, PyAny>>,
    damping: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let records = batch::records(py, Some(records))?;
    let periods = match periods {
        Some(p) => periods_arg(p)?,
        None => parse_periods(DEFAULT_PERIODS).map_err(|e| to_py_err(&e))?,
    };
    let dampings = match damping {
        Some(d) => one_or_many(d, "damping")?.0,
        None => vec![0.05],
    };
    let s = py
        .detach(|| response_spectra(&records, &periods, &dampings))
        .map_err(|e| to_py_err(&e))?;
    json_to_py(py, &serde_json::to_string(&s).expect("spectra serialise"))
}

/// One record matched to a target spectrum (SPEC string as `slidestack match --target`).
#[pyfunction]
#[pyo3(name = "match", signature = (record, target, settings=None))]
fn match_<'py>(
    py: Python<'py>,
    record: &Bound<'py, PyAny>,
    target: &str,
    settings: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let rec = record_of(py, record)?;
    let spec: TargetSpectrum = target
        .parse()
        .map_err(|e| PyValueError::new_err(format!("invalid `target` `{target}`: {e}")))?;
    let settings: MatchSettings = match settings.filter(|s| !s.is_none()) {
        Some(s) => serde_yaml::from_value(to_yaml_value(s, "settings")?)
            .map_err(|e| PyValueError::new_err(format!("invalid `settings`: {e}")))?,
        None => MatchSettings::default(),
    };
    let (lo, hi) = settings.check_range_s;
    spec.check_covers(lo, hi).map_err(|e| {
        PyValueError::new_err(format!("the target does not cover the matching range: {e}"))
    })?;
    let m = py
        .detach(|| match_record(&rec.accel_g, rec.dt_s, &spec, &settings))
        .map_err(|e| to_py_err(&e))?;
    let d = PyDict::new(py);
    d.set_item("record", &rec.name)?;
    d.set_item("accel_g", m.accel_g.into_pyarray(py))?;
    d.set_item("dt_s", rec.dt_s)?;
    let report = serde_json::to_string(&m.report).expect("a report serialises");
    d.set_item("report", json_to_py(py, &report)?)?;
    Ok(d)
}

/// `T_new` of one structure from a finished study: the dict `slidestack design --json` prints.
#[pyfunction]
#[pyo3(signature = (study, zone, period, alpha, mu, extrapolate=false, storeys=None, floor=None))]
#[allow(clippy::too_many_arguments)]
fn design<'py>(
    py: Python<'py>,
    study: PathBuf,
    zone: String,
    period: f64,
    alpha: &Bound<'py, PyAny>,
    mu: &Bound<'py, PyAny>,
    extrapolate: bool,
    storeys: Option<&Bound<'py, PyAny>>,
    floor: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let storeys = (storeys.filter(|s| !s.is_none()))
        .map(|s| convert::whole(s, "storeys", 1))
        .transpose()?;
    let floor = match floor.filter(|f| !f.is_none()) {
        None => None,
        Some(f) => {
            let text = f.str()?.to_string();
            Some(
                (text.parse::<StackFloor>())
                    .map_err(|why| PyValueError::new_err(format!("floor: {why}")))?,
            )
        }
    };
    let building = match (storeys, floor) {
        (Some(n), Some(f)) => Some((n, f)),
        (None, None) => None,
        _ => {
            return Err(PyValueError::new_err(
                "a building study's design needs both `storeys` and `floor`",
            ));
        }
    };
    let q = Query {
        zone,
        period_s: period,
        alpha: convert::float_vec(alpha, "alpha")?,
        mu: convert::float_vec(mu, "mu")?,
        extrapolate,
        building,
    };
    let a = py
        .detach(|| design_query(&study, &q))
        .map_err(|e| to_py_err(&e))?;
    json_to_py(
        py,
        &serde_json::to_string(&a).expect("an answer serialises"),
    )
}

/// A building case's FEMA P-58 demands under `records` (paths or `(accel_g, dt)` pairs) in
/// pelicun's demand-sample format, written to `out` (CSV): what `slidestack export edp` writes.
/// Returns `out`.
#[pyfunction]
#[pyo3(signature = (config, records, out, attached=false))]
fn export_edp<'py>(
    py: Python<'py>,
    config: PathBuf,
    records: &Bound<'py, PyList>,
    out: PathBuf,
    attached: bool,
) -> PyResult<PathBuf> {
    let records = batch::records(py, Some(records))?;
    let stacks = if attached {
        Stacks::Attached
    } else {
        Stacks::Sliding
    };
    py.detach(|| edp::export(&config, &records, stacks, &out))
        .map_err(|e| to_py_err(&e))?;
    Ok(out)
}

/// One case of a finished building study (`study`, its output directory), its FEMA P-58
/// demands under its zone's motions written to `out` (CSV): what `slidestack export edp --study`
/// writes. Returns `out`.
#[pyfunction]
#[pyo3(signature = (study, zone, storeys, stack_floor, period, alpha, mu, out, attached=false))]
#[allow(clippy::too_many_arguments)]
fn export_frame_edp<'py>(
    py: Python<'py>,
    study: PathBuf,
    zone: String,
    storeys: &Bound<'py, PyAny>,
    stack_floor: &Bound<'py, PyAny>,
    period: f64,
    alpha: &Bound<'py, PyAny>,
    mu: &Bound<'py, PyAny>,
    out: PathBuf,
    attached: bool,
) -> PyResult<PathBuf> {
    let text = stack_floor.str()?.to_string();
    let q = FrameQuery {
        zone,
        storeys: convert::whole(storeys, "storeys", 1)?,
        stack_floor: (text.parse::<StackFloor>())
            .map_err(|why| PyValueError::new_err(format!("stack_floor: {why}")))?,
        period_s: period,
        alpha: convert::float_vec(alpha, "alpha")?,
        mu: convert::float_vec(mu, "mu")?,
    };
    let stacks = if attached {
        Stacks::Attached
    } else {
        Stacks::Sliding
    };
    py.detach(|| export_frame(&study, &q, stacks, &out))
        .map_err(|e| to_py_err(&e))?;
    Ok(out)
}

/// Panics on purpose: the tests check that a panic reaches Python as an exception (the cargo
/// profile `python` unwinds) and leaves the interpreter running.
#[pyfunction]
fn _panic() {
    panic!("a deliberate panic (slidestack._native._panic)");
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", slidestack::VERSION)?;
    m.add("Error", m.py().get_type::<errors::Error>())?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(read_record, m)?)?;
    m.add_function(wrap_pyfunction!(spectrum, m)?)?;
    m.add_function(wrap_pyfunction!(spectra, m)?)?;
    m.add_function(wrap_pyfunction!(match_, m)?)?;
    m.add_function(wrap_pyfunction!(design, m)?)?;
    m.add_function(wrap_pyfunction!(export_edp, m)?)?;
    m.add_function(wrap_pyfunction!(export_frame_edp, m)?)?;
    m.add_function(wrap_pyfunction!(batch::simulate_many, m)?)?;
    m.add_function(wrap_pyfunction!(_panic, m)?)?;
    pipeline::register(m)?;
    Ok(())
}
