//! Back end oracles: templates + grids checked by code that does not trust the crate
//! (conformity, validity, wall placement recomputed here), TFI exactness, angle measurement.

use crate::common;

use medial_blocks::domain::Circle;
use medial_blocks::geometry::Point;
use medial_blocks::grid::{build_grids, tfi, GridError, MAX_CELLS_PER_SIDE};
use medial_blocks::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use medial_blocks::mesh::BlockGrid;
use medial_blocks::quality::{cell_corners, measure};
use medial_blocks::templates::{annulus, disk};
use proptest::prelude::*;

// ---------- independent checkers ----------

/// Nodes of side k of a grid, in the side's direction, read straight from the node array.
fn side_nodes(g: &BlockGrid, k: usize) -> Vec<Point> {
    let at = |i: usize, j: usize| g.nodes[i + j * (g.ni + 1)];
    match k {
        0 => (0..=g.ni).map(|i| at(i, 0)).collect(),
        1 => (0..=g.nj).map(|j| at(g.ni, j)).collect(),
        2 => (0..=g.ni).rev().map(|i| at(i, g.nj)).collect(),
        _ => (0..=g.nj).rev().map(|j| at(0, j)).collect(),
    }
}

fn bits(p: Point) -> [u64; 2] {
    [p[0].to_bits(), p[1].to_bits()]
}

/// Every non-wall side has exactly one partner side (same end coordinates, either order)
/// with bitwise identical nodes (reversed as needed); wall sides have no partner.
fn check_conformity(layout: &BlockLayout, grids: &[BlockGrid]) {
    assert_eq!(layout.blocks.len(), grids.len());
    let mut sides = Vec::new();
    for (b, g) in grids.iter().enumerate() {
        assert_eq!(g.nodes.len(), (g.ni + 1) * (g.nj + 1));
        for k in 0..4 {
            sides.push((b, k, side_nodes(g, k)));
        }
    }
    for (x, (b, k, nodes)) in sides.iter().enumerate() {
        let first = bits(nodes[0]);
        let last = bits(*nodes.last().unwrap());
        let partners: Vec<_> = sides
            .iter()
            .enumerate()
            .filter(|(y, (_, _, other))| {
                *y != x
                    && ((bits(other[0]) == first && bits(*other.last().unwrap()) == last)
                        || (bits(other[0]) == last && bits(*other.last().unwrap()) == first))
            })
            .collect();
        let edge = layout.blocks[*b].sides[*k].edge as usize;
        let is_wall = matches!(layout.edges[edge].kind, EdgeKind::Wall(_));
        if is_wall {
            assert!(
                partners.is_empty(),
                "wall side {b}/{k} has a partner {partners:?}"
            );
        } else {
            assert_eq!(
                partners.len(),
                1,
                "side {b}/{k}: {} partners",
                partners.len()
            );
            let other = &partners[0].1 .2;
            let mut rev = other.clone();
            rev.reverse();
            let same = |a: &[Point], c: &[Point]| {
                a.len() == c.len() && a.iter().zip(c).all(|(p, q)| bits(*p) == bits(*q))
            };
            assert!(
                same(nodes, other) || same(nodes, &rev),
                "side {b}/{k}: partner nodes differ"
            );
        }
    }
}

/// Every node of every wall side lies on its circle within `tol`.
fn check_walls(
    layout: &BlockLayout,
    grids: &[BlockGrid],
    circle: &dyn Fn(i32) -> Circle,
    tol: f64,
) {
    for (b, block) in layout.blocks.iter().enumerate() {
        for k in 0..4 {
            if let EdgeKind::Wall(id) = layout.edges[block.sides[k].edge as usize].kind {
                let c = circle(id);
                for p in side_nodes(&grids[b], k) {
                    let d = (p[0] - c.center[0]).hypot(p[1] - c.center[1]) - c.radius;
                    assert!(
                        d.abs() <= tol,
                        "block {b} side {k}: node {p:?} off circle {id} by {d:e}"
                    );
                }
            }
        }
    }
}

/// Layout-level sanity: corners CCW with positive polygon area.
fn check_corners_ccw(layout: &BlockLayout) {
    for (b, block) in layout.blocks.iter().enumerate() {
        let p = block.corners.map(|v| layout.vertices[v as usize]);
        let mut area2 = 0.0;
        for k in 0..4 {
            let (a, c) = (p[k], p[(k + 1) % 4]);
            area2 += a[0] * c[1] - a[1] * c[0];
        }
        assert!(area2 > 0.0, "block {b} corners not CCW");
    }
}

