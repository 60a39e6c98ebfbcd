//! Interior points and internal springs from a constrained Delaunay tetrahedralization by an
//! external `tetgen` program (Ma et al. 2012, Sec. 3.1, the paper's own choice).
//!
//! `tetgen` (Debian package `tetgen`, version 1.5) is AGPL: it is only ever *run*, as a
//! separate process found on the `PATH`; nothing of it is linked or copied. For each closed,
//! consistently oriented component found by [`lattice::solids`] (the same components, and the
//! same reasons for skipping the others, as the lattice):
//!
//! 1. its surface (base positions, the component's own vertices in ascending id order) is
//!    written as a `.smesh` file into a fresh temporary directory
//!    (`$TMPDIR/morphkit-tetgen-<pid>-<counter>`, removed afterwards, on error as well);
//! 2. `tetgen -p -q1.414 -Y -z -F -a<V>` tetrahedralizes it: `-p` the surface as a PLC,
//!    `-q1.414` a radius–edge bound, `-Y` no Steiner point on the surface (the surface
//!    vertices stay exactly the mesh's own, and the first output nodes are the input vertices
//!    in order — checked by their coordinates, a mismatch is an error), `-z` 0-based output
//!    numbering, `-F` no `.face`/`.edge` output, and a maximum tetrahedron volume
//!    $V = L^3 / (6\sqrt2)$, the volume of a regular tetrahedron with edge
//!    $L = 2 \bar e / \text{density}$ ($\bar e$ the component's mean surface edge): the same
//!    length as the lattice spacing $h$, so a density means about the same resolution in both.
//!    `-Q` (quiet) is *not* passed: with it `tetgen` aborts on a bad input without saying why.
//!    Its output is captured (through `stdbuf -oL` where that is on the `PATH`, so that the
//!    reason survives the abort) and its last lines are quoted in the error;
//! 3. the `.node` and `.ele` files are read back.
//!
//! The interior points are the Steiner nodes beyond the input vertices (those used by a
//! tetrahedron), numbered after the surface vertices component by component; the internal
//! springs are every tetrahedron edge that is not a surface mesh edge (deduplicated, sorted);
//! the tetrahedra, positively oriented in the base, are kept for the per-frame inversion count.
//! `tetgen` is deterministic, so the same input gives the same interior.
//!
//! The lattice-only options ([`InteriorOptions::margin`], `ties_per_vertex`, `tie_radius`) do
//! not apply.

use super::lattice::{self, Interior, SkippedComponent, Solid};
use super::{InteriorError, InteriorOptions};
use crate::mesh::{norm, sub, Point};
use std::ffi::{OsStr, OsString};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The radius–edge quality bound passed as `-q`.
pub const QUALITY: f64 = 1.414;

/// The maximum tetrahedron volume `-a` for a component of mean surface edge `mean_edge`: a
/// regular tetrahedron with edge $L = 2 \bar e / \text{density}$, $V = L^3 / (6\sqrt2)$.
pub fn max_volume(mean_edge: f64, density: f64) -> f64 {
    let l = 2.0 * mean_edge / density;
    l * l * l / (6.0 * std::f64::consts::SQRT_2)
}

fn not_found() -> InteriorError {
    InteriorError::Tetgen(
        "no tetgen executable on the PATH (Debian package 'tetgen'; AGPL, run only as a separate program); use --interior lattice".into(),
    )
}

