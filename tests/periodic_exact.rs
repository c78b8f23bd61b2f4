//! Periodic domains in exact mode (issue 6): every check reads node coordinates only.
//!
//! - six blocks per hole;
//! - every block side is a wall (nodes on a hole's circle), bitwise shared with another side,
//!   or a zig-zag side whose nodes equal another side's plus a non-zero period shift within
//!   `1e-12` of the period (found by search over shifts, not read from the connectivity);
//! - every cell is counter-clockwise at all four corners;
//! - the first grid line off every wall is normal to it within 0.5 degrees;
//! - wall clustering: the first cell height is the requested one;
//! - the cells' area is the period's minus the holes'.

use medial_blocks::exact_mode::{Clustering, FirstCell};
use medial_blocks::layouts::SplitMix64;
use medial_blocks::periodic::{mesh_periodic, periodic_layout, PeriodicDomain};
use medial_blocks::{Circle, Mesh, Options};
use proptest::prelude::*;

type P = [f64; 2];

/// Holes at random positions with their periodic images apart; when `cross`, the first hole
/// sits on the box's corner and the second on its left edge.
fn holes(n: usize, size: P, seed: u64, cross: bool) -> Vec<Circle> {
    let mut rng = SplitMix64(seed);
    let m = size[0].min(size[1]);
    let mut out: Vec<Circle> = Vec::new();
    let mut tries = 0;
    while out.len() < n && tries < 20_000 {
        tries += 1;
        let r = m * (0.04 + 0.14 * rng.next_f64());
        let mut c = [rng.next_f64() * size[0], rng.next_f64() * size[1]];
        if cross && out.is_empty() {
            c = [0.3 * r * rng.next_f64(), -0.3 * r * rng.next_f64()];
        } else if cross && out.len() == 1 {
            c[0] = 0.5 * r * (rng.next_f64() - 0.5);
        }
        let apart = out.iter().all(|o| {
            (-1..=1).all(|a| {
                (-1..=1).all(|b| {
                    let dx = c[0] - o.center[0] + a as f64 * size[0];
                    let dy = c[1] - o.center[1] + b as f64 * size[1];
                    dx.hypot(dy) > r + o.radius + 0.03 * m
                })
            })
        });
        if apart {
            out.push(Circle::new(c[0], c[1], r));
        }
    }
    out
}

fn cross(o: P, a: P, b: P) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// The hole whose circle carries all of `nodes` (relative 1e-9), if any.
fn wall_of(pd: &PeriodicDomain, nodes: &[P]) -> Option<usize> {
    pd.holes().iter().position(|c| {
        nodes.iter().all(|p| {
            ((p[0] - c.center[0]).hypot(p[1] - c.center[1]) - c.radius).abs() <= 1e-9 * c.radius
        })
    })
}

fn matches(a: &[P], b: &[P], t: P, tol: f64) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| (p[0] + t[0] - q[0]).hypot(p[1] + t[1] - q[1]) <= tol)
}

