//! Exact mode checked without trusting the code: on random layouts (rejection-sampled
//! non-overlapping holes, h = 2..30) every property is recomputed here from node coordinates:
//! counting identities, conformity (sides with the same node set are bitwise identical), wall
//! nodes on their circles, the first grid line off every wall along the circle's normal, and a
//! positive cross product at every cell corner. Also: clustering gives the requested first
//! cell height; smoothing never lowers the smallest scaled Jacobian and keeps all of the above.

use crate::common;

use medial_blocks::domain::{Circle, Domain};
use medial_blocks::exact_mode::annulus::ANNULUS_ARCS;
use medial_blocks::exact_mode::{Clustering, FirstCell};
use medial_blocks::layouts::SplitMix64;
use medial_blocks::{mesh, Mesh, Mode, Options};
use proptest::prelude::*;
use std::collections::HashMap;

/// Up to `h` random holes with gaps of at least `min_gap * R`.
fn layout(seed: u64, h: usize, min_gap: f64) -> Domain {
    let mut rng = SplitMix64(seed);
    let big_r = 1.0 + 9.0 * rng.next_f64();
    let center = [rng.next_f64() * 10.0 - 5.0, rng.next_f64() * 10.0 - 5.0];
    let holes = common::random_holes(&mut rng, h, big_r, center, min_gap);
    Domain::bounded(
        Circle {
            center,
            radius: big_r,
        },
        holes,
    )
    .expect("generated layout is valid")
}

type Key = (u64, u64);
fn key(p: [f64; 2]) -> Key {
    (p[0].to_bits(), p[1].to_bits())
}

fn side_nodes(m: &Mesh, b: usize, s: usize) -> Vec<[f64; 2]> {
    let g = &m.grids[b];
    let at = |i: usize, j: usize| g.nodes[i + j * (g.ni + 1)];
    match s {
        0 => (0..=g.ni).map(|i| at(i, 0)).collect(),
        1 => (0..=g.nj).map(|j| at(g.ni, j)).collect(),
        2 => (0..=g.ni).rev().map(|i| at(i, g.nj)).collect(),
        _ => (0..=g.nj).rev().map(|j| at(0, j)).collect(),
    }
}

fn circles(d: &Domain) -> Vec<Circle> {
    std::iter::once(d.bounding())
        .chain(d.holes().iter().copied())
        .collect()
}

fn on_circle(p: [f64; 2], c: &Circle, tol: f64) -> bool {
    ((p[0] - c.center[0]).hypot(p[1] - c.center[1]) - c.radius).abs() <= tol
}

/// The smallest scaled Jacobian (sine of the corner angle) over every cell corner.
fn min_scaled_jacobian(m: &Mesh) -> f64 {
    let mut out = f64::INFINITY;
    for g in &m.grids {
        for j in 0..g.nj {
            for i in 0..g.ni {
                let q = [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ];
                for k in 0..4 {
                    let (p, a, b) = (q[k], q[(k + 1) % 4], q[(k + 3) % 4]);
                    let (ea, eb) = ([a[0] - p[0], a[1] - p[1]], [b[0] - p[0], b[1] - p[1]]);
                    let cross = ea[0] * eb[1] - ea[1] * eb[0];
                    let s = cross / (ea[0].hypot(ea[1]) * eb[0].hypot(eb[1]));
                    out = if s.is_nan() {
                        f64::NEG_INFINITY
                    } else {
                        out.min(s)
                    };
                }
            }
        }
    }
    out
}