fn find_in(name: &str, search_path: &OsStr) -> Option<PathBuf> {
    std::env::split_paths(search_path)
        .filter(|d| !d.as_os_str().is_empty())
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// Longest a tetgen run may take before it is stopped (a hang guard).
const TETGEN_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(600);

/// The `tetgen` executable in `search_path` (a `PATH`-style list; `None`: the process's
/// `PATH`), or the error saying it is missing.
pub fn find_program(search_path: Option<&OsStr>) -> Result<PathBuf, InteriorError> {
    let from_env: Option<OsString> = std::env::var_os("PATH");
    let path = match search_path {
        Some(p) => p.to_os_string(),
        None => from_env.ok_or_else(not_found)?,
    };
    find_in("tetgen", &path).ok_or_else(not_found)
}

/// A temporary directory, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new() -> Result<Self, InteriorError> {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let root = std::env::temp_dir();
        for _ in 0..1000 {
            let k = COUNTER.fetch_add(1, Ordering::Relaxed);
            let d = root.join(format!("morphkit-tetgen-{}-{k}", std::process::id()));
            match std::fs::create_dir(&d) {
                Ok(()) => return Ok(Self(d)),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => {
                    return Err(InteriorError::Tetgen(format!(
                        "cannot create a temporary directory {}: {e}",
                        d.display()
                    )))
                }
            }
        }
        Err(InteriorError::Tetgen(format!(
            "cannot create a fresh temporary directory in {}",
            root.display()
        )))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Builds the tetgen interior of every solid, running `tetgen` from the process's `PATH`.
pub fn build_in(
    base: &[Point],
    triangles: &[[u32; 3]],
    solids: &[Solid],
    skipped: Vec<SkippedComponent>,
    o: &InteriorOptions,
) -> Result<Interior, InteriorError> {
    let program = find_program(None)?;
    build_with(&program, base, triangles, solids, skipped, o)
}

/// Builds the tetgen interior of every closed component of `base` (see [`lattice::solids`]).
pub fn build(
    base: &[Point],
    triangles: &[[u32; 3]],
    o: &InteriorOptions,
) -> Result<Interior, InteriorError> {
    let (solids, skipped) = lattice::solids(base, triangles);
    build_in(base, triangles, &solids, skipped, o)
}

/// As [`build_in`] with an explicit `tetgen` executable.
pub fn build_with(
    program: &Path,
    base: &[Point],
    triangles: &[[u32; 3]],
    solids: &[Solid],
    mut skipped: Vec<SkippedComponent>,
    o: &InteriorOptions,
) -> Result<Interior, InteriorError> {
    let n = base.len() as u32;
    let stdbuf = std::env::var_os("PATH").and_then(|p| find_in("stdbuf", &p));
    let mut out = Interior::default();
    for s in solids {
        if s.capped_holes > 0 {
            skipped.push(SkippedComponent {
                component: s.component,
                example_vertex: s.vertices[0],
                reason: "open (tetgen needs a closed surface; the lattice caps small holes)".into(),
            });
            continue;
        }
        let tris: Vec<[u32; 3]> = triangles
            .iter()
            .copied()
            .filter(|t| s.vertices.binary_search(&t[0]).is_ok())
            .collect();
        let before = out.tets.len();
        fill(program, stdbuf.as_deref(), base, s, &tris, o, n, &mut out)?;
        if out.tets.len() == before {
            skipped.push(SkippedComponent {
                component: s.component,
                example_vertex: s.vertices[0],
                reason: "tetgen made no tetrahedra".into(),
            });
        }
    }
    skipped.sort_by_key(|k| k.component);
    out.skipped = skipped;
    Ok(out)
}

fn err(msg: String) -> InteriorError {
    InteriorError::Tetgen(msg)
}

/// The last `k` non-empty lines of `text`, joined by " | ".
fn last_lines(text: &str, k: usize) -> String {
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    lines[lines.len().saturating_sub(k)..].join(" | ")
}

#[allow(clippy::too_many_arguments)]
fn fill(
    program: &Path,
    stdbuf: Option<&Path>,
    base: &[Point],
    s: &Solid,
    tris: &[[u32; 3]],
    o: &InteriorOptions,
    n: u32,
    out: &mut Interior,
) -> Result<(), InteriorError> {
    let nv = s.vertices.len();
    let local = |v: u32| {
        s.vertices
            .binary_search(&v)
            .expect("vertex of the component") as u32
    };
    let dir = TempDir::new()?;
    let input = dir.0.join("surface.smesh");
    let mut text = format!("{nv} 3 0 0\n");
    for (k, &v) in s.vertices.iter().enumerate() {
        let p = base[v as usize];
        text.push_str(&format!("{k} {:e} {:e} {:e}\n", p[0], p[1], p[2]));
    }
    text.push_str(&format!("{} 0\n", tris.len()));
    for t in tris {
        let l = t.map(local);
        text.push_str(&format!("3 {} {} {}\n", l[0], l[1], l[2]));
    }
    text.push_str("0\n0\n");
    std::fs::write(&input, text)
        .map_err(|e| err(format!("cannot write {}: {e}", input.display())))?;
    let volume = max_volume(s.mean_edge, o.density);
    let switches = format!("-pq{QUALITY}YzFa{volume:e}");
    let mut cmd = match stdbuf {
        Some(sb) => {
            let mut c = Command::new(sb);
            c.arg("-oL").arg(program);
            c
        }
        None => Command::new(program),
    };
    // Output goes to files (no pipe can fill up), and a tetgen that runs past
    // `TETGEN_TIMEOUT` is killed: a guard against a hang, not a numerical decision.
    let (out_path, err_path) = (dir.0.join("tetgen.out"), dir.0.join("tetgen.err"));
    let open = |p: &Path| {
        std::fs::File::create(p).map_err(|e| err(format!("cannot create {}: {e}", p.display())))
    };
    cmd.arg(&switches)
        .arg(&input)
        .current_dir(&dir.0)
        .stdin(std::process::Stdio::null())
        .stdout(open(&out_path)?)
        .stderr(open(&err_path)?);
    let mut child = cmd
        .spawn()
        .map_err(|e| err(format!("cannot run {}: {e}", program.display())))?;
    let started = std::time::Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if started.elapsed() > TETGEN_TIMEOUT => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(err(format!(
                    "'{} {switches}' on component {} ran for more than {} s and was stopped",
                    program.display(),
                    s.component,
                    TETGEN_TIMEOUT.as_secs()
                )));
            }
            Ok(None) => std::thread::sleep(std::time::Duration::from_millis(10)),
            Err(e) => return Err(err(format!("waiting for {}: {e}", program.display()))),
        }
    };
    if !status.success() {
        let read =
            |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
        let said = format!("{}\n{}", read(&out_path), read(&err_path));
        let how = match status.code() {
            Some(c) => format!("exited with status {c}"),
            None => "was killed by a signal".into(),
        };
        let hint = if said.to_lowercase().contains("intersect") {
            " (the surface of the component intersects itself)"
        } else {
            ""
        };
        return Err(err(format!(
            "'{} {switches}' on component {} (vertex {}, {nv} vertices) {how}{hint}: {}",
            program.display(),
            s.component,
            s.vertices[0],
            last_lines(&said, 4)
        )));
    }
    let node_path = dir.0.join("surface.1.node");
    let ele_path = dir.0.join("surface.1.ele");
    let nodes = read_nodes(&node_path)?;
    let tets = read_tets(&ele_path, nodes.len())?;
    // The first nodes are the input vertices, in order.
    let (lo, hi) = crate::mesh::bounding_box(
        &s.vertices
            .iter()
            .map(|&v| base[v as usize])
            .collect::<Vec<_>>(),
    );
    let tol = 1e-9 * norm(sub(hi, lo)).max(f64::MIN_POSITIVE);
    if nodes.len() < nv {
        return Err(err(format!(
            "{} has {} nodes, fewer than the {nv} input vertices",
            node_path.display(),
            nodes.len()
        )));
    }
    for (k, &v) in s.vertices.iter().enumerate() {
        let (p, q) = (nodes[k], base[v as usize]);
        if norm(sub(p, q)) > tol {
            return Err(err(format!(
                "node {k} of {} is at {p:?}, not at input vertex {v} {q:?}: tetgen changed the surface",
                node_path.display()
            )));
        }
    }
    // Steiner nodes used by a tetrahedron, in tetgen's order.
    let mut used = vec![false; nodes.len()];
    tets.iter().flatten().for_each(|&k| used[k as usize] = true);
    let mut global = vec![u32::MAX; nodes.len()];
    for (k, &v) in s.vertices.iter().enumerate() {
        global[k] = v;
    }
    for k in nv..nodes.len() {
        if used[k] {
            global[k] = n + out.points.len() as u32;
            out.points.push(nodes[k]);
        }
    }
    let pos = |v: u32| {
        if v < n {
            base[v as usize]
        } else {
            out.points[(v - n) as usize]
        }
    };
    let mut surface_edges: Vec<[u32; 2]> = tris
        .iter()
        .flat_map(|t| [order(t[0], t[1]), order(t[1], t[2]), order(t[2], t[0])])
        .collect();
    surface_edges.sort_unstable();
    surface_edges.dedup();
    let mut springs = Vec::new();
    let first_tet = out.tets.len();
    for t in &tets {
        let g = t.map(|k| global[k as usize]);
        for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            let e = order(g[a], g[b]);
            if surface_edges.binary_search(&e).is_err() {
                springs.push(e);
            }
        }
        let g = if lattice::tet_volume6(pos, g) < 0.0 {
            [g[0], g[1], g[3], g[2]]
        } else {
            g
        };
        out.tets.push(g);
    }
    springs.sort_unstable();
    springs.dedup();
    out.springs.extend(springs);
    if out.tets.len() > first_tet {
        out.spacing
            .push((s.component, 2.0 * s.mean_edge / o.density));
    }
    Ok(())
}

