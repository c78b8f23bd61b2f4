//! Helpers shared by the integration tests: `mod common;` at the top of a test file.
//!
//! Each test file is its own crate and uses only some of these, hence `dead_code` allowed.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// The built `medial-blocks` binary, ready for arguments.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
}

/// Run the binary with `args` and collect its output.
pub fn run(args: &[&str]) -> Output {
    bin()
        .args(args)
        .output()
        .expect("the medial-blocks binary runs")
}

/// Every file under `dir` as (path relative to `dir` with `/` separators, bytes), sorted by
/// path: two trees are byte-identical exactly when their `tree`s are equal.
pub fn tree(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("readable directory") {
            let p = e.expect("directory entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p
                    .strip_prefix(dir)
                    .expect("under dir")
                    .to_string_lossy()
                    .replace('\\', "/");
                out.push((rel, std::fs::read(&p).expect("readable file")));
            }
        }
    }
    out.sort();
    out
}
