//! The CLI's worker pinning (issue 8, `src/cli/affinity.rs`): with one worker per CPU the
//! process may run on, worker `i` runs on the `i`-th CPU unless `--no-pin`. These tests check
//! that this changes nothing a user can see but the speed: the same files byte for byte
//! (every format, one and several threads), and that `timings.json`'s `pinned_threads` says
//! which way it ran: pinned by default where there are several CPUs, not with `--no-pin`,
//! nor with fewer workers than CPUs.

use crate::common;

use common::{bin, tree};
use std::path::Path;

/// The CPUs this test process may run on (what the tool sees too: it inherits the mask).
fn allowed_cpus() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Mesh the 7-hole example with every format and `--timings` plus `extra` global flags into
/// `dir/name`; the files without timings.json, and its `pinned_threads` and `threads`.
fn mesh(dir: &Path, name: &str, extra: &[&str]) -> (Vec<(String, Vec<u8>)>, bool, u64) {
    let target = dir.join(name);
    let out = bin()
        .env_remove("RAYON_NUM_THREADS")
        .args(extra)
        .args(["--quiet", "mesh", "-o"])
        .arg(&target)
        .args(["--format", "all", "--timings"])
        .output()
        .expect("the medial-blocks binary runs");
    assert!(out.status.success(), "{out:?}");
    let text = std::fs::read_to_string(target.join("timings.json")).expect("timings.json");
    let v: serde_json::Value = serde_json::from_str(&text).expect("timings.json parses");
    let pinned = v["pinned_threads"]
        .as_bool()
        .expect("pinned_threads is a boolean");
    let threads = v["threads"].as_u64().expect("threads is a number");
    let files = tree(&target)
        .into_iter()
        .filter(|(p, _)| p != "timings.json")
        .collect();
    (files, pinned, threads)
}

#[test]
fn pinning_changes_no_file_and_timings_say_whether_it_ran() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let cpus = allowed_cpus();
    let (default, pinned, threads) = mesh(dir, "default", &[]);
    assert_eq!(threads as usize, cpus);
    #[cfg(target_os = "linux")]
    assert_eq!(pinned, cpus >= 2, "pinned by default with several CPUs");
    let (unpinned, p, _) = mesh(dir, "no_pin", &["--no-pin"]);
    assert!(!p, "--no-pin pins nothing");
    assert_eq!(default, unpinned, "the same files pinned or not");
    let (one, p, t) = mesh(dir, "one", &["--threads", "1"]);
    assert!(!p && t == 1, "one worker is not pinned");
    assert_eq!(default, one, "the same files on one thread");
    if cpus >= 2 {
        let more = (cpus + 1).to_string();
        let (more_files, p, _) = mesh(dir, "more", &["--threads", &more]);
        assert!(!p, "more workers than CPUs are not pinned");
        assert_eq!(default, more_files);
    }
    assert!(
        default.iter().any(|(p, _)| p == "mesh.vtu"),
        "every format was written"
    );
}
