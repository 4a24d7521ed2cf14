//! `simulate_many`'s compiled half: many cases (each a dict of `simulate`'s keywords) under one
//! or more records, run by [`slidestack::one_case::batch::Batch`] on the library's threads with
//! the GIL released. The answer is `simulate`'s dicts, `[case][record]`, each parsed from the
//! same JSON (so bit for bit `simulate`'s numbers); python/slidestack/_batch.py labels them.

use crate::convert::{json_to_py, warn};
use crate::errors::{internal, to_py_err};
use crate::interrupt::on_worker;
use crate::{CASE_KEYS, Cancel, base_settings, case_mapping, record_of};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use slidestack::ground_motion::{Record, builtin};
use slidestack::one_case::Settings;
use slidestack::one_case::batch::{Batch, BatchError};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// Each case (a dict) as settings over `config`'s, checked before any run: a bad one is a
/// `ValueError` naming its index and key.
fn case_settings(cases: &Bound<'_, PyList>, base: &Settings) -> PyResult<Vec<Settings>> {
    let at = |case: usize, e: PyErr| {
        let py = cases.py();
        PyValueError::new_err(format!("case {case}: {}", e.value(py)))
    };
    let mut all = Vec::with_capacity(cases.len());
    for (case, item) in cases.iter().enumerate() {
        let dict = item.cast::<PyDict>().map_err(|_| {
            PyValueError::new_err(format!(
                "case {case}: a case is a dict of simulate's keywords, got a {}",
                item.get_type()
                    .name()
                    .map_or_else(|_| "?".into(), |n| n.to_string())
            ))
        })?;
        let mut keys = Vec::with_capacity(dict.len());
        for (k, v) in dict.iter() {
            let key: String = k
                .extract()
                .map_err(|_| PyValueError::new_err(format!("case {case}: key {k} is not a str")))?;
            if !CASE_KEYS.contains(&key.as_str()) {
                let why = match key.as_str() {
                    "record" | "config" => format!("`{key}` is given once for all the cases"),
                    "history" => "`history` is not kept by simulate_many".to_string(),
                    _ => format!(
                        "unknown key `{key}`; a case's keys: {}",
                        CASE_KEYS.join(", ")
                    ),
                };
                return Err(PyValueError::new_err(format!("case {case}: {why}")));
            }
            keys.push((key, v));
        }
        let mapping =
            case_mapping(keys.iter().map(|(k, v)| (k.as_str(), v))).map_err(|e| at(case, e))?;
        let settings = Settings::from_mapping(mapping)
            .and_then(|s| s.over(base.clone()))
            .map_err(|e| {
                to_py_err(&BatchError::Case {
                    case,
                    source: Box::new(e),
                })
            })?;
        all.push(settings);
    }
    Ok(all)
}

/// The records (paths or `(accel_g, dt)` pairs), each read once; `None`: the built-in record.
pub fn records(py: Python<'_>, given: Option<&Bound<'_, PyList>>) -> PyResult<Vec<Record>> {
    let Some(given) = given else {
        return Ok(vec![builtin()]);
    };
    given.iter().map(|r| record_of(py, &r)).collect()
}

/// Every case under every record: `simulate`'s dicts, a list per case of one per record.
#[pyfunction]
#[pyo3(signature = (cases, records=None, threads=None, config=None))]
pub fn simulate_many<'py>(
    py: Python<'py>,
    cases: &Bound<'py, PyList>,
    records: Option<&Bound<'py, PyList>>,
    threads: Option<&Bound<'py, PyAny>>,
    config: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let threads = (threads.filter(|t| !t.is_none()))
        .map(|t| crate::convert::whole(t, "threads", 1))
        .transpose()?;
    let base = base_settings(config.as_deref())?;
    let settings = case_settings(cases, &base)?;
    let records = self::records(py, records)?;
    let batch = py
        .detach(|| Batch::new(settings, records))
        .map_err(|e| to_py_err(&e))?;
    let cancel = Arc::new(AtomicBool::new(false));
    let watch = Cancel(Arc::clone(&cancel));
    let waited = on_worker(py, cancel, || true, move || batch.run(threads, &watch))?;
    let ran = match (waited.result, waited.interrupt) {
        (Ok(Err(e @ BatchError::Stopped { .. })), Some(_)) => return Err(to_py_err(&e)),
        (_, Some(interrupt)) => return Err(interrupt),
        (Ok(r), None) => r.map_err(|e| to_py_err(&e))?,
        (Err(why), None) => return Err(internal(&why)),
    };
    warn(py, &ran.warnings)?;
    let text = serde_json::to_string(&ran.outcomes).expect("outcomes serialise");
    json_to_py(py, &text)
}
