//! Quality metrics on hand-made cells and meshes, and the `report.json` keys.

use medial_blocks::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use medial_blocks::mesh::{BlockGrid, Mesh};
use medial_blocks::output::report::Report;
use medial_blocks::quality::{cell_metrics, quality_metrics, Histogram};
use medial_blocks::{mesh, Circle, Domain, Options};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

#[test]
fn unit_square() {
    let m = cell_metrics([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    assert!(close(m.equiangle_skewness, 0.0), "{m:?}");
    assert!(close(m.edge_ratio, 1.0));
    assert!(close(m.scaled_jacobian, 1.0));
    assert!(close(m.aspect_ratio, 1.0));
    assert!(close(m.min_angle_deg, 90.0) && close(m.max_angle_deg, 90.0));
}

#[test]
fn rhombus_60_degrees() {
    let h = 0.75f64.sqrt();
    let m = cell_metrics([[0.0, 0.0], [1.0, 0.0], [1.5, h], [0.5, h]]);
    assert!(close(m.equiangle_skewness, 1.0 / 3.0), "{m:?}");
    assert!(close(m.scaled_jacobian, 60f64.to_radians().sin()));
    assert!(close(m.edge_ratio, 1.0));
    assert!(close(m.aspect_ratio, 1.0));
    assert!(close(m.min_angle_deg, 60.0) && close(m.max_angle_deg, 120.0));
}

#[test]
fn rectangle_and_inverted_cell() {
    let m = cell_metrics([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]);
    assert!(close(m.edge_ratio, 2.0) && close(m.aspect_ratio, 2.0));
    assert!(close(m.equiangle_skewness, 0.0));
    // Clockwise: every corner Jacobian negative.
    let m = cell_metrics([[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]);
    assert!(close(m.scaled_jacobian, -1.0));
    // A zero-length edge: infinite edge ratio, scaled Jacobian 0.
    let m = cell_metrics([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    assert!(m.edge_ratio.is_infinite());
    assert!(m.scaled_jacobian <= 0.0);
}

#[test]
fn histogram_bins() {
    let mut h = Histogram::new(&[0.0, 1.0, 2.0]);
    for x in [-5.0, 0.0, 0.5, 1.0, 1.5, 2.0, 9.0, f64::NAN] {
        h.add(x);
    }
    // Below the first edge in the first bin; at/above the last edge and NaN in the last.
    assert_eq!(h.counts, vec![3, 5]);
}

/// Two blocks side by side, `[0,1]x[0,1]` and `[1,3]x[0,1]`, one cell each: the cell heights
/// normal to the interface `x = 1` are 1 and 2.
fn two_blocks() -> (BlockLayout, Vec<BlockGrid>) {
    let vertices = vec![
        [0.0, 0.0],
        [1.0, 0.0],
        [3.0, 0.0],
        [3.0, 1.0],
        [1.0, 1.0],
        [0.0, 1.0],
    ];
    let pairs: [[u32; 2]; 7] = [[0, 1], [1, 4], [4, 5], [5, 0], [1, 2], [2, 3], [3, 4]];
    let edges = pairs
        .iter()
        .map(|&ends| Edge {
            ends,
            curve: Curve::Segment,
            kind: if ends == [1, 4] {
                EdgeKind::Interface
            } else {
                EdgeKind::Wall(-1)
            },
        })
        .collect();
    let s = |edge: u32, reversed: bool| SideRef { edge, reversed };
    let blocks = vec![
        Block {
            corners: [0, 1, 4, 5],
            sides: [s(0, false), s(1, false), s(2, false), s(3, false)],
            wall: None,
        },
        Block {
            corners: [1, 2, 3, 4],
            sides: [s(4, false), s(5, false), s(6, false), s(1, true)],
            wall: None,
        },
    ];
    let grids = vec![
        BlockGrid {
            ni: 1,
            nj: 1,
            nodes: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
        },
        BlockGrid {
            ni: 1,
            nj: 1,
            nodes: vec![[1.0, 0.0], [3.0, 0.0], [1.0, 1.0], [3.0, 1.0]],
        },
    ];
    (
        BlockLayout {
            vertices,
            edges,
            blocks,
        },
        grids,
    )
}

#[test]
fn growth_ratio_across_an_interface() {
    let (layout, grids) = two_blocks();
    let q = quality_metrics(&layout, &grids);
    let g = &q.interface_growth_ratio;
    assert_eq!(g.samples, 1);
    assert_eq!(g.min, Some(2.0));
    assert_eq!(g.max, Some(2.0));
    assert_eq!(g.outside, 1); // 2 > 1.5
    assert_eq!(q.edge_ratio.max, Some(2.0));
    assert_eq!(q.edge_ratio.samples, 2);
    // Straight walls: no wall arc, so no orthogonality figure.
    assert_eq!(q.max_wall_orthogonality_deviation_deg, None);
}

#[test]
fn concentric_annulus_is_wall_orthogonal() {
    let d = Domain::bounded(Circle::new(0.0, 0.0, 2.0), vec![Circle::new(0.0, 0.0, 0.5)]).unwrap();
    let m = mesh(
        &d,
        &Options {
            cells: 6,
            ..Options::default()
        },
    )
    .unwrap();
    let q = quality_metrics(&m.layout, &m.grids);
    let dev = q.max_wall_orthogonality_deviation_deg.unwrap();
    assert!(dev < 1e-6, "deviation {dev}");
}

fn small_hexagon() -> Mesh {
    mesh(
        &Domain::hexagon_example(),
        &Options {
            cells: 4,
            ..Options::default()
        },
    )
    .unwrap()
}

#[test]
fn histograms_count_every_cell_and_ranges_hold() {
    let m = small_hexagon();
    let cells: u64 = m.grids.iter().map(|g| g.cells() as u64).sum();
    let q = quality_metrics(&m.layout, &m.grids);
    for (name, s) in q.named() {
        let total: u64 = s.histogram.counts.iter().sum();
        assert_eq!(total, s.samples, "{name}");
        assert_eq!(
            s.histogram.counts.len() + 1,
            s.histogram.edges.len(),
            "{name}"
        );
        let want = match name {
            "angle_deg" => 4 * cells,
            "interface_growth_ratio" => s.samples,
            _ => cells,
        };
        assert_eq!(s.samples, want, "{name}");
        assert!(s.outside <= cells, "{name}");
        let (lo, hi) = (s.min.unwrap(), s.max.unwrap());
        assert!(lo <= hi, "{name}");
    }
    assert!(q.interface_growth_ratio.samples > 0);
    assert!(q.scaled_jacobian.min.unwrap() > 0.0);
    assert!(q.edge_ratio.min.unwrap() >= 1.0);
    assert!(q.equiangle_skewness.min.unwrap() >= 0.0);
    let dev = q.max_wall_orthogonality_deviation_deg.unwrap();
    assert!((0.0..90.0).contains(&dev), "{dev}");
}

#[test]
fn report_has_every_key() {
    let m = small_hexagon();
    let v = serde_json::to_value(Report::from_mesh(&m)).unwrap();
    for key in [
        "holes",
        "blocks",
        "cells",
        "nodes",
        "min_angle_deg",
        "max_angle_deg",
        "mean_min_angle_deg",
        "mean_max_angle_deg",
        "inverted_cells",
        "min_scaled_jacobian",
        "medial_vertices",
        "medial_arcs",
        "max_wall_orthogonality_deviation_deg",
        "max_aspect_ratio",
        "quality",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    let cells = v["cells"].as_u64().unwrap();
    for metric in [
        "angle_deg",
        "equiangle_skewness",
        "edge_ratio",
        "scaled_jacobian",
        "interface_growth_ratio",
        "aspect_ratio",
    ] {
        let q = &v["quality"][metric];
        for key in ["min", "max", "histogram", "acceptable", "outside"] {
            assert!(q.get(key).is_some(), "missing quality.{metric}.{key}");
        }
        let counts: u64 = q["histogram"]["counts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_u64().unwrap())
            .sum();
        let edges = q["histogram"]["edges"].as_array().unwrap().len() as u64;
        assert_eq!(
            edges,
            q["histogram"]["counts"].as_array().unwrap().len() as u64 + 1
        );
        match metric {
            "angle_deg" => assert_eq!(counts, 4 * cells),
            "interface_growth_ratio" => assert!(counts > 0),
            _ => assert_eq!(counts, cells, "{metric}"),
        }
        assert_eq!(q["acceptable"].as_array().unwrap().len(), 2);
    }
    assert_eq!(v["quality"]["angle_deg"]["acceptable"][0], 40.0);
    assert_eq!(v["quality"]["angle_deg"]["acceptable"][1], 135.0);
    assert_eq!(v["quality"]["scaled_jacobian"]["acceptable"][0], 0.3);
    assert_eq!(v["max_aspect_ratio"], v["quality"]["aspect_ratio"]["max"],);
}
