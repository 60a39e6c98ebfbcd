//! Fuzzes the markers JSON reader: any text gives markers or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "limit.rs"]
mod limit;

/// The harness's memory limit (`limit.rs`): an allocation past it aborts, a crash.
#[global_allocator]
static ALLOC: limit::Limited = limit::Limited;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = morphkit::transfer::Markers::from_json(text);
    }
});
