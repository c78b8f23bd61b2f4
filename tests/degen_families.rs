//! Degenerate families (tracker issue 4): square and rectangular lattices, exactly co-circular
//! near-regular n-gons around one empty circle, hexagonal packings, the same nudged by one ulp.
//! Ground truth is analytic: the groups a lattice must report, none for the hexagonal packing,
//! none once nudged (but the short arc is still collapsed); no block with non-positive area.

use medial_blocks::blocking::block_area;
use medial_blocks::domain::{Circle, Domain};
use medial_blocks::{mesh, Mesh, Options};

fn opts() -> Options {
    Options {
        cells: 3,
        ..Options::paper()
    }
}

/// Every block has a positive outline area and the counting identity holds.
fn check_mesh(m: &Mesh) {
    for b in 0..m.layout.blocks.len() {
        let a = block_area(&m.layout, b);
        assert!(a > 0.0, "block {b} has area {a}");
    }
    let h = m.holes + m.inserted_holes.len();
    assert_eq!(m.medial_vertices, 2 * (h - 1));
    assert_eq!(m.medial_arcs, 3 * (h - 1));
    assert_eq!(
        m.layout.blocks.len(),
        6 * (h - 1) - 2 * m.collapsed_arcs + 2 * m.split_arcs + m.template_blocks
    );
    assert_eq!(m.grids.len(), m.layout.blocks.len());
}

/// An `nx` by `ny` lattice with spacings `sx`, `sy` and hole radius `r`, centred on 0.
fn lattice(nx: usize, ny: usize, sx: f64, sy: f64, r: f64) -> Vec<Circle> {
    let mut holes = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            let x = (i as f64 - (nx as f64 - 1.0) / 2.0) * sx;
            let y = (j as f64 - (ny as f64 - 1.0) / 2.0) * sy;
            holes.push(Circle::new(x, y, r));
        }
    }
    holes
}

/// The analytic groups of a lattice: one per cell, its four corner holes, centred in the cell.
fn lattice_groups(
    nx: usize,
    ny: usize,
    sx: f64,
    sy: f64,
    r: f64,
) -> Vec<(Vec<i32>, [f64; 2], f64)> {
    let id = |i: usize, j: usize| (i * ny + j) as i32;
    let mut out = Vec::new();
    for i in 0..nx - 1 {
        for j in 0..ny - 1 {
            let mut holes = vec![id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)];
            holes.sort_unstable();
            let x = (i as f64 + 0.5 - (nx as f64 - 1.0) / 2.0) * sx;
            let y = (j as f64 + 0.5 - (ny as f64 - 1.0) / 2.0) * sy;
            let rho = (0.5 * sx).hypot(0.5 * sy) - r;
            out.push((holes, [x, y], rho));
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn assert_groups(m: &Mesh, want: &[(Vec<i32>, [f64; 2], f64)]) {
    let got: Vec<_> = m
        .cocircular_groups
        .iter()
        .map(|g| (g.holes.clone(), g.center, g.radius))
        .collect();
    assert_eq!(got.len(), want.len(), "groups {got:?}");
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g.0, w.0);
        // Centres are exact here (cell centres are dyadic); radii are correctly rounded.
        assert_eq!(g.1, w.1);
        assert!((g.2 - w.2).abs() <= 1e-15 * w.2.max(1.0), "{g:?} vs {w:?}");
    }
}

#[test]
fn square_lattice_groups_equal_the_analytic_list() {
    for n in [2usize, 3, 4, 5] {
        let holes = lattice(n, n, 1.0, 1.0, 0.3);
        let d = Domain::bounded(Circle::new(0.0, 0.0, n as f64), holes).unwrap();
        let m = mesh(&d, &opts()).unwrap();
        check_mesh(&m);
        assert_groups(&m, &lattice_groups(n, n, 1.0, 1.0, 0.3));
        // Each 4-group is two triangles joined by one zero-length arc, always collapsed.
        assert!(m.collapsed_arcs >= (n - 1) * (n - 1));
    }
}

