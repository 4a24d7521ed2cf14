//! Python values to and from the library's: arguments into the YAML values a case file or study
//! file would hold (so they are checked by the same deserialisers), JSON text into Python
//! objects, warnings into Python's `warnings`.

use pyo3::exceptions::{PyRuntimeWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// `obj` as the YAML value of key `key`: None, bool, int, float, str, os.PathLike, mappings,
/// sequences, numpy arrays and scalars (through `tolist`).
pub fn to_yaml_value(obj: &Bound<'_, PyAny>, key: &str) -> PyResult<serde_yaml::Value> {
    use serde_yaml::Value;
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if obj.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(obj.extract()?));
    }
    if obj.is_instance_of::<PyInt>() {
        return match obj.extract::<i64>() {
            Ok(i) => Ok(Value::Number(i.into())),
            Err(_) => Err(PyValueError::new_err(format!(
                "`{key}`: {obj} does not fit in 64 bits"
            ))),
        };
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(Value::Number(obj.extract::<f64>()?.into()));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(Value::String(obj.extract()?));
    }
    if obj.hasattr("__fspath__")? {
        let path: std::path::PathBuf = obj.extract()?;
        return Ok(Value::String(path.to_string_lossy().into_owned()));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut m = serde_yaml::Mapping::new();
        for (k, v) in d.iter() {
            let name: String = k.extract().map_err(|_| {
                PyValueError::new_err(format!("`{key}`: mapping keys must be str, got {k:?}"))
            })?;
            let inner = format!("{key}.{name}");
            m.insert(Value::String(name), to_yaml_value(&v, &inner)?);
        }
        return Ok(Value::Mapping(m));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let items = obj
            .try_iter()?
            .enumerate()
            .map(|(i, v)| to_yaml_value(&v?, &format!("{key}[{i}]")))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(Value::Sequence(items));
    }
    if obj.hasattr("tolist")? {
        return to_yaml_value(&obj.call_method0("tolist")?, key);
    }
    Err(PyValueError::new_err(format!(
        "`{key}`: cannot use a {} here",
        obj.get_type().name()?
    )))
}

/// A whole-number keyword argument `key` (a Python or numpy integer, not a bool) of at least
/// `min`; anything else a `ValueError` naming `key` (pyo3's own conversion raises
/// `OverflowError` for a negative number and `TypeError` for a float).
pub fn whole(obj: &Bound<'_, PyAny>, key: &str, min: usize) -> PyResult<usize> {
    let bad = || {
        PyValueError::new_err(format!(
            "`{key}` must be a whole number ≥ {min}, got {}",
            obj.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        ))
    };
    if obj.is_instance_of::<PyBool>() {
        return Err(bad());
    }
    let index = obj
        .py()
        .import("operator")?
        .call_method1("index", (obj,))
        .map_err(|_| bad())?;
    index
        .extract::<usize>()
        .ok()
        .filter(|&n| n >= min)
        .ok_or_else(bad)
}

/// A 1-D float64 sequence (a number list, tuple or numpy array).
pub fn float_vec(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let np = obj.py().import("numpy")?;
    let arr = np
        .call_method1("asarray", (obj, "float64"))
        .map_err(|e| PyValueError::new_err(format!("`{what}` must be numbers: {e}")))?;
    let ndim: usize = arr.getattr("ndim")?.extract()?;
    if ndim != 1 {
        return Err(PyValueError::new_err(format!(
            "`{what}` must be one-dimensional, got {ndim} dimensions"
        )));
    }
    let arr = arr.cast_into::<numpy::PyArray1<f64>>()?;
    Ok(numpy::PyArrayMethods::to_vec(&arr)?)
}

/// The Python object of JSON `text` (Python's own parser: floats round-trip exactly).
pub fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// Each message as a `RuntimeWarning` (the CLI prints them as `warning:` lines).
pub fn warn(py: Python<'_>, messages: &[String]) -> PyResult<()> {
    if messages.is_empty() {
        return Ok(());
    }
    let warnings = py.import("warnings")?;
    let category = py.get_type::<PyRuntimeWarning>();
    for m in messages {
        warnings.call_method1("warn", (m, &category, 2))?;
    }
    Ok(())
}
