//! Deformation transfer (Sumner & Popović 2004; Wang & Lee 2008 Sec. 4): `Correspondence`
//! (markers → triangle correspondence by least-squares meshes) and `Transfer` (prefactored,
//! then one cheap solve per frame with the GIL released).

use crate::args::{self, Elements};
use crate::arrays::{self, to_array, to_array3};
use crate::dict::to_dict;
use crate::errors::{new_err, IntoPyResult, Kind};
use crate::mesh::from_arrays;
use crate::transfer_options::{
    combine_of, correspondence_options, transfer_dict, TransferKeywords,
};
use crate::weld::{mesh_weld, unweld, welded_target_corr};
use morphkit::mesh::{TriMesh, Weld};
use morphkit::transfer::rig::{RigOptions, RigTransfer};
use morphkit::transfer::{
    correspond, match_confidence, AnimationTransfer, Correspondence, Markers, TransferOptions,
};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A target-triangle → source-triangles correspondence, reusable across transfers and saved
/// as the same JSON file the CLI's `morphkit correspond` writes.
///
/// >>> c = morphkit.Correspondence.from_markers(VS, FS, VT, FT, [[12, 40], [503, 388], ...])
/// >>> c.save("horse-camel.corr.json")
#[pyclass(name = "Correspondence", module = "morphkit", frozen)]
pub struct PyCorrespondence {
    pub inner: Correspondence,
    /// The warped meshes (only after `from_markers`).
    warped: Option<(Vec<morphkit::mesh::Point>, Vec<morphkit::mesh::Point>)>,
}

