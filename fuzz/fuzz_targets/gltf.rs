//! Fuzzes the glTF/GLB reader: any bytes give a rig (whose frames can be evaluated) or an
//! error, never a panic. External buffer URIs resolve under a directory that does not exist.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "limit.rs"]
mod limit;

/// The harness's memory limit (`limit.rs`): an allocation past it aborts, a crash.
#[global_allocator]
static ALLOC: limit::Limited = limit::Limited;

fuzz_target!(|data: &[u8]| {
    let name = if data.starts_with(b"glTF") {
        "fuzz.glb"
    } else {
        "fuzz.gltf"
    };
    let path = Path::new("/nonexistent-morphkit-fuzz").join(name);
    if let Ok(rig) = morphkit::io::parse_gltf_morphs(&path, data.to_vec()) {
        if morphkit::mesh::validate(&rig.base).is_ok() {
            let _ = morphkit::io::gltf_to_frames(&path, &rig);
        }
    }
});
