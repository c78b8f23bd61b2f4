//! Replays the committed `parse_json` and `parse_csv` fuzz corpora (`fuzz/corpus/parse_*/`)
//! through the fuzz targets' checks (`medial_blocks::fuzzing::{check_json_bytes,
//! check_csv_bytes}`), so `cargo test` keeps them green without nightly or cargo-fuzz.

use medial_blocks::fuzzing::{check_csv_bytes, check_json_bytes};
use std::path::Path;

fn replay(name: &str, check: fn(&[u8]) -> Result<(), String>) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(name);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("corpus directory")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(
        files.len() >= 10,
        "{name} corpus has only {} files",
        files.len()
    );
    let failures: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let data = std::fs::read(f).expect("readable corpus file");
            check(&data).err().map(|e| format!("{}: {e}", f.display()))
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn replay_parse_json_corpus() {
    replay("parse_json", check_json_bytes);
}

#[test]
fn replay_parse_csv_corpus() {
    replay("parse_csv", check_csv_bytes);
}

/// Found by the `parse_json` fuzz target (`fuzz/corpus/parse_json/regress_float_roundtrip_16_digits`):
/// without serde_json's `float_roundtrip` feature, `9007129954740993.0` (what the domain
/// writes back for the integer `9007129954740993`) was read as `9007129954740994`, so a domain
/// did not survive its own JSON. Every decimal must be read correctly rounded.
#[test]
fn json_numbers_are_read_correctly_rounded() {
    use medial_blocks::Domain;
    for (text, want) in [
        ("9007129954740993", 9007129954740993.0_f64),
        ("9007129954740993.0", 9007129954740993.0),
        (
            "0.1000000000000000055511151231257827021181583404541015625",
            0.1,
        ),
        ("2.2250738585072011e-308", 2.225_073_858_507_201e-308),
    ] {
        let json = format!(
            "{{\"bounding\": {{\"center\": [{text}, 0], \"radius\": 1e17}}, \"holes\": []}}"
        );
        match Domain::from_json_str(&json) {
            Ok(d) => assert_eq!(d.bounding().center[0].to_bits(), want.to_bits(), "{text}"),
            Err(e) => panic!("{text}: {e}"),
        }
    }
}
