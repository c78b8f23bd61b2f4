//! End-to-end properties of `mesh()` on generated layouts, checked without trusting the
//! layout: counting identities, conformity found from node coordinates alone, positive
//! Jacobians recomputed here, wall nodes on their circles, and the cells exactly tiling the
//! polygonal fluid region (area identity).

use medial_blocks::domain::{Circle, Domain};
use medial_blocks::grid::MAX_ARC_PER_CELL;
use medial_blocks::layout::Curve;
use medial_blocks::layouts::SplitMix64;
use medial_blocks::{mesh, Mesh, Options};
use proptest::prelude::*;
use std::collections::HashMap;

/// Up to `h` random holes (rejection sampling) with gaps of at least `min_gap * R`.
fn layout(seed: u64, h: usize, min_gap: f64) -> Domain {
    let mut rng = SplitMix64(seed);
    let big_r = 1.0 + 9.0 * rng.next_f64();
    let center = [rng.next_f64() * 10.0 - 5.0, rng.next_f64() * 10.0 - 5.0];
    let mut holes: Vec<Circle> = Vec::new();
    let mut tries = 0;
    while holes.len() < h && tries < 20_000 {
        tries += 1;
        let r = big_r * (0.03 + 0.15 * rng.next_f64());
        let a = rng.next_f64() * std::f64::consts::TAU;
        let d = (big_r - r - min_gap * big_r) * rng.next_f64().sqrt();
        let c = [center[0] + d * a.cos(), center[1] + d * a.sin()];
        let ok = holes.iter().all(|o| {
            let dd = ((c[0] - o.center[0]).powi(2) + (c[1] - o.center[1]).powi(2)).sqrt();
            dd - r - o.radius > min_gap * big_r
        });
        if ok {
            holes.push(Circle {
                center: c,
                radius: r,
            });
        }
    }
    Domain::bounded(
        Circle {
            center,
            radius: big_r,
        },
        holes,
    )
    .expect("generated layout is valid")
}

/// A node's exact coordinates.
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

fn on_circle(p: [f64; 2], c: &Circle, tol: f64) -> bool {
    (((p[0] - c.center[0]).powi(2) + (p[1] - c.center[1]).powi(2)).sqrt() - c.radius).abs() <= tol
}

fn shoelace(p: &[[f64; 2]]) -> f64 {
    (0..p.len())
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % p.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        * 0.5
}