fn check_annulus(big: Circle, hole: Circle, cells: usize) {
    let layout = annulus(big, hole);
    assert_eq!(layout.blocks.len(), 4);
    check_corners_ccw(&layout);
    let grids = build_grids(&layout, cells).expect("grids");
    check_conformity(&layout, &grids);
    assert_eq!(
        common::count_inverted_cells(&grids),
        0,
        "inverted cells for {big:?} {hole:?} n={cells}"
    );
    let circle = |id: i32| if id < 0 { big } else { hole };
    check_walls(&layout, &grids, &circle, 1e-12 * big.radius);
    let q = measure(&grids);
    assert_eq!(q.inverted_cells, 0);
    assert_eq!(q.cells, grids.iter().map(|g| g.ni * g.nj).sum::<usize>());
    assert_eq!(grids.len(), 4);
    // Every side has at least the target count; wall arcs at most 15 degrees a cell.
    assert!(grids.iter().all(|g| g.ni >= cells && g.nj >= cells));
    for b in &layout.blocks {
        assert_eq!(b.wall, Some(0));
        assert!(matches!(
            layout.edges[b.sides[0].edge as usize].kind,
            EdgeKind::Wall(0)
        ));
        assert!(matches!(
            layout.edges[b.sides[2].edge as usize].kind,
            EdgeKind::Wall(-1)
        ));
    }
}

// ---------- templates ----------

#[test]
fn disk_template_is_conforming_and_valid() {
    for (center, radius) in [([0.0, 0.0], 1.0), ([3.5, -2.0], 0.25), ([-1e3, 1e3], 1e3)] {
        let big = Circle { center, radius };
        let layout = disk(big);
        assert_eq!(layout.blocks.len(), 5);
        check_corners_ccw(&layout);
        for cells in [1, 2, 3, 8, 17] {
            let grids = build_grids(&layout, cells).unwrap();
            check_conformity(&layout, &grids);
            assert_eq!(common::count_inverted_cells(&grids), 0);
            check_walls(&layout, &grids, &|_| big, 1e-12 * radius);
            let q = measure(&grids);
            assert_eq!(q.cells, grids.iter().map(|g| g.ni * g.nj).sum::<usize>());
            assert_eq!(grids.len(), 5);
            // Every side has at least the target count; wall arcs at most 15 degrees a cell.
            assert!(grids.iter().all(|g| g.ni >= cells && g.nj >= cells));
            assert!(q.min_angle_deg > 40.0 && q.max_angle_deg < 140.0, "{q:?}");
        }
        // Outer blocks: wall on side 0, on the bounding circle.
        for b in &layout.blocks[..4] {
            assert_eq!(b.wall, Some(-1));
            assert_eq!(
                layout.edges[b.sides[0].edge as usize].kind,
                EdgeKind::Wall(-1)
            );
        }
        assert_eq!(layout.blocks[4].wall, None);
    }
}

#[test]
fn concentric_annulus_is_polar() {
    let big = Circle {
        center: [1.0, 2.0],
        radius: 2.0,
    };
    let hole = Circle {
        center: [1.0, 2.0],
        radius: 0.5,
    };
    check_annulus(big, hole, 8);
    let q = measure(&build_grids(&annulus(big, hole), 8).unwrap());
    assert!((q.min_angle_deg - 90.0).abs() < 6.0, "{q:?}");
}

