//! `medial-blocks mesh` in exact mode (the default) and its flags: modes, clustering,
//! smoothing, `--compare-modes`, and exit code 2 for bad flag values.

use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .arg("mesh")
        .args(args)
        .output()
        .expect("binary runs")
}

/// `mesh` with `--quiet` and `args` succeeds and prints nothing (no note, no summary).
fn assert_quiet_is_silent(args: &[&str]) {
    let mut quiet = vec!["--quiet"];
    quiet.extend_from_slice(args);
    let q = run(&quiet);
    assert!(
        q.status.success() && q.stderr.is_empty() && q.stdout.is_empty(),
        "{q:?}"
    );
}

fn read_json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("file written")).expect("JSON")
}

#[test]
fn default_is_exact_and_compare_modes_writes_both() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let o = run(&[
        "-o",
        out,
        "--format",
        "json",
        "--cells",
        "6",
        "--compare-modes",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let modes = read_json(&dir.path().join("modes.json"));
    let dev = |m: &str| {
        modes[m]["max_wall_orthogonality_deviation_deg"]
            .as_f64()
            .unwrap()
    };
    assert!(dev("exact") < 1e-6, "{modes}");
    assert!(dev("paper") > 1.0, "{modes}");
    assert_eq!(modes["exact"]["inverted_cells"], 0);
    // The written mesh is the exact one.
    let report = read_json(&dir.path().join("report.json"));
    assert_eq!(report["cells"], modes["exact"]["cells"]);
}

#[test]
fn clustering_smoothing_and_paper_mode_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    for extra in [
        vec![
            "--first-height-rel",
            "0.01",
            "--growth",
            "1.15",
            "--smooth",
            "5",
        ],
        vec![
            "--first-height",
            "0.001",
            "--circle-clustering",
            "-1:0.01r:1.1",
            "--wall-cells",
            "0:20",
            "--cell-size",
            "0.05",
        ],
        vec!["--mode", "paper"],
    ] {
        let mut args = vec!["-o", out, "--format", "json", "-q"];
        args.extend(extra.iter().copied());
        let o = run(&args);
        assert!(
            o.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let report = read_json(&dir.path().join("report.json"));
        assert_eq!(report["inverted_cells"], 0, "{extra:?}");
    }
}

#[test]
fn bad_values_are_input_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    for bad in [
        vec!["--growth", "0.5"],
        vec!["--first-height", "-1"],
        vec!["--cell-size", "0"],
        vec!["--wall-cells", "3"],
        vec!["--wall-cells", "3:0"],
        vec!["--circle-clustering", "1:x"],
        vec!["--mode", "fancy"],
    ] {
        let mut args = vec!["-o", out, "--format", "json", "-q"];
        args.extend(bad.iter().copied());
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{bad:?}");
    }
}

#[test]
fn compare_modes_puts_per_mode_figures_in_report_json() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args(["-q", "mesh", "--cells", "4", "--compare-modes", "-o"])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let read = |n: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(n)).unwrap()).unwrap()
    };
    let report = read("report.json");
    let modes = read("modes.json");
    assert_eq!(report["modes"], modes);
    // The run itself is exact mode (the default): its figures are the top-level ones.
    assert_eq!(report["min_angle_deg"], modes["exact"]["min_angle_deg"]);
    assert_eq!(report["holes"], 7);
}

/// `report.json` names the geometry: exact on a co-circular lattice (collapsed vertices) and
/// on the built-in hexagon, paper with `--mode paper`; the hexagon's angles are within 3
/// degrees of 60/120.
#[test]
fn report_names_the_geometry_used() {
    let dir = tempfile::tempdir().unwrap();
    let lattice = dir.path().join("lattice.json");
    let o = Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args(["example", "square-lattice", "--holes", "9", "-o"])
        .arg(&lattice)
        .output()
        .expect("binary runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cases: [(Vec<&str>, &str); 3] = [
        (vec![lattice.to_str().unwrap()], "exact"),
        (vec![], "exact"),
        (vec!["--mode", "paper"], "paper"),
    ];
    for (k, (input, want)) in cases.iter().enumerate() {
        let out = dir.path().join(format!("out{k}"));
        let mut args = input.clone();
        args.extend([
            "-o",
            out.to_str().unwrap(),
            "--format",
            "json",
            "--cells",
            "4",
        ]);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = read_json(&out.join("report.json"));
        assert_eq!(r["geometry"], *want, "case {k}");
        if k == 0 {
            assert_eq!(r["cocircular_groups"].as_array().unwrap().len(), 4);
            assert_eq!(r["blocks"], 6 * 8 - 2 * 4);
        }
        if k == 1 {
            assert!(r["min_angle_deg"].as_f64().unwrap() >= 57.0, "{r}");
            assert!(r["max_angle_deg"].as_f64().unwrap() <= 123.0, "{r}");
        }
    }
}

