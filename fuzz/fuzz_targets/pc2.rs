//! Fuzzes the PC2 point-cache reader: any bytes give a cache or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "limit.rs"]
mod limit;

/// The harness's memory limit (`limit.rs`): an allocation past it aborts, a crash.
#[global_allocator]
static ALLOC: limit::Limited = limit::Limited;

fuzz_target!(|data: &[u8]| {
    let _ = morphkit::io::pc2::parse_pc2(Path::new("fuzz.pc2"), data);
});