#[test]
fn annulus_fixed_off_centre_cases() {
    let big = Circle {
        center: [0.0, 0.0],
        radius: 1.0,
    };
    for &(r, gap) in &[
        (0.01, 0.01),
        (0.2, 0.01),
        (0.5, 0.01),
        (0.9, 0.01),
        (0.98, 0.01),
        (0.3, 0.3),
    ] {
        for k in 0..8 {
            let a = k as f64 * 0.785 + 0.1;
            let off = 1.0 - r - gap;
            let hole = Circle {
                center: [off * a.cos(), off * a.sin()],
                radius: r,
            };
            for cells in [1, 2, 3, 5, 12] {
                check_annulus(big, hole, cells);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn random_annuli_are_valid(
        cx in -10.0f64..10.0, cy in -10.0f64..10.0, big_r in 0.1f64..100.0,
        fr in 0.01f64..0.98, t in 0.0f64..=1.0, a in -4.0f64..4.0, cells in 1usize..14,
        at_limit in proptest::bool::ANY,
    ) {
        let big = Circle { center: [cx, cy], radius: big_r };
        let r = fr * big_r;
        // Gap at least 1% of R; `at_limit` puts the hole exactly at the 1% gap.
        let max_off = (big_r - r - 0.01 * big_r).max(0.0);
        let off = if at_limit { max_off } else { t * max_off };
        let hole = Circle { center: [cx + off * a.cos(), cy + off * a.sin()], radius: r };
        check_annulus(big, hole, cells);
    }
}

// ---------- TFI and angles ----------

fn seg(a: Point, b: Point, n: usize) -> Vec<Point> {
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        })
        .collect()
}

#[test]
fn tfi_reproduces_bilinear_maps() {
    // A parallelogram and a general (non-parallelogram) convex quad: uniform straight sides.
    for p in [
        [[0.0, 0.0], [3.0, 0.5], [4.0, 2.5], [1.0, 2.0]],
        [[-1.0, -1.0], [2.0, -0.5], [2.5, 3.0], [-0.5, 1.5]],
    ] {
        let (ni, nj) = (7, 4);
        let g = tfi(
            &seg(p[0], p[1], ni),
            &seg(p[1], p[2], nj),
            &seg(p[2], p[3], ni),
            &seg(p[3], p[0], nj),
        )
        .unwrap();
        for j in 0..=nj {
            for i in 0..=ni {
                let (u, v) = (i as f64 / ni as f64, j as f64 / nj as f64);
                let w = [(1.0 - u) * (1.0 - v), u * (1.0 - v), u * v, (1.0 - u) * v];
                let e = [0, 1].map(|d| (0..4).map(|k| w[k] * p[k][d]).sum::<f64>());
                let n = g.nodes[i + j * (ni + 1)];
                assert!((n[0] - e[0]).abs() < 1e-12 && (n[1] - e[1]).abs() < 1e-12);
            }
        }
    }
    // The same through build_grids on a hand-made one-block layout with a reversed side.
    let v = vec![[0.0, 0.0], [3.0, 0.5], [4.0, 2.5], [1.0, 2.0]];
    let e = |a: u32, b: u32| Edge {
        ends: [a, b],
        curve: Curve::Segment,
        kind: EdgeKind::Interface,
    };
    let layout = BlockLayout {
        vertices: v.clone(),
        edges: vec![e(0, 1), e(1, 2), e(3, 2), e(3, 0)],
        blocks: vec![Block {
            corners: [0, 1, 2, 3],
            sides: [
                SideRef {
                    edge: 0,
                    reversed: false,
                },
                SideRef {
                    edge: 1,
                    reversed: false,
                },
                SideRef {
                    edge: 2,
                    reversed: true,
                },
                SideRef {
                    edge: 3,
                    reversed: false,
                },
            ],
            wall: None,
        }],
    };
    let g = &build_grids(&layout, 5).unwrap()[0];
    for j in 0..=5 {
        for i in 0..=5 {
            let (u, w) = (i as f64 / 5.0, j as f64 / 5.0);
            let wt = [(1.0 - u) * (1.0 - w), u * (1.0 - w), u * w, (1.0 - u) * w];
            let ex = [0, 1].map(|d| (0..4).map(|k| wt[k] * v[k][d]).sum::<f64>());
            let n = g.nodes[i + j * 6];
            assert!((n[0] - ex[0]).abs() < 1e-12 && (n[1] - ex[1]).abs() < 1e-12);
        }
    }
    // Corners are exactly the vertices.
    assert_eq!(g.nodes[0], v[0]);
    assert_eq!(g.nodes[5], v[1]);
    assert_eq!(g.nodes[35], v[2]);
    assert_eq!(g.nodes[30], v[3]);
}

#[test]
fn angles_of_hand_made_cells() {
    let sq = cell_corners([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    for k in 0..4 {
        assert!((sq.angle_deg[k] - 90.0).abs() < 1e-12);
        assert!((sq.jacobian[k] - 1.0).abs() < 1e-12);
    }
    let s3 = 3f64.sqrt() / 2.0;
    let rh = cell_corners([[0.0, 0.0], [1.0, 0.0], [1.5, s3], [0.5, s3]]);
    let min = rh.angle_deg.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = rh
        .angle_deg
        .iter()
        .cloned()
        .fold(f64::NEG_INFINITY, f64::max);
    assert!((min - 60.0).abs() < 1e-9 && (max - 120.0).abs() < 1e-9);
    // Clockwise cell: all Jacobians negative -> inverted.
    let cw = cell_corners([[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]);
    assert!(cw.jacobian.iter().all(|&j| j < 0.0));
    // Mesh-level figures on one square cell and one rhombus cell.
    let grids = vec![
        BlockGrid {
            ni: 1,
            nj: 1,
            nodes: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
        },
        BlockGrid {
            ni: 1,
            nj: 1,
            nodes: vec![[0.0, 0.0], [1.0, 0.0], [0.5, s3], [1.5, s3]],
        },
    ];
    let q = measure(&grids);
    assert_eq!(q.cells, 2);
    assert_eq!(q.inverted_cells, 0);
    assert!((q.min_angle_deg - 60.0).abs() < 1e-9);
    assert!((q.max_angle_deg - 120.0).abs() < 1e-9);
    assert!((q.mean_min_angle_deg - 75.0).abs() < 1e-9);
    assert!((q.mean_max_angle_deg - 105.0).abs() < 1e-9);
    // An inverted (bow-tie) cell is counted; a malformed grid is skipped, not a panic.
    let bad = vec![
        BlockGrid {
            ni: 1,
            nj: 1,
            nodes: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        },
        BlockGrid {
            ni: 3,
            nj: 3,
            nodes: vec![[0.0, 0.0]],
        },
    ];
    let q = measure(&bad);
    assert_eq!((q.cells, q.inverted_cells, q.malformed_grids), (1, 1, 1));
}

// ---------- errors, not panics ----------

#[test]
fn grid_errors() {
    let layout = disk(Circle {
        center: [0.0, 0.0],
        radius: 1.0,
    });
    assert_eq!(build_grids(&layout, 0), Err(GridError::ZeroCells));
    assert!(matches!(
        build_grids(&layout, MAX_CELLS_PER_SIDE + 1),
        Err(GridError::TooManyCellsPerSide { .. })
    ));
    // 5 blocks of 10^5 x 10^5: refused before allocating.
    assert!(matches!(
        build_grids(&layout, MAX_CELLS_PER_SIDE),
        Err(GridError::TooManyNodes { .. })
    ));
    assert!(matches!(
        build_grids(&layout, usize::MAX),
        Err(GridError::TooManyCellsPerSide { .. })
    ));

    let mut l = layout.clone();
    l.blocks[0].sides[1].edge = 999;
    assert!(matches!(
        build_grids(&l, 4),
        Err(GridError::InvalidLayout(_))
    ));
    let mut l = layout.clone();
    l.blocks[0].sides[1].reversed = !l.blocks[0].sides[1].reversed;
    assert!(matches!(
        build_grids(&l, 4),
        Err(GridError::InvalidLayout(_))
    ));
    let mut l = layout.clone();
    l.edges[0].ends[0] = 1000;
    assert!(matches!(
        build_grids(&l, 4),
        Err(GridError::InvalidLayout(_))
    ));
    let mut l = layout.clone();
    l.vertices[4] = [f64::NAN, 0.0];
    assert!(matches!(
        build_grids(&l, 4),
        Err(GridError::InvalidLayout(_))
    ));
    let mut l = layout.clone();
    if let Curve::Arc { radius, .. } = &mut l.edges[0].curve {
        *radius = 2.0;
    }
    assert!(matches!(
        build_grids(&l, 4),
        Err(GridError::InvalidLayout(_))
    ));
    let mut l = layout.clone();
    l.edges[4].curve = Curve::Polyline(vec![[0.0, 0.0]]);
    assert!(matches!(
        build_grids(&l, 4),
        Err(GridError::InvalidLayout(_))
    ));
    // Empty layout: no grids, no error.
    assert_eq!(build_grids(&BlockLayout::default(), 4), Ok(vec![]));
}

#[test]
fn polyline_edges_are_divided_by_arc_length() {
    // One block whose side 0 is an L-shaped polyline of length 2 from (0,0) via (1,0) to (1,1)
    // ... closed by straight sides to (0,2) and back: nodes at equal arc length.
    let vertices = vec![[0.0, 0.0], [2.0, 1.0], [2.0, 3.0], [0.0, 3.0]];
    let poly = vec![[0.0, 0.0], [1.5, 0.0], [2.0, 0.0], [2.0, 1.0]];
    let layout = BlockLayout {
        vertices,
        edges: vec![
            Edge {
                ends: [0, 1],
                curve: Curve::Polyline(poly),
                kind: EdgeKind::Medial,
            },
            Edge {
                ends: [1, 2],
                curve: Curve::Segment,
                kind: EdgeKind::Interface,
            },
            Edge {
                ends: [2, 3],
                curve: Curve::Segment,
                kind: EdgeKind::Interface,
            },
            Edge {
                ends: [3, 0],
                curve: Curve::Segment,
                kind: EdgeKind::Interface,
            },
        ],
        blocks: vec![Block {
            corners: [0, 1, 2, 3],
            sides: [0, 1, 2, 3].map(|e| SideRef {
                edge: e,
                reversed: false,
            }),
            wall: None,
        }],
    };
    let g = &build_grids(&layout, 6).unwrap()[0];
    let s0 = side_nodes(g, 0);
    // Length 3, 6 cells: steps of 0.5 along the polyline.
    let expect = [
        [0.0, 0.0],
        [0.5, 0.0],
        [1.0, 0.0],
        [1.5, 0.0],
        [2.0, 0.0],
        [2.0, 0.5],
        [2.0, 1.0],
    ];
    for (p, e) in s0.iter().zip(expect) {
        assert!(
            (p[0] - e[0]).abs() < 1e-12 && (p[1] - e[1]).abs() < 1e-12,
            "{p:?} vs {e:?}"
        );
    }
}