/// All the coordinate checks; `first`: the requested relative first cell height.
fn check(pd: &PeriodicDomain, mesh: &Mesh, first: Option<f64>) {
    let h = pd.hole_count();
    let size = pd.size();
    let l = size[0].max(size[1]);
    // Six blocks per hole (inserted ones included), two fewer per collapsed zero-length arc
    // orbit (co-circular groups), two more per split arc, and the templates in inserted holes.
    let hi = h + mesh.inserted_holes.len();
    let blocks = 6 * hi + 2 * mesh.split_arcs + mesh.template_blocks - 2 * mesh.collapsed_arcs;
    assert_eq!(
        mesh.layout.blocks.len(),
        blocks,
        "6 h - 2 collapsed + 2 split + template blocks"
    );
    assert_eq!(mesh.grids.len(), blocks);
    assert_eq!(mesh.geometry, medial_blocks::mesh::Geometry::Exact);
    let sides: Vec<(usize, usize, Vec<P>)> = (0..mesh.grids.len())
        .flat_map(|b| (0..4).map(move |k| (b, k)))
        .map(|(b, k)| (b, k, mesh.grids[b].side(k)))
        .collect();
    let mut zigzag = 0;
    for (b, k, nodes) in &sides {
        if *k == 0 && mesh.layout.blocks[*b].wall.is_some() {
            assert!(wall_of(pd, nodes).is_some(), "block {b}: side 0 is a wall");
            continue;
        }
        let rev: Vec<P> = nodes.iter().rev().copied().collect();
        let others = sides.iter().filter(|(b2, k2, _)| (b2, k2) != (b, k));
        let shared = others.clone().any(|(_, _, o)| *o == *nodes || *o == rev);
        if shared {
            continue;
        }
        let mut found = false;
        'search: for (_, k2, o) in others {
            if *k2 == 0 {
                continue;
            }
            for a in -2i32..=2 {
                for bb in -2i32..=2 {
                    if (a, bb) == (0, 0) {
                        continue;
                    }
                    let t = [a as f64 * size[0], bb as f64 * size[1]];
                    if matches(nodes, o, t, 1e-12 * l) || matches(&rev, o, t, 1e-12 * l) {
                        found = true;
                        break 'search;
                    }
                }
            }
        }
        assert!(
            found,
            "block {b} side {k}: neither shared nor a periodic copy"
        );
        zigzag += 1;
    }
    assert!(zigzag > 0, "one period has a zig-zag boundary");
    let mut area = 0.0;
    for (b, g) in mesh.grids.iter().enumerate() {
        for j in 0..g.nj {
            for i in 0..g.ni {
                let q = [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ];
                for c in 0..4 {
                    let z = cross(q[c], q[(c + 1) % 4], q[(c + 3) % 4]);
                    assert!(z > 0.0, "block {b} cell ({i}, {j}) corner {c}: {z:e}");
                }
                area += 0.5 * (cross(q[0], q[1], q[2]) + cross(q[0], q[2], q[3]));
            }
        }
        // The first grid line off the wall is normal to it (blocks on a wall: not those
        // around or inside an inserted hole).
        if mesh.layout.blocks[b].wall.is_none() {
            continue;
        }
        let w = wall_of(pd, &g.side(0)).expect("wall");
        let c = pd.holes()[w];
        for i in 0..=g.ni {
            let (p, q) = (g.node(i, 0), g.node(i, 1));
            let u = [p[0] - c.center[0], p[1] - c.center[1]];
            let v = [q[0] - p[0], q[1] - p[1]];
            let ang = cross([0.0, 0.0], u, v)
                .atan2(u[0] * v[0] + u[1] * v[1])
                .to_degrees()
                .abs();
            assert!(ang < 0.5, "block {b} node {i}: wall angle off by {ang} deg");
            if let Some(f) = first {
                let len = (g.node(i, g.nj)[0] - p[0]).hypot(g.node(i, g.nj)[1] - p[1]);
                let want = f * c.radius;
                if g.nj > 1 && (g.nj as f64) * want < len {
                    let got = v[0].hypot(v[1]);
                    assert!(
                        (got - want).abs() <= 1e-6 * want,
                        "first cell {got} vs {want}"
                    );
                }
            }
        }
    }
    let holes: f64 = pd
        .holes()
        .iter()
        .map(|c| std::f64::consts::PI * c.radius * c.radius)
        .sum();
    let want = size[0] * size[1] - holes;
    assert!(
        (area - want).abs() < 0.01 * size[0] * size[1],
        "period area {area} vs {want}"
    );
}

#[test]
fn exact_mode_is_the_default_for_periodic_domains() {
    let size = [3.0, 2.0];
    let hs = vec![
        Circle::new(0.05, 0.05, 0.3),
        Circle::new(1.5, 1.98, 0.25),
        Circle::new(2.9, 1.0, 0.2),
        Circle::new(1.4, 0.9, 0.35),
        Circle::new(-0.7, 0.8, 0.15),
    ];
    let pd = PeriodicDomain::new(size, hs).unwrap();
    let mesh = mesh_periodic(&pd, &Options::default()).unwrap();
    check(&pd, &mesh, None);
    assert_eq!(mesh.geometry, medial_blocks::mesh::Geometry::Exact);
    // One hole in a square box: a degenerate (co-circular) periodic Voronoi diagram. Its
    // zero-length arc is collapsed into a vertex of degree 4, exactly (6 h - 2 collapsed
    // blocks, checked by `check`).
    let pd = PeriodicDomain::new([1.0, 1.0], vec![Circle::new(0.5, 0.5, 0.2)]).unwrap();
    let mesh = mesh_periodic(&pd, &Options::default()).unwrap();
    assert_eq!(mesh.collapsed_arcs, 1);
    assert_eq!(mesh.cocircular_groups.len(), 1);
    check(&pd, &mesh, None);
}

