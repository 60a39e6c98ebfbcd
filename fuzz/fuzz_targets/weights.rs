//! Fuzzes the weights-file reader (CSV and JSON): any text gives rows or an error, never a
//! panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

#[path = "limit.rs"]
mod limit;

/// The harness's memory limit (`limit.rs`): an allocation past it aborts, a crash.
#[global_allocator]
static ALLOC: limit::Limited = limit::Limited;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = morphkit::io::parse_weights(Path::new("fuzz.csv"), text, false);
    }
});
