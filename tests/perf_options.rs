//! Issue #8's options: `Options::block_cells` / `--block-cells N` (an `N x N` grid per block in
//! exact mode) and `--timings` / `mesh_timed` (per-stage wall time, never in other outputs).
//!
//! Oracles: block sizes against the wall sweeps of the layout (15 degrees per cell), conformity
//! from node coordinates alone, byte comparison of whole output directories, and an O(n^2)
//! re-check of the bubble generator.

use crate::common;

use common::{run as cli, tree};
use medial_blocks::grid::{GridError, MAX_CELLS_PER_SIDE};
use medial_blocks::layout::Curve;
use medial_blocks::mesher::mesh_timed;
use medial_blocks::timings::STAGES;
use medial_blocks::{layouts, mesh, Domain, Mesh, MeshError, Mode, Options};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

const WALL_ANGLE_DEG: f64 = 15.0;

fn block_cells(n: usize) -> Options {
    Options {
        block_cells: Some(n),
        ..Options::default()
    }
}

fn domains() -> Vec<(String, Domain)> {
    let mut v = vec![
        ("hexagon".to_string(), layouts::hexagon()),
        ("lattice".to_string(), layouts::lattice().unwrap()),
    ];
    for seed in 1..=3 {
        v.push((
            format!("bubbles(40, {seed})"),
            layouts::bubbles(40, seed).unwrap(),
        ));
    }
    v
}

/// |sweep| in degrees of block `b`'s wall (side 0), 0 when it is not an arc.
fn wall_sweep_deg(m: &Mesh, b: usize) -> f64 {
    let side = m.layout.blocks[b].sides[0];
    match m.layout.edges[side.edge as usize].curve {
        Curve::Arc { sweep, .. } => sweep.abs().to_degrees(),
        _ => 0.0,
    }
}

/// The other block whose side 2 is the same edge (the arc's partner), if any.
fn partner(m: &Mesh, b: usize) -> Option<usize> {
    let e = m.layout.blocks[b].sides[2].edge;
    (0..m.layout.blocks.len()).find(|&o| o != b && m.layout.blocks[o].sides[2].edge == e)
}

/// The bit patterns of a side's two end nodes, sorted.
type Ends = [(u64, u64); 2];

fn bits(p: [f64; 2]) -> (u64, u64) {
    (p[0].to_bits(), p[1].to_bits())
}

/// Every spoke and arc side (1, 2, 3) of every block equals, node for node and bit for bit,
/// exactly one side of another block (in reverse or in the same direction), found from the
/// coordinates of its end nodes alone.
fn assert_conforming(m: &Mesh, what: &str) {
    let mut by_ends: HashMap<Ends, Vec<(usize, usize)>> = HashMap::new();
    for (b, g) in m.grids.iter().enumerate() {
        for k in 0..4 {
            let s = g.side(k);
            let mut ends = [bits(s[0]), bits(s[s.len() - 1])];
            ends.sort();
            by_ends.entry(ends).or_default().push((b, k));
        }
    }
    for (b, g) in m.grids.iter().enumerate() {
        for k in 1..4 {
            let s = g.side(k);
            let mut ends = [bits(s[0]), bits(s[s.len() - 1])];
            ends.sort();
            let matches: Vec<(usize, usize)> = by_ends[&ends]
                .iter()
                .filter(|&&(o, _)| o != b)
                .filter(|&&(o, ok)| {
                    let t = m.grids[o].side(ok);
                    let rev: Vec<[f64; 2]> = t.iter().rev().copied().collect();
                    let same = |u: &[[f64; 2]]| {
                        u.len() == s.len() && u.iter().zip(&s).all(|(p, q)| bits(*p) == bits(*q))
                    };
                    same(&t) || same(&rev)
                })
                .copied()
                .collect();
            assert_eq!(
                matches.len(),
                1,
                "{what}: side {k} of block {b} matches {matches:?} (ni {}, nj {})",
                g.ni,
                g.nj
            );
        }
    }
}

