//! Decode bytes into a degenerate point set, triangulate, and check the result exactly
//! (`medial_blocks::geometry::fuzzing::check_bytes`). Run with
//! `cargo +nightly fuzz run triangulate` from the repository root.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = medial_blocks::geometry::fuzzing::check_bytes(data) {
        panic!("{e}");
    }
});
