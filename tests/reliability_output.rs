//! A failed `mesh` run never leaves a complete-looking mesh: `output::write_files` stages every
//! file in `DIR/.medial-blocks-staging-PID/` and moves them into place at the end,
//! `report.json` last, removing the staging directory on error.

use medial_blocks::output::{staging_dir, write_files, Format};
use medial_blocks::{mesh, Domain, Options};
use std::path::{Path, PathBuf};
use std::process::Command;

fn hexagon_mesh() -> medial_blocks::Mesh {
    mesh(
        &Domain::hexagon_example(),
        &Options {
            cells: 4,
            ..Options::default()
        },
    )
    .expect("mesh")
}

/// Every path under `dir`, relative.
fn tree(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(dir.join(&rel)) else {
            continue;
        };
        for e in entries.flatten() {
            let p = rel.join(e.file_name());
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                stack.push(p.clone());
            }
            out.push(p);
        }
    }
    out.sort();
    out
}

fn assert_no_leftovers(dir: &Path) {
    for p in tree(dir) {
        let s = p.to_string_lossy();
        assert!(
            !s.contains(".medial-blocks-staging") && !s.ends_with(".tmp"),
            "left behind: {s}"
        );
    }
}

#[test]
fn success_publishes_everything_and_leaves_no_staging() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    write_files(&hexagon_mesh(), &out, &Format::parse_list("all").unwrap()).unwrap();
    for f in [
        "report.json",
        "connectivity.json",
        "mesh.vtm",
        "mesh/block_0035.vts",
        "mesh.xyz",
        "mesh.p3d",
        "mesh.msh",
        "mesh.geo",
        "mesh.svg",
        "mesh.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert!(!staging_dir(&out).exists());
    assert_no_leftovers(&out);
}

#[test]
fn failure_midway_leaves_no_report_and_no_staging() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let m = hexagon_mesh();
    // A first, complete run.
    write_files(&m, &out, &[Format::Vtk, Format::Json]).unwrap();
    assert!(out.join("report.json").is_file());
    // Make `mesh/` a regular file: the VTK block files cannot be moved into place.
    std::fs::remove_dir_all(out.join("mesh")).unwrap();
    std::fs::write(out.join("mesh"), "in the way").unwrap();
    let e = write_files(&m, &out, &[Format::Vtk, Format::Json]);
    assert!(e.is_err());
    // The old report (which would now describe files that are not all there) is gone, the new
    // one was never published, and no staging or temporary file remains.
    assert!(!out.join("report.json").exists());
    assert!(!staging_dir(&out).exists());
    assert_no_leftovers(&out);
    // A fresh directory with the same obstacle: no report.json at all.
    let out2 = tmp.path().join("out2");
    std::fs::create_dir(&out2).unwrap();
    std::fs::write(out2.join("mesh"), "in the way").unwrap();
    assert!(write_files(&m, &out2, &Format::parse_list("all").unwrap()).is_err());
    assert!(!out2.join("report.json").exists());
    assert_no_leftovers(&out2);
}

#[test]
fn cli_failure_midway_exits_1_without_report() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("mesh"), "in the way").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args(["mesh", "--cells", "4", "--format", "vtk,json", "-q", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot write into"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.join("report.json").exists());
    assert_no_leftovers(&out);
}

/// A reader that stops early (`medial-blocks mesh ... | head -1`) ends the run as it ends
/// `cat`: no panic, no backtrace, and the files (written before the summary) complete. Rust
/// ignores `SIGPIPE`, so the summary's `println!` used to panic with "failed printing to
/// stdout: Broken pipe".
#[cfg(unix)]
#[test]
fn a_closed_stdout_pipe_ends_the_run_without_a_panic() {
    use std::io::Read;
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    for args in [
        vec!["mesh", "--cells", "4", "--format", "json", "-o"],
        vec!["example", "bubbles", "--holes", "20000"],
    ] {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_medial-blocks"));
        cmd.args(&args);
        if args[0] == "mesh" {
            cmd.arg(&out);
        }
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Read one byte, then close our end of the pipe, as `head -c 1` does.
        let mut stdout = child.stdout.take().unwrap();
        let mut first = [0u8; 1];
        stdout.read_exact(&mut first).unwrap();
        drop(stdout);
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(
            o.status.success() || o.status.signal() == Some(libc::SIGPIPE),
            "{args:?}: {:?} {err}",
            o.status
        );
    }
    // The mesh run's files are complete: the report parses.
    let report = std::fs::read_to_string(out.join("report.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&report).unwrap();
    assert!(v["cells"].as_u64().unwrap() > 0);
}

/// A first run into a directory moves the staged `mesh/` of block files in with one rename;
/// a later run exchanges a `mesh/` holding only files it replaces in one step (on Linux: the
/// directory itself is then the new one), and one that holds anything more (a stale block
/// file of an earlier, larger mesh, a user's file) file by file, so the rest stays; the block
/// files are the same bytes every time.
#[test]
fn a_new_block_directory_moves_in_whole_and_an_existing_one_keeps_its_other_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let m = hexagon_mesh();
    let vtk = Format::parse_list("vtk").unwrap();
    write_files(&m, &out, &vtk).unwrap();
    assert_no_leftovers(&out);
    let blocks: Vec<Vec<u8>> = (0..m.layout.blocks.len())
        .map(|b| std::fs::read(out.join(format!("mesh/block_{b:04}.vts"))).unwrap())
        .collect();
    let files = |dir: &Path| std::fs::read_dir(dir.join("mesh")).unwrap().count();
    let same_blocks = |when: &str| {
        for (b, want) in blocks.iter().enumerate() {
            let got = std::fs::read(out.join(format!("mesh/block_{b:04}.vts"))).unwrap();
            assert!(&got == want, "block {b} differs {when}");
        }
    };
    assert_eq!(files(&out), blocks.len(), "exactly the block files");
    // The directory's identity tells the whole exchange from the file-by-file replacement.
    #[cfg(target_os = "linux")]
    let dir_id = || {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata(out.join("mesh")).unwrap().ino()
    };
    // Only the files the run replaces: exchanged whole on Linux.
    #[cfg(target_os = "linux")]
    let before = dir_id();
    write_files(&m, &out, &vtk).unwrap();
    assert_no_leftovers(&out);
    #[cfg(target_os = "linux")]
    assert_ne!(dir_id(), before, "mesh/ was not exchanged whole");
    assert_eq!(files(&out), blocks.len());
    same_blocks("after the whole exchange");
    // A stale block file and a user's file: replaced file by file, both stay.
    std::fs::write(out.join("mesh/notes.txt"), b"mine").unwrap();
    std::fs::write(out.join("mesh/block_9999.vts"), b"old").unwrap();
    #[cfg(target_os = "linux")]
    let before = dir_id();
    write_files(&m, &out, &vtk).unwrap();
    assert_no_leftovers(&out);
    #[cfg(target_os = "linux")]
    assert_eq!(
        dir_id(),
        before,
        "mesh/ with other files was replaced whole"
    );
    assert_eq!(std::fs::read(out.join("mesh/notes.txt")).unwrap(), b"mine");
    assert_eq!(
        std::fs::read(out.join("mesh/block_9999.vts")).unwrap(),
        b"old"
    );
    assert_eq!(files(&out), blocks.len() + 2);
    same_blocks("between the two runs");
}
