//! Animation synthesis (Wang & Lee 2008, Sec. 3.2 and 4): flexibility, partitions and
//! intelligent scribbling, Eq. 5 blend weights, heat-method geodesics, and whole recipes.

use crate::args::{self, Elements};
use crate::arrays::{self, faces_to_array, to_array3};
use crate::errors::{new_err, IntoPyResult, Kind};
use crate::mesh::from_arrays;
use morphkit::mesh::{Topology, TriMesh};
use morphkit::synth::{
    self as msynth, Flexibility, Partitions, RecipeFile, Scribble, WeightSolver, GAMMA, KAPPA,
};
use numpy::ndarray::Array1;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1};
use pyo3::prelude::*;
use std::path::PathBuf;

/// Per-triangle flexibility (Sec. 3.2, Eq. 1): the largest change of relative deformation
/// between adjacent triangles over `frames` `(k, n, 3)` of the reference `(V, F)`; a new
/// `(m,)` array, ≥ 0.
#[pyfunction]
pub fn flexibility<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    frames: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let mesh = from_arrays("reference", v, f)?;
    let frames = arrays::frames("frames", frames, Some(mesh.num_vertices()))?;
    let flex = py
        .detach(|| msynth::flexibility(&mesh, &frames))
        .py(Kind::Transfer)?;
    Ok(Array1::from(flex.values).into_pyarray(py))
}

/// Partitions of a target `(V, F)` by a per-triangle flexibility (Sec. 3.2.1): stiff regions
/// (flexibility below `gamma` × the largest, default 0.1) flood-filled into partitions, every
/// other triangle a flexible partition of its own. Refines scribbles and solves Eq. 5 weights.
#[pyclass(name = "Partitions", module = "morphkit", frozen)]
pub struct PyPartitions {
    inner: Partitions,
    mesh: TriMesh,
    topology: Topology,
}

fn mask_of(name: &str, obj: &Bound<'_, PyAny>, len: usize) -> PyResult<Vec<bool>> {
    let m: Vec<bool> = obj
        .extract::<PyReadonlyArray1<'_, bool>>()
        .map_or_else(
            |_| obj.extract::<Vec<bool>>(),
            |a| Ok(a.as_array().to_vec()),
        )
        .map_err(|_| {
            new_err(
                Kind::Mesh,
                format!("{name}: expected a boolean array of length {len}"),
            )
        })?;
    if m.len() != len {
        return Err(new_err(
            Kind::Mesh,
            format!("{name}: has {} entries, expected {len}", m.len()),
        ));
    }
    Ok(m)
}

#[pymethods]
impl PyPartitions {
    /// `flexibility`: one finite value ≥ 0 per triangle of `f` (as :func:`flexibility`
    /// returns); anything else is a :class:`MeshError` naming the first bad entry.
    #[new]
    #[pyo3(signature = (v, f, flexibility, *, gamma=GAMMA))]
    fn new(
        v: &Bound<'_, PyAny>,
        f: &Bound<'_, PyAny>,
        flexibility: &Bound<'_, PyAny>,
        gamma: f64,
    ) -> PyResult<Self> {
        let mesh = from_arrays("target", v, f)?;
        let values = arrays::non_negative(
            "flexibility",
            flexibility,
            mesh.num_triangles(),
            "one per triangle of F",
        )?;
        let topology = Topology::new(mesh.num_vertices(), &mesh.triangles);
        let flex = Flexibility { values };
        let inner = Partitions::new(&flex, &topology, gamma).py(Kind::Transfer)?;
        Ok(Self {
            inner,
            mesh,
            topology,
        })
    }