fn order(a: u32, b: u32) -> [u32; 2] {
    [a.min(b), a.max(b)]
}

/// The non-empty, non-comment lines of a tetgen file, with their 1-based line numbers.
fn data_lines(path: &Path) -> Result<Vec<(usize, Vec<String>)>, InteriorError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| err(format!("cannot read tetgen output {}: {e}", path.display())))?;
    Ok(text
        .lines()
        .enumerate()
        .filter_map(|(i, l)| {
            let l = l.split('#').next().unwrap_or("");
            let w: Vec<String> = l.split_whitespace().map(str::to_owned).collect();
            (!w.is_empty()).then_some((i + 1, w))
        })
        .collect())
}

fn bad(path: &Path, line: usize, what: &str) -> InteriorError {
    err(format!(
        "cannot parse tetgen output {} line {line}: {what}",
        path.display()
    ))
}

fn field<T: std::str::FromStr>(
    path: &Path,
    line: usize,
    words: &[String],
    k: usize,
    what: &str,
) -> Result<T, InteriorError> {
    words
        .get(k)
        .and_then(|w| w.parse().ok())
        .ok_or_else(|| bad(path, line, &format!("expected {what} in field {}", k + 1)))
}

/// Reads a `.node` file (0-based, `-z`).
fn read_nodes(path: &Path) -> Result<Vec<Point>, InteriorError> {
    let lines = data_lines(path)?;
    let Some((l0, head)) = lines.first() else {
        return Err(bad(path, 1, "the file is empty"));
    };
    let count: usize = field(path, *l0, head, 0, "the number of nodes")?;
    let dim: usize = field(path, *l0, head, 1, "the dimension")?;
    if dim != 3 {
        return Err(bad(path, *l0, &format!("dimension {dim}, expected 3")));
    }
    if lines.len() - 1 < count {
        return Err(bad(
            path,
            lines.last().map_or(*l0, |l| l.0),
            &format!("{count} nodes announced, {} found", lines.len() - 1),
        ));
    }
    let mut out = Vec::with_capacity(count);
    for (k, (l, w)) in lines[1..=count].iter().enumerate() {
        let id: usize = field(path, *l, w, 0, "the node index")?;
        if id != k {
            return Err(bad(path, *l, &format!("node index {id}, expected {k}")));
        }
        let mut p: Point = [0.0; 3];
        for (a, c) in p.iter_mut().enumerate() {
            *c = field(path, *l, w, a + 1, "a coordinate")?;
            if !c.is_finite() {
                return Err(bad(path, *l, "a coordinate is not finite"));
            }
        }
        out.push(p);
    }
    Ok(out)
}

