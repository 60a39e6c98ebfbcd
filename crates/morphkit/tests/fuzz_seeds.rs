//! The fuzz seeds (`fuzz/seeds/TARGET/`) through the readers their fuzz targets feed, in every
//! `cargo test` (the fuzz crate is nightly-only and not built in CI), under the harness's own
//! memory limit (`fuzz/fuzz_targets/limit.rs`, this binary's allocator too: an infallible
//! allocation past 2 GiB live aborts the test). Each seed must be read, or, when its name
//! starts with `refused-`, refused with a one-line error naming the file; issue 55's
//! amplifying shapes must be among the seeds ([`AMPLIFYING`]).
//!
//! The generated seeds are written by `cargo test -p morphkit --test fuzz_seeds -- --ignored`
//! ([`write_generated_seeds`]); a crash that a fuzz run finds joins them.

#[path = "../../../fuzz/fuzz_targets/limit.rs"]
mod limit;

#[global_allocator]
static ALLOC: limit::Limited = limit::Limited;

use morphkit::io;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz")
}

/// What fuzz target `target` does with `data` (`fuzz/fuzz_targets/TARGET.rs`): `Ok` when the
/// reader reads it (and the mesh then goes through what the target does with it), else the
/// error's message.
fn feed(target: &str, path: &Path, data: &[u8]) -> Result<(), String> {
    let e = |e: io::IoError| e.to_string();
    let text = || std::str::from_utf8(data).map_err(|e| e.to_string());
    match target {
        "obj" => io::obj::parse_obj(path, data).map(|m| {
            let _ = morphkit::mesh::validate(&m);
        }),
        "off" => io::off::parse_off(path, data).map(|m| {
            let _ = morphkit::mesh::validate(&m);
        }),
        "ply" => io::ply::parse_ply(path, data).map(|m| {
            let _ = morphkit::mesh::validate(&m);
        }),
        "pc2" => io::pc2::parse_pc2(path, data).map(drop),
        "gltf" => io::parse_gltf_morphs(path, data.to_vec()).map(|rig| {
            if morphkit::mesh::validate(&rig.base).is_ok() {
                let _ = io::gltf_to_frames(path, &rig);
            }
        }),
        "weights" => return io::parse_weights(path, text()?, false).map(drop).map_err(e),
        "markers" => {
            return morphkit::transfer::Markers::from_json(text()?)
                .map(drop)
                .map_err(|e| e.to_string())
        }
        other => panic!("fuzz/seeds/{other}: no such fuzz target"),
    }
    .map_err(e)
}

/// Issue 55's amplifying and data-changing shapes, each a seed: `(target, file, what its
/// error says)`; an empty fragment for a seed that must be read.
const AMPLIFYING: &[(&str, &str, &str)] = &[
    // 12 primitives sharing one all-zero accessor (no buffer view) of 22.4M vertices.
    (
        "gltf",
        "refused-amplify-shared-zeros.glb",
        "would decode about",
    ),
    // 300 morph targets sharing one accessor of 1M vertices (no buffer view).
    (
        "gltf",
        "refused-amplify-shared-targets.glb",
        "would decode about",
    ),
    // 260 EXT_meshopt_compression views decoding one stream.
    (
        "gltf",
        "refused-amplify-meshopt-views.glb",
        "compressed views",
    ),
    // buffers[0].byteLength 800 over a BIN chunk of 1068 bytes, a view past 800.
    (
        "gltf",
        "refused-view-past-buffer.glb",
        "reaches past the 800 bytes",
    ),
    // An unused view with byteOffset 2^64 - 4 (wrapped to 1064 before).
    (
        "gltf",
        "refused-view-offset-wraps.glb",
        "byteOffset 18446744073709551612",
    ),
    // `property list uchar float x`: every x was read as 0.
    (
        "ply",
        "refused-list-coordinate.ply",
        "is declared as a list",
    ),
    // CR-only line breaks: read as one line before.
    ("obj", "cr-only.obj", ""),
];