    /// Partition label of each triangle, `(m,) int64`.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let l: Vec<i64> = self.inner.labels().iter().map(|&x| i64::from(x)).collect();
        Array1::from(l).into_pyarray(py)
    }

    /// Whether each triangle is in a stiff partition, `(m,) bool`.
    #[getter]
    fn stiff<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        Array1::from(self.inner.stiff_mask()).into_pyarray(py)
    }

    /// Number of partitions (stiff and flexible).
    #[getter]
    fn num_partitions(&self) -> usize {
        self.inner.num_partitions()
    }

    /// Intelligent scribbling (Sec. 3.2.1): a stiff partition is selected when more than half
    /// of its triangles are scribbled. `triangles` or `vertices` (0-based ids; a vertex
    /// scribble covers the triangles whose three vertices are scribbled). Returns the selected
    /// triangles as an `(m,) bool` array.
    #[pyo3(signature = (*, triangles=None, vertices=None))]
    fn refine<'py>(
        &self,
        py: Python<'py>,
        triangles: Option<&Bound<'py, PyAny>>,
        vertices: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let (nv, nf) = (self.mesh.num_vertices(), self.mesh.num_triangles());
        let scribble = match (triangles, vertices) {
            (Some(t), None) => Scribble::Triangles(args::indices(
                "triangles",
                t,
                Kind::Transfer,
                Elements::triangles(nf),
            )?),
            (None, Some(v)) => Scribble::Vertices(args::indices(
                "vertices",
                v,
                Kind::Transfer,
                Elements::vertices(nv),
            )?),
            _ => {
                return Err(new_err(
                    Kind::Transfer,
                    "refine: give exactly one of triangles= or vertices=",
                ))
            }
        };
        let sel = msynth::refine_scribble(
            &scribble,
            &self.inner,
            self.mesh.num_vertices(),
            &self.mesh.triangles,
        )
        .py(Kind::Transfer)?;
        Ok(Array1::from(sel.triangles).into_pyarray(py))
    }

    /// Pose modification (Sec. 3.2.4): the partitions selected by the scribble `scribble` (an
    /// `(m,) bool` triangle mask, refined as in :meth:`refine`) turn by `angle` radians about
    /// `axis`, the flexible joints blend (Eq. 5 weights), the unselected stiff parts stay put.
    /// Returns the edited reference pose, a new `(n, 3)` array.
    fn edit_pose<'py>(
        &self,
        py: Python<'py>,
        scribble: &Bound<'py, PyAny>,
        axis: [f64; 3],
        angle: f64,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let mask = mask_of("scribble", scribble, self.mesh.num_triangles())?;
        let (mesh, parts) = (&self.mesh, &self.inner);
        let edit = py
            .detach(|| msynth::edit_pose(mesh, parts, &mask, axis, angle))
            .py(Kind::Transfer)?;
        Ok(crate::arrays::to_array(py, &edit.positions))
    }

    /// Eq. 5 blend weights of a selection (`(m,) bool`, e.g. from :meth:`refine`): 1 on the
    /// selected stiff partitions, 0 on the other stiff ones, harmonic in between (`kappa`,
    /// default 1e4, the constraint weight). A new `(m,)` array in [0, 1].
    #[pyo3(signature = (selection, *, kappa=KAPPA))]
    fn blend_weights<'py>(
        &self,
        py: Python<'py>,
        selection: &Bound<'py, PyAny>,
        kappa: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let nf = self.mesh.num_triangles();
        let selected = mask_of("selection", selection, nf)?;
        let stiff = self.inner.stiff_mask();
        let topo = &self.topology;
        let w = py
            .detach(|| WeightSolver::new(topo, &stiff, kappa)?.solve(&selected))
            .py(Kind::Transfer)?;
        Ok(Array1::from(w.values).into_pyarray(py))
    }
}

/// Heat-method geodesic distance (Crane et al. 2013) on `(V, F)` from the vertex ids
/// `sources`: a new `(n,)` array (infinity on components without a source).
#[pyfunction]
pub fn geodesic_distance<'py>(
    py: Python<'py>,
    v: &Bound<'py, PyAny>,
    f: &Bound<'py, PyAny>,
    sources: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let mesh = from_arrays("mesh", v, f)?;
    let sources = args::indices(
        "sources",
        sources,
        Kind::Transfer,
        Elements::vertices(mesh.num_vertices()),
    )?;
    let d = py
        .detach(|| msynth::geodesic_distance(&mesh, &sources))
        .py(Kind::Transfer)?;
    Ok(Array1::from(d).into_pyarray(py))
}

/// Runs a synthesis recipe (the TOML file `morphkit synth` reads) and returns
/// `(frames, F)`: the synthesized target frames `(k, n, 3)` and the target's triangles.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn synthesize<'py>(
    py: Python<'py>,
    recipe: PathBuf,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray2<i64>>)> {
    use crate::errors::chain;
    let (frames, target) = py
        .detach(|| {
            let built = RecipeFile::read(&recipe)
                .and_then(|rf| rf.build())
                .map_err(|e| (Kind::File, chain(&e)))?;
            // In the target's own layout (the synthesizer solves on the welded target).
            let frames = built
                .frames()
                .map(|r| r.map(|f| f.positions))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| (Kind::Transfer, chain(&e)))?;
            Ok::<_, (Kind, String)>((frames, built.target))
        })
        .map_err(|(kind, msg)| new_err(kind, msg))?;
    Ok((
        to_array3(py, &frames, target.num_vertices()),
        faces_to_array(py, &target.triangles),
    ))
}