/// Every check of this file; returns the wall circle index (into [`circles`]) of each block.
fn check(domain: &Domain, m: &Mesh) -> Vec<usize> {
    let h = domain.holes().len();
    let blocks = m.grids.len();
    if h == 1 {
        // The closed medial loop without a vertex, cut into ANNULUS_ARCS pieces.
        assert_eq!(
            (m.medial_vertices, m.medial_arcs, m.collapsed_arcs),
            (0, 0, 0)
        );
        assert_eq!(m.split_arcs, ANNULUS_ARCS);
        assert_eq!(blocks, 2 * ANNULUS_ARCS);
    } else {
        assert_eq!(m.medial_vertices, 2 * (h - 1));
        assert_eq!(m.medial_arcs, 3 * (h - 1));
        // Short arcs may be collapsed (two blocks fewer each).
        assert_eq!(blocks + 2 * m.collapsed_arcs, 6 * (h - 1));
    }
    assert_eq!(m.geometry, medial_blocks::mesh::Geometry::Exact);
    assert!(m.inserted_holes.is_empty());
    assert_eq!(m.layout.blocks.len(), blocks);
    for g in &m.grids {
        assert_eq!(g.nodes.len(), (g.ni + 1) * (g.nj + 1));
        assert!(g.ni >= 1 && g.nj >= 1);
    }
    let cs = circles(domain);
    let scale = domain.bounding().radius
        + domain.bounding().center[0]
            .abs()
            .max(domain.bounding().center[1].abs());
    let tol = 1e-13 * scale * 16.0;

    // Conformity from coordinates.
    let mut by_nodes: HashMap<Vec<Key>, Vec<(usize, usize)>> = HashMap::new();
    for b in 0..blocks {
        for s in 0..4 {
            let mut k: Vec<_> = side_nodes(m, b, s).into_iter().map(key).collect();
            k.sort_unstable();
            by_nodes.entry(k).or_default().push((b, s));
        }
    }
    let mut wall_of = vec![usize::MAX; blocks];
    for users in by_nodes.values() {
        match users.len() {
            1 => {
                let (b, s) = users[0];
                assert_eq!(s, 0, "block {b}: unpartnered side {s} (only walls are)");
                let n = side_nodes(m, b, s);
                let c = cs
                    .iter()
                    .position(|c| n.iter().all(|&p| on_circle(p, c, tol)))
                    .unwrap_or_else(|| panic!("wall side of block {b} is not on a circle"));
                wall_of[b] = c;
            }
            2 => {
                let (a, sa) = users[0];
                let (b, sb) = users[1];
                assert!(sa != 0 && sb != 0, "a wall side is shared");
                let mut na = side_nodes(m, a, sa);
                let nb = side_nodes(m, b, sb);
                if key(na[0]) != key(nb[0]) {
                    na.reverse();
                }
                let ka: Vec<_> = na.iter().map(|&p| key(p)).collect();
                let kb: Vec<_> = nb.iter().map(|&p| key(p)).collect();
                assert_eq!(ka, kb, "blocks {a}/{b} share a node set but not the order");
            }
            k => panic!("{k} block sides have the same nodes"),
        }
    }
    // Every block's wall is side 0.
    assert!(
        wall_of.iter().all(|&c| c != usize::MAX),
        "a block without a wall side"
    );

    // Wall normality: the line from node (i, 0) to (i, 1) along the circle's normal.
    for (b, g) in m.grids.iter().enumerate() {
        let c = cs[wall_of[b]].center;
        for i in 0..=g.ni {
            let (p, q) = (g.node(i, 0), g.node(i, 1));
            let n = [p[0] - c[0], p[1] - c[1]];
            let t = [q[0] - p[0], q[1] - p[1]];
            let ang = (n[0] * t[1] - n[1] * t[0])
                .abs()
                .atan2((n[0] * t[0] + n[1] * t[1]).abs())
                .to_degrees();
            assert!(
                ang < 1e-6,
                "block {b} node {i}: {ang} degrees off the wall normal"
            );
        }
    }

    // Positive Jacobians at every cell corner.
    for (b, g) in m.grids.iter().enumerate() {
        for j in 0..g.nj {
            for i in 0..g.ni {
                let q = [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ];
                for k in 0..4 {
                    let (p, a, bb) = (q[k], q[(k + 1) % 4], q[(k + 3) % 4]);
                    let cross = (a[0] - p[0]) * (bb[1] - p[1]) - (a[1] - p[1]) * (bb[0] - p[0]);
                    assert!(cross > 0.0, "block {b} cell ({i}, {j}) corner {k}: {cross}");
                }
            }
        }
    }
    wall_of
}

/// Exact mode without macro Delaunay refinement: every block of these layouts has a wall
/// (inserted holes and their templates are checked in `exactmode_degenerate.rs`).
fn exact(cells: usize) -> Options {
    Options {
        mode: Mode::Exact,
        cells,
        refine_ratio: None,
        ..Options::default()
    }
}

#[test]
fn exact_is_the_default_mode() {
    assert_eq!(Options::default().mode, Mode::Exact);
}

#[test]
fn hexagon_example_is_valid_and_orthogonal() {
    let d = Domain::hexagon_example();
    let m = mesh(&d, &exact(8)).expect("mesh");
    check(&d, &m);
}

