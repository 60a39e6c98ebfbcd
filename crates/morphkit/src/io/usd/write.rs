//! Writing `.usda` layers: baked animation and `UsdSkel` blend shapes (layouts in the
//! [module documentation](super)).

use super::text::{f32_text, identifier, int_array, quoted, vec3_array};
use super::{UpAxis, UsdOptions};
use crate::io::{write_atomic, IoError};
use crate::mesh::{bounding_box, Point, Topology, TriMesh};
use std::fmt::Write;
use std::path::Path;

/// Checks that every position is finite and representable as `f32`.
fn check_points(path: &Path, what: &str, p: &[Point], nv: usize) -> Result<(), IoError> {
    if p.len() != nv {
        return Err(IoError::content(
            path,
            format!("{what} has {} points, the mesh has {nv} vertices", p.len()),
        ));
    }
    crate::io::atomic::check_fits_f32(path, what, p)
}

/// The layer header: `#usda 1.0` and the stage metadata.
fn header(out: &mut String, opts: &UsdOptions, prim: &str, frames: Option<(usize, f64)>) {
    out.push_str("#usda 1.0\n(\n");
    if let Some(data) = &opts.custom_data {
        let _ = writeln!(
            out,
            "    customLayerData = {{\n        string morphkit = {}\n    }}",
            quoted(&data.to_string())
        );
    }
    let _ = writeln!(out, "    defaultPrim = {}", quoted(prim));
    let _ = writeln!(
        out,
        "    doc = {}",
        quoted(concat!("Written by morphkit ", env!("CARGO_PKG_VERSION")))
    );
    if let Some((n, fps)) = frames {
        let _ = writeln!(out, "    endTimeCode = {}", n.saturating_sub(1));
        let _ = writeln!(out, "    framesPerSecond = {fps}");
    }
    let _ = writeln!(out, "    metersPerUnit = {}", opts.meters_per_unit);
    if let Some((_, fps)) = frames {
        let _ = writeln!(out, "    startTimeCode = 0");
        let _ = writeln!(out, "    timeCodesPerSecond = {fps}");
    }
    let axis = match opts.up_axis {
        UpAxis::Y => "Y",
        UpAxis::Z => "Z",
    };
    let _ = writeln!(out, "    upAxis = \"{axis}\"\n)\n");
}

/// `faceVertexCounts` and `faceVertexIndices` (original polygons when the mesh kept them),
/// `doubleSided` for open meshes and `subdivisionScheme`.
fn topology(out: &mut String, mesh: &TriMesh, indent: &str) {
    let open = !Topology::new(mesh.num_vertices(), &mesh.triangles)
        .boundary_edges()
        .is_empty();
    if open {
        let _ = writeln!(out, "{indent}uniform bool doubleSided = 1");
    }
    let (counts, indices): (Vec<u32>, Vec<u32>) = match &mesh.polygons {
        Some(p) => (
            p.iter().map(|f| f.len() as u32).collect(),
            p.indices.clone(),
        ),
        None => (
            vec![3; mesh.num_triangles()],
            mesh.triangles.iter().flatten().copied().collect(),
        ),
    };
    let _ = write!(out, "{indent}int[] faceVertexCounts = ");
    int_array(out, counts);
    let _ = write!(out, "\n{indent}int[] faceVertexIndices = ");
    int_array(out, indices);
    out.push('\n');
}

fn extent(out: &mut String, p: &[Point]) {
    let (lo, hi) = bounding_box(p);
    vec3_array(out, &[lo, hi]);
}

fn validate_fps(path: &Path, fps: f64) -> Result<(), IoError> {
    if fps.is_finite() && fps > 0.0 {
        Ok(())
    } else {
        Err(IoError::content(
            path,
            format!("frame rate {fps} is not positive"),
        ))
    }
}