#[test]
fn every_seed_is_read_or_refused_cleanly() {
    let seeds = fuzz_dir().join("seeds");
    let mut count = 0;
    for dir in std::fs::read_dir(&seeds).unwrap() {
        let dir = dir.unwrap().path();
        let target = dir.file_name().unwrap().to_str().unwrap().to_string();
        assert!(
            fuzz_dir()
                .join("fuzz_targets")
                .join(format!("{target}.rs"))
                .exists(),
            "{}: no fuzz target {target}",
            dir.display()
        );
        for file in std::fs::read_dir(&dir).unwrap() {
            let file = file.unwrap().path();
            let name = file.file_name().unwrap().to_str().unwrap();
            let data = std::fs::read(&file).unwrap();
            match feed(&target, Path::new(name), &data) {
                Ok(()) => assert!(!name.starts_with("refused-"), "{target}/{name} was read"),
                Err(e) => {
                    assert!(name.starts_with("refused-"), "{target}/{name}: {e}");
                    assert!(
                        e.contains(name) && !e.contains('\n'),
                        "{target}/{name}: {e}"
                    );
                }
            }
            count += 1;
        }
    }
    assert!(count >= 20, "{count} seeds");
}

#[test]
fn the_amplifying_shapes_are_seeds() {
    for &(target, name, says) in AMPLIFYING {
        let file = fuzz_dir().join("seeds").join(target).join(name);
        let data = std::fs::read(&file)
            .unwrap_or_else(|e| panic!("{}: {e} (write it: see the module doc)", file.display()));
        match feed(target, Path::new(name), &data) {
            Ok(()) => assert!(says.is_empty(), "{target}/{name} was read"),
            Err(e) => assert!(!says.is_empty() && e.contains(says), "{target}/{name}: {e}"),
        }
    }
    // The CR-only OBJ is read line by line: a quad's two triangles.
    let obj = std::fs::read(fuzz_dir().join("seeds/obj/cr-only.obj")).unwrap();
    let m = io::obj::parse_obj(Path::new("cr-only.obj"), &obj).unwrap();
    assert_eq!((m.num_vertices(), m.triangles.len()), (4, 2));
}

/// Every fuzz target has the harness's memory limit as its allocator, and `run.sh` passes
/// libFuzzer's limits on every run (the fuzz crate is not built here, so this reads them).
#[test]
fn every_fuzz_target_runs_under_the_memory_limit() {
    let targets = fuzz_dir().join("fuzz_targets");
    for file in std::fs::read_dir(&targets).unwrap() {
        let file = file.unwrap().path();
        if file.file_name().unwrap() == "limit.rs" {
            continue;
        }
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(
            text.contains("#[global_allocator]\nstatic ALLOC: limit::Limited = limit::Limited;"),
            "{} does not install the memory limit",
            file.display()
        );
    }
    let run = std::fs::read_to_string(fuzz_dir().join("run.sh")).unwrap();
    assert!(run.contains("-rss_limit_mb=") && run.contains("-malloc_limit_mb="));
    // The limit refuses what a reader asks for beyond it, fallibly.
    let mut v: Vec<u8> = Vec::new();
    assert!(v.try_reserve(limit::LIMIT_BYTES + 1).is_err());
    assert!(v.try_reserve(1 << 20).is_ok());
}

