//! Exact mode on degenerate and refined layouts (issues #4 and #5): co-circular groups and
//! collapsed arcs give collapsed vertices of degree n with 2n blocks, inserted holes are filled
//! by templates, and the result is still exact geometry (no fallback to paper geometry).
//!
//! Oracles that do not trust the code: block counts from analytic group lists and the counting
//! identity, vertex degrees counted from block corners, conformity and validity recomputed from
//! coordinates ([`check_mesh_with`]), wall orthogonality measured on the grids, inserted holes
//! checked to be fully covered by template nodes that are bitwise the outer blocks' nodes.

use crate::common;

use medial_blocks::domain::{Circle, Domain};
use medial_blocks::exact_mode::metrics::max_wall_orthogonality_deviation_deg;
use medial_blocks::fuzzing::{check_mesh_with, Checks};
use medial_blocks::layout::EdgeKind;
use medial_blocks::layouts::{self, SplitMix64};
use medial_blocks::mesh::Geometry;
use medial_blocks::quality::measure;
use medial_blocks::{mesh, Mesh, Options};
use proptest::prelude::*;
use std::collections::{HashMap, HashSet};

fn opts(cells: usize) -> Options {
    Options {
        cells,
        ..Options::default()
    }
}

/// Everything exact mode promises, from coordinates.
fn check_exact(d: &Domain, m: &Mesh) {
    assert_eq!(m.geometry, Geometry::Exact, "fell back to paper geometry");
    let r = check_mesh_with(
        d,
        m,
        Checks {
            no_inverted_cells: true,
        },
    )
    .unwrap_or_else(|e| panic!("mesh check: {e}"));
    assert_eq!(r.inverted_cells, 0);
    assert_eq!(measure(&m.grids).inverted_cells, 0);
    let dev = max_wall_orthogonality_deviation_deg(d, &m.layout, &m.grids);
    assert!(dev <= 0.5, "wall orthogonality deviation {dev} deg");
    // Counting identity with collapse, splits and templates (h counts inserted holes).
    let h = d.hole_count() + m.inserted_holes.len();
    assert_eq!(
        m.layout.blocks.len() + 2 * m.collapsed_arcs,
        6 * (h - 1) + 2 * m.split_arcs + m.template_blocks
    );
    // No wall on an inserted hole: the template blocks cover it.
    for b in &m.layout.blocks {
        if let Some(c) = b.wall {
            assert!(
                c < d.hole_count() as i32,
                "block with wall on inserted hole {c}"
            );
        }
    }
    for e in &m.layout.edges {
        if let EdgeKind::Wall(c) = e.kind {
            assert!(c < d.hole_count() as i32, "wall edge on inserted hole {c}");
        }
    }
    check_inserted_holes_filled(m);
}

/// Every node on an inserted hole's circle belongs both to an outer block and to a template
/// block (bitwise), and the template blocks' nodes never leave the hole's disk.
fn check_inserted_holes_filled(m: &Mesh) {
    if m.inserted_holes.is_empty() {
        assert_eq!(m.template_blocks, 0);
        return;
    }
    assert!(m.template_blocks >= 5 * m.inserted_holes.len());
    let first = m.layout.blocks.len() - m.template_blocks;
    let key = |p: [f64; 2]| (p[0].to_bits(), p[1].to_bits());
    let mut outer: HashSet<(u64, u64)> = HashSet::new();
    for g in &m.grids[..first] {
        outer.extend(g.nodes.iter().map(|&p| key(p)));
    }
    let mut inner: HashSet<(u64, u64)> = HashSet::new();
    for g in &m.grids[first..] {
        inner.extend(g.nodes.iter().map(|&p| key(p)));
    }
    for c in &m.inserted_holes {
        let on_circle = |p: [f64; 2]| {
            ((p[0] - c.center[0]).hypot(p[1] - c.center[1]) - c.radius).abs() <= 1e-9 * c.radius
        };
        let mut seen = 0;
        for g in &m.grids[..first] {
            for &p in &g.nodes {
                if on_circle(p) {
                    seen += 1;
                    assert!(
                        inner.contains(&key(p)),
                        "outer node {p:?} not in a template"
                    );
                }
            }
        }
        assert!(seen >= 4, "no outer nodes on inserted hole {c:?}");
        let mut inside = 0;
        for g in &m.grids[first..] {
            for &p in &g.nodes {
                let r = (p[0] - c.center[0]).hypot(p[1] - c.center[1]);
                if r <= c.radius * (1.0 + 1e-9) {
                    inside += 1;
                    if on_circle(p) {
                        assert!(
                            outer.contains(&key(p)),
                            "template node {p:?} not conforming"
                        );
                    }
                }
            }
        }
        assert!(inside > 0);
    }
}

