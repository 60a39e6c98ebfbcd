//! `morphkit info`: counts, size, boundary, components and shared connectivity of meshes.

use crate::util::progress;
use morphkit::mesh::{Topology, Weld, WELD_TOLERANCE};
use morphkit::TriMesh;
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::PathBuf;

const EXAMPLES: &str = "\
Examples:
  morphkit info horse-reference.obj.gz
  morphkit info cat-run/*.obj.gz            # also says whether all share one connectivity
  morphkit info --json face.glb neutral.obj > info.json
  morphkit info --mesh Face character.glb   # the mesh named Face, when several have morph targets";

/// Arguments of `morphkit info`.
#[derive(clap::Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct InfoArgs {
    /// Mesh files (.obj, .obj.gz, .ply, .off, .gltf, .glb).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// The mesh of .glb/.gltf files to describe, by name or index (`--mesh 1`; an index where
    /// meshes share a name), when several have morph targets.
    #[arg(long, value_name = "NAME|INDEX")]
    pub mesh: Option<String>,
}

/// What `info` reports about one file.
fn describe(path: &std::path::Path, mesh: &TriMesh, warnings: &[String]) -> Value {
    let topo = Topology::new(mesh.num_vertices(), &mesh.triangles);
    let (lo, hi) = mesh.bounding_box();
    json!({
        "file": path.display().to_string(),
        "vertices": mesh.num_vertices(),
        "triangles": mesh.num_triangles(),
        "polygons": mesh.polygons.as_ref().map(|p| p.len()),
        "bbox_min": lo,
        "bbox_max": hi,
        "bbox_diagonal": mesh.bbox_diagonal(),
        "edges": topo.edges().len(),
        "boundary_edges": topo.boundary_edges().len(),
        "non_manifold_edges": topo.non_manifold_edges().len(),
        "components": topo.num_components(),
        "closed": topo.is_closed(),
        "consistently_oriented": topo.is_consistently_oriented(),
        // Split vertices (seams, hard edges) that solves weld: those within WELD_TOLERANCE of
        // the diagonal of another vertex of the file.
        "welded_vertices": Weld::of_mesh(mesh, WELD_TOLERANCE).merged(),
        "warnings": warnings,
    })
}

fn yes_no(v: &Value) -> &'static str {
    if v.as_bool() == Some(true) {
        "yes"
    } else {
        "no"
    }
}

/// Runs `morphkit info`.
pub fn run(args: &InfoArgs) -> anyhow::Result<()> {
    crate::util::announce_reading(&args.files);
    let pb = progress(args.files.len() as u64, "reading");
    let mut reports = Vec::with_capacity(args.files.len());
    let mut first: Option<TriMesh> = None;
    let mut shared = true;
    for path in &args.files {
        let gltf = morphkit::io::GltfReadOptions {
            mesh: args.mesh.clone(),
        };
        let (mesh, report) = morphkit::io::read_mesh_with(path, &gltf)?;
        let warnings: Vec<String> = report.warnings.iter().map(|w| w.to_string()).collect();
        reports.push(describe(path, &mesh, &warnings));
        match &first {
            None => first = Some(mesh),
            Some(f) => {
                shared &= f.num_vertices() == mesh.num_vertices() && f.triangles == mesh.triangles
            }
        }
        pb.inc(1);
    }
    pb.finish_and_clear();
    let mut out = String::new();
    if args.json {
        let doc = json!({ "files": reports, "shared_connectivity": shared });
        writeln!(out, "{}", serde_json::to_string_pretty(&doc)?)?;
        return emit(&out);
    }
    for r in &reports {
        writeln!(out, "{}", r["file"].as_str().unwrap_or(""))?;
        writeln!(out, "  vertices               {}", r["vertices"])?;
        writeln!(out, "  triangles              {}", r["triangles"])?;
        if let Some(p) = r["polygons"].as_u64() {
            writeln!(out, "  polygons               {p}")?;
        }
        writeln!(
            out,
            "  bounding-box diagonal  {}",
            fmt_size(r["bbox_diagonal"].as_f64().unwrap_or(f64::NAN))
        )?;
        writeln!(out, "  boundary edges         {}", r["boundary_edges"])?;
        writeln!(out, "  non-manifold edges     {}", r["non_manifold_edges"])?;
        writeln!(out, "  components             {}", r["components"])?;
        writeln!(out, "  closed                 {}", yes_no(&r["closed"]))?;
        writeln!(
            out,
            "  consistently oriented  {}",
            yes_no(&r["consistently_oriented"])
        )?;
        writeln!(
            out,
            "  welded vertices        {} (split at seams or hard edges: coincident, one vertex for solves)",
            r["welded_vertices"]
        )?;
        match r["warnings"].as_array() {
            Some(w) if !w.is_empty() => {
                for w in w {
                    writeln!(out, "  warning: {}", w.as_str().unwrap_or(""))?;
                }
            }
            _ => writeln!(out, "  warnings               none")?,
        }
    }
    if reports.len() > 1 {
        writeln!(
            out,
            "shared connectivity: {}",
            if shared {
                "yes, all files have the same vertex count and triangles"
            } else {
                "no"
            }
        )?;
    }
    emit(&out)
}

/// Prints `text` to stdout; a closed pipe (`morphkit info … | head`) is not an error.
fn emit(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => Ok(r?),
    }
}

/// A size in fixed notation where that shows it (1e-3 to 1e9), else in scientific notation, so
/// that a denormal mesh does not print as 0.000000.
fn fmt_size(x: f64) -> String {
    if x == 0.0 || (1e-3..1e9).contains(&x.abs()) {
        format!("{x:.6}")
    } else {
        format!("{x:.6e}")
    }
}