/// When exact mode (the default) ends with the paper pipeline's geometry on a layout of one
/// or more holes (one hole: the template ring), the CLI says so on stderr (unless `--quiet`); never otherwise. Checked as
/// "note printed exactly when report.json says paper in exact mode", over cases that include
/// a fallback (a first cell height far below the coordinates' precision).
#[test]
fn a_fallback_to_paper_geometry_is_noted() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let one_hole = d.join("one.json");
    std::fs::write(
        &one_hole,
        r#"{"bounding": {"center": [0, 0], "radius": 4}, "holes": [{"center": [0.5, 0], "radius": 1}]}"#,
    )
    .unwrap();
    let one = one_hole.to_str().unwrap();
    let cases: [&[&str]; 7] = [
        &[],
        &["--first-height", "1e-20"],
        &["--mode", "paper"],
        &["--mode", "paper", "--first-height", "1e-20"],
        &[one],
        &[one, "--first-height", "1e-20"],
        &[one, "--mode", "paper"],
    ];
    let mut noted = 0;
    for (k, extra) in cases.iter().enumerate() {
        let out_dir = d.join(format!("o{k}"));
        let mut args = vec!["-o", out_dir.to_str().unwrap(), "--format", "json"];
        args.extend_from_slice(extra);
        let out = run(&args);
        assert!(out.status.success(), "{extra:?}: {out:?}");
        let report = read_json(&out_dir.join("report.json"));
        let paper = report["geometry"] == "paper";
        let exact_mode = !extra.contains(&"paper");
        let holes = report["holes"].as_u64().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let note = stderr.contains("note: exact mode fell back to the paper pipeline's geometry");
        assert_eq!(
            note,
            exact_mode && paper && holes >= 1,
            "{extra:?}: geometry {}, stderr {stderr}",
            report["geometry"]
        );
        noted += usize::from(note);
        // --quiet prints nothing, the note included.
        assert_quiet_is_silent(&args);
    }
    assert!(noted > 0, "some case fell back, so the note was seen");
}

/// One hole in exact mode (the default): the annulus on its medial loop, 8 blocks, walls
/// exactly orthogonal, and the clustering flags reach it (the template ring of paper mode
/// ignores them).
#[test]
fn one_hole_is_exact_and_clustered() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = d.join("one.json");
    std::fs::write(
        &input,
        r#"{"bounding": {"center": [0, 0], "radius": 10}, "holes": [{"center": [6, 2], "radius": 1}]}"#,
    )
    .unwrap();
    let input = input.to_str().unwrap();
    let mut cells = Vec::new();
    for (k, extra) in [
        vec![],
        vec!["--first-height", "0.002", "--growth", "1.1"],
        vec!["--mode", "paper"],
    ]
    .iter()
    .enumerate()
    {
        let out = d.join(format!("o{k}"));
        let mut args = vec![input, "-o", out.to_str().unwrap(), "--format", "json"];
        args.extend_from_slice(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = read_json(&out.join("report.json"));
        let paper = extra.contains(&"paper");
        assert_eq!(r["geometry"], if paper { "paper" } else { "exact" }, "{r}");
        assert_eq!(r["blocks"], if paper { 4 } else { 8 }, "{r}");
        assert_eq!(r["inverted_cells"], 0, "{r}");
        if !paper {
            let dev = r["max_wall_orthogonality_deviation_deg"].as_f64().unwrap();
            assert!(dev < 1e-6, "{r}");
        }
        cells.push(r["cells"].as_u64().unwrap());
    }
    // A first cell 0.002 thick needs more wall-normal cells than the default spacing.
    assert!(cells[1] > cells[0], "{cells:?}");
}

/// A domain without holes is the disk template: exact-mode wall options given for it are
/// named in a note on stderr (they do not apply), never printed without them or with
/// `--quiet`.
#[test]
fn wall_options_on_a_disk_are_noted() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let disk = d.join("disk.json");
    std::fs::write(
        &disk,
        r#"{"bounding": {"center": [0, 0], "radius": 2}, "holes": []}"#,
    )
    .unwrap();
    let disk = disk.to_str().unwrap();
    let note = "note: a domain without holes is meshed by the disk template";
    for (k, (extra, want)) in [
        (vec![], false),
        (vec!["--first-height", "0.01"], true),
        (vec!["--smooth", "3"], true),
        (vec!["--mode", "paper", "--cells", "4"], false),
    ]
    .into_iter()
    .enumerate()
    {
        let out = d.join(format!("o{k}"));
        let mut args = vec![disk, "-o", out.to_str().unwrap(), "--format", "json"];
        args.extend_from_slice(&extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(stderr.contains(note), want, "{extra:?}: {stderr}");
        assert_quiet_is_silent(&args);
    }
}

