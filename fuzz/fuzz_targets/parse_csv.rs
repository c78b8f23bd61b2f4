//! The CLI's CSV parsers (`medial_blocks::input`) on arbitrary bytes: no panic; accepted rows
//! re-serialise and re-parse bit for bit (`medial_blocks::fuzzing::check_csv_bytes`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = medial_blocks::fuzzing::check_csv_bytes(data) {
        panic!("{e}");
    }
});