#[test]
fn block_cells_gives_n_by_n_raised_only_by_long_walls() {
    let _turn = common::turn();
    let mut exact_layouts = 0;
    for (name, d) in domains() {
        for n in [4usize, 16] {
            let m = mesh(&d, &block_cells(n)).unwrap_or_else(|e| panic!("{name}: {e}"));
            let limit = n as f64 * WALL_ANGLE_DEG;
            let mut raised = 0;
            for (b, g) in m.grids.iter().enumerate() {
                let what = format!("{name}, N = {n}, block {b}");
                assert_eq!(g.nj, n, "{what}: spokes");
                assert!(g.ni >= n, "{what}: ni {}", g.ni);
                let own = wall_sweep_deg(&m, b);
                let other = partner(&m, b).map_or(0.0, |o| wall_sweep_deg(&m, o));
                // Raised only where a wall needs more than N cells of 15 degrees ...
                if g.ni > n {
                    raised += 1;
                    assert!(own + other > limit - 1e-6, "{what}: {own} + {other} deg");
                }
                // ... and always there.
                if own.max(other) > limit + 1e-6 {
                    assert!(g.ni > n, "{what}: wall of {own} deg in {} cells", g.ni);
                }
            }
            let no_long_wall = (0..m.grids.len()).all(|b| {
                wall_sweep_deg(&m, b) + partner(&m, b).map_or(0.0, |o| wall_sweep_deg(&m, o))
                    <= limit
            });
            if no_long_wall {
                exact_layouts += 1;
                eprintln!("{name}, N = {n}: every block {n} x {n}");
                assert_eq!(raised, 0, "{name}, N = {n}");
                assert!(m.grids.iter().all(|g| g.ni == n && g.nj == n));
                let cells: usize = m.grids.iter().map(|g| g.cells()).sum();
                assert_eq!(cells, n * n * m.layout.blocks.len());
            }
        }
    }
    // The precondition holds for the lattice at N = 16 (a bubble next to the bounding circle
    // has a long wall, and so has an outer hole of the tight built-in hexagon).
    assert!(exact_layouts >= 1, "{exact_layouts}");
}