#[test]
fn rectangular_lattices() {
    for (nx, ny, sx, sy) in [
        (3usize, 2usize, 1.5, 1.0),
        (4, 3, 1.0, 1.25),
        (2, 5, 0.75, 1.0),
    ] {
        let holes = lattice(nx, ny, sx, sy, 0.25);
        let big = (nx as f64 * sx).hypot(ny as f64 * sy) * 0.5 + 0.5;
        let d = Domain::bounded(Circle::new(0.0, 0.0, big), holes).unwrap();
        let m = mesh(&d, &opts()).unwrap();
        check_mesh(&m);
        assert_groups(&m, &lattice_groups(nx, ny, sx, sy, 0.25));
    }
}

/// Integer points on the circle `x^2 + y^2 = N` for `N = (5 13 17 29)^2` (many
/// representations), scaled by `2^-14`: exactly co-circular, nearly regular n-gons.
fn ngon(n: usize) -> Vec<[f64; 2]> {
    let big_n: i64 = (5 * 13 * 17 * 29i64).pow(2);
    let mut pts: Vec<(i64, i64)> = Vec::new();
    let s = (big_n as f64).sqrt() as i64 + 1;
    for x in -s..=s {
        let y2 = big_n - x * x;
        if y2 < 0 {
            continue;
        }
        let y = (y2 as f64).sqrt().round() as i64;
        if y * y == y2 {
            pts.push((x, y));
            if y != 0 {
                pts.push((x, -y));
            }
        }
    }
    (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            let &(x, y) = pts
                .iter()
                .min_by(|a, b| {
                    let da = (a.1 as f64).atan2(a.0 as f64) - t;
                    let db = (b.1 as f64).atan2(b.0 as f64) - t;
                    let wrap = |d: f64| {
                        (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                            - std::f64::consts::PI
                    };
                    wrap(da).abs().total_cmp(&wrap(db).abs())
                })
                .unwrap();
            let scale = 2f64.powi(-14);
            [x as f64 * scale, y as f64 * scale]
        })
        .collect()
}

#[test]
fn regular_ngons_around_one_empty_circle() {
    for n in 4..=12usize {
        let r = 0.35 * (std::f64::consts::PI / n as f64).sin() * 2.0;
        let holes: Vec<Circle> = ngon(n)
            .into_iter()
            .map(|c| Circle {
                center: c,
                radius: r,
            })
            .collect();
        let d = Domain::bounded(Circle::new(0.0, 0.0, 3.5), holes).unwrap();
        let m = mesh(&d, &opts()).unwrap();
        check_mesh(&m);
        let all: Vec<i32> = (0..n as i32).collect();
        let central: Vec<_> = m
            .cocircular_groups
            .iter()
            .filter(|g| g.holes == all)
            .collect();
        assert_eq!(central.len(), 1, "n = {n}: {:?}", m.cocircular_groups);
        let g = central[0];
        assert!(g.center[0].abs() < 1e-12 && g.center[1].abs() < 1e-12);
        let rho = 1.0f64.hypot(0.0) * ((5 * 13 * 17 * 29) as f64) * 2f64.powi(-14) - r;
        assert!((g.radius - rho).abs() < 1e-12, "{} vs {rho}", g.radius);
        // n - 2 triangles, n - 3 zero-length arcs, all collapsed: one vertex of degree n.
        assert_eq!(g.vertices.len(), n - 2);
        assert!(m.collapsed_arcs >= n - 3);
        // The merged vertex (the layout vertex nearest the centre) has degree n: 2n blocks
        // meet there.
        let centre = (0..m.layout.vertices.len())
            .min_by(|&a, &b| {
                let d = |v: usize| m.layout.vertices[v][0].hypot(m.layout.vertices[v][1]);
                d(a).total_cmp(&d(b))
            })
            .unwrap() as u32;
        let around = m
            .layout
            .blocks
            .iter()
            .filter(|b| b.corners.contains(&centre))
            .count();
        assert_eq!(around, 2 * n, "n = {n}");
        println!(
            "ngon {n}: {} blocks, {} collapsed, {} inserted, quality {:?}",
            m.layout.blocks.len(),
            m.collapsed_arcs,
            m.inserted_holes.len(),
            medial_blocks::quality::measure(&m.grids).min_angle_deg
        );
    }
}

