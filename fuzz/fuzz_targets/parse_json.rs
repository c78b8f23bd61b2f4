//! `Domain::from_json_str` on arbitrary bytes: no panic; an accepted domain re-serialises and
//! re-parses bit for bit (`medial_blocks::fuzzing::check_json_bytes`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = medial_blocks::fuzzing::check_json_bytes(data) {
        panic!("{e}");
    }
});
