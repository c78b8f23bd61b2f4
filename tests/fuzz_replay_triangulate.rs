//! Replays every file of the committed fuzz corpus (`fuzz/corpus/triangulate/`) through the
//! fuzz target's decode + exact check, so `cargo test` keeps the corpus green without nightly.

use medial_blocks::geometry::fuzzing::check_bytes;

#[test]
fn replay_corpus() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/triangulate");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("corpus directory")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(files.len() >= 20, "corpus has only {} files", files.len());
    let mut failures = Vec::new();
    for f in &files {
        let data = std::fs::read(f).expect("readable corpus file");
        if let Err(e) = check_bytes(&data) {
            failures.push(format!("{}: {e}", f.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
