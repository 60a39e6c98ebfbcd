//! Library errors as Python exceptions (`morphkit/_errors.py` defines the classes).

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyType;
use std::error::Error;

/// Which exception class an error becomes.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// `MeshError`: arrays and meshes.
    Mesh,
    /// `FileError`: reading and writing files.
    File,
    /// `BlendError`: physical blends.
    Blend,
    /// `TransferError`: correspondences and transfers.
    Transfer,
}

impl Kind {
    fn class_name(self) -> &'static str {
        match self {
            Kind::Mesh => "MeshError",
            Kind::File => "FileError",
            Kind::Blend => "BlendError",
            Kind::Transfer => "TransferError",
        }
    }
}

/// The message of `e` followed by its causes, `": "`-separated (the CLI prints the same chain).
pub fn chain(e: &dyn Error) -> String {
    let mut msg = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !msg.contains(&text) {
            msg.push_str(": ");
            msg.push_str(&text);
        }
        cause = c.source();
    }
    msg
}

/// A Python exception of class `kind` with `message`.
pub fn new_err(kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    Python::attach(|py| {
        let class = py
            .import("morphkit._errors")
            .and_then(|m| m.getattr(kind.class_name()))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
        match class {
            Ok(class) => PyErr::from_type(class, message),
            Err(_) => PyValueError::new_err(message),
        }
    })
}

/// Converts library errors into Python exceptions of one class.
pub trait IntoPyResult<T> {
    /// `Err(e)` becomes an exception of class `kind` carrying `e`'s message chain.
    fn py(self, kind: Kind) -> PyResult<T>;
}

impl<T, E: Error> IntoPyResult<T> for Result<T, E> {
    fn py(self, kind: Kind) -> PyResult<T> {
        self.map_err(|e| new_err(kind, chain(&e)))
    }
}