/// Reads an `.ele` file (0-based, `-z`) of linear tetrahedra over `nodes` nodes.
fn read_tets(path: &Path, nodes: usize) -> Result<Vec<[u32; 4]>, InteriorError> {
    let lines = data_lines(path)?;
    let Some((l0, head)) = lines.first() else {
        return Err(bad(path, 1, "the file is empty"));
    };
    let count: usize = field(path, *l0, head, 0, "the number of tetrahedra")?;
    let per: usize = field(path, *l0, head, 1, "the nodes per tetrahedron")?;
    if per != 4 {
        return Err(bad(
            path,
            *l0,
            &format!("{per} nodes per tetrahedron, expected 4"),
        ));
    }
    if lines.len() - 1 < count {
        return Err(bad(
            path,
            lines.last().map_or(*l0, |l| l.0),
            &format!("{count} tetrahedra announced, {} found", lines.len() - 1),
        ));
    }
    let mut out = Vec::with_capacity(count);
    for (k, (l, w)) in lines[1..=count].iter().enumerate() {
        let id: usize = field(path, *l, w, 0, "the tetrahedron index")?;
        if id != k {
            return Err(bad(
                path,
                *l,
                &format!("tetrahedron index {id}, expected {k}"),
            ));
        }
        let mut t = [0u32; 4];
        for (a, v) in t.iter_mut().enumerate() {
            let i: usize = field(path, *l, w, a + 1, "a node index")?;
            if i >= nodes {
                return Err(bad(
                    path,
                    *l,
                    &format!("node {i} out of range (0..{nodes})"),
                ));
            }
            *v = i as u32;
        }
        if (0..4).any(|a| (a + 1..4).any(|b| t[a] == t[b])) {
            return Err(bad(path, *l, "a tetrahedron repeats a node"));
        }
        out.push(t);
    }
    Ok(out)
}

#[cfg(test)]
#[path = "tetgen_tests.rs"]
mod tests;
