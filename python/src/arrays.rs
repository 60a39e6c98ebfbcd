//! numpy arrays in and out, in libigl's conventions: vertices `V` as `(n, 3) float64`,
//! triangles `F` as `(m, 3)` integers, sequences of frames as `(k, n, 3) float64`.
//!
//! Any strided array is read through a view (no copy on the Python side); `float32` vertices
//! and any integer dtype for faces (signed or unsigned, 8 to 64 bits) are accepted and
//! converted. Everything else is a `MeshError` naming the argument, its dtype or shape, and
//! the offending row.

use crate::errors::{new_err, Kind};
use morphkit::mesh::Point;
use numpy::ndarray::{Array2, Array3, ArrayView2};
use numpy::{
    IntoPyArray, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyString;

fn describe(obj: &Bound<'_, PyAny>) -> String {
    match obj.cast::<PyUntypedArray>() {
        Ok(a) => format!("an array of dtype {} and shape {:?}", a.dtype(), a.shape()),
        Err(_) => format!(
            "a {}",
            obj.get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_else(|_| "value".into())
        ),
    }
}

fn rows_of(name: &str, view: ArrayView2<'_, f64>) -> PyResult<Vec<Point>> {
    if view.ncols() != 3 {
        return Err(new_err(
            Kind::Mesh,
            format!("{name}: expected shape (n, 3), got {:?}", view.shape()),
        ));
    }
    let mut out = Vec::with_capacity(view.nrows());
    for (i, r) in view.outer_iter().enumerate() {
        let p = [r[0], r[1], r[2]];
        if let Some(k) = p.iter().position(|x| !x.is_finite()) {
            return Err(new_err(
                Kind::Mesh,
                format!(
                    "{name}: row {i} has a non-finite coordinate {} ({})",
                    k, p[k]
                ),
            ));
        }
        out.push(p);
    }
    Ok(out)
}

/// Reads an `(n, 3)` float array (`float64`, or `float32` converted) into points, refusing
/// NaN and infinity.
pub fn points(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<Point>> {
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, f64>>() {
        return rows_of(name, a.as_array());
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, f32>>() {
        let v = a.as_array().mapv(f64::from);
        return rows_of(name, v.view());
    }
    Err(new_err(
        Kind::Mesh,
        format!(
            "{name}: expected a float64 array of shape (n, 3), got {}",
            describe(obj)
        ),
    ))
}

fn check_faces<T: Copy + Into<i128>>(
    name: &str,
    view: ArrayView2<'_, T>,
    num_vertices: Option<usize>,
) -> PyResult<Vec<[u32; 3]>> {
    if view.ncols() != 3 {
        return Err(new_err(
            Kind::Mesh,
            format!(
                "{name}: expected shape (m, 3) (triangles), got {:?}",
                view.shape()
            ),
        ));
    }
    let limit = num_vertices.map_or(i128::from(u32::MAX) + 1, |n| n as i128);
    let mut out = Vec::with_capacity(view.nrows());
    for (f, r) in view.outer_iter().enumerate() {
        let mut t = [0u32; 3];
        for k in 0..3 {
            let i: i128 = r[k].into();
            if i < 0 {
                return Err(new_err(
                    Kind::Mesh,
                    format!("{name}: face {f} has a negative vertex index {i}"),
                ));
            }
            if i >= limit {
                return Err(new_err(
                    Kind::Mesh,
                    format!(
                        "{name}: face {f} has vertex index {i} out of range{}",
                        num_vertices.map_or(String::new(), |n| format!(" (0..{n})"))
                    ),
                ));
            }
            t[k] = u32::try_from(i).expect("checked below the limit");
        }
        out.push(t);
    }
    Ok(out)
}

/// `check_faces` of `obj` read as an `(m, 3)` array of each integer dtype in turn.
macro_rules! faces_of {
    ($name:expr, $obj:expr, $n:expr, $($t:ty),+) => {
        $(
            if let Ok(a) = $obj.extract::<PyReadonlyArray2<'_, $t>>() {
                return check_faces($name, a.as_array(), $n);
            }
        )+
    };
}

/// Reads an `(m, 3)` array of vertex indices of any integer dtype (signed or unsigned, 8 to 64
/// bits), each in `0..num_vertices`; negative indices are refused.
pub fn faces(
    name: &str,
    obj: &Bound<'_, PyAny>,
    num_vertices: Option<usize>,
) -> PyResult<Vec<[u32; 3]>> {
    faces_of!(
        name,
        obj,
        num_vertices,
        i64,
        i32,
        u32,
        u64,
        i16,
        u16,
        i8,
        u8
    );
    Err(new_err(
        Kind::Mesh,
        format!(
            "{name}: expected an integer array of shape (m, 3), got {}",
            describe(obj)
        ),
    ))
}

/// Reads one number per element (a 1-D array of a real dtype, or a sequence of numbers)
/// of length `len` (`what` says what the entries are for, in messages), each finite and
/// `≥ 0`; the first bad entry is named by its index.
pub fn non_negative(
    name: &str,
    obj: &Bound<'_, PyAny>,
    len: usize,
    what: &str,
) -> PyResult<Vec<f64>> {
    let v: Vec<f64> = if let Ok(a) = obj.extract::<PyReadonlyArray1<'_, f64>>() {
        a.as_array().to_vec()
    } else if let Ok(a) = obj.extract::<PyReadonlyArray1<'_, f32>>() {
        a.as_array().iter().map(|&x| f64::from(x)).collect()
    } else {
        let not_numbers = || {
            new_err(
                Kind::Mesh,
                format!(
                    "{name}: expected a float64 array of shape ({len},), {what}, got {}",
                    describe(obj)
                ),
            )
        };
        if obj.is_instance_of::<PyString>() {
            return Err(not_numbers());
        }
        obj.extract().map_err(|_| not_numbers())?
    };
    if v.len() != len {
        return Err(new_err(
            Kind::Mesh,
            format!("{name}: has {} entries, expected {len} ({what})", v.len()),
        ));
    }
    if let Some(i) = v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
        return Err(new_err(
            Kind::Mesh,
            format!("{name}[{i}] = {} is not a finite number ≥ 0", v[i]),
        ));
    }
    Ok(v)
}

