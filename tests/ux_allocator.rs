//! The CLI's malloc tuning (issue 8, `src/cli/allocator.rs`): with `--huge-pages`, where the
//! kernel gives transparent huge pages on request, the tool starts itself again with
//! `GLIBC_TUNABLES=glibc.malloc.hugetlb=1:...`. These tests check that this changes nothing a
//! user can see but the speed: the same files byte for byte, the same arguments (odd bytes
//! included), exit codes, messages and standard input; that it is off without the flag and
//! with a user's own malloc settings; and that `timings.json` says which way it ran.

use crate::common;

use common::{bin, tree};
use std::path::Path;
use std::process::{Output, Stdio};

/// Whether this kernel gives huge pages on request, the only case where `--huge-pages`
/// restarts the tool.
fn kernel_madvise() -> bool {
    cfg!(all(target_os = "linux", target_env = "gnu"))
        && std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled")
            .is_ok_and(|s| s.contains("[madvise]"))
}

/// The binary without the malloc tuning variables of the test's own environment.
fn untuned_bin() -> std::process::Command {
    let mut c = bin();
    c.env_remove("GLIBC_TUNABLES")
        .env_remove("MEDIAL_BLOCKS_HUGE_PAGES")
        .env_remove("MALLOC_TRIM_THRESHOLD_")
        .env_remove("MALLOC_TOP_PAD_")
        .env_remove("MALLOC_MMAP_THRESHOLD_");
    c
}

/// Run the CLI with `env` added (and the tuning variables of the test's own environment
/// removed, so the default case is the default).
fn run_with(args: &[&std::ffi::OsStr], env: &[(&str, &str)]) -> Output {
    let mut c = untuned_bin();
    for (k, v) in env {
        c.env(k, v);
    }
    c.args(args)
        .output()
        .expect("the medial-blocks binary runs")
}

fn os(s: &str) -> &std::ffi::OsStr {
    std::ffi::OsStr::new(s)
}

/// `huge_pages` of `dir/timings.json`.
fn huge_pages_flag(dir: &Path) -> bool {
    let text = std::fs::read_to_string(dir.join("timings.json")).expect("timings.json");
    let v: serde_json::Value = serde_json::from_str(&text).expect("timings.json parses");
    v["huge_pages"].as_bool().expect("huge_pages is a boolean")
}

/// Mesh the lattice example with every format, with `huge` (`--huge-pages`) or not; the tree
/// without timings.json and the `huge_pages` flag of timings.json.
fn mesh_all(dir: &Path, huge: bool) -> (Vec<(String, Vec<u8>)>, bool) {
    let layout = dir.join("lattice.json");
    if !layout.exists() {
        let out = run_with(
            &[
                os("example"),
                os("lattice"),
                os("-o"),
                layout.as_os_str(),
                os("--quiet"),
            ],
            &[],
        );
        assert!(out.status.success(), "{out:?}");
    }
    let target = dir.join(format!("out{huge}"));
    let mut args = vec![
        os("--quiet"),
        os("mesh"),
        layout.as_os_str(),
        os("-o"),
        target.as_os_str(),
        os("--format"),
        os("all"),
        os("--timings"),
    ];
    if huge {
        args.push(os("--huge-pages"));
    }
    let out = run_with(&args, &[]);
    assert!(out.status.success(), "{out:?}");
    assert!(out.stdout.is_empty() && out.stderr.is_empty(), "{out:?}");
    let flag = huge_pages_flag(&target);
    std::fs::remove_file(target.join("timings.json")).unwrap();
    (tree(&target), flag)
}

/// Huge pages on (where the kernel allows) or off, every file is the same, and
/// `timings.json` says which way the run went.
#[test]
fn huge_pages_change_no_file_and_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let (default, on) = mesh_all(dir.path(), true);
    let (off, flag_off) = mesh_all(dir.path(), false);
    assert_eq!(
        on,
        kernel_madvise(),
        "huge pages used exactly when the kernel offers them"
    );
    assert!(!flag_off, "normal pages without --huge-pages");
    assert!(
        default.len() > 5,
        "every format wrote files: {}",
        default.len()
    );
    assert_eq!(default.len(), off.len());
    for (a, b) in default.iter().zip(&off) {
        assert_eq!(a.0, b.0);
        assert!(a.1 == b.1, "{} differs between huge and normal pages", a.0);
    }
}