/// A GLB of `doc` and, when given, a BIN chunk (padded to 4 bytes).
fn glb(doc: &Value, bin: Option<&[u8]>) -> Vec<u8> {
    let mut j = serde_json::to_vec(doc).unwrap();
    j.resize(j.len().next_multiple_of(4), b' ');
    let bin_chunk = bin.map_or(0, |b| 8 + b.len().next_multiple_of(4));
    let total = 12 + 8 + j.len() + bin_chunk;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    if let Some(b) = bin {
        out.extend_from_slice(&(b.len().next_multiple_of(4) as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(b);
        out.resize(total, 0);
    }
    out
}

/// A VEC3 float accessor of `count` vertices, on `view` (or none: all zeros).
fn positions(count: usize, view: Option<usize>) -> Value {
    let mut a = json!({"componentType": 5126, "count": count, "type": "VEC3",
        "min": [0, 0, 0], "max": [0, 0, 0]});
    if let Some(v) = view {
        a["bufferView"] = json!(v);
    }
    a
}

/// The generated seeds of [`AMPLIFYING`] (the others are older and hand-made).
fn generated() -> Vec<(&'static str, &'static str, Vec<u8>)> {
    let targets: Vec<Value> = (0..300).map(|_| json!({"POSITION": 1})).collect();
    let shared_targets = json!({"asset": {"version": "2.0"},
        "accessors": [positions(1_000_000, None), positions(1_000_000, None)],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "targets": targets}]}]});
    // 260 views, each decoding 1 Mi vertices of 16 bytes (16 MiB) from one 64 KiB stream,
    // within the codec's ratio of 256 each, 4.1 GiB together (the stream is 1 Mi zero
    // vertices encoded, zero-padded to 64 KiB: the budget refuses before it is decoded).
    let count = 1 << 20;
    let mut enc = meshopt::encode_vertex_buffer(&vec![[0u32; 4]; count]).unwrap();
    enc.resize(16 * count / 256, 0);
    let mut views = vec![json!({"buffer": 0, "byteLength": 36})];
    for _ in 0..260 {
        views.push(
            json!({"buffer": 1, "byteLength": 16 * count, "byteStride": 16,
            "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteLength": enc.len(),
                "byteStride": 16, "count": count, "mode": "ATTRIBUTES"}}}),
        );
    }
    let meshopt = json!({"asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression"],
        "buffers": [{"byteLength": enc.len()}, {"byteLength": 16 * count,
            "extensions": {"EXT_meshopt_compression": {"fallback": true}}}],
        "bufferViews": views,
        "accessors": [positions(3, Some(0))],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]});
    let wraps = json!({"asset": {"version": "2.0"},
        "buffers": [{"byteLength": 800}],
        "bufferViews": [{"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": u64::MAX - 3, "byteLength": 8}],
        "accessors": [positions(3, Some(0))],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]});
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty list uchar float x\n\
               property float y\nproperty float z\nelement face 1\n\
               property list uchar int vertex_indices\nend_header\n\
               1 0 0 0\n1 1 0 0\n1 0 1 0\n3 0 1 2\n";
    let obj = "v 0 0 0\rv 1 0 0\rv 1 1 0\rv 0 1 0\rf 1 2 3 4\r";
    vec![
        (
            "gltf",
            "refused-amplify-shared-targets.glb",
            glb(&shared_targets, None),
        ),
        (
            "gltf",
            "refused-amplify-meshopt-views.glb",
            glb(&meshopt, Some(&enc)),
        ),
        (
            "gltf",
            "refused-view-offset-wraps.glb",
            glb(&wraps, Some(&[0u8; 1068])),
        ),
        (
            "ply",
            "refused-list-coordinate.ply",
            ply.as_bytes().to_vec(),
        ),
        ("obj", "cr-only.obj", obj.as_bytes().to_vec()),
    ]
}

/// Writes the generated seeds into `fuzz/seeds` (run by hand, see the module doc).
#[test]
#[ignore = "writes fuzz/seeds in the checkout: run by hand to regenerate them (CI runs the seed checks above)"]
fn write_generated_seeds() {
    for (target, name, bytes) in generated() {
        let p = fuzz_dir().join("seeds").join(target).join(name);
        std::fs::write(&p, &bytes).unwrap();
        eprintln!("{}: {} bytes", p.display(), bytes.len());
    }
}