/// Writes `frames` (absolute positions over `mesh`'s connectivity, at least one) as a baked
/// animation at `fps` frames per second, atomically (layout in the [module
/// documentation](super)). One frame gives a static mesh without time samples.
///
/// Errors: no frames, a frame with another vertex count, coordinates that overflow `f32`, a
/// frame rate that is not positive, and the errors of [`write_atomic`].
pub fn write_usd_animation(
    path: &Path,
    mesh: &TriMesh,
    frames: &[Vec<Point>],
    fps: f64,
    opts: &UsdOptions,
) -> Result<(), IoError> {
    validate_fps(path, fps)?;
    let Some(first) = frames.first() else {
        return Err(IoError::content(path, "no frames to write"));
    };
    let nv = mesh.num_vertices();
    for (k, f) in frames.iter().enumerate() {
        check_points(path, &format!("frame {k}"), f, nv)?;
    }
    let prim = identifier(&opts.name);
    let animated = frames.len() > 1;
    let mut out = String::with_capacity(40 * nv * (frames.len() + 1));
    header(
        &mut out,
        opts,
        &prim,
        animated.then_some((frames.len(), fps)),
    );
    let _ = writeln!(
        out,
        "def Xform {} (\n    kind = \"component\"\n)\n{{\n    def Mesh \"mesh\"\n    {{",
        quoted(&prim)
    );
    let ind = "        ";
    let _ = write!(out, "{ind}float3[] extent = ");
    extent(&mut out, first);
    out.push('\n');
    if animated {
        let _ = writeln!(out, "{ind}float3[] extent.timeSamples = {{");
        for (k, f) in frames.iter().enumerate() {
            let _ = write!(out, "{ind}    {k}: ");
            extent(&mut out, f);
            out.push_str(",\n");
        }
        let _ = writeln!(out, "{ind}}}");
    }
    topology(&mut out, mesh, ind);
    let _ = write!(out, "{ind}point3f[] points = ");
    vec3_array(&mut out, first);
    out.push('\n');
    if animated {
        let _ = writeln!(out, "{ind}point3f[] points.timeSamples = {{");
        for (k, f) in frames.iter().enumerate() {
            let _ = write!(out, "{ind}    {k}: ");
            vec3_array(&mut out, f);
            out.push_str(",\n");
        }
        let _ = writeln!(out, "{ind}}}");
    }
    let _ = writeln!(
        out,
        "{ind}uniform token subdivisionScheme = \"none\"\n    }}\n}}"
    );
    write_atomic(path, out.as_bytes())
}

/// Writes a `UsdSkel` rig to `path`: the base mesh bound to one `BlendShape` per shape (`#V`
/// absolute positions in `shapes`, stored as offsets of the points that move, as `f32`),
/// named by `names`, all weights 0, atomically. Prim names are the names made valid USD
/// identifiers (made unique with a suffix); `skel:blendShapes` keeps the names as given.
///
/// Errors: as many names as shapes, unique names, shapes with another vertex count,
/// coordinates that overflow `f32`, and the errors of [`write_atomic`].
pub fn write_usd_blendshapes(
    path: &Path,
    base: &TriMesh,
    shapes: &[Vec<Point>],
    names: &[String],
    opts: &UsdOptions,
) -> Result<(), IoError> {
    if names.len() != shapes.len() {
        return Err(IoError::content(
            path,
            format!("{} names for {} blend shapes", names.len(), shapes.len()),
        ));
    }
    let nv = base.num_vertices();
    for (s, p) in shapes.iter().enumerate() {
        check_points(path, &format!("blend shape {s} ('{}')", names[s]), p, nv)?;
    }
    let deltas: Vec<Vec<Point>> = shapes
        .iter()
        .map(|p| {
            p.iter()
                .zip(&base.positions)
                .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
                .collect()
        })
        .collect();
    let shapes: Vec<UsdBlendShape> = names
        .iter()
        .zip(&deltas)
        .map(|(name, offsets)| UsdBlendShape {
            name,
            offsets,
            inbetweens: Vec::new(),
        })
        .collect();
    write_usd_blendshape_rig(path, base, &shapes, opts)
}

/// One `UsdSkel` blend shape: its `#V` displacements at weight 1, and its in-between shapes
/// (`UsdSkelInbetweenShape`: `#V` displacements at weights strictly between 0 and 1, which
/// UsdSkel interpolates piecewise linearly with the shape itself at 1).
#[derive(Clone, Debug)]
pub struct UsdBlendShape<'a> {
    /// Its name in `skel:blendShapes`.
    pub name: &'a str,
    /// `#V` displacements at weight 1.
    pub offsets: &'a [Point],
    /// `(weight, #V displacements)`, weights increasing in `(0, 1)`.
    pub inbetweens: Vec<(f64, &'a [Point])>,
}