#[test]
fn first_cell_height_is_as_requested() {
    let d = Domain::hexagon_example();
    let first = 1e-3;
    let opts = Options {
        clustering: Clustering {
            first: Some(FirstCell::Absolute(first)),
            growth: 1.15,
        },
        // A relative first height on the centre hole, 1% of its radius (0.3).
        circle_clustering: vec![(
            0,
            Clustering {
                first: Some(FirstCell::Relative(0.01)),
                growth: 1.1,
            },
        )],
        // A fixed wall-normal count on hole 3.
        wall_cells: vec![(3, 30)],
        ..exact(8)
    };
    let m = mesh(&d, &opts).expect("mesh");
    let wall_of = check(&d, &m);
    let cs = circles(&d);
    for (b, g) in m.grids.iter().enumerate() {
        let want = if wall_of[b] == 1 { 0.01 * 0.3 } else { first };
        if wall_of[b] == 4 {
            assert_eq!(g.nj, 30);
        }
        for i in 0..=g.ni {
            let got = {
                let (p, q) = (g.node(i, 0), g.node(i, 1));
                (q[0] - p[0]).hypot(q[1] - p[1])
            };
            let spoke = {
                let (p, q) = (g.node(i, 0), g.node(i, g.nj));
                (q[0] - p[0]).hypot(q[1] - p[1])
            };
            if spoke > want * g.nj as f64 {
                assert!(
                    ((got - want) / want).abs() < 1e-9,
                    "block {b} (circle {:?}) spoke {i}: first cell {got}, asked {want}",
                    cs[wall_of[b]]
                );
            }
        }
    }
}

#[test]
fn smoothing_never_lowers_the_min_scaled_jacobian() {
    for (seed, h) in [(1u64, 6usize), (7, 12), (11, 3)] {
        let d = layout(seed, h, 0.02);
        let plain = mesh(&d, &exact(6)).expect("mesh");
        let smooth = mesh(
            &d,
            &Options {
                smooth: 20,
                ..exact(6)
            },
        )
        .expect("mesh");
        check(&d, &smooth);
        let (a, b) = (min_scaled_jacobian(&plain), min_scaled_jacobian(&smooth));
        assert!(
            b >= a,
            "smoothing lowered the min scaled Jacobian: {a} -> {b}"
        );
        // Walls and the first layer do not move.
        for (g0, g1) in plain.grids.iter().zip(&smooth.grids) {
            for i in 0..=g0.ni {
                assert_eq!(key(g0.node(i, 0)), key(g1.node(i, 0)));
                assert_eq!(key(g0.node(i, 1)), key(g1.node(i, 1)));
            }
        }
    }
}

#[test]
fn options_are_validated() {
    let d = Domain::hexagon_example();
    for bad in [
        Options {
            cell_size: Some(0.0),
            ..exact(8)
        },
        Options {
            clustering: Clustering {
                first: Some(FirstCell::Absolute(-1.0)),
                growth: 1.2,
            },
            ..exact(8)
        },
        Options {
            clustering: Clustering {
                first: None,
                growth: 0.5,
            },
            ..exact(8)
        },
        Options {
            wall_cells: vec![(0, 0)],
            ..exact(8)
        },
    ] {
        assert!(matches!(
            mesh(&d, &bad),
            Err(medial_blocks::MeshError::Options(_))
        ));
    }
}

#[test]
fn cell_size_controls_resolution() {
    let d = Domain::hexagon_example();
    let coarse = mesh(
        &d,
        &Options {
            cell_size: Some(0.1),
            ..exact(8)
        },
    )
    .unwrap();
    let fine = mesh(
        &d,
        &Options {
            cell_size: Some(0.05),
            ..exact(8)
        },
    )
    .unwrap();
    let cells = |m: &Mesh| m.grids.iter().map(|g| g.ni * g.nj).sum::<usize>();
    let ratio = cells(&fine) as f64 / cells(&coarse) as f64;
    assert!(
        ratio > 3.0 && ratio < 5.0,
        "halving the size gave {ratio}x cells"
    );
    check(&d, &fine);
}