/// For every medial layout vertex (a block corner not on a wall), the number of blocks around it.
fn corner_degrees(m: &Mesh) -> HashMap<u32, usize> {
    let mut deg: HashMap<u32, usize> = HashMap::new();
    let first = m.layout.blocks.len() - m.template_blocks;
    for b in &m.layout.blocks[..first] {
        // Corners 2 and 3 of a medial block are on the medial axis.
        for &v in &b.corners[2..] {
            *deg.entry(v).or_default() += 1;
        }
    }
    deg
}

#[test]
fn square_lattices_collapse_every_group_into_a_degree_four_vertex() {
    for k in [2usize, 3, 4, 5] {
        let d = layouts::square_lattice(k * k).unwrap();
        let m = mesh(&d, &opts(4)).unwrap();
        check_exact(&d, &m);
        // The analytic groups: one per unit square of the lattice, four holes each.
        let groups = (k - 1) * (k - 1);
        assert_eq!(m.cocircular_groups.len(), groups, "k = {k}");
        assert!(m.inserted_holes.is_empty());
        let h = k * k;
        assert_eq!(m.layout.blocks.len(), 6 * (h - 1) - 2 * groups, "k = {k}");
        // Eight blocks meet at each group's centre (the centre of a unit square).
        let deg = corner_degrees(&m);
        let eights: Vec<[f64; 2]> = deg
            .iter()
            .filter(|(_, &n)| n == 8)
            .map(|(&v, _)| m.layout.vertices[v as usize])
            .collect();
        assert_eq!(eights.len(), groups, "k = {k}");
        let half = (k as f64 - 1.0) / 2.0;
        for p in eights {
            for x in p {
                let frac = (x + half).fract();
                assert!((frac - 0.5).abs() < 1e-12, "group centre {p:?}");
            }
        }
    }
}

/// `n` equal holes on a circle of radius 1 around an empty centre.
fn ngon(n: usize) -> Domain {
    let r = 0.6 * (std::f64::consts::PI / n as f64).sin();
    let holes = (0..n)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / n as f64;
            Circle::new(a.cos(), a.sin(), r)
        })
        .collect();
    Domain::bounded(Circle::new(0.0, 0.0, 2.0), holes).unwrap()
}

#[test]
fn regular_ngons_have_one_central_vertex_of_degree_n() {
    for n in 4..=12 {
        let d = ngon(n);
        let m = mesh(&d, &opts(3)).unwrap();
        check_exact(&d, &m);
        // The central empty circle touches all n holes: n - 2 medial vertices, n - 3 arcs
        // between them collapsed (exactly, or as short arcs when rounding broke the symmetry).
        let deg = corner_degrees(&m);
        let (&v, _) = deg
            .iter()
            .find(|(_, &k)| k == 2 * n)
            .unwrap_or_else(|| panic!("n = {n}: no vertex with {} blocks", 2 * n));
        let c = m.layout.vertices[v as usize];
        assert!(c[0].hypot(c[1]) < 1e-9, "n = {n}: centre {c:?}");
        assert!(m.collapsed_arcs >= n - 3, "n = {n}");
    }
}