#[test]
fn hexagonal_packing_has_no_group() {
    let mut holes = Vec::new();
    for j in -2i32..=2 {
        for i in -2i32..=2 {
            let x = i as f64 + 0.5 * j as f64;
            let y = j as f64 * 3f64.sqrt() / 2.0;
            if x.hypot(y) < 2.6 {
                holes.push(Circle::new(x, y, 0.3));
            }
        }
    }
    let d = Domain::bounded(Circle::new(0.0, 0.0, 3.5), holes).unwrap();
    let m = mesh(&d, &opts()).unwrap();
    check_mesh(&m);
    assert!(m.cocircular_groups.is_empty(), "{:?}", m.cocircular_groups);
}

#[test]
fn nudged_layouts_have_no_exact_group_but_collapse_the_short_arc() {
    // A 2 x 2 square: one group; nudge one hole by one ulp: no group, one short arc.
    let mut holes = lattice(2, 2, 1.0, 1.0, 0.3);
    let d = Domain::bounded(Circle::new(0.0, 0.0, 2.0), holes.clone()).unwrap();
    let m = mesh(&d, &opts()).unwrap();
    assert_eq!(m.cocircular_groups.len(), 1);
    assert_eq!(m.collapsed_arcs, 1);
    holes[0].center[0] = f64::from_bits(holes[0].center[0].to_bits() + 1);
    let d = Domain::bounded(Circle::new(0.0, 0.0, 2.0), holes).unwrap();
    let m = mesh(&d, &opts()).unwrap();
    check_mesh(&m);
    assert!(m.cocircular_groups.is_empty());
    assert_eq!(m.collapsed_arcs, 1);
    assert_eq!(m.layout.blocks.len(), 6 * 3 - 2);
    // Nudged n-gons: no exact group, every short arc collapsed, no degenerate block.
    for n in [5usize, 8] {
        let r = 0.35 * (std::f64::consts::PI / n as f64).sin() * 2.0;
        let mut holes: Vec<Circle> = ngon(n)
            .into_iter()
            .map(|c| Circle {
                center: c,
                radius: r,
            })
            .collect();
        holes[1].radius = f64::from_bits(holes[1].radius.to_bits() - 1);
        let d = Domain::bounded(Circle::new(0.0, 0.0, 3.5), holes).unwrap();
        let m = mesh(&d, &opts()).unwrap();
        check_mesh(&m);
        // The other n - 1 holes still touch the central circle exactly.
        let rest: Vec<i32> = (0..n as i32).filter(|&i| i != 1).collect();
        let groups: Vec<_> = m
            .cocircular_groups
            .iter()
            .map(|g| g.holes.clone())
            .collect();
        assert_eq!(groups, vec![rest]);
        assert!(m.collapsed_arcs >= n - 3);
    }
}

/// More than 12 co-circular holes: the fan's smallest angle is below 15 degrees, so macro
/// Delaunay refinement (default ratio 2) inserts a hole at the common centre first (paper
/// section 4.2) and the group is gone.
#[test]
fn large_ngons_are_refined_not_collapsed() {
    for n in [13usize, 16] {
        let r = 0.35 * (std::f64::consts::PI / n as f64).sin() * 2.0;
        let holes: Vec<Circle> = ngon(n)
            .into_iter()
            .map(|c| Circle {
                center: c,
                radius: r,
            })
            .collect();
        let d = Domain::bounded(Circle::new(0.0, 0.0, 3.5), holes).unwrap();
        let m = mesh(&d, &opts()).unwrap();
        check_mesh(&m);
        let all: Vec<i32> = (0..n as i32).collect();
        assert!(m.cocircular_groups.iter().all(|g| g.holes != all));
        assert!(
            m.inserted_holes
                .iter()
                .any(|c| c.center[0].hypot(c.center[1]) < 1e-9),
            "n = {n}: {:?}",
            m.inserted_holes
        );
        println!(
            "ngon {n}: {} inserted, {} blocks, {} collapsed",
            m.inserted_holes.len(),
            m.layout.blocks.len(),
            m.collapsed_arcs
        );
    }
}