#[test]
fn deterministic() {
    let d = layout(5, 9, 0.02);
    let a = mesh(&d, &exact(5)).unwrap();
    let b = mesh(&d, &exact(5)).unwrap();
    assert_eq!(a.grids, b.grids);
    assert_eq!(a.layout, b.layout);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
    #[test]
    fn random_layouts_are_valid_orthogonal_and_conforming(seed in any::<u64>(), h in 2usize..30) {
        let d = layout(seed, h, 0.02);
        prop_assume!(d.holes().len() >= 2);
        let m = mesh(&d, &exact(3)).expect("exact mode");
        check(&d, &m);
    }

    #[test]
    fn clustered_and_smoothed_layouts_stay_valid(seed in any::<u64>(), h in 2usize..12) {
        let d = layout(seed, h, 0.01);
        prop_assume!(d.holes().len() >= 2);
        let opts = Options {
            clustering: Clustering { first: Some(FirstCell::Relative(0.01)), growth: 1.2 },
            smooth: 5,
            ..exact(3)
        };
        let m = mesh(&d, &opts).expect("exact mode");
        check(&d, &m);
    }

    #[test]
    fn close_holes_still_mesh(seed in any::<u64>(), h in 2usize..12) {
        let d = layout(seed, h, 0.002);
        prop_assume!(d.holes().len() >= 2);
        let m = mesh(&d, &exact(2)).expect("exact mode");
        check(&d, &m);
    }
}

#[test]
fn layout_matches_grids() {
    use medial_blocks::grid::validate_layout;
    use medial_blocks::layout::{Curve, EdgeKind};
    let d = layout(3, 10, 0.02);
    let m = mesh(&d, &exact(4)).unwrap();
    validate_layout(&m.layout).expect("valid layout");
    for (b, block) in m.layout.blocks.iter().enumerate() {
        for s in 0..4 {
            let nodes = side_nodes(&m, b, s);
            assert_eq!(
                key(nodes[0]),
                key(m.layout.vertices[block.corners[s] as usize])
            );
            let edge = &m.layout.edges[block.sides[s].edge as usize];
            match (s, edge.kind, &edge.curve) {
                (0, EdgeKind::Wall(_), Curve::Arc { .. }) => {}
                (2, EdgeKind::Medial, Curve::Polyline(p)) => {
                    // The polyline is the medial nodes themselves.
                    let mut p = p.clone();
                    if block.sides[s].reversed {
                        p.reverse();
                    }
                    let a: Vec<_> = p.into_iter().map(key).collect();
                    let b: Vec<_> = nodes.into_iter().map(key).collect();
                    assert_eq!(a, b);
                }
                (1 | 3, EdgeKind::Spoke, Curve::Segment) => {}
                other => panic!("block {b} side {s}: {other:?}"),
            }
        }
    }
}

#[test]
fn cocircular_holes_do_not_panic() {
    // Four equal holes on a square: one empty circle touches all four (a zero-length arc and
    // two zero-area blocks if they were not collapsed).
    let holes = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
        .map(|c| Circle {
            center: c,
            radius: 0.25,
        })
        .to_vec();
    let d = Domain::bounded(
        Circle {
            center: [0.5, 0.5],
            radius: 3.0,
        },
        holes,
    )
    .unwrap();
    // Exact mode sees the exact geometry disagree with the sampled combinatorics and hands the
    // layout to the degeneracy handling: one co-circular group, its zero-length arc collapsed.
    let m = mesh(&d, &exact(4)).expect("co-circular holes mesh");
    assert_eq!(m.cocircular_groups.len(), 1);
    assert_eq!(m.collapsed_arcs, 1);
    assert_eq!(m.grids.len(), 18 - 2);
    assert_eq!(medial_blocks::quality::measure(&m.grids).inverted_cells, 0);
}

/// One hole anywhere in the bounding circle, its gap to the bounding circle at least
/// `min_gap * R` (concentric for `concentric`).
fn one_hole(seed: u64, min_gap: f64, concentric: bool) -> Domain {
    let mut rng = SplitMix64(seed);
    let big_r = 0.5 + 20.0 * rng.next_f64();
    let center = [rng.next_f64() * 100.0 - 50.0, rng.next_f64() * 100.0 - 50.0];
    // Radius from 1e-3 R to nearly R, offset anywhere the gap allows.
    let r = big_r * (1e-3 + (1.0 - 1e-3 - 2.0 * min_gap) * rng.next_f64().powi(2));
    let room = big_r - r - min_gap * big_r;
    let (dist, angle) = if concentric {
        (0.0, 0.0)
    } else {
        (
            room * rng.next_f64().sqrt(),
            std::f64::consts::TAU * rng.next_f64(),
        )
    };
    let hole = Circle {
        center: [
            center[0] + dist * angle.cos(),
            center[1] + dist * angle.sin(),
        ],
        radius: r,
    };
    Domain::bounded(
        Circle {
            center,
            radius: big_r,
        },
        vec![hole],
    )
    .expect("generated one-hole layout is valid")
}

