//! Library statistics (serde-serializable structs) as Python dicts.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::Value;

fn value<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_u64(), n.as_i64()) {
            (Some(u), _) => u.into_pyobject(py)?.into_any(),
            (None, Some(i)) => i.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => {
            let list = PyList::empty(py);
            for x in a {
                list.append(value(py, x)?)?;
            }
            list.into_any()
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, value(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// `s` as a dict of plain Python values (ints, floats, bools, lists, dicts).
pub fn to_dict<'py, T: serde::Serialize>(py: Python<'py>, s: &T) -> PyResult<Bound<'py, PyAny>> {
    let v = serde_json::to_value(s)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    value(py, &v)
}
