//! Integer arguments, read in one way everywhere: counts and options (`threads`,
//! `max_newton_iterations`, …) and element indices (`sources`, `fixed`, pull vertices, …).
//!
//! Each is read from the Python object as a signed integer (anything with `__index__`: `int`,
//! numpy integer scalars), so that a negative or a huge value reaches the range check instead
//! of pyo3's bare `OverflowError`. A value that is not an integer is a `TypeError` naming the
//! argument; an integer outside its range is the module's error (`kind`, a `ValueError`)
//! naming the argument, the value and the allowed range.

use crate::errors::{new_err, Kind};
use pyo3::exceptions::{PyOverflowError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyString;

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "value".into())
}

/// The integer value of `obj`: `Ok(Ok(v))`, `Ok(Err(text))` for an integer outside `i64`
/// (`text`, its decimal digits, is then quoted in messages), or a `TypeError` naming `name`.
fn int_of(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Result<i64, String>> {
    match obj.extract::<i64>() {
        Ok(v) => Ok(Ok(v)),
        Err(e) if e.is_instance_of::<PyOverflowError>(obj.py()) => Ok(Err(obj
            .str()
            .map(|s| s.to_string())
            .unwrap_or_else(|_| "a huge integer".into()))),
        Err(_) => Err(PyTypeError::new_err(format!(
            "{name}: expected an integer, got {}",
            type_name(obj)
        ))),
    }
}

/// A count or option: an integer `≥ min` (and `≤ max` when given). Without `max`, an integer
/// too large for 64 bits counts as `i64::MAX` (Python's integers are unbounded; "more than
/// can be used" is what it means).
pub fn int(
    name: &str,
    obj: &Bound<'_, PyAny>,
    kind: Kind,
    min: i64,
    max: Option<i64>,
) -> PyResult<i64> {
    let range = match max {
        Some(max) => format!("an integer in [{min}, {max}]"),
        None => format!("an integer ≥ {min}"),
    };
    match int_of(name, obj)? {
        Ok(v) if v >= min && max.is_none_or(|m| v <= m) => Ok(v),
        Ok(v) => Err(new_err(kind, format!("{name}: must be {range}, got {v}"))),
        Err(text) if max.is_none() && !text.starts_with('-') => Ok(i64::MAX),
        Err(text) => Err(new_err(
            kind,
            format!("{name}: must be {range}, got {text}"),
        )),
    }
}

/// A non-negative count or option as a `usize` (`≥ min`).
pub fn count(name: &str, obj: &Bound<'_, PyAny>, kind: Kind, min: usize) -> PyResult<usize> {
    let v = int(
        name,
        obj,
        kind,
        i64::try_from(min).unwrap_or(i64::MAX),
        None,
    )?;
    Ok(usize::try_from(v).expect("checked non-negative"))
}

/// [`count`] of an optional argument (`None` stays `None`).
pub fn opt_count(
    name: &str,
    obj: Option<&Bound<'_, PyAny>>,
    kind: Kind,
    min: usize,
) -> PyResult<Option<usize>> {
    obj.filter(|o| !o.is_none())
        .map(|o| count(name, o, kind, min))
        .transpose()
}

/// What an index points into, for the messages: `"vertex"` / `"vertices"`, or
/// `"triangle"` / `"triangles"`, of a mesh with `len` of them.
#[derive(Clone, Copy, Debug)]
pub struct Elements {
    pub one: &'static str,
    pub many: &'static str,
    pub len: usize,
}

impl Elements {
    pub fn vertices(len: usize) -> Self {
        Self {
            one: "vertex",
            many: "vertices",
            len,
        }
    }

    pub fn triangles(len: usize) -> Self {
        Self {
            one: "triangle",
            many: "triangles",
            len,
        }
    }
}

/// One index into `of`, named `label` in messages (`"sources[0]"`): an integer in
/// `0..of.len`.
pub fn index(label: &str, obj: &Bound<'_, PyAny>, kind: Kind, of: Elements) -> PyResult<u32> {
    let bad = |text: &str| {
        new_err(
            kind,
            format!(
                "{label} = {text} is not a {} index (mesh has {} {})",
                of.one, of.len, of.many
            ),
        )
    };
    match int_of(label, obj)? {
        Ok(v) => usize::try_from(v)
            .ok()
            .filter(|&i| i < of.len)
            .and_then(|i| u32::try_from(i).ok())
            .ok_or_else(|| bad(&v.to_string())),
        Err(text) => Err(bad(&text)),
    }
}

/// A sequence (a list, a tuple, a 1-D integer array) of indices into `of`, the `k`th named
/// `name[k]` in messages.
pub fn indices(name: &str, obj: &Bound<'_, PyAny>, kind: Kind, of: Elements) -> PyResult<Vec<u32>> {
    let not_a_sequence = || {
        PyTypeError::new_err(format!(
            "{name}: expected a sequence of {} indices, got {}",
            of.one,
            type_name(obj)
        ))
    };
    if obj.is_instance_of::<PyString>() {
        return Err(not_a_sequence());
    }
    let iter = obj.try_iter().map_err(|_| not_a_sequence())?;
    iter.enumerate()
        .map(|(k, item)| index(&format!("{name}[{k}]"), &item?, kind, of))
        .collect()
}
