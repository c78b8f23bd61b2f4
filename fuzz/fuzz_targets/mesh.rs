//! Decode bytes into a degenerate circle layout, mesh it, and check the mesh's invariants
//! (`medial_blocks::fuzzing::check_layout_bytes`). Run with
//! `cargo +nightly fuzz run mesh` from the repository root.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = medial_blocks::fuzzing::check_layout_bytes(data) {
        panic!("{e}");
    }
});