#[test]
fn exactly_cocircular_square_is_one_group() {
    // Four holes at (+-1, 0), (0, +-1): exactly co-circular with the empty circle at 0.
    let holes = vec![
        Circle::new(1.0, 0.0, 0.4),
        Circle::new(0.0, 1.0, 0.4),
        Circle::new(-1.0, 0.0, 0.4),
        Circle::new(0.0, -1.0, 0.4),
    ];
    let d = Domain::bounded(Circle::new(0.0, 0.0, 2.0), holes).unwrap();
    let m = mesh(&d, &opts(4)).unwrap();
    check_exact(&d, &m);
    assert_eq!(m.cocircular_groups.len(), 1);
    assert_eq!(m.cocircular_groups[0].center, [0.0, 0.0]);
    let deg = corner_degrees(&m);
    let (&v, _) = deg.iter().find(|(_, &k)| k == 8).expect("degree-4 vertex");
    assert_eq!(m.layout.vertices[v as usize], [0.0, 0.0]);
}

#[test]
fn ulp_nudged_lattices_stay_exact() {
    for k in [3usize, 4] {
        let base = layouts::square_lattice(k * k).unwrap();
        for which in [0usize, k + 1] {
            let mut holes = base.holes().to_vec();
            let x = holes[which].center[0];
            holes[which].center[0] = f64::from_bits(x.to_bits() + 1);
            let d = Domain::bounded(base.bounding(), holes).unwrap();
            let m = mesh(&d, &opts(3)).unwrap();
            check_exact(&d, &m);
        }
    }
}

#[test]
fn hexagon_example_is_within_three_degrees_of_its_limit() {
    let d = Domain::hexagon_example();
    let m = mesh(&d, &Options::default()).unwrap();
    check_exact(&d, &m);
    assert_eq!(m.layout.blocks.len(), 36);
    let q = measure(&m.grids);
    assert!(q.min_angle_deg >= 57.0, "{}", q.min_angle_deg);
    assert!(q.max_angle_deg <= 123.0, "{}", q.max_angle_deg);
    assert!(m.cocircular_groups.is_empty());
    assert_eq!(m.collapsed_arcs, 0);
}

