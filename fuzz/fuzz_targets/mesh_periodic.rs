//! Decode bytes into a degenerate periodic layout (lattices, hexagonal packings, holes on the
//! box's edges and corners, near-touching images), mesh one period and check it
//! (`medial_blocks::fuzzing::check_periodic_bytes`). Run with
//! `cargo +nightly fuzz run mesh_periodic` from the repository root.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = medial_blocks::fuzzing::check_periodic_bytes(data) {
        panic!("{e}");
    }
});
