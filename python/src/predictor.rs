//! `Predictor`: a physical blend's predictor P(w) on its own, callable from any thread while
//! the blend solves.

use crate::arrays::to_array;
use crate::errors::{IntoPyResult, Kind};
use crate::weld::unweld;
use morphkit::mesh::Weld;
use morphkit::springs::SurfacePredictor;
use numpy::PyArray2;
use pyo3::prelude::*;
use std::sync::Arc;

/// The predictor P(w) of a physical blend, on its own: the rotation-aware interpolation of the
/// shapes that every solve starts from (exact at each shape's one-hot weights; fixed vertices
/// at their linear blend; no pulls, no obstacles). It costs one prefactored solve, so a UI can
/// show it while a slider moves and replace it by the equilibrium when that is ready. It
/// shares the blend's set-up and may be called from any thread, also while the blend solves.
///
/// >>> preview = blend.predictor()
/// >>> X = preview.predict([0.5])
#[pyclass(name = "Predictor", module = "morphkit", frozen)]
pub struct PyPredictor {
    inner: SurfacePredictor,
    targets: usize,
    /// The weld of the blend it predicts for (`None`: none).
    weld: Option<Arc<Weld>>,
}

impl PyPredictor {
    pub fn new(inner: SurfacePredictor, targets: usize) -> Self {
        Self {
            inner,
            targets,
            weld: None,
        }
    }

    /// Predictions scattered back through `weld` (that of the blend's welded rig).
    pub fn welded(mut self, weld: Option<Arc<Weld>>) -> Self {
        self.weld = weld;
        self
    }
}

#[pymethods]
impl PyPredictor {
    /// The predicted shape for `weights` (as in :meth:`PhysicalBlend.solve`) as a new `(n, 3)`
    /// array. The GIL is released.
    #[pyo3(signature = (weights, *, convex=false))]
    pub fn predict<'py>(
        &self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
        convex: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let w = crate::blend_args::weights(weights, convex, self.targets)?;
        let inner = &self.inner;
        let weld = self.weld.as_deref();
        let p = py
            .detach(|| inner.predict(&w).map(|p| unweld(weld, p)))
            .py(Kind::Blend)?;
        Ok(to_array(py, &p))
    }

    fn __repr__(&self) -> String {
        format!("Predictor(targets={})", self.targets)
    }
}
