//! The new report keys, SVG marks and CLI flags of tracker issue 4, and the inserted-hole
//! template on its own.

use medial_blocks::blocking::block_area;
use medial_blocks::domain::{Circle, Domain};
use medial_blocks::grid::build_grids;
use medial_blocks::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use medial_blocks::output::{report::Report, svg};
use medial_blocks::templates::fill_inserted_hole;
use medial_blocks::{mesh, Options};
use std::process::Command;

fn square2() -> Domain {
    let holes = vec![
        Circle::new(-0.5, -0.5, 0.3),
        Circle::new(0.5, -0.5, 0.3),
        Circle::new(-0.5, 0.5, 0.3),
        Circle::new(0.5, 0.5, 0.3),
    ];
    Domain::bounded(Circle::new(0.0, 0.0, 2.0), holes).unwrap()
}

fn poor() -> Domain {
    Domain::bounded(
        Circle::new(0.0, 0.0, 3.0),
        vec![
            Circle::new(-0.31, 0.0, 0.3),
            Circle::new(0.31, 0.0, 0.3),
            Circle::new(0.0, -2.0, 0.3),
        ],
    )
    .unwrap()
}

#[test]
fn report_has_groups_collapses_and_inserted_holes() {
    let m = mesh(&square2(), &Options::paper()).unwrap();
    let v = serde_json::to_value(Report::from_mesh(&m)).unwrap();
    // Correctly rounded from the exact sqrt(1/2) - 3/10 (the f64 expression is one ulp off).
    let rho = 0.40710678118654753;
    assert!((rho - (0.5f64.sqrt() - 0.3)).abs() < 1e-16);
    assert_eq!(
        v["cocircular_groups"],
        serde_json::json!([{"holes": [0, 1, 2, 3], "center": [0.0, 0.0], "radius": rho}])
    );
    assert_eq!(v["collapsed_arcs"], serde_json::json!(1));
    assert_eq!(v["inserted_holes"], serde_json::json!([]));
    assert!(svg::to_string(&m)
        .unwrap()
        .contains("class=\"cocircular-group\""));

    let m = mesh(&poor(), &Options::paper()).unwrap();
    let v = serde_json::to_value(Report::from_mesh(&m)).unwrap();
    let ins = v["inserted_holes"].as_array().unwrap();
    assert_eq!(ins.len(), 1);
    assert!(ins[0]["center"].is_array() && ins[0]["radius"].as_f64().unwrap() > 0.0);
    assert!(svg::to_string(&m)
        .unwrap()
        .contains("class=\"inserted-hole\""));
}