/// [`write_usd_blendshapes`] for shapes given as displacements with in-betweens: each
/// `BlendShape` stores the points that move in its shape or any of its in-betweens
/// (`pointIndices`), and every in-between as `inbetweens:wN` with its `weight`.
///
/// Errors: those of [`write_usd_blendshapes`], and in-between weights not increasing in
/// `(0, 1)`.
pub fn write_usd_blendshape_rig(
    path: &Path,
    base: &TriMesh,
    shapes: &[UsdBlendShape],
    opts: &UsdOptions,
) -> Result<(), IoError> {
    let names: Vec<String> = shapes.iter().map(|s| s.name.to_string()).collect();
    for (i, n) in names.iter().enumerate() {
        if names[..i].contains(n) {
            return Err(IoError::content(
                path,
                format!("blend shape {i}: the name '{n}' is used twice"),
            ));
        }
    }
    let nv = base.num_vertices();
    check_points(path, "the base", &base.positions, nv)?;
    for (s, shape) in shapes.iter().enumerate() {
        let what = format!("blend shape {s} ('{}')", names[s]);
        check_points(path, &what, shape.offsets, nv)?;
        let mut last = 0.0;
        for (w, d) in &shape.inbetweens {
            if !(*w > last && *w < 1.0) {
                return Err(IoError::content(
                    path,
                    format!("{what}: in-between weights must increase within (0, 1), not {w}"),
                ));
            }
            last = *w;
            check_points(path, &format!("{what}, in-between at {w}"), d, nv)?;
        }
    }
    let mut prims: Vec<String> = Vec::with_capacity(names.len());
    for n in &names {
        let id = identifier(n);
        let mut unique = id.clone();
        let mut k = 1;
        while prims.contains(&unique) || unique == "skel" {
            unique = format!("{id}_{k}");
            k += 1;
        }
        prims.push(unique);
    }
    let root = identifier(&opts.name);
    let tokens = |out: &mut String| {
        out.push('[');
        for (i, n) in names.iter().enumerate() {
            if i > 0 {
                out.push_str(", ");
            }
            out.push_str(&quoted(n));
        }
        out.push(']');
    };
    let mut out = String::new();
    header(&mut out, opts, &root, None);
    let _ = writeln!(
        out,
        "def SkelRoot {} (\n    kind = \"component\"\n)\n{{",
        quoted(&root)
    );
    let _ = writeln!(
        out,
        "    def Mesh \"mesh\" (\n        prepend apiSchemas = [\"SkelBindingAPI\"]\n    )\n    {{"
    );
    let ind = "        ";
    let _ = write!(out, "{ind}float3[] extent = ");
    extent(&mut out, &base.positions);
    out.push('\n');
    topology(&mut out, base, ind);
    let _ = write!(out, "{ind}point3f[] points = ");
    vec3_array(&mut out, &base.positions);
    let _ = write!(out, "\n{ind}uniform token[] skel:blendShapes = ");
    tokens(&mut out);
    let _ = write!(out, "\n{ind}rel skel:blendShapeTargets = [");
    for (i, p) in prims.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        let _ = write!(out, "</{root}/mesh/{p}>");
    }
    let _ = writeln!(out, "]\n{ind}rel skel:skeleton = </{root}/skel>");
    let _ = writeln!(out, "{ind}uniform token subdivisionScheme = \"none\"");
    for (s, shape) in shapes.iter().enumerate() {
        let b = &base.positions;
        let moves = |d: &[Point], v: usize| {
            (0..3).any(|k| ((b[v][k] + d[v][k]) as f32) != (b[v][k] as f32))
        };
        let moved: Vec<usize> = (0..nv)
            .filter(|&v| {
                moves(shape.offsets, v) || shape.inbetweens.iter().any(|(_, d)| moves(d, v))
            })
            .collect();
        let at = |d: &[Point]| -> Vec<Point> { moved.iter().map(|&v| d[v]).collect() };
        let _ = writeln!(out, "\n{ind}def BlendShape {}\n{ind}{{", quoted(&prims[s]));
        let _ = write!(out, "{ind}    uniform vector3f[] offsets = ");
        vec3_array(&mut out, &at(shape.offsets));
        let _ = write!(out, "\n{ind}    uniform int[] pointIndices = ");
        int_array(&mut out, moved.iter().map(|&v| v as u32));
        for (w, d) in &shape.inbetweens {
            let name = format!("w{}", format!("{w}").replace(['.', '-'], "_"));
            let _ = write!(out, "\n{ind}    uniform vector3f[] inbetweens:{name} = ");
            vec3_array(&mut out, &at(d));
            let _ = write!(out, " (\n{ind}        weight = ");
            f32_text(&mut out, *w);
            let _ = write!(out, "\n{ind}    )");
        }
        let _ = writeln!(out, "\n{ind}}}");
    }
    out.push_str("    }\n\n");
    let _ = writeln!(
        out,
        "    def Skeleton \"skel\" (\n        prepend apiSchemas = [\"SkelBindingAPI\"]\n    )\n    {{"
    );
    let _ = writeln!(out, "{ind}uniform token[] joints = []");
    let _ = writeln!(out, "{ind}rel skel:animationSource = </{root}/skel/anim>\n");
    let _ = writeln!(out, "{ind}def SkelAnimation \"anim\"\n{ind}{{");
    let _ = write!(out, "{ind}    uniform token[] blendShapes = ");
    tokens(&mut out);
    let _ = write!(out, "\n{ind}    float[] blendShapeWeights = [");
    for i in 0..names.len() {
        if i > 0 {
            out.push_str(", ");
        }
        f32_text(&mut out, 0.0);
    }
    let _ = writeln!(out, "]\n{ind}}}\n    }}\n}}");
    write_atomic(path, out.as_bytes())
}
