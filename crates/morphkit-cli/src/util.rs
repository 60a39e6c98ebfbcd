//! Helpers shared by the subcommands: progress bars, JSON reports, flag checks and numbers in
//! messages.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// A progress bar on stderr, hidden when stderr is not a terminal.
pub fn progress(len: u64, message: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    if std::io::stderr().is_terminal() {
        pb.set_draw_target(ProgressDrawTarget::stderr());
    } else {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    pb.set_style(
        ProgressStyle::with_template(
            "{msg:>12} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    pb.set_message(message.to_string());
    pb
}

/// Inputs at least this large (bytes, all files together) are announced before reading.
pub const LARGE_INPUT_BYTES: u64 = 64 << 20;

/// Meshes with at least this many vertices are announced before long work on them.
pub const LARGE_MESH_VERTICES: usize = 250_000;

/// Warns once on stderr about what a solve leaves out or carries along unchanged in the mesh
/// read from `path`: triangles that use a vertex twice (kept in the output, left out of the
/// energy) and vertices no triangle uses (moved with the linear blend). The message gives the
/// count and the first ids.
pub fn warn_carried(path: &Path, mesh: &morphkit::TriMesh) {
    let Ok(report) = morphkit::mesh::validate(mesh) else {
        return;
    };
    for w in &report.warnings {
        if matches!(
            w,
            morphkit::mesh::ValidationWarning::RepeatedVertexTriangles(_)
                | morphkit::mesh::ValidationWarning::IsolatedVertices(_)
        ) {
            eprintln!("warning: {}: {w}", path.display());
        }
    }
}

/// The input `path` as an [`morphkit::io::MeshTemplate`] for outputs, when it is an OBJ or a
/// PLY of `vertices` vertices (results keep the input's layout): outputs of its format are
/// written into the artist's own file.
pub fn template(
    path: &Path,
    vertices: usize,
) -> anyhow::Result<Option<morphkit::io::MeshTemplate>> {
    let t = morphkit::io::MeshTemplate::read(path)?;
    Ok(t.filter(|t| t.num_vertices() == vertices))
}

/// The input `path` as an [`morphkit::io::ObjTemplate`] (what frame directories are written
/// into), when it is an OBJ of `vertices` vertices.
pub fn obj_template(
    path: &Path,
    vertices: usize,
) -> anyhow::Result<Option<morphkit::io::ObjTemplate>> {
    if !matches!(
        morphkit::io::Format::from_path(path),
        Some(morphkit::io::Format::Obj { .. })
    ) {
        return Ok(None);
    }
    Ok(template(path, vertices)?.and_then(morphkit::io::MeshTemplate::into_obj))
}

/// Prints `reading N files (X MiB)…` on stderr before reading inputs that are large, so a
/// long read is never silent (the progress bars show only on a terminal).
pub fn announce_reading(paths: &[PathBuf]) {
    if let Some(m) = reading_message(paths, LARGE_INPUT_BYTES) {
        eprintln!("{m}");
    }
}

/// The message of [`announce_reading`] when `paths` hold at least `threshold` bytes.
pub fn reading_message(paths: &[PathBuf], threshold: u64) -> Option<String> {
    let bytes: u64 = paths
        .iter()
        .filter_map(|p| std::fs::metadata(p).ok())
        .map(|m| m.len())
        .sum();
    (bytes >= threshold).then(|| {
        format!(
            "reading {} file{} ({:.1} MiB)…",
            paths.len(),
            if paths.len() == 1 { "" } else { "s" },
            bytes as f64 / (1 << 20) as f64
        )
    })
}

/// Prints `WHAT (V vertices)…` on stderr before long work on a large mesh.
pub fn announce_work(what: &str, vertices: usize) {
    if vertices >= LARGE_MESH_VERTICES {
        eprintln!("{what} ({vertices} vertices)…");
    }
}

/// A number for messages: plain for ordinary magnitudes, scientific (`1e-300`) otherwise, so
/// a message never spells out hundreds of digits.
pub fn num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `value` of the flag `flag` when it is finite and within `[min, max]` (`min` excluded when
/// `open_min`); the error names the flag and says which condition fails.
pub fn check_range(
    flag: &str,
    value: f64,
    min: f64,
    open_min: bool,
    max: f64,
) -> anyhow::Result<f64> {
    if !value.is_finite() {
        anyhow::bail!("{flag} {}: not finite; give a finite number", num(value));
    }
    let low = if open_min { value <= min } else { value < min };
    if low || value > max {
        let lo = if open_min { "greater than" } else { "at least" };
        if max.is_finite() {
            anyhow::bail!(
                "{flag} {}: must be {lo} {} and at most {}",
                num(value),
                num(min),
                num(max)
            );
        }
        anyhow::bail!("{flag} {}: must be {lo} {}", num(value), num(min));
    }
    Ok(value)
}

/// Refuses `flag`, when `given`, without the flag `needed` (`present`), saying `what` it does.
/// clap's `requires` does not hold where `needed` conflicts with another argument given (it
/// then counts `needed` as not required: `blend --base … --mesh X`, where --rig conflicts with
/// --base), so such a flag would otherwise be ignored with exit status 0.
pub fn only_with(
    flag: &str,
    given: bool,
    needed: &str,
    present: bool,
    what: &str,
) -> anyhow::Result<()> {
    if given && !present {
        anyhow::bail!(
            "{flag} is used only with {needed} ({what}); give {needed} or leave {flag} out"
        );
    }
    Ok(())
}

/// Refuses a colour output `path` of `flag` that is not a `.ply` file (colours are written
/// only as PLY); `what` names the colours in the message.
pub fn require_ply(flag: &str, path: &std::path::Path, what: &str) -> anyhow::Result<()> {
    if morphkit::io::Format::from_path(path) != Some(morphkit::io::Format::Ply) {
        anyhow::bail!("{flag} {}: {what} are written as .ply", path.display());
    }
    Ok(())
}

/// `value` of `flag` when it is finite and positive.
pub fn check_positive(flag: &str, value: f64) -> anyhow::Result<f64> {
    check_range(flag, value, 0.0, true, f64::INFINITY)
}

/// Frame rates accepted by `--fps`: key times `frame / fps` stay representable as glTF's `f32`.
pub const FPS_RANGE: (f64, f64) = (1e-3, 1e5);

/// Checks `--fps`.
pub fn check_fps(fps: f64) -> anyhow::Result<f64> {
    check_range("--fps", fps, FPS_RANGE.0, false, FPS_RANGE.1)
}

/// Reads a JSON file as text, without a UTF-8 byte-order mark; errors name the file.
pub fn read_json(path: &Path, what: &str) -> anyhow::Result<serde_json::Value> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot read the {what}: {e}", path.display()))?;
    serde_json::from_str(morphkit::io::strip_bom_str(&text))
        .map_err(|e| anyhow::anyhow!("{}: invalid JSON: {e}", path.display()))
}

/// Says on stderr what an output of positions and triangles (`output`, not glTF) leaves out of
/// a glTF `input` (materials, textures, skins, UV sets, other meshes, …), so a user knows that
/// a `.glb`/`.gltf` output would keep them. Nothing for other inputs or glTF outputs.
pub fn note_not_carried(input: &Path, output: &Path, mesh: Option<&str>) {
    use morphkit::io::{Format, GltfAsset, GltfReadOptions};
    let gltf = |p: &Path| matches!(Format::from_path(p), Some(Format::Glb | Format::Gltf));
    if !gltf(input) || gltf(output) {
        return;
    }
    let opts = GltfReadOptions {
        mesh: mesh.map(str::to_string),
    };
    let Ok(asset) = GltfAsset::read(input, &opts) else {
        return;
    };
    let lost = asset.not_geometry();
    if !lost.is_empty() {
        eprintln!(
            "note: {} keeps positions and triangles only; it leaves out what {} also holds: {} (a .glb or .gltf output keeps them)",
            output.display(),
            input.display(),
            lost.join(", ")
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_compact_and_flags_named() {
        assert_eq!(num(1e-300), "1e-300");
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(1e300), "1e300");
        assert_eq!(num(f64::INFINITY), "inf");
        let e = check_positive("--omega", f64::INFINITY)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "--omega inf: not finite; give a finite number");
        let e = check_positive("--k0", -1e-300).unwrap_err().to_string();
        assert_eq!(e, "--k0 -1e-300: must be greater than 0");
        let e = check_fps(1e-300).unwrap_err().to_string();
        assert!(e.starts_with("--fps 1e-300"), "{e}");
    }

    #[test]
    fn large_inputs_are_announced() {
        let p = std::env::temp_dir().join(format!("morphkit-announce-{}", std::process::id()));
        std::fs::write(&p, vec![b'x'; 3 << 19]).unwrap();
        let paths = [p.clone(), p.clone()];
        assert_eq!(
            reading_message(&paths, 1 << 20).as_deref(),
            Some("reading 2 files (3.0 MiB)…")
        );
        assert_eq!(reading_message(&paths, 4 << 20), None);
        let _ = std::fs::remove_file(&p);
        let e = check_fps(1e-300).unwrap_err().to_string();
        assert!(e.starts_with("--fps 1e-300: must be at least 0.001"), "{e}");
    }
}