fn run_cli(dir: &std::path::Path, domain: &Domain, extra: &[&str]) -> serde_json::Value {
    let input = dir.join("in.json");
    std::fs::write(&input, domain.to_json_string()).unwrap();
    let out = dir.join("out");
    let status = Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args(["mesh", input.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .args(["--format", "json", "--cells", "2", "-q", "--mode", "paper"])
        .args(extra)
        .output()
        .expect("binary runs");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap()
}

#[test]
fn cli_flags() {
    let dir = tempfile::tempdir().unwrap();
    let v = run_cli(dir.path(), &poor(), &[]);
    assert_eq!(v["inserted_holes"].as_array().unwrap().len(), 1);
    let v = run_cli(dir.path(), &poor(), &["--no-refine"]);
    assert_eq!(v["inserted_holes"].as_array().unwrap().len(), 0);
    let v = run_cli(dir.path(), &poor(), &["--refine-ratio", "100"]);
    assert_eq!(v["inserted_holes"].as_array().unwrap().len(), 0);
    let v = run_cli(dir.path(), &square2(), &["--collapse-fraction", "0"]);
    assert_eq!(v["collapsed_arcs"], serde_json::json!(1));
    assert_eq!(v["blocks"], serde_json::json!(16));
}

/// A ring of `k` blocks around a unit hole, each with the hole arc on side 0 (stored clockwise,
/// like the medial blocks' walls), a straight outer side, and spokes.
fn ring(k: usize, sweeps: &[f64]) -> BlockLayout {
    let mut layout = BlockLayout::default();
    let mut angles = vec![0.0];
    for s in sweeps {
        angles.push(angles.last().unwrap() + s);
    }
    for &a in &angles[..k] {
        layout.vertices.push([f64::cos(a), f64::sin(a)]);
    }
    for &a in &angles[..k] {
        layout.vertices.push([3.0 * f64::cos(a), 3.0 * f64::sin(a)]);
    }
    let inner = |i: usize| (i % k) as u32;
    let outer = |i: usize| (k + i % k) as u32;
    for i in 0..k {
        // Hole arc p_{i+1} -> p_i, clockwise.
        layout.edges.push(Edge {
            ends: [inner(i + 1), inner(i)],
            curve: Curve::Arc {
                center: [0.0, 0.0],
                radius: 1.0,
                start: angles[i + 1],
                sweep: -sweeps[i],
            },
            kind: EdgeKind::Wall(5),
        });
    }
    for i in 0..k {
        layout.edges.push(Edge {
            ends: [inner(i), outer(i)],
            curve: Curve::Segment,
            kind: EdgeKind::Spoke,
        });
    }
    for i in 0..k {
        layout.edges.push(Edge {
            ends: [outer(i), outer(i + 1)],
            curve: Curve::Segment,
            kind: EdgeKind::Wall(-1),
        });
    }
    let s = |edge: usize, reversed: bool| SideRef {
        edge: edge as u32,
        reversed,
    };
    for i in 0..k {
        // Fluid outside the hole: corners p_{i+1}, p_i, o_i, o_{i+1} counter-clockwise.
        layout.blocks.push(Block {
            corners: [inner(i + 1), inner(i), outer(i), outer(i + 1)],
            sides: [
                s(i, false),
                s(k + i, false),
                s(2 * k + i, false),
                s(k + (i + 1) % k, true),
            ],
            wall: Some(5),
        });
    }
    layout
}

/// The blocks of `layout` (a [`ring`] of `k` arcs with its hole filled) cover the outer
/// polygon exactly: their areas add up to the polygon's (vertices `k..2k`).
fn assert_covers_the_polygon(layout: &BlockLayout, k: usize) {
    let area: f64 = (0..layout.blocks.len())
        .map(|b| block_area(layout, b))
        .sum();
    let poly: f64 = (0..k)
        .map(|i| {
            let a = layout.vertices[k + i];
            let c = layout.vertices[k + (i + 1) % k];
            0.5 * (a[0] * c[1] - a[1] * c[0])
        })
        .sum();
    assert!((area - poly).abs() < 1e-9 * poly, "{area} vs {poly}");
}

/// Many arcs around an inserted hole (a void that dozens of particles border): the template
/// is still a valid conforming quadrangulation of the polygon, its core is an `a x b`
/// arrangement with `a + b = k / 2` (the ladder is `b = 1`), and no cell is a sliver. On the
/// ladder of a circle core the end blocks had corners of `360 / k` degrees (9 degrees at
/// `k = 40`).
#[test]
fn template_of_many_arcs_has_no_sliver_cells() {
    let unit = Circle::new(0.0, 0.0, 1.0);
    let tau = std::f64::consts::TAU;
    for k in [20usize, 24, 30, 40, 42, 64] {
        for uneven in [false, true] {
            let mut sweeps: Vec<f64> = (0..k)
                .map(|i| {
                    if uneven {
                        1.0 + 0.5 * (i % 5) as f64
                    } else {
                        1.0
                    }
                })
                .collect();
            let total: f64 = sweeps.iter().sum();
            sweeps.iter_mut().for_each(|s| *s *= tau / total);
            let mut layout = ring(k, &sweeps);
            let added = fill_inserted_hole(&mut layout, 5, unit).unwrap();
            // k ring blocks and a x b core blocks.
            let core = added - k;
            assert!(
                (1..=k / 4).any(|b| b * (k / 2 - b) == core),
                "k = {k}: {core} core blocks"
            );
            for b in 0..layout.blocks.len() {
                assert!(block_area(&layout, b) > 0.0, "k = {k}: block {b}");
            }
            // Every edge is the side of one block (the outer walls of the outer blocks) or two.
            let mut uses = vec![0usize; layout.edges.len()];
            for b in &layout.blocks {
                for s in b.sides {
                    uses[s.edge as usize] += 1;
                }
            }
            for (e, &n) in uses.iter().enumerate() {
                let outer = layout.edges[e].kind == EdgeKind::Wall(-1);
                assert_eq!(n, if outer { 1 } else { 2 }, "k = {k}: edge {e}");
            }
            let grids = build_grids(&layout, 4).unwrap();
            assert_covers_the_polygon(&layout, k);
            let q = medial_blocks::quality::measure(&grids[k..]);
            assert_eq!(q.inverted_cells, 0, "k = {k}");
            // A circle core whose blocks have corners of 20 degrees or more is kept (k = 20
            // uneven); the grid cores of these polygons have cells of 45 degrees or more.
            let bound = if k >= 24 { 40.0 } else { 18.0 };
            assert!(
                q.min_angle_deg > bound,
                "k = {k}, uneven {uneven}: template cells down to {} degrees",
                q.min_angle_deg
            );
        }
    }
}

#[test]
fn template_conforms_for_even_side_counts_and_refuses_odd() {
    let unit = Circle::new(0.0, 0.0, 1.0);
    for k in [4usize, 6, 8, 10] {
        let tau = std::f64::consts::TAU;
        // Uneven sweeps, summing to a full turn.
        let mut sweeps: Vec<f64> = (0..k).map(|i| 1.0 + 0.3 * (i % 3) as f64).collect();
        let total: f64 = sweeps.iter().sum();
        sweeps.iter_mut().for_each(|s| *s *= tau / total);
        let mut layout = ring(k, &sweeps);
        let added = fill_inserted_hole(&mut layout, 5, unit).unwrap();
        assert_eq!(added, k + k / 2 - 1);
        assert_eq!(layout.blocks.len(), k + added);
        for b in 0..layout.blocks.len() {
            assert!(block_area(&layout, b) > 0.0, "k = {k}: block {b}");
        }
        assert!(layout.edges.iter().all(|e| e.kind != EdgeKind::Wall(5)));
        assert!(layout.blocks.iter().all(|b| b.wall.is_none()));
        // The grids conform (build_grids copies each edge's nodes to both sides) and cover
        // the annulus between the outer polygon and nothing: total area is the polygon's.
        let grids = build_grids(&layout, 3).unwrap();
        assert_covers_the_polygon(&layout, k);
        let q = medial_blocks::quality::measure(&grids);
        assert_eq!(q.inverted_cells, 0, "k = {k}");
    }
    let tau = std::f64::consts::TAU;
    for k in [3usize, 5] {
        let sweeps = vec![tau / k as f64; k];
        let mut layout = ring(k, &sweeps);
        let before = layout.clone();
        assert!(fill_inserted_hole(&mut layout, 5, unit).is_err());
        assert_eq!(layout, before);
    }
}