/// Marker pairs: the path of a markers JSON file, or `(source, target)` vertex pairs, the
/// source vertex an index into `source`, the target vertex into `target`.
fn markers_of(obj: &Bound<'_, PyAny>, source: Elements, target: Elements) -> PyResult<Markers> {
    if let Ok(path) = obj.extract::<PathBuf>() {
        if !obj.is_instance_of::<pyo3::types::PyList>() {
            return Markers::read(&path).py(Kind::File);
        }
    }
    let pairs: Vec<[Bound<'_, PyAny>; 2]> = obj.extract().map_err(|_| {
        new_err(
            Kind::Transfer,
            "markers: expected a markers JSON path or a sequence of (source, target) vertex pairs",
        )
    })?;
    let pairs = pairs
        .iter()
        .enumerate()
        .map(|(k, [s, t])| {
            Ok([
                args::index(&format!("markers[{k}][0]"), s, Kind::Transfer, source)?,
                args::index(&format!("markers[{k}][1]"), t, Kind::Transfer, target)?,
            ])
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(Markers::new(pairs))
}

#[pymethods]
impl PyCorrespondence {
    /// Computes the correspondence of source `(VS, FS)` and target `(VT, FT)` from marker
    /// pairs (a sequence of `(source_vertex, target_vertex)`, 0-based, or the path of a
    /// `{"pairs": [[s, t], …]}` JSON file), by least-squares-mesh warps (Wang & Lee Sec. 4.1),
    /// then refined by closest points (Sumner & Popović 2004, Sec. 5) unless `refine=False`
    /// (`morphkit correspond --no-refine`). `refine=None` (default) is the library's default,
    /// as the CLI's (`morphkit.transfer_defaults()["refine"]`).
    ///
    /// `weld` (default True): vertices split at seams and hard edges are one vertex while the
    /// meshes are warped (as `morphkit correspond`); the correspondence and `warped` are of
    /// the meshes as given.
    #[staticmethod]
    #[pyo3(signature = (vs, fs, vt, ft, markers, *, refine=None, weld=true))]
    #[allow(clippy::too_many_arguments)]
    fn from_markers(
        py: Python<'_>,
        vs: &Bound<'_, PyAny>,
        fs: &Bound<'_, PyAny>,
        vt: &Bound<'_, PyAny>,
        ft: &Bound<'_, PyAny>,
        markers: &Bound<'_, PyAny>,
        refine: Option<bool>,
        weld: bool,
    ) -> PyResult<Self> {
        let source = from_arrays("source", vs, fs)?;
        let target = from_arrays("target", vt, ft)?;
        let markers = markers_of(
            markers,
            Elements::vertices(source.num_vertices()),
            Elements::vertices(target.num_vertices()),
        )?;
        let (sw, tw) = (mesh_weld(&source, weld), mesh_weld(&target, weld));
        let given = markers.clone();
        let markers = Markers::new(
            markers
                .pairs
                .iter()
                .map(|&[a, b]| {
                    [
                        sw.as_ref().map_or(a, |w| w.to_welded()[a as usize]),
                        tw.as_ref().map_or(b, |w| w.to_welded()[b as usize]),
                    ]
                })
                .collect(),
        );
        let (source, target) = (
            sw.as_ref().map_or(source.clone(), |w| w.mesh(&source)),
            tw.as_ref().map_or(target.clone(), |w| w.mesh(&target)),
        );
        let opts = correspondence_options(refine);
        let mut r = py
            .detach(|| correspond(&source, &target, &markers, &opts))
            .py(Kind::Transfer)?;
        if sw.is_some() || tw.is_some() {
            // Back to the meshes as given: counts, markers as given, warped vertices scattered.
            fn back(w: &Option<Weld>) -> Option<(&[u32], usize)> {
                w.as_ref().map(|w| (w.representative(), w.num_input()))
            }
            r.correspondence = r.correspondence.renumbered(back(&sw), back(&tw));
            if !r.correspondence.identity {
                r.correspondence.markers = given.pairs;
            }
            r.warped_source = unweld(sw.as_ref(), r.warped_source);
            r.warped_target = unweld(tw.as_ref(), r.warped_target);
        }
        Ok(Self {
            inner: r.correspondence,
            warped: Some((r.warped_source, r.warped_target)),
        })
    }

    /// The identity correspondence of a mesh `(V, F)` with itself.
    #[staticmethod]
    fn identity(v: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>) -> PyResult<Self> {
        let mesh = from_arrays("mesh", v, f)?;
        Ok(Self {
            inner: Correspondence::identity(&mesh),
            warped: None,
        })
    }

    /// Reads a correspondence JSON file (from `morphkit correspond` or :meth:`save`).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let text = py
            .detach(|| std::fs::read_to_string(&path))
            .map_err(|e| new_err(Kind::File, format!("{}: {e}", path.display())))?;
        let inner = Correspondence::from_json(&text).map_err(|e| {
            new_err(
                Kind::File,
                format!("{}: {}", path.display(), crate::errors::chain(&e)),
            )
        })?;
        Ok(Self {
            inner,
            warped: None,
        })
    }

    /// Writes the correspondence as JSON, atomically.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let json = self.inner.to_json();
        py.detach(|| morphkit::io::write_atomic(&path, json.as_bytes()))
            .py(Kind::File)
    }

    /// Source triangles matched to each target triangle, as a list of lists (nearest first).
    #[getter]
    fn matches(&self) -> Vec<Vec<u32>> {
        (0..self.inner.target_triangles)
            .map(|t| self.inner.matches_of(t).to_vec())
            .collect()
    }

    /// Per marker: source and target vertex, residuals, and the relative residual, as dicts.
    #[getter]
    fn marker_residuals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_dict(py, &self.inner.marker_residuals)
    }

    /// Target triangles whose match fails the normal test (places that need more markers).
    #[getter]
    fn normal_violations(&self) -> Vec<u32> {
        self.inner.normal_violations.clone()
    }

    /// Per target triangle, the confidence of its matches in the reference meshes
    /// (`transfer::match_confidence`, as `morphkit correspond` reports it): 1 where the
    /// matches face as the triangle does, towards 0 where they face away (below 0.5: about 65°
    /// or more; places that need markers). `(n_target_triangles,)` float64.
    ///
    /// `combine` as `Transfer`'s (`None`: the library's default).
    #[pyo3(signature = (vs, fs, vt, ft, combine = None))]
    fn match_confidence<'py>(
        &self,
        py: Python<'py>,
        vs: &Bound<'py, PyAny>,
        fs: &Bound<'py, PyAny>,
        vt: &Bound<'py, PyAny>,
        ft: &Bound<'py, PyAny>,
        combine: Option<&str>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let combine = combine_of(combine)?;
        let c = &self.inner;
        let (v, _, _) = build(py, [vs, fs, vt, ft], |s, t| {
            match_confidence(s, t, c, combine)
        })?;
        Ok(numpy::ndarray::Array1::from(v).into_pyarray(py))
    }

    /// Whether the closest-point refinement made this correspondence.
    #[getter]
    fn refined(&self) -> bool {
        !self.inner.refinement.is_empty()
    }

    /// The warped source and target vertices `(WS, WT)` of :meth:`from_markers`, or `None`.
    #[getter]
    #[allow(clippy::type_complexity)]
    fn warped<'py>(
        &self,
        py: Python<'py>,
    ) -> Option<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
        self.warped
            .as_ref()
            .map(|(s, t)| (to_array(py, s), to_array(py, t)))
    }

    fn __repr__(&self) -> String {
        format!(
            "Correspondence(source_triangles={}, target_triangles={}, identity={})",
            self.inner.source_triangles, self.inner.target_triangles, self.inner.identity
        )
    }
}

