//! Quality measures on any `V, F`: the library's blend metrics (edge-length and area strain,
//! enclosed volume) and fold metrics, measured against a rest shape.

use crate::arrays;
use crate::dict::to_dict;
use crate::errors::{new_err, IntoPyResult, Kind};
use crate::mesh::from_arrays;
use morphkit::mesh::{ShapeSet, Topology};
use morphkit::springs::{blend_metrics, fold_metrics, Weights};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Measures a deformed shape `V` `(n, 3)` against its rest shape `V_rest` over the
/// connectivity `F`, and returns a dict:
///
/// - `edge_length_rms`, `edge_length_max`: RMS and max over edges of `(ℓ − ℓ_rest) / ℓ_rest`;
/// - `area_rms`: RMS over triangles of `A / A_rest − 1`;
/// - `volume`, `volume_ratio`: enclosed volume and `V / V_rest` (closed meshes; else `None`);
/// - `folds`: triangles whose normal turned more than 120° from the rest normal;
/// - `creases`: interior edges whose dihedral angle is more than 30° off the rest angle.
///
/// >>> morphkit.metrics(V_rest, V, F)["edge_length_rms"]
#[pyfunction]
pub fn metrics<'py>(
    py: Python<'py>,
    v_rest: &Bound<'py, PyAny>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let rest = from_arrays("rest", v_rest, f)?;
    let x = arrays::points("V", v)?;
    if x.len() != rest.num_vertices() {
        return Err(new_err(
            Kind::Mesh,
            format!(
                "V: has {} vertices, V_rest has {}",
                x.len(),
                rest.num_vertices()
            ),
        ));
    }
    let topo = Topology::new(rest.num_vertices(), &rest.triangles);
    let positions = rest.positions.clone();
    let shapes = ShapeSet::new(rest, vec![("rest".into(), positions)]).py(Kind::Mesh)?;
    let w = Weights::Delta(Vec::new());
    let (m, fm) = py
        .detach(|| {
            let m = blend_metrics(&shapes, &topo, &w, &x)?;
            let fm = fold_metrics(&shapes, &topo, &w, &x)?;
            Ok::<_, morphkit::springs::BlendError>((m, fm))
        })
        .py(Kind::Blend)?;
    let d = to_dict(py, &m)?.cast_into::<PyDict>()?;
    d.set_item("folds", fm.folds)?;
    d.set_item("creases", fm.creases)?;
    Ok(d)
}