/// Every medial node of a one-hole mesh (side 2 of every block) lies on the ellipse
/// `|m - c| + |m - h| = R + r` (equidistant from both walls), recomputed from the nodes.
fn medial_nodes_are_equidistant(d: &Domain, m: &Mesh) {
    let (big, hole) = (d.bounding(), d.holes()[0]);
    let scale = big.radius + big.center[0].abs().max(big.center[1].abs());
    for b in 0..m.grids.len() {
        for p in side_nodes(m, b, 2) {
            let to_hole = (p[0] - hole.center[0]).hypot(p[1] - hole.center[1]) - hole.radius;
            let to_big = big.radius - (p[0] - big.center[0]).hypot(p[1] - big.center[1]);
            assert!(
                (to_hole - to_big).abs() <= 1e-12 * scale,
                "block {b}: medial node {p:?} is {to_hole} from the hole, {to_big} from the \
                 bounding circle"
            );
        }
    }
}

#[test]
fn one_hole_is_meshed_exactly_on_its_medial_loop() {
    // Concentric, off-centre, a large hole with a thin gap (a small hole far off-centre gets a
    // seeded hole instead: `a_small_hole_by_the_wall_is_meshed_with_a_seeded_hole`).
    let cases = [
        (Circle::new(0.0, 0.0, 10.0), Circle::new(0.0, 0.0, 1.0)),
        (Circle::new(0.0, 0.0, 10.0), Circle::new(3.0, -2.0, 1.0)),
        (Circle::new(0.0, 0.0, 1.0), Circle::new(0.0, 0.05, 0.9)),
    ];
    for (big, hole) in cases {
        let d = Domain::bounded(big, vec![hole]).unwrap();
        for opts in [exact(8), block_cells(16)] {
            let m = mesh(&d, &opts).expect("mesh");
            check(&d, &m);
            medial_nodes_are_equidistant(&d, &m);
            // One block per wall per piece: half on the hole, half on the bounding circle.
            let walls: Vec<_> = m.layout.blocks.iter().map(|b| b.wall).collect();
            assert_eq!(
                walls.iter().filter(|&&w| w == Some(0)).count(),
                ANNULUS_ARCS
            );
            assert_eq!(
                walls.iter().filter(|&&w| w == Some(-1)).count(),
                ANNULUS_ARCS
            );
        }
    }
}

/// A small hole far off-centre: its medial loop is a long thin ellipse and the ring's cells
/// shear (3.4 degrees, aspect ratios of 8000 for a hole of 1e-3 R by the wall). Below
/// `LONE_HOLE_GOOD_ANGLE_DEG` the lone hole is also meshed with a fluid hole seeded opposite
/// it, and that mesh is kept: exact, one inserted hole, no inverted cell, a smallest angle
/// above the ring's (built here on its own) and above 14 degrees.
#[test]
fn a_small_hole_by_the_wall_is_meshed_with_a_seeded_hole() {
    use medial_blocks::exact_mode::annulus::build_annulus;
    use medial_blocks::mesher::LONE_HOLE_GOOD_ANGLE_DEG;
    use medial_blocks::quality::measure;
    let cases = [
        (
            Circle::new(5.0, 5.0, 10.0),
            Circle::new(5.0 + 9.9, 5.0, 0.05),
        ),
        (Circle::new(0.0, 0.0, 1.0), Circle::new(0.0, -0.98, 0.01)),
        (Circle::new(0.0, 0.0, 1.0), Circle::new(0.7, 0.7, 0.001)),
    ];
    for (big, hole) in cases {
        let d = Domain::bounded(big, vec![hole]).unwrap();
        for opts in [exact(8), block_cells(8)] {
            let ring = build_annulus(&d, &opts).unwrap().expect("ring");
            let ring_min = measure(&ring.grids).min_angle_deg;
            assert!(ring_min < LONE_HOLE_GOOD_ANGLE_DEG, "{ring_min}");
            let m = mesh(&d, &opts).expect("mesh");
            let q = measure(&m.grids);
            assert_eq!(m.geometry, medial_blocks::mesh::Geometry::Exact);
            assert_eq!((m.holes, m.inserted_holes.len()), (1, 1));
            assert_eq!(q.inverted_cells, 0);
            assert!(
                q.min_angle_deg > ring_min,
                "{} vs ring {ring_min} ({hole:?}, {:?})",
                q.min_angle_deg,
                opts.block_cells
            );
            // The ring's long sheared cells are gone.
            let aspect = |grids: &[medial_blocks::BlockGrid]| {
                grids
                    .iter()
                    .flat_map(|g| medial_blocks::quality::cell_fields(g).aspect_ratio)
                    .fold(0.0, f64::max)
            };
            let (ring_aspect, seeded_aspect) = (aspect(&ring.grids), aspect(&m.grids));
            assert!(
                seeded_aspect * 4.0 < ring_aspect,
                "aspect {seeded_aspect} vs ring {ring_aspect} ({hole:?}, {:?})",
                opts.block_cells
            );
            medial_blocks::fuzzing::check_mesh(&d, &m).unwrap();
        }
    }
}