#[test]
fn block_cells_meshes_conform_from_coordinates() {
    let _turn = common::turn();
    for (name, d) in domains() {
        for n in [3usize, 8] {
            let m = mesh(&d, &block_cells(n)).unwrap();
            assert_eq!(m.grids.len(), m.layout.blocks.len());
            assert_conforming(&m, &format!("{name}, N = {n}"));
            medial_blocks::fuzzing::check_mesh(&d, &m).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}

#[test]
fn block_cells_is_refused_out_of_range_or_with_other_counts() {
    let _turn = common::turn();
    let d = layouts::hexagon();
    assert!(matches!(
        mesh(&d, &block_cells(0)),
        Err(MeshError::Options(_))
    ));
    assert!(matches!(
        mesh(&d, &block_cells(MAX_CELLS_PER_SIDE + 1)),
        Err(MeshError::Grid(GridError::TooManyCellsPerSide { .. }))
    ));
    let with_size = Options {
        cell_size: Some(0.1),
        ..block_cells(8)
    };
    assert!(matches!(mesh(&d, &with_size), Err(MeshError::Options(_))));
    let with_wall = Options {
        wall_cells: vec![(0, 3)],
        ..block_cells(8)
    };
    assert!(matches!(mesh(&d, &with_wall), Err(MeshError::Options(_))));
    // Also for the disk and the annulus (template paths).
    let disk = Domain::bounded(medial_blocks::Circle::new(0.0, 0.0, 1.0), vec![]).unwrap();
    assert!(matches!(
        mesh(&disk, &block_cells(0)),
        Err(MeshError::Options(_))
    ));
}

#[test]
fn block_cells_in_paper_mode_means_cells() {
    let _turn = common::turn();
    let d = layouts::hexagon();
    let a = mesh(
        &d,
        &Options {
            mode: Mode::Paper,
            block_cells: Some(7),
            ..Options::default()
        },
    )
    .unwrap();
    let b = mesh(
        &d,
        &Options {
            mode: Mode::Paper,
            cells: 7,
            ..Options::default()
        },
    )
    .unwrap();
    assert_eq!(a.grids, b.grids);
    assert_eq!(a.layout, b.layout);
}

/// The spans of a library run: per stage as many as its calls, adding up to its row; every
/// check of the exact build but the first is a rework check, and each rebuild it checks
/// started with a recollapse or a resampling (a `blocking` or `sampling` span since the check
/// before), never a rebuild of an unchanged collapse. Bubbles at 1e3, a size whose exact build
/// has local-fix rounds, and a small layout.
#[test]
fn spans_add_up_and_every_rebuild_follows_a_recollapse() {
    let _turn = common::turn();
    for (n, seed) in [(1000, 1), (30, 7)] {
        let d = layouts::bubbles(n, seed).unwrap();
        let (_, t) = mesh_timed(&d, &block_cells(16)).unwrap();
        common::assert_spans_add_up(&t.to_json());
        let checks: Vec<usize> = (0..t.spans.len())
            .filter(|&i| t.spans[i].stage == "quality_check")
            .collect();
        assert!(!checks.is_empty(), "{n}: no check");
        assert_eq!(t.rework().checks, checks.len() - 1, "{n}");
        for w in checks.windows(2) {
            let between = &t.spans[w[0] + 1..w[1]];
            assert!(
                between
                    .iter()
                    .any(|s| s.stage == "blocking" || s.stage == "sampling"),
                "{n}: a rebuild without a recollapse: {:?}",
                between.iter().map(|s| &s.stage).collect::<Vec<_>>()
            );
        }
        let after: f64 = t.spans[checks[0] + 1..]
            .iter()
            .filter(|s| s.stage != "quality")
            .map(|s| s.seconds)
            .sum();
        assert!(t.rework().seconds <= after + 1e-12, "{n}");
    }
}

#[test]
fn mesh_timed_is_mesh_and_times_every_stage() {
    let _turn = common::turn();
    let d = layouts::bubbles(30, 7).unwrap();
    let opts = block_cells(6);
    let plain = mesh(&d, &opts).unwrap();
    let (timed, t) = mesh_timed(&d, &opts).unwrap();
    assert_eq!(plain.grids, timed.grids);
    assert_eq!(plain.layout, timed.layout);
    // Every stage exact mode runs was entered.
    for s in [
        "sampling",
        "triangulation",
        "medial_graph",
        "blocking",
        "exact_geometry",
        "node_counts",
        "grids",
        "quality_check",
    ] {
        assert!(t.stages.iter().any(|(n, _)| n == s), "{s} missing: {t:?}");
    }
    assert!(t.stages.iter().all(|(_, x)| x.is_finite() && *x >= 0.0));
    let sum: f64 = t.stages.iter().map(|(_, x)| x).sum();
    assert!(sum <= t.total_seconds * (1.0 + 1e-9) + 1e-9, "{t:?}");
    let json = t.to_json();
    for s in STAGES.iter().chain(&["other"]) {
        assert!(json["stages"][s].as_f64().is_some_and(|x| x >= 0.0), "{s}");
    }
    if cfg!(target_os = "linux") {
        assert!(t.peak_memory_bytes.is_some_and(|b| b > 0));
    }
    // Errors come back as errors.
    assert!(mesh_timed(&d, &block_cells(0)).is_err());
}

#[test]
fn bubbles_are_separated_inside_and_reproducible() {
    let _turn = common::turn();
    for (n, seed) in [(1, 3u64), (50, 1), (1500, 42)] {
        let d = layouts::bubbles(n, seed).unwrap();
        assert_eq!(d.hole_count(), n);
        assert_eq!(layouts::bubbles(n, seed).unwrap(), d);
        let b = d.bounding();
        let h = d.holes();
        for (i, c) in h.iter().enumerate() {
            assert!((0.3..=0.6).contains(&c.radius));
            let to_b = (c.center[0] - b.center[0]).hypot(c.center[1] - b.center[1]);
            assert!(to_b + c.radius + 0.1 <= b.radius + 1e-12, "bubble {i}");
            for o in &h[..i] {
                let dist = (c.center[0] - o.center[0]).hypot(c.center[1] - o.center[1]);
                assert!(dist >= c.radius + o.radius + 0.1 - 1e-12, "bubble {i}");
            }
        }
    }
    assert!(layouts::bubbles(0, 1).is_err());
}

// ---- the CLI ----

#[test]
fn timings_flag_writes_timings_json_and_nothing_else_changes() {
    let _turn = common::turn();
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("bubbles.json");
    let formats = "vtk,vtu,plot3d,gmsh,svg,json";
    assert!(cli(&[
        "example",
        "bubbles",
        "--holes",
        "25",
        "--seed",
        "5",
        "-o",
        input.to_str().unwrap()
    ])
    .status
    .success());
    let (with, without) = (tmp.path().join("with"), tmp.path().join("without"));
    let run = |dir: &Path, extra: &[&str]| {
        let mut args = vec![
            "mesh",
            input.to_str().unwrap(),
            "-o",
            dir.to_str().unwrap(),
            "--block-cells",
            "6",
            "--format",
            formats,
        ];
        args.extend_from_slice(extra);
        let o = cli(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        o
    };
    let o = run(&with, &["--timings"]);
    run(&without, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("peak memory") && stderr.contains("triangulation"));

    let files = |d: &Path| tree(d).into_iter().collect::<BTreeMap<String, Vec<u8>>>();
    let mut a = files(&with);
    let b = files(&without);
    let timings = a.remove("timings.json").expect("timings.json");
    assert!(!b.contains_key("timings.json"));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "same files"
    );
    for (k, v) in &a {
        assert!(v == &b[k], "{k} differs with --timings");
    }
    let report: serde_json::Value = serde_json::from_slice(&b["report.json"]).unwrap();
    assert!(report.get("timings").is_none() && report.get("stages").is_none());

    // A later run without --timings into the same directory leaves no stale timings.json
    // (it would describe another mesh), and the directory then equals the one never timed.
    run(&with, &[]);
    assert!(
        !with.join("timings.json").exists(),
        "stale timings.json kept"
    );
    assert!(files(&with) == b, "rerun without --timings differs");

    let t: serde_json::Value = serde_json::from_slice(&timings).unwrap();
    let mut keys: Vec<String> = STAGES.iter().map(|s| s.to_string()).collect();
    keys.push("other".into());
    for f in formats.split(',') {
        keys.push(format!("write_{f}"));
    }
    for k in &keys {
        let x = t["stages"][k.as_str()].as_f64();
        assert!(x.is_some_and(|x| x >= 0.0), "stage {k}: {t}");
    }
    common::assert_stages_add_up(&t);
    common::assert_spans_add_up(&t);
    assert!(t["peak_memory_bytes"].is_null() || t["peak_memory_bytes"].as_u64().unwrap() > 0);
    if !t["cpu_stages"].is_null() {
        for k in &keys {
            let x = t["cpu_stages"][k.as_str()].as_f64();
            assert!(x.is_some_and(|x| x >= 0.0), "cpu stage {k}: {t}");
        }
    }
    // Page faults per stage add up to the run's count (`other` is the rest), and the grids
    // stage, which writes every node into fresh memory, has at least one fault per 2 MiB of
    // nodes (one per 4 KiB without huge pages).
    if cfg!(target_os = "linux") {
        let all = t["page_faults"].as_u64().expect("page_faults on Linux");
        let sum: u64 = t["fault_stages"]
            .as_object()
            .expect("fault_stages")
            .values()
            .map(|v| v.as_u64().expect("a count"))
            .sum();
        assert_eq!(sum, all, "{t}");
        for k in &keys {
            assert!(
                t["fault_stages"][k.as_str()].is_u64(),
                "fault stage {k}: {t}"
            );
        }
        let report: serde_json::Value = serde_json::from_slice(&b["report.json"]).unwrap();
        let node_bytes = report["nodes"].as_u64().unwrap() * 16;
        let grids = t["fault_stages"]["grids"].as_u64().unwrap();
        assert!(
            grids >= node_bytes >> 21,
            "{grids} faults for {node_bytes} B: {t}"
        );
        assert!(stderr.contains("faults"), "{stderr}");
    }
    // Sampling triangulates at least once per attempt; every stage that ran was entered.
    assert!(
        t["calls"]["triangulation"].as_u64().is_some_and(|c| c >= 1),
        "{t}"
    );
    assert!(t["calls"]["write_vtk"].as_u64() == Some(1), "{t}");
    assert_eq!(t["holes"], 25);
    assert_eq!(t["blocks"], report["blocks"]);
    assert_eq!(t["cells"], report["cells"]);
}

/// `medial-blocks --quiet mesh -o DIR --format json --timings EXTRA...` on the built-in
/// example: the process's output and `DIR/timings.json`.
fn quiet_json_timings(extra: &[&str]) -> (std::process::Output, serde_json::Value) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("t");
    let mut args = vec![
        "--quiet",
        "mesh",
        "-o",
        out.to_str().unwrap(),
        "--format",
        "json",
        "--timings",
    ];
    args.extend_from_slice(extra);
    let o = cli(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let t =
        serde_json::from_str(&std::fs::read_to_string(out.join("timings.json")).unwrap()).unwrap();
    (o, t)
}

/// `--compare-modes` meshes a second time after the first mesh was written: its stages are
/// spans of their own, not rework of the first mesh.
#[test]
fn compare_modes_second_mesh_is_not_rework() {
    let _turn = common::turn();
    let (_, t) = quiet_json_timings(&["--compare-modes"]);
    common::assert_spans_add_up(&t);
    let spans = t["spans"].as_array().unwrap();
    let quality = spans.iter().position(|s| s["stage"] == "quality").unwrap();
    // The second mesh's meshing spans come after the first mesh's report.
    assert!(
        spans[quality..].iter().any(|s| s["stage"] == "grids"),
        "{t}"
    );
    // Rework: between the first mesh's first check and its report, nothing later.
    let check = spans
        .iter()
        .position(|s| s["stage"] == "quality_check")
        .unwrap();
    let redone: f64 = spans[check + 1..quality]
        .iter()
        .map(|s| s["seconds"].as_f64().unwrap())
        .sum();
    let got = t["rework"]["seconds"].as_f64().unwrap();
    assert!((got - redone).abs() <= 1e-12, "{got} vs {redone}: {t}");
}

#[test]
fn timings_with_quiet_prints_nothing_but_writes_the_file() {
    let _turn = common::turn();
    let (o, t) = quiet_json_timings(&[]);
    assert!(o.stdout.is_empty() && o.stderr.is_empty());
    assert_eq!(t["blocks"], 36);
}

#[test]
fn block_cells_flag_errors_exit_2() {
    let _turn = common::turn();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x");
    let out = out.to_str().unwrap();
    for bad in [
        vec!["--block-cells", "0"],
        vec!["--block-cells", "-3"],
        vec!["--block-cells", "4", "--cells", "8"],
        vec!["--block-cells", "4", "--cell-size", "0.1"],
        vec!["--block-cells", "4", "--wall-cells", "0:3"],
        vec!["--block-cells", "100001"],
    ] {
        let mut args = vec!["mesh", "-o", out, "--format", "json"];
        args.extend_from_slice(&bad);
        let o = cli(&args);
        assert_eq!(o.status.code(), Some(2), "{bad:?}");
        assert!(!o.stderr.is_empty(), "{bad:?}");
    }
    assert!(!Path::new(out).join("report.json").exists());
    // And a good one: the hexagon (no wall longer than 16 x 15 degrees), 36 blocks of 16 x 16.
    let o = cli(&["mesh", "-o", out, "--format", "json", "--block-cells", "16"]);
    assert!(o.status.success());
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(Path::new(out).join("report.json")).unwrap())
            .unwrap();
    assert_eq!(r["cells"], 36 * 256);
}

#[test]
fn summary_and_report_json_show_the_same_figures() {
    let _turn = common::turn();
    // The CLI measures the mesh once for both: the printed summary must match report.json.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    let o = cli(&[
        "mesh",
        "-o",
        out.to_str().unwrap(),
        "--cells",
        "4",
        "--format",
        "json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let first = format!(
        "{} holes -> {} blocks, {} cells",
        r["holes"], r["blocks"], r["cells"]
    );
    assert!(stdout.contains(&first), "{first:?} not in {stdout}");
    let angles = format!(
        "mean smallest angle {:.1} deg, mean largest {:.1} deg",
        r["mean_min_angle_deg"].as_f64().unwrap(),
        r["mean_max_angle_deg"].as_f64().unwrap()
    );
    assert!(stdout.contains(&angles), "{angles:?} not in {stdout}");
}
