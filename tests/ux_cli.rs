//! The CLI contract, run on the built binary: file names, `example`, exit codes, thread-count
//! independence, help texts.

use crate::common;

use common::{run, tree};
use medial_blocks::Domain;
use std::collections::BTreeSet;
use std::path::Path;

/// The relative paths of every file under `dir`.
fn files(dir: &Path) -> BTreeSet<String> {
    tree(dir).into_iter().map(|(name, _)| name).collect()
}

#[test]
fn format_all_writes_exactly_the_contract_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = run(&[
        "mesh",
        "-o",
        out.to_str().unwrap(),
        "--cells",
        "2",
        "--format",
        "all",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got = files(&out);
    let mut want: BTreeSet<String> = [
        "mesh.vtm",
        "mesh.vtu",
        "mesh.xyz",
        "mesh.p3d",
        "mesh.msh",
        "mesh.geo",
        "mesh.svg",
        "mesh.png",
        "connectivity.json",
        "report.json",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if cfg!(feature = "cgns") {
        want.insert("mesh.cgns".into());
    }
    for b in 0..36 {
        want.insert(format!("mesh/block_{b:04}.vts"));
    }
    assert_eq!(got, want);
    // The summary table names every metric.
    let stdout = String::from_utf8_lossy(&o.stdout);
    for m in [
        "angle_deg",
        "equiangle_skewness",
        "scaled_jacobian",
        "interface_growth_ratio",
    ] {
        assert!(stdout.contains(m), "{stdout}");
    }
}

#[test]
fn default_formats_and_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    let o = run(&["mesh", "-q", "-o", out.to_str().unwrap(), "--cells", "2"]);
    assert!(o.status.success());
    assert!(o.stdout.is_empty() && o.stderr.is_empty());
    let got = files(&out);
    assert!(got.contains("mesh.vtm") && got.contains("mesh.svg") && got.contains("report.json"));
    assert!(!got.contains("mesh.vtu") && !got.contains("mesh.msh"));
}

#[test]
fn thread_count_does_not_change_the_output() {
    let dir = tempfile::tempdir().unwrap();
    let mut trees = Vec::new();
    for t in ["1", "2"] {
        let out = dir.path().join(format!("t{t}"));
        let o = run(&[
            "--threads",
            t,
            "mesh",
            "-q",
            "-o",
            out.to_str().unwrap(),
            "--cells",
            "3",
            "--format",
            "vtk,vtu,plot3d,gmsh,svg,json",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        trees.push(tree(&out));
    }
    assert!(!trees[0].is_empty());
    assert!(
        trees[0] == trees[1],
        "outputs differ between --threads 1 and 2"
    );
}

#[test]
fn example_layouts_are_accepted_by_mesh() {
    let dir = tempfile::tempdir().unwrap();
    for (kind, extra, count) in [
        ("hexagon", vec![], 7),
        ("lattice", vec![], 21),
        ("bubbles", vec!["--holes", "12", "--seed", "5"], 12),
        ("square-lattice", vec!["--holes", "10"], 9),
    ] {
        let file = dir.path().join(format!("{kind}.json"));
        let mut args = vec!["example", kind, "-o", file.to_str().unwrap()];
        args.extend(&extra);
        let o = run(&args);
        assert!(
            o.status.success(),
            "{kind}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let text = std::fs::read_to_string(&file).unwrap();
        let d = Domain::from_json_str(&text).unwrap();
        assert_eq!(d.hole_count(), count, "{kind}");
        // Standard output gives the same JSON.
        let mut args = vec!["example", kind];
        args.extend(&extra);
        let o = run(&args);
        assert!(o.status.success());
        assert_eq!(String::from_utf8(o.stdout).unwrap(), text, "{kind}");
        let out = dir.path().join(format!("{kind}_out"));
        let o = run(&[
            "mesh",
            file.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
            "--cells",
            "2",
            "--format",
            "json",
        ]);
        assert!(
            o.status.success(),
            "{kind}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
                .unwrap();
        assert_eq!(report["holes"], count as u64, "{kind}");
    }
}

#[test]
fn bad_input_exits_2_and_output_failure_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = run(&["mesh", "-o", out.to_str().unwrap(), "--format", "vtk,nope"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("unknown format 'nope'"), "{err}");
    assert!(!out.exists());

    let o = run(&["--threads", "0", "mesh", "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&["example", "hexagon", "--holes", "5"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("fixed"));

    // The output "directory" is below a regular file: cannot be created.
    let file = dir.path().join("a_file");
    std::fs::write(&file, "x").unwrap();
    let bad = file.join("sub");
    let o = run(&["mesh", "-o", bad.to_str().unwrap(), "--cells", "2"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: "));
    let o = run(&[
        "example",
        "lattice",
        "-o",
        bad.join("x.json").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));

    if !cfg!(feature = "cgns") {
        let o = run(&["mesh", "-o", out.to_str().unwrap(), "--format", "cgns"]);
        assert_eq!(o.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&o.stderr).contains("--features cgns"));
    }
}

#[test]
fn every_help_has_examples() {
    for sub in [vec![], vec!["mesh"], vec!["triangulate"], vec!["example"]] {
        let mut args = sub.clone();
        args.push("--help");
        let o = run(&args);
        assert!(o.status.success(), "{sub:?}");
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("Examples:"), "{sub:?}: {text}");
        assert!(
            text.lines()
                .any(|l| l.trim_start().starts_with("medial-blocks ")),
            "{sub:?}: {text}"
        );
    }
    let o = run(&["--help"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("--threads") && text.contains("--quiet") && text.contains("Exit codes"));
}