/// A `k x m` lattice of equal holes (spacing `d`, offset `o`) in a box of `k d x m d`: every
/// cell corner is a co-circular group of four images.
fn lattice(k: usize, m: usize, d: [f64; 2], r: f64, o: P) -> PeriodicDomain {
    let hs = (0..k)
        .flat_map(|i| (0..m).map(move |j| (i, j)))
        .map(|(i, j)| Circle::new(o[0] + i as f64 * d[0], o[1] + j as f64 * d[1], r))
        .collect();
    PeriodicDomain::new([k as f64 * d[0], m as f64 * d[1]], hs).unwrap()
}

/// Periodic arrays of cylinders (square and rectangular lattices, the classic periodic
/// layouts, on and off the box's edges) are meshed in exact geometry: collapsed vertices of
/// degree 4, spoke-aligned grids, clustering honoured.
#[test]
fn lattices_are_exact_with_collapsed_vertices() {
    for (k, m, d, r, o) in [
        (1, 1, [1.0, 1.0], 0.3, [0.5, 0.5]),
        (1, 1, [2.0, 1.0], 0.4, [0.0, 0.0]),
        (2, 2, [1.0, 1.0], 0.2, [0.5, 0.5]),
        (3, 2, [1.0, 1.5], 0.45, [0.1, 0.0]),
    ] {
        let pd = lattice(k, m, d, r, o);
        let opts = Options {
            cells: 6,
            clustering: Clustering {
                first: Some(FirstCell::Relative(0.02)),
                growth: 1.2,
            },
            ..Options::default()
        };
        let mesh = mesh_periodic(&pd, &opts).unwrap();
        // Each hole's lattice cell has one co-circular corner (a zero-length arc orbit).
        assert_eq!(mesh.collapsed_arcs, k * m, "{k} x {m}");
        check(&pd, &mesh, Some(0.02));
    }
}

#[test]
fn paper_mode_keeps_the_paper_geometry() {
    let pd = PeriodicDomain::new(
        [2.0, 1.5],
        vec![Circle::new(0.3, 0.4, 0.2), Circle::new(1.3, 1.0, 0.3)],
    )
    .unwrap();
    let opts = Options {
        cells: 6,
        ..Options::paper()
    };
    let mesh = mesh_periodic(&pd, &opts).unwrap();
    let p = periodic_layout(&pd, &opts).unwrap();
    let grids = medial_blocks::grid::build_grids(&p.layout, 6).unwrap();
    assert_eq!(
        mesh.grids, grids,
        "--mode paper: equal spacing TFI as before"
    );
    assert!(mesh.grids.iter().all(|g| g.ni >= 6));
}

#[test]
fn clustering_on_hole_walls() {
    let size = [2.0, 2.0];
    let pd = PeriodicDomain::new(size, holes(6, size, 11, true)).unwrap();
    let opts = Options {
        cells: 8,
        clustering: Clustering {
            first: Some(FirstCell::Relative(0.01)),
            growth: 1.2,
        },
        ..Options::default()
    };
    let mesh = mesh_periodic(&pd, &opts).unwrap();
    check(&pd, &mesh, Some(0.01));
}

