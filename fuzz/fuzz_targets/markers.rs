//! Fuzzes the markers JSON reader: any text gives markers or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = morphkit::transfer::Markers::from_json(text);
    }
});
