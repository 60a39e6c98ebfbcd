//! `BakedRig`: physical correctives baked into ordinary blendshapes (the library's
//! `morphkit::bake`, issue 56), returned by `PhysicalBlend.bake`. `evaluate` is exactly what a
//! DCC or viewer computes from the baked shapes, so a bake is testable without one.

use crate::arrays::to_array;
use crate::blend_args::weights as weights_of;
use numpy::PyArray2;
use pyo3::exceptions::PyIndexError;
use pyo3::prelude::*;

/// In-between and combination shapes of a rig (see `PhysicalBlend.bake`).
#[pyclass(name = "BakedRig", module = "morphkit", frozen)]
pub struct PyBakedRig {
    pub(crate) inner: morphkit::bake::BakedRig,
}

impl PyBakedRig {
    fn delta_weights(&self, weights: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let n = self.inner.targets.len();
        let w = weights_of(weights, false, n)?;
        let c = w
            .coefficients(n + 1)
            .map_err(|e| crate::errors::new_err(crate::errors::Kind::Blend, e.to_string()))?;
        Ok(c[1..].to_vec())
    }
}

#[pymethods]
impl PyBakedRig {
    /// The baked shape at delta weights `weights` (one per target, or a number for one
    /// target) as a new `(n, 3)` array: base + each target's in-betweens interpolated
    /// piecewise linearly at its weight + each combination shape at
    /// :meth:`combination_weights`. What a client playing the baked shapes computes.
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        weights: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let w = self.delta_weights(weights)?;
        Ok(to_array(py, &self.inner.evaluate(&w)))
    }

    /// The weight of every stored shape at `weights` (each target's in-betweens in order,
    /// then each combination's): the mapping from slider weights to shape weights a client
    /// computes; `evaluate(w)` is `base` plus these weights times the shapes.
    fn shape_weights(&self, weights: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let w = self.delta_weights(weights)?;
        Ok(self.inner.shape_weights(&w))
    }

    /// The weight of every combination shape at `weights` (in :attr:`combinations`' order):
    /// `4 wi wj ((wi + wj) / sum of the positive weights) ** damping`, 0 unless both are
    /// positive.
    fn combination_weights(&self, weights: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let w = self.delta_weights(weights)?;
        Ok(self
            .inner
            .combinations
            .iter()
            .map(|c| self.inner.combination_weight(c, &w))
            .collect())
    }

    /// The `(n, 3)` displacement of target `target`'s in-between `k` (at
    /// `inbetween_weights[target][k]`; the last is the target itself at 1).
    fn inbetween<'py>(
        &self,
        py: Python<'py>,
        target: usize,
        k: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = self
            .inner
            .targets
            .get(target)
            .and_then(|t| t.deltas.get(k))
            .ok_or_else(|| {
                PyIndexError::new_err(format!("no in-between {k} of target {target}"))
            })?;
        Ok(to_array(py, d))
    }

    /// The `(n, 3)` displacement of combination `k`'s in-between `level` (at combination
    /// weight `combination_levels[k][level]`).
    #[pyo3(signature = (k, level=0))]
    fn combination<'py>(
        &self,
        py: Python<'py>,
        k: usize,
        level: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = self
            .inner
            .combinations
            .get(k)
            .and_then(|c| c.shape.deltas.get(level))
            .ok_or_else(|| {
                PyIndexError::new_err(format!("no in-between {level} of combination {k}"))
            })?;
        Ok(to_array(py, d))
    }

    /// Per combination, the combination weights of its in-betweens (`4 s²` for the pair
    /// sample at `(s, s)`).
    #[getter]
    fn combination_levels(&self) -> Vec<Vec<f64>> {
        self.inner
            .combinations
            .iter()
            .map(|c| c.shape.weights.clone())
            .collect()
    }

    /// The base, `(n, 3)`.
    #[getter]
    fn base<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        to_array(py, &self.inner.base)
    }

    /// Per target, the weights of its in-betweens (increasing, the last 1).
    #[getter]
    fn inbetween_weights(&self) -> Vec<Vec<f64>> {
        self.inner
            .targets
            .iter()
            .map(|t| t.weights.clone())
            .collect()
    }

    /// The target pairs `(i, j)` with a combination shape.
    #[getter]
    fn combinations(&self) -> Vec<(usize, usize)> {
        self.inner.combinations.iter().map(|c| c.targets).collect()
    }

    /// The exponent of the combination weights' damping.
    #[getter]
    fn damping(&self) -> f64 {
        self.inner.damping
    }

    /// Shapes a client holds: every in-between (the targets included) and combination.
    #[getter]
    fn num_shapes(&self) -> usize {
        self.inner.num_shapes()
    }
}