#[test]
fn exact_periodic_meshes_are_deterministic() {
    let size = [1.5, 1.0];
    let pd = PeriodicDomain::new(size, holes(5, size, 3, true)).unwrap();
    let a = mesh_periodic(&pd, &Options::default()).unwrap();
    let b = mesh_periodic(&pd, &Options::default()).unwrap();
    assert_eq!(a.grids, b.grids);
    assert_eq!(a.layout, b.layout);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20, ..ProptestConfig::default() })]

    /// Random layouts, with holes across the box's corner and edge (one hole: its four
    /// images are co-circular, a collapsed vertex of degree 4).
    #[test]
    fn random_exact_periodic_layouts(
        n in 1usize..8,
        lx in 0.6f64..2.0,
        ly in 0.6f64..2.0,
        seed in any::<u64>(),
        crossing in any::<bool>(),
    ) {
        let size = [lx, ly];
        let hs = holes(n, size, seed, crossing);
        let pd = PeriodicDomain::new(size, hs).unwrap();
        let mesh = mesh_periodic(&pd, &Options { cells: 6, ..Options::default() }).unwrap();
        check(&pd, &mesh, None);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    /// Random lattices: any spacing, radius and offset (holes across the edges too).
    #[test]
    fn random_lattices_are_exact(
        k in 1usize..4,
        m in 1usize..4,
        dx in 0.5f64..2.0,
        dy in 0.5f64..2.0,
        fill in 0.1f64..0.9,
        ox in 0.0f64..1.0,
        oy in 0.0f64..1.0,
    ) {
        let r = 0.5 * fill * dx.min(dy);
        let pd = lattice(k, m, [dx, dy], r, [ox * dx, oy * dy]);
        let mesh = mesh_periodic(&pd, &Options { cells: 5, ..Options::default() }).unwrap();
        check(&pd, &mesh, None);
    }
}

/// A 2 x 2 array moved off the lattice by `nudge` on two holes: nearly co-circular groups.
/// At 1e-9 only collapsing the short arcs gives blocks of positive area (exact mode returned
/// an internal error there before); every nudge is meshed in exact geometry, without slivers.
#[test]
fn nearly_co_circular_lattices_are_exact() {
    for nudge in [0.0, 1e-12, 1e-9, 1e-8, 1e-7, 1e-6, 1e-4] {
        let hs = vec![
            Circle::new(1.0 + nudge, 1.0, 0.5),
            Circle::new(3.0, 1.0, 0.5),
            Circle::new(1.0, 3.0 + nudge, 0.5),
            Circle::new(3.0, 3.0, 0.5),
        ];
        let pd = PeriodicDomain::new([4.0, 4.0], hs).unwrap();
        let mesh = mesh_periodic(&pd, &Options::default())
            .unwrap_or_else(|e| panic!("nudge {nudge}: {e}"));
        check(&pd, &mesh, None);
        // No sliver: the nearly zero-length arcs are collapsed (a 1e-6 nudge left blocks
        // whose cells had edge ratios of 1e11). Longest over shortest edge of every cell,
        // from the nodes.
        let worst = mesh
            .grids
            .iter()
            .flat_map(|g| {
                // Cell (i, j) from node (i, j) counter-clockwise: the edge from corner k to
                // corner k + 1 is the difference of nodes at these offsets.
                let at = |i: usize, j: usize, k: usize| {
                    let [di, dj] = [[0, 0], [1, 0], [1, 1], [0, 1]][k % 4];
                    g.node(i + di, j + dj)
                };
                (0..g.nj).flat_map(move |j| {
                    (0..g.ni).map(move |i| {
                        let e = (0..4).map(|k| {
                            let (a, b) = (at(i, j, k), at(i, j, k + 1));
                            (b[0] - a[0]).hypot(b[1] - a[1])
                        });
                        let hi = e.clone().fold(0.0f64, f64::max);
                        hi / e.fold(f64::INFINITY, f64::min)
                    })
                })
            })
            .fold(1.0f64, f64::max);
        assert!(worst < 10.0, "nudge {nudge}: a cell edge ratio of {worst}");
        if nudge <= 1e-4 {
            // Both co-circular corners of each hole's cell, merged.
            assert_eq!(mesh.collapsed_arcs, 4, "nudge {nudge}");
        }
    }
}

/// |sweep| in degrees of block `b`'s wall (side 0), 0 when it is not an arc.
fn wall_sweep_deg(m: &Mesh, b: usize) -> f64 {
    let side = m.layout.blocks[b].sides[0];
    match m.layout.edges[side.edge as usize].curve {
        medial_blocks::layout::Curve::Arc { sweep, .. } => sweep.abs().to_degrees(),
        _ => 0.0,
    }
}