/// Two nearly touching holes far from a third: a sliver triangle that refinement must fix.
fn sliver() -> Domain {
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
fn inserted_holes_are_filled_by_conforming_templates() {
    let d = sliver();
    let m = mesh(&d, &opts(4)).unwrap();
    assert!(!m.inserted_holes.is_empty(), "refinement inserted nothing");
    check_exact(&d, &m);
    assert!(m.template_blocks > 0);
    // Without refinement, no template.
    let plain = mesh(
        &d,
        &Options {
            refine_ratio: None,
            ..opts(4)
        },
    )
    .unwrap();
    check_exact(&d, &plain);
    assert!(plain.inserted_holes.is_empty());
}

#[test]
fn degenerate_meshes_are_deterministic() {
    for d in [sliver(), layouts::square_lattice(9).unwrap(), ngon(7)] {
        let a = mesh(&d, &opts(3)).unwrap();
        let b = mesh(&d, &opts(3)).unwrap();
        assert_eq!(a.layout, b.layout);
        assert_eq!(a.grids, b.grids);
    }
}

/// Up to `h` random holes of radii in `[0.03, 0.18] R` with gaps of at least `min_gap R`.
fn random_layout(seed: u64, h: usize, min_gap: f64) -> Domain {
    let mut rng = SplitMix64(seed);
    let big_r = 1.0 + 4.0 * rng.next_f64();
    let holes = common::random_holes(&mut rng, h, big_r, [0.0, 0.0], min_gap);
    Domain::bounded(Circle::new(0.0, 0.0, big_r), holes).expect("valid layout")
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random layouts with poor angles (small gaps): refinement and collapse with the default
    /// options, and aggressive collapsing; exact geometry every time.
    #[test]
    fn random_poor_layouts_are_meshed_exactly(
        seed in any::<u64>(),
        h in 2usize..14,
        gap in 0.002f64..0.05,
        fraction in prop_oneof![Just(0.0), Just(0.05), Just(0.3)],
    ) {
        let d = random_layout(seed, h, gap);
        prop_assume!(d.hole_count() >= 2);
        let o = Options { cells: 2, collapse_fraction: fraction, ..Options::default() };
        let m = mesh(&d, &o).unwrap();
        check_exact(&d, &m);
    }
}

/// A case `random_poor_layouts_are_meshed_exactly` found (it fell back to paper geometry on
/// an earlier version), kept as a named regression.
#[test]
fn regression_random_poor_layout_seed_14924378680947049249() {
    let d = random_layout(14924378680947049249, 6, 0.04783174593658949);
    let o = Options {
        cells: 2,
        collapse_fraction: 0.0,
        ..Options::default()
    };
    let m = mesh(&d, &o).unwrap();
    check_exact(&d, &m);
}

#[test]
fn clustering_and_smoothing_on_degenerate_layouts() {
    use medial_blocks::exact_mode::{Clustering, FirstCell};
    for d in [sliver(), layouts::square_lattice(9).unwrap(), ngon(6)] {
        let o = Options {
            clustering: Clustering {
                first: Some(FirstCell::Relative(0.01)),
                growth: 1.2,
            },
            smooth: 10,
            ..opts(4)
        };
        let m = mesh(&d, &o).unwrap();
        check_exact(&d, &m);
        // The first cell off every real wall has the requested height.
        for (b, g) in m.layout.blocks.iter().zip(&m.grids) {
            let Some(c) = b.wall else { continue };
            let circle = d.circle(c);
            let want = 0.01 * circle.radius;
            for i in 0..=g.ni {
                let (p, q) = (g.node(i, 0), g.node(i, 1));
                let got = (q[0] - p[0]).hypot(q[1] - p[1]);
                // Clustered unless the spoke is too short for nj cells of that height
                // (then equal spacing, see exact_mode::clustering).
                let top = g.node(i, g.nj);
                let len = (top[0] - p[0]).hypot(top[1] - p[1]);
                if len > 1.01 * g.nj as f64 * want {
                    assert!(
                        (got - want).abs() <= 1e-9 * want.max(1.0),
                        "{got} vs {want}"
                    );
                }
            }
        }
    }
}

#[test]
fn report_names_the_geometry() {
    use medial_blocks::output::report::Report;
    let d = sliver();
    let exact = mesh(&d, &opts(3)).unwrap();
    assert_eq!(Report::from_mesh(&exact).geometry, "exact");
    let paper = mesh(
        &d,
        &Options {
            cells: 3,
            ..Options::paper()
        },
    )
    .unwrap();
    assert_eq!(paper.geometry, Geometry::Paper);
    assert_eq!(Report::from_mesh(&paper).geometry, "paper");
    let json = serde_json::to_string(&Report::from_mesh(&exact)).unwrap();
    assert!(json.contains("\"geometry\":\"exact\""));
}

/// The layout of `degen_refine::regression_zero_sweep_arc_on_inserted_hole` (paper mode's
/// known zero-sweep arc next to an inserted hole): exact mode builds its own arcs around
/// inserted holes and must mesh it exactly.
#[test]
fn zero_sweep_regression_layout_is_exact() {
    let d = random_layout(17649210200229903181, 9, 0.002);
    for fraction in [0.0, 0.05] {
        let o = Options {
            cells: 2,
            collapse_fraction: fraction,
            ..Options::default()
        };
        let m = mesh(&d, &o).unwrap();
        assert!(!m.inserted_holes.is_empty());
        check_exact(&d, &m);
    }
}