/// Two circles 1e-5 apart (2.5e-5 of their radius): exact mode's own counts keep cells about
/// square in the gap, thousands along its walls. A note on stderr says so, with the cell count
/// of report.json and the longest block side of connectivity.json; not with `--block-cells`,
/// not for a layout without such a gap, never with `--quiet`.
#[test]
fn a_nearly_touching_pair_notes_its_fine_gap() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let pair = d.join("pair.json");
    let (r, g) = (0.4f64, 1e-5f64);
    std::fs::write(
        &pair,
        format!(
            r#"{{"bounding": {{"center": [0, 0], "radius": 2}}, "holes": [
                {{"center": [{a}, 0], "radius": {r}}}, {{"center": [{b}, 0], "radius": {r}}}]}}"#,
            a = -(r + g / 2.0),
            b = r + g / 2.0
        ),
    )
    .unwrap();
    let pair = pair.to_str().unwrap();
    let note = "along one block side: exact mode keeps cells about square";
    let cases = [
        (pair, vec![], true),
        (pair, vec!["--block-cells", "16"], false),
        (pair, vec!["--mode", "paper"], false),
        ("", vec![], false),
    ];
    note_cases(d, &cases, note, |want, stderr, out| {
        let report = read_json(&out.join("report.json"));
        let conn = read_json(&out.join("connectivity.json"));
        let longest = conn["blocks"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|b| b["dims"].as_array().unwrap().iter())
            .map(|n| n.as_u64().unwrap())
            .max()
            .unwrap()
            - 1; // "dims" counts nodes
                 // The note appears exactly when a side reaches the threshold, and names the figures
                 // the files hold.
        assert_eq!(want, longest >= 2048, "{longest}");
        if want {
            let line = format!("note: {} cells, {longest} along one", report["cells"]);
            assert!(stderr.contains(&line), "{stderr}");
        }
    });
}

/// Runs `mesh [INPUT] -o DIR/oK --format json EXTRA...` for each case `(INPUT, EXTRA, want)`
/// (an empty INPUT: the built-in example): it succeeds, its stderr holds `note` exactly when
/// `want`, and with `--quiet` it prints nothing; `check(want, stderr, DIR/oK)` checks the
/// rest.
fn note_cases(
    d: &std::path::Path,
    cases: &[(&str, Vec<&str>, bool)],
    note: &str,
    mut check: impl FnMut(bool, &str, &std::path::Path),
) {
    for (k, (input, extra, want)) in cases.iter().enumerate() {
        let out = d.join(format!("o{k}"));
        let mut args = vec!["-o", out.to_str().unwrap(), "--format", "json"];
        if !input.is_empty() {
            args.insert(0, input);
        }
        args.extend_from_slice(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(stderr.contains(note), *want, "{extra:?}: {stderr}");
        check(*want, &stderr, &out);
        assert_quiet_is_silent(&args);
    }
}

/// A default target size that would exceed the node budget is coarsened, and the CLI says
/// so: a note on stderr naming both sizes and the cells of the mesh written, and
/// `report.json`'s `coarsened_cell_size` `[default, used]` (`null` when not coarsened, with
/// `--block-cells`, and for the built-in example); nothing with `--quiet`.
#[test]
fn a_coarsened_default_size_is_noted_and_reported() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let two = d.join("two.json");
    std::fs::write(
        &two,
        r#"{"bounding":{"center":[0,0],"radius":10},"holes":[{"center":[0.5,0],"radius":0.0001},{"center":[0.5003,2e-05],"radius":8e-05}]}"#,
    )
    .unwrap();
    let two = two.to_str().unwrap();
    let note = "so it was coarsened to";
    let cases = [
        (two, vec![], true),
        (two, vec!["--block-cells", "8"], false),
        ("", vec![], false),
    ];
    note_cases(d, &cases, note, |want, stderr, out| {
        let report = read_json(&out.join("report.json"));
        let sizes = &report["coarsened_cell_size"];
        if want {
            let (from, to) = (sizes[0].as_f64().unwrap(), sizes[1].as_f64().unwrap());
            assert!(to > from && from > 0.0, "{sizes}");
            assert!(
                stderr.contains(&format!("({} cells)", report["cells"])),
                "{stderr}"
            );
            assert!(stderr.contains(&format!("{to:.4e}")), "{stderr}");
            let budget = medial_blocks::exact_mode::node_budget(
                report["blocks"].as_u64().unwrap() as usize,
                16,
            );
            assert!(report["nodes"].as_u64().unwrap() as usize <= budget);
        } else {
            assert!(sizes.is_null(), "{sizes}");
        }
    });
}