/// A user's own malloc settings are left alone: no restart, so no huge pages from the tool.
#[test]
fn user_malloc_settings_are_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    for env in [
        [("GLIBC_TUNABLES", "glibc.malloc.tcache_count=7")],
        [("MALLOC_TOP_PAD_", "1048576")],
        [("MALLOC_TRIM_THRESHOLD_", "131072")],
        [("MALLOC_MMAP_THRESHOLD_", "131072")],
        // The tool's own marker without its tunables (a restart whose environment was
        // stripped) must not restart again.
        [("MEDIAL_BLOCKS_HUGE_PAGES", "on")],
    ] {
        let out_dir = dir.path().join(env[0].0);
        let out = run_with(
            &[
                os("--huge-pages"),
                os("--quiet"),
                os("mesh"),
                os("-o"),
                out_dir.as_os_str(),
                os("--format"),
                os("json"),
                os("--timings"),
            ],
            &env,
        );
        assert!(out.status.success(), "{env:?}: {out:?}");
        assert!(!huge_pages_flag(&out_dir), "{env:?} turned huge pages on");
    }
}

/// The restart passes every argument through unchanged, odd bytes included.
#[cfg(unix)]
#[test]
fn restart_keeps_arguments_byte_for_byte() {
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    // Not UTF-8, a space, a non-ASCII letter and a leading dash inside the name.
    let name = std::ffi::OsStr::from_bytes(b"out\xff -dir \xc3\xa9");
    let target = dir.path().join(name);
    let out = run_with(
        &[
            os("--quiet"),
            os("mesh"),
            os("-o"),
            target.as_os_str(),
            os("--format"),
            os("json"),
            os("--timings"),
            os("--huge-pages"),
        ],
        &[],
    );
    assert!(out.status.success(), "{out:?}");
    assert!(
        target.join("report.json").is_file(),
        "written under the odd name"
    );
    assert_eq!(huge_pages_flag(&target), kernel_madvise(), "and restarted");
}

/// Exit codes and messages are those of a run with normal pages; standard input reaches
/// the restarted process.
#[cfg(target_os = "linux")]
#[test]
fn restart_keeps_exit_codes_messages_and_stdin() {
    let cases: [&[&str]; 3] = [
        &["mesh", "/nonexistent/layout.json"],
        &["mesh", "--bogus-flag"],
        &["--threads", "0", "mesh"],
    ];
    for args in cases {
        let b: Vec<&std::ffi::OsStr> = args.iter().map(|a| os(a)).collect();
        let a: Vec<&std::ffi::OsStr> = std::iter::once(os("--huge-pages"))
            .chain(b.iter().copied())
            .collect();
        let (a, b) = (run_with(&a, &[]), run_with(&b, &[]));
        assert_eq!(a.status.code(), Some(2), "{args:?}: {a:?}");
        assert_eq!(a.status.code(), b.status.code(), "{args:?}");
        assert_eq!(a.stderr, b.stderr, "{args:?}");
        assert!(!a.stderr.is_empty());
        assert_eq!(a.stdout, b.stdout, "{args:?}");
    }
    // Points on standard input, read through its path.
    let points = "0,0\n1,0\n0,1\n1,1\n0.5,0.25\n";
    let mut outs = Vec::new();
    for huge in [true, false] {
        let mut c = untuned_bin();
        if huge {
            c.arg("--huge-pages");
        }
        let mut child = c
            .args(["triangulate", "/dev/stdin"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        use std::io::Write;
        child
            .stdin
            .take()
            .unwrap()
            .write_all(points.as_bytes())
            .unwrap();
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success(), "{out:?}");
        outs.push(out.stdout);
    }
    assert!(!outs[0].is_empty());
    assert_eq!(outs[0], outs[1], "the same triangles through the restart");
}