/// A deformation transfer from a source reference `(VS, FS)` onto a target `(VT, FT)`, set up
/// once (the target's normal equations are factored), then :meth:`transfer` per frame.
///
/// Every keyword left at `None` is the library's default, the same as `morphkit transfer`'s
/// without flags (`morphkit.transfer_defaults()`; issue 55): the local-stretch frame,
/// area weights, the fold guard, inverse-distance weights and the following translation.
/// `combine`: `"inverse-distance"`, `"mean"` or `"nearest"`, how several matched source
/// gradients combine (`--combine`). `translation`: `"follow"` (the target's marker centroid
/// follows the source's, scaled by the size ratio) or `"fixed"` (the paper's convention,
/// `--fixed-vertex`). `local_stretch=False` carries matched gradients unchanged in world
/// coordinates (`--world-frame`); `area_weighted=False` weights triangles uniformly
/// (`--uniform-weights`); `fold_guard=False` turns the crease guard of the local-stretch
/// frame off (`--no-fold-guard`). `local_stretch=False, area_weighted=False` with an
/// unrefined correspondence is the configuration before issue 40.
///
/// >>> t = morphkit.Transfer(VS, FS, VT, FT, c)
/// >>> frames_t = t.transfer_many(frames_s)
#[pyclass(name = "Transfer", module = "morphkit", frozen)]
pub struct PyTransfer {
    inner: AnimationTransfer,
    /// The options it was built with.
    options: TransferOptions,
    source_vertices: usize,
    target_vertices: usize,
    /// The target's weld (`None`: nothing welded).
    weld: Option<Weld>,
}