/// `block_cells` (`--block-cells N`) in a periodic box: `N` cells along every spoke and `N`
/// along every arc, raised only where a wall of the arc's two blocks (blocks `2o` and
/// `2o + 1` of arc orbit `o`) needs more than `N` cells of 15 degrees, and always there
/// (it was ignored: the counts came from the geometry as without it).
#[test]
fn block_cells_gives_n_by_n_per_block() {
    let mut all_square = 0;
    for seed in 1..=3u64 {
        let size = [2.0, 1.5];
        let pd = PeriodicDomain::new(size, holes(6, size, seed, seed == 2)).unwrap();
        for n in [4usize, 10] {
            let o = Options {
                block_cells: Some(n),
                cells: n,
                ..Options::default()
            };
            let mesh = mesh_periodic(&pd, &o).unwrap();
            assert_eq!(mesh.geometry, medial_blocks::mesh::Geometry::Exact);
            check(&pd, &mesh, None);
            let limit = n as f64 * 15.0;
            for (b, g) in mesh.grids.iter().enumerate() {
                let what = format!("seed {seed}, N = {n}, block {b}");
                assert_eq!(g.nj, n, "{what}: spokes");
                assert!(g.ni >= n, "{what}: ni {}", g.ni);
                let (own, other) = (wall_sweep_deg(&mesh, b), wall_sweep_deg(&mesh, b ^ 1));
                if g.ni > n {
                    assert!(own + other > limit - 1e-6, "{what}: {own} + {other} deg");
                }
                if own.max(other) > limit + 1e-6 {
                    assert!(g.ni > n, "{what}: wall of {own} deg in {} cells", g.ni);
                }
            }
            if mesh.grids.iter().all(|g| g.ni == n) {
                all_square += 1;
                let cells: usize = mesh.grids.iter().map(|g| g.cells()).sum();
                assert_eq!(cells, n * n * mesh.layout.blocks.len());
            }
        }
    }
    assert!(all_square >= 1, "{all_square}");
}

/// A periodic close pack with gaps of 1e-5 of the radius: every medial vertex is tiny, so
/// is the default target size, and the counts exceeded `exact_mode::node_budget` (5.8 M
/// cells for 24 blocks). The default size is coarsened until the nodes fit the budget, as in
/// bounded domains, and the mesh says so; with the size used passed as `cell_size` the mesh
/// is the same, and nothing is coarsened with `block_cells`.
#[test]
fn a_tiny_default_size_is_coarsened_in_periodic_boxes() {
    use medial_blocks::exact_mode::node_budget;
    let (a, g) = (1.0f64, 1e-5f64);
    let h = a * 3f64.sqrt() / 2.0;
    let mut rng = SplitMix64(5);
    let mut hs = Vec::new();
    for j in 0..2 {
        for i in 0..2 {
            let x = i as f64 * a + if j % 2 == 1 { 0.5 * a } else { 0.0 };
            let y = j as f64 * h;
            let jitter = |r: &mut SplitMix64| (2.0 * r.next_f64() - 1.0) * 0.3 * g;
            let (dx, dy) = (jitter(&mut rng), jitter(&mut rng));
            hs.push(Circle::new(x + dx, y + dy, a / 2.0 - g));
        }
    }
    let pd = PeriodicDomain::new([2.0 * a, 2.0 * h], hs).unwrap();
    let options = Options::default();
    let mesh = mesh_periodic(&pd, &options).unwrap();
    check(&pd, &mesh, None);
    let nodes: usize = mesh.grids.iter().map(|g| g.nodes.len()).sum();
    let budget = node_budget(mesh.layout.blocks.len(), options.cells);
    assert!(
        nodes <= budget && nodes >= budget / 4,
        "{nodes} nodes, budget {budget}"
    );
    let [from, to] = mesh.coarsened_cell_size.expect("coarsened");
    assert!(from > 0.0 && to > 1.2 * from, "{from} -> {to}");
    let sized = Options {
        cell_size: Some(to),
        ..Options::default()
    };
    let again = mesh_periodic(&pd, &sized).unwrap();
    assert_eq!(again.coarsened_cell_size, None);
    assert_eq!(again.grids.len(), mesh.grids.len());
    for (x, y) in again.grids.iter().zip(&mesh.grids) {
        assert_eq!((x.ni, x.nj), (y.ni, y.nj));
        assert!(x.nodes.iter().zip(&y.nodes).all(|(p, q)| p == q));
    }
    let uniform = Options {
        block_cells: Some(8),
        cells: 8,
        ..Options::default()
    };
    assert_eq!(
        mesh_periodic(&pd, &uniform).unwrap().coarsened_cell_size,
        None
    );
}