/// Every check of this file on one domain; returns the mesh. `valid`: also require every cell
/// corner to have a positive Jacobian. Paper mode (equally spaced nodes on the medial arc and
/// on the wall, as the paper's section 6 admits) can fold cells where a hole nearly touches the
/// bounding circle or an interior triangle is a sliver; those layouts are checked for
/// everything else (the signed area identity holds even for folded TFI grids).
fn check(domain: &Domain, cells: usize, valid: bool) -> Mesh {
    let m = mesh(
        domain,
        &Options {
            cells,
            ..Options::paper()
        },
    )
    .expect("mesh");
    let h = domain.holes().len();
    let big_r = domain.bounding().radius;
    let tol = 1e-12 * big_r.max(1.0) * 16.0;

    // Counting identities.
    let blocks = m.grids.len();
    match h {
        0 => assert_eq!(blocks, 5),
        1 => assert_eq!(blocks, 4),
        _ => {
            // Holes inserted by macro Delaunay refinement count as holes of the medial graph;
            // collapsed arcs remove two blocks each, split pairs add two, templates fill the
            // inserted holes.
            let h = h + m.inserted_holes.len();
            assert_eq!(m.medial_vertices, 2 * (h - 1));
            assert_eq!(m.medial_arcs, 3 * (h - 1));
            assert_eq!(
                blocks,
                6 * (h - 1) - 2 * m.collapsed_arcs + 2 * m.split_arcs + m.template_blocks
            );
        }
    }

    // No wall cell spans more than grid::MAX_ARC_PER_CELL of its circle.
    for (block, g) in m.layout.blocks.iter().zip(&m.grids) {
        for (s, side) in block.sides.iter().enumerate() {
            if let Curve::Arc { sweep, .. } = m.layout.edges[side.edge as usize].curve {
                let n = if s % 2 == 0 { g.ni } else { g.nj };
                assert!(sweep.abs() / n as f64 <= MAX_ARC_PER_CELL * (1.0 + 1e-12));
                assert!(n >= cells);
            }
        }
    }

    // Conformity from coordinates: sides keyed by the set of their node coordinates (two
    // medial arcs or two wall arcs may share both end points, so ends alone are ambiguous).
    let mut by_ends: HashMap<Vec<Key>, Vec<(usize, usize)>> = HashMap::new();
    for b in 0..blocks {
        for s in 0..4 {
            let mut k: Vec<_> = side_nodes(&m, b, s).into_iter().map(key).collect();
            k.sort_unstable();
            by_ends.entry(k).or_default().push((b, s));
        }
    }
    let circles: Vec<Circle> = std::iter::once(domain.bounding())
        .chain(domain.holes().iter().copied())
        .collect();
    let mut wall_nodes: Vec<Vec<[f64; 2]>> = vec![Vec::new(); circles.len()];
    for users in by_ends.values() {
        match users.len() {
            1 => {
                // A boundary side: all its nodes on one circle.
                let (b, s) = users[0];
                let n = side_nodes(&m, b, s);
                let c = circles
                    .iter()
                    .position(|c| n.iter().all(|&p| on_circle(p, c, tol * (1.0 + c.radius))))
                    .unwrap_or_else(|| {
                        panic!("unpartnered side {s} of block {b} is not on a circle")
                    });
                wall_nodes[c].extend(n);
            }
            2 => {
                let (a, sa) = users[0];
                let (b, sb) = users[1];
                let mut na = side_nodes(&m, a, sa);
                let nb = side_nodes(&m, b, sb);
                if key(na[0]) != key(nb[0]) {
                    na.reverse();
                }
                let ka: Vec<_> = na.iter().map(|&p| key(p)).collect();
                let kb: Vec<_> = nb.iter().map(|&p| key(p)).collect();
                assert_eq!(ka, kb, "blocks {a}/{b} share ends but not nodes");
            }
            k => panic!("{k} block sides have the same nodes"),
        }
    }

    // Validity: every corner of every cell has a positive cross product.
    let mut cell_area = 0.0;
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
                    let cross = (a[0] - p[0]) * (b[1] - p[1]) - (a[1] - p[1]) * (b[0] - p[0]);
                    assert!(!valid || cross > 0.0, "inverted corner");
                }
                cell_area += shoelace(&q);
            }
        }
    }

    // Area identity: cells tile the region between the wall polygons, no gap, no overlap.
    let mut expected = 0.0;
    for (k, nodes) in wall_nodes.iter_mut().enumerate() {
        assert!(!nodes.is_empty(), "circle {} has no wall", k as i64 - 1);
        let c = circles[k].center;
        nodes.sort_by(|p, q| {
            let ap = (p[1] - c[1]).atan2(p[0] - c[0]);
            let aq = (q[1] - c[1]).atan2(q[0] - c[0]);
            ap.total_cmp(&aq)
        });
        nodes.dedup_by(|p, q| key(*p) == key(*q));
        let a = shoelace(nodes);
        expected += if k == 0 { a } else { -a };
    }
    let rel = (cell_area - expected).abs() / expected;
    assert!(
        rel < 1e-9,
        "cells cover {cell_area}, the fluid polygon is {expected}"
    );
    m
}

#[test]
fn hexagon_example_has_36_conforming_valid_blocks() {
    let m = check(&Domain::hexagon_example(), 8, true);
    assert_eq!(m.grids.len(), 36);
}

#[test]
fn disk_and_annulus_templates() {
    check(&layout(1, 0, 0.05), 6, true);
    for seed in 0..8 {
        check(&layout(seed, 1, 0.02), 5, true);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
    #[test]
    fn random_layouts_conform_and_count(seed in any::<u64>(), h in 2usize..30) {
        let d = layout(seed, h, 0.02);
        check(&d, 3, false);
    }

    #[test]
    fn close_holes_still_mesh(seed in any::<u64>(), h in 2usize..12) {
        let d = layout(seed, h, 0.002);
        check(&d, 2, false);
    }
}