/// [`build`] with the target welded (`weld`): `make` gets the source, the welded target and
/// the correspondence for it; returns what it built, the two input vertex counts and the weld.
#[allow(clippy::type_complexity)]
fn build_welded<T: Send, E: std::error::Error + Send>(
    py: Python<'_>,
    [vs, fs, vt, ft]: [&Bound<'_, PyAny>; 4],
    corr: &Correspondence,
    weld: bool,
    make: impl FnOnce(&TriMesh, &TriMesh, &Correspondence) -> Result<T, E> + Send,
) -> PyResult<(T, usize, usize, Option<Weld>)> {
    let source = from_arrays("source", vs, fs)?;
    let target = from_arrays("target", vt, ft)?;
    let w = mesh_weld(&target, weld);
    let inner = match &w {
        None => py.detach(|| make(&source, &target, corr)),
        Some(w) => {
            let (t, c) = (w.mesh(&target), welded_target_corr(corr, w));
            py.detach(|| make(&source, &t, &c))
        }
    }
    .py(Kind::Transfer)?;
    Ok((inner, source.num_vertices(), target.num_vertices(), w))
}

/// Reads the source and target meshes `[V_s, F_s, V_t, F_t]` and runs the set-up `make` on
/// them with the GIL released; returns what it built and the two vertex counts.
fn build<T: Send, E: std::error::Error + Send>(
    py: Python<'_>,
    [vs, fs, vt, ft]: [&Bound<'_, PyAny>; 4],
    make: impl FnOnce(&TriMesh, &TriMesh) -> Result<T, E> + Send,
) -> PyResult<(T, usize, usize)> {
    let source = from_arrays("source", vs, fs)?;
    let target = from_arrays("target", vt, ft)?;
    let inner = py.detach(|| make(&source, &target)).py(Kind::Transfer)?;
    Ok((inner, source.num_vertices(), target.num_vertices()))
}

#[pymethods]
impl PyTransfer {
    #[new]
    #[pyo3(signature = (vs, fs, vt, ft, correspondence, *, combine=None, translation=None,
        local_stretch=None, area_weighted=None, fold_guard=None, weld=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        vs: &Bound<'_, PyAny>,
        fs: &Bound<'_, PyAny>,
        vt: &Bound<'_, PyAny>,
        ft: &Bound<'_, PyAny>,
        correspondence: &PyCorrespondence,
        combine: Option<&str>,
        translation: Option<&str>,
        local_stretch: Option<bool>,
        area_weighted: Option<bool>,
        fold_guard: Option<bool>,
        weld: bool,
    ) -> PyResult<Self> {
        let opts = TransferKeywords {
            combine,
            translation,
            local_stretch,
            area_weighted,
            fold_guard,
        }
        .options()?;
        let (inner, source_vertices, target_vertices, weld) = build_welded(
            py,
            [vs, fs, vt, ft],
            &correspondence.inner,
            weld,
            |s, t, c| AnimationTransfer::new(s, t, c, &opts),
        )?;
        Ok(Self {
            inner,
            options: opts,
            source_vertices,
            target_vertices,
            weld,
        })
    }

    /// The options in use, as the keyword values that ask for them (the keys of
    /// `morphkit.transfer_defaults()` but `refine`).
    #[getter]
    fn options<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        transfer_dict(py, &self.options)
    }

    /// One source frame `(n_s, 3)` (same connectivity as the source reference) onto the
    /// target: a new `(n_t, 3)` array.
    fn transfer<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let frame = arrays::points("frame", frame)?;
        if frame.len() != self.source_vertices {
            return Err(new_err(
                Kind::Mesh,
                format!(
                    "frame: has {} vertices, the source has {}",
                    frame.len(),
                    self.source_vertices
                ),
            ));
        }
        let (inner, w) = (&self.inner, self.weld.as_ref());
        one(py, &frame, |f| {
            inner.transfer_frame(f).map(|x| unweld(w, x))
        })
    }

    /// Every frame of `frames` (`(k, n_s, 3)` or a list) onto the target: `(k, n_t, 3)`.
    fn transfer_many<'py>(
        &self,
        py: Python<'py>,
        frames: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let (inner, w) = (&self.inner, self.weld.as_ref());
        many(
            py,
            ("frames", frames),
            (self.source_vertices, self.target_vertices),
            |_, f| inner.transfer_frame(f).map(|x| unweld(w, x)),
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "Transfer(source_vertices={}, target_vertices={})",
            self.source_vertices, self.target_vertices
        )
    }
}

