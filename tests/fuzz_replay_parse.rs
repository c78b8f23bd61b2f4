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
