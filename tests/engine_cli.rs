//! The `triangulate` command's contract: CSV in, JSON out, exit codes (2 bad input, 1 output).

use std::io::Write;
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .arg("triangulate")
        .args(args)
        .output()
        .expect("binary runs")
}

fn csv(content: &str) -> tempfile::NamedTempFile {
    let mut f = tempfile::NamedTempFile::new().expect("temp file");
    f.write_all(content.as_bytes()).expect("write");
    f
}

fn json(out: &[u8]) -> serde_json::Value {
    serde_json::from_slice(out).expect("valid JSON")
}

#[test]
fn square_with_header_blank_lines_and_duplicate() {
    let f = csv("x,y\n 0, 0\n\n1,0\n1 ,1\n0,1\n1,0\n");
    let out = run(&[f.path().to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&out.stdout);
    assert_eq!(v["triangles"].as_array().unwrap().len(), 2);
    assert_eq!(v["duplicates"], serde_json::json!([[1, 4]]));
    assert_eq!(v["cocircular_groups"], serde_json::json!([[0, 1, 2, 3]]));
    for t in v["triangles"].as_array().unwrap() {
        let t: Vec<u64> = t
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap())
            .collect();
        assert!(
            t[0] < t[1] && t[0] < t[2],
            "rotated to smallest first: {t:?}"
        );
    }
}

#[test]
fn output_file_and_builtin_example() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.json");
    let out = run(&["-o", path.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty());
    let v = json(&std::fs::read(&path).unwrap());
    assert!(v["triangles"].as_array().unwrap().len() > 100);
    assert_eq!(v["duplicates"], serde_json::json!([[9, 64]]));
    let groups = v["cocircular_groups"].as_array().unwrap();
    let circle: Vec<u64> = (65..77).collect();
    assert!(groups.iter().any(|g| g
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .eq(circle.iter().copied())));
}

fn expect_input_error(content: &str, needle: &str) {
    let f = csv(content);
    let out = run(&[f.path().to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{content:?}: {err}");
    assert!(
        err.contains(needle),
        "{content:?}: stderr {err:?} lacks {needle:?}"
    );
}

#[test]
fn malformed_input_exits_2_naming_the_line() {
    expect_input_error("0,0\n1,0\n1,abc\n", ":3:");
    expect_input_error("x,y\n0,0\n1,0,2\n", ":3:");
    expect_input_error("0,0\n1\n", ":2:");
    expect_input_error("0,0\n1,0\nnan,1\n", ":3:");
    expect_input_error("", "no points");
    expect_input_error("x,y\n\n", "no points");
    expect_input_error("0,0\n1,1\n0,0\n", "3 distinct");
    expect_input_error("0,0\n1,1\n2,2\n", "collinear");
}

#[test]
fn unreadable_input_exits_2_and_unwritable_output_exits_1() {
    let out = run(&["/nonexistent/points.csv"]);
    assert_eq!(out.status.code(), Some(2));
    let f = csv("0,0\n1,0\n0,1\n");
    let out = run(&[
        f.path().to_str().unwrap(),
        "-o",
        "/nonexistent/dir/out.json",
    ]);
    assert_eq!(out.status.code(), Some(1));
}