/// Reads frames: a `(k, n, 3)` float array or a sequence of `(n, 3)` arrays. Each frame must
/// have `num_vertices` rows when given.
pub fn frames(
    name: &str,
    obj: &Bound<'_, PyAny>,
    num_vertices: Option<usize>,
) -> PyResult<Vec<Vec<Point>>> {
    let out: Vec<Vec<Point>> = if let Ok(a) = obj.extract::<PyReadonlyArray3<'_, f64>>() {
        let v = a.as_array();
        let mut out = Vec::with_capacity(v.shape()[0]);
        for (i, f) in v.outer_iter().enumerate() {
            out.push(rows_of(&format!("{name}[{i}]"), f)?);
        }
        out
    } else {
        // Other dtypes and sequences of (n, 3) arrays, frame by frame.
        if let Ok(a) = obj.cast::<PyUntypedArray>() {
            if a.ndim() != 3 {
                return Err(new_err(
                    Kind::Mesh,
                    format!("{name}: expected shape (k, n, 3), got {:?}", a.shape()),
                ));
            }
        }
        let iter = obj.try_iter().map_err(|_| {
            new_err(
                Kind::Mesh,
                format!(
                    "{name}: expected a (k, n, 3) array or a sequence of (n, 3) arrays, got {}",
                    describe(obj)
                ),
            )
        })?;
        let mut out = Vec::new();
        for (i, item) in iter.enumerate() {
            out.push(points(&format!("{name}[{i}]"), &item?)?);
        }
        out
    };
    if let Some(n) = num_vertices {
        if let Some(i) = out.iter().position(|f| f.len() != n) {
            return Err(new_err(
                Kind::Mesh,
                format!("{name}[{i}]: has {} vertices, expected {n}", out[i].len()),
            ));
        }
    }
    Ok(out)
}

/// Points as a new `(n, 3) float64` array.
pub fn to_array<'py>(py: Python<'py>, p: &[Point]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flatten().copied().collect();
    Array2::from_shape_vec((p.len(), 3), flat)
        .expect("n × 3 elements")
        .into_pyarray(py)
}

/// Frames as a new `(k, n, 3) float64` array (all frames have `n` vertices).
pub fn to_array3<'py>(
    py: Python<'py>,
    frames: &[Vec<Point>],
    n: usize,
) -> Bound<'py, PyArray3<f64>> {
    let flat: Vec<f64> = frames.iter().flatten().flatten().copied().collect();
    Array3::from_shape_vec((frames.len(), n, 3), flat)
        .expect("k × n × 3 elements")
        .into_pyarray(py)
}

/// Triangles as a new `(m, 3) int64` array.
pub fn faces_to_array<'py>(py: Python<'py>, t: &[[u32; 3]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = t.iter().flatten().map(|&i| i64::from(i)).collect();
    Array2::from_shape_vec((t.len(), 3), flat)
        .expect("m × 3 elements")
        .into_pyarray(py)
}
