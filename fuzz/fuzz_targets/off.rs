//! Fuzzes the OFF reader: any bytes give a mesh that passes validation or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "limit.rs"]
mod limit;

/// The harness's memory limit (`limit.rs`): an allocation past it aborts, a crash.
#[global_allocator]
static ALLOC: limit::Limited = limit::Limited;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = morphkit::io::off::parse_off(Path::new("fuzz.off"), data) {
        let _ = morphkit::mesh::validate(&mesh);
    }
});