fn block_cells(n: usize) -> Options {
    Options {
        block_cells: Some(n),
        ..exact(n)
    }
}

#[test]
fn one_hole_first_cell_height_is_as_requested() {
    // The clustering options reach both walls of the annulus (the template ring ignores them).
    let d = Domain::bounded(Circle::new(0.0, 0.0, 4.0), vec![Circle::new(1.2, 0.7, 0.5)]).unwrap();
    let opts = Options {
        clustering: Clustering {
            first: Some(FirstCell::Absolute(2e-3)),
            growth: 1.15,
        },
        circle_clustering: vec![(
            0,
            Clustering {
                first: Some(FirstCell::Relative(0.01)),
                growth: 1.1,
            },
        )],
        ..exact(8)
    };
    let m = mesh(&d, &opts).expect("mesh");
    let wall_of = check(&d, &m);
    for (b, g) in m.grids.iter().enumerate() {
        // Circle index 1 is the hole (0.01 of its radius 0.5), 0 the bounding circle.
        let want = if wall_of[b] == 1 { 0.01 * 0.5 } else { 2e-3 };
        for i in 0..=g.ni {
            let (p, q) = (g.node(i, 0), g.node(i, 1));
            let got = (q[0] - p[0]).hypot(q[1] - p[1]);
            assert!(
                ((got - want) / want).abs() < 1e-9,
                "block {b} spoke {i}: first cell {got}, asked {want}"
            );
        }
    }
    // A fixed wall-normal count on the hole.
    let fixed = Options {
        wall_cells: vec![(0, 23)],
        ..exact(8)
    };
    let m = mesh(&d, &fixed).expect("mesh");
    let wall_of = check(&d, &m);
    for (b, g) in m.grids.iter().enumerate() {
        if wall_of[b] == 1 {
            assert_eq!(g.nj, 23, "block {b}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]
    #[test]
    fn one_hole_layouts_are_valid_orthogonal_and_conforming(
        seed in any::<u64>(),
        gap in prop::sample::select(vec![1e-1, 1e-2, 1e-4]),
        concentric in any::<bool>(),
        smooth in prop::sample::select(vec![0usize, 5]),
    ) {
        let d = one_hole(seed, gap, concentric);
        let opts = Options {
            clustering: Clustering { first: Some(FirstCell::Relative(0.01)), growth: 1.2 },
            smooth,
            ..block_cells(6)
        };
        let m = mesh(&d, &opts).expect("exact mode");
        if m.inserted_holes.is_empty() {
            check(&d, &m);
            medial_nodes_are_equidistant(&d, &m);
        } else {
            // A small hole far off-centre, meshed with a seeded hole (see
            // `a_small_hole_by_the_wall_is_meshed_with_a_seeded_hole`): the general checks.
            prop_assert_eq!(m.inserted_holes.len(), 1);
            prop_assert_eq!(medial_blocks::quality::measure(&m.grids).inverted_cells, 0);
            medial_blocks::fuzzing::check_mesh(&d, &m).unwrap();
        }
        // The same layout, the same mesh.
        let again = mesh(&d, &opts).expect("exact mode");
        prop_assert_eq!(&m.grids, &again.grids);
    }
}