/// A blendshape rig moved onto a new character (`morphkit rig`): the source neutral
/// `(VS, FS)` is aligned to the target `(VT, FT)` by the best similarity through the
/// correspondence's markers, the target is factored once, and each expression (positions over
/// the source neutral's connectivity) becomes a target shape with no root motion: the target's
/// neutral stays where it is, per connected part.
///
/// >>> rig = morphkit.RigTransfer(VN, FN, VH, FH, corr)
/// >>> shapes = rig.transfer_many([V_jawOpen, V_smile])  # (2, n_t, 3), absolute positions
#[pyclass(name = "RigTransfer", module = "morphkit", frozen)]
pub struct PyRigTransfer {
    inner: RigTransfer,
    source_vertices: usize,
    target_vertices: usize,
    /// The target's weld (`None`: nothing welded).
    weld: Option<Weld>,
}

#[pymethods]
impl PyRigTransfer {
    #[new]
    #[pyo3(signature = (vs, fs, vt, ft, correspondence, *, combine=None, weld=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        vs: &Bound<'_, PyAny>,
        fs: &Bound<'_, PyAny>,
        vt: &Bound<'_, PyAny>,
        ft: &Bound<'_, PyAny>,
        correspondence: &PyCorrespondence,
        combine: Option<&str>,
        weld: bool,
    ) -> PyResult<Self> {
        // The rig's own defaults, as `morphkit rig`'s.
        let mut opts = RigOptions::default();
        opts.transfer.combine = combine_of(combine)?;
        let (inner, source_vertices, target_vertices, weld) = build_welded(
            py,
            [vs, fs, vt, ft],
            &correspondence.inner,
            weld,
            |s, t, c| RigTransfer::new(s, t, c, &opts),
        )?;
        Ok(Self {
            inner,
            source_vertices,
            target_vertices,
            weld,
        })
    }

    /// One expression `(n_s, 3)` onto the target: a new `(n_t, 3)` array.
    fn transfer<'py>(
        &self,
        py: Python<'py>,
        shape: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let shape = arrays::points("shape", shape)?;
        let (inner, w) = (&self.inner, self.weld.as_ref());
        one(py, &shape, |s| {
            inner.transfer_shape(0, s).map(|(x, _)| unweld(w, x))
        })
    }

    /// Every expression of `shapes` (`(k, n_s, 3)` or a list) onto the target: `(k, n_t, 3)`.
    fn transfer_many<'py>(
        &self,
        py: Python<'py>,
        shapes: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let (inner, w) = (&self.inner, self.weld.as_ref());
        many(
            py,
            ("shapes", shapes),
            (self.source_vertices, self.target_vertices),
            |i, s| inner.transfer_shape(i, s).map(|(x, _)| unweld(w, x)),
        )
    }
}

type Points = Vec<morphkit::mesh::Point>;

/// One transfer with the GIL released: a new `(n_t, 3)` array.
fn one<'py>(
    py: Python<'py>,
    input: &[morphkit::mesh::Point],
    f: impl Fn(&[morphkit::mesh::Point]) -> Result<Points, morphkit::transfer::TransferError>
        + Send
        + Sync,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let x = py.detach(|| f(input)).py(Kind::Transfer)?;
    Ok(to_array(py, &x))
}

/// Every frame of `frames` (`(k, n_s, 3)` or a list, named `name` in errors) through `f`,
/// with the GIL released: a new `(k, n_t, 3)` array. Signals are checked between frames, so
/// that Ctrl-C (`KeyboardInterrupt`) interrupts a long batch after the frame being solved.
fn many<'py>(
    py: Python<'py>,
    (name, frames): (&str, &Bound<'py, PyAny>),
    (n_s, n_t): (usize, usize),
    f: impl Fn(usize, &[morphkit::mesh::Point]) -> Result<Points, morphkit::transfer::TransferError>
        + Send
        + Sync,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let frames = arrays::frames(name, frames, Some(n_s))?;
    let mut out = Vec::with_capacity(frames.len());
    for (i, x) in frames.iter().enumerate() {
        py.check_signals()?;
        out.push(py.detach(|| f(i, x)).py(Kind::Transfer)?);
    }
    Ok(to_array3(py, &out, n_t))
}
