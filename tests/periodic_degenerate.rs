//! Degenerate periodic layouts (issues 4 and 6): co-circular hole groups on the torus.
//!
//! The commonest periodic layouts are degenerate: one hole in a box (its images form a
//! rectangular lattice, every box corner is the centre of an empty circle touching four
//! images), square lattices, holes on the box's edges and corners. Their zero-length medial
//! arcs must be collapsed, identically in every copy: on the torus `V = 2h`, `E = 3h` and
//! `6h - 2 collapsed` blocks. Every mesh is checked with the fuzz target's independent
//! checker ([`check_periodic_mesh`]: no zero-length side, torus counts, periodic partners
//! exact translates, walls on their holes, signed areas), here with no inverted cell allowed
//! (the bounded analogues of these layouts have none either).

use medial_blocks::fuzzing::{check_periodic_mesh, Checks};
use medial_blocks::periodic::{mesh_periodic, PeriodicDomain};
use medial_blocks::{Circle, Mesh, Options};

const STRICT: Checks = Checks {
    no_inverted_cells: true,
};

fn mesh(size: [f64; 2], holes: Vec<Circle>, options: &Options) -> (PeriodicDomain, Mesh) {
    let pd = PeriodicDomain::new(size, holes).expect("valid periodic domain");
    let m = mesh_periodic(&pd, options).unwrap_or_else(|e| panic!("{}: {e}", pd.to_json_string()));
    check_periodic_mesh(&pd, &m, STRICT).unwrap_or_else(|e| panic!("{}: {e}", pd.to_json_string()));
    (pd, m)
}

/// Only zero-length arcs are collapsed.
fn zero_only() -> Options {
    Options {
        collapse_fraction: 0.0,
        ..Options::default()
    }
}

/// `n x n` unit cells, one hole of radius `r` in each, offset by `offset` in the cell.
fn square_lattice(n: usize, r: f64, offset: [f64; 2]) -> Vec<Circle> {
    let mut holes = Vec::new();
    for i in 0..n {
        for j in 0..n {
            holes.push(Circle::new(i as f64 + offset[0], j as f64 + offset[1], r));
        }
    }
    holes
}

/// The empty circles of a lattice of cell `[a, b]` whose holes sit at `offset` in the cell
/// are centred at the cell corners shifted by `offset - (a/2, b/2)`, wrapped into the box.
fn assert_groups(m: &Mesh, size: [f64; 2], cell: [f64; 2], offset: [f64; 2], r: f64) {
    let nx = (size[0] / cell[0]).round() as usize;
    let ny = (size[1] / cell[1]).round() as usize;
    assert_eq!(m.cocircular_groups.len(), nx * ny, "one group per cell");
    let rho = 0.5 * cell[0].hypot(cell[1]) - r;
    let tol = 1e-12 * size[0].max(size[1]);
    let mut seen = vec![false; nx * ny];
    for g in &m.cocircular_groups {
        assert_eq!(
            g.holes.len(),
            4,
            "four holes touch each empty circle: {g:?}"
        );
        assert!(g.holes.iter().all(|&k| k >= 0 && (k as usize) < nx * ny));
        assert!(
            (g.radius - rho).abs() <= tol,
            "radius {} vs {rho}",
            g.radius
        );
        for (d, &l) in size.iter().enumerate() {
            assert!(
                (0.0..l).contains(&g.center[d]),
                "centre {:?} outside the box",
                g.center
            );
        }
        // The centre is a cell corner moved by the offset (mod the period).
        let u = [
            (g.center[0] - offset[0] + 0.5 * cell[0]) / cell[0],
            (g.center[1] - offset[1] + 0.5 * cell[1]) / cell[1],
        ];
        let k = [u[0].round(), u[1].round()];
        for d in 0..2 {
            assert!(
                ((u[d] - k[d]) * cell[d]).abs() <= tol,
                "centre {:?} is no lattice corner",
                g.center
            );
        }
        let (i, j) = (
            (k[0] as i64).rem_euclid(nx as i64) as usize,
            (k[1] as i64).rem_euclid(ny as i64) as usize,
        );
        assert!(!seen[i * ny + j], "two groups at one corner {:?}", g.center);
        seen[i * ny + j] = true;
    }
}

#[test]
fn one_hole_in_a_square_box() {
    // Centred, at a corner, on an edge, anywhere: the images form a square lattice, one
    // co-circular group of four images per period, one zero-length arc collapsed.
    for (c, r) in [
        ([0.5, 0.5], 0.25),
        ([0.0, 0.0], 0.3),
        ([0.5, 0.0], 0.2),
        ([0.0, 0.5], 0.45),
        ([0.3, 0.7], 0.1),
    ] {
        let (_, m) = mesh([1.0, 1.0], vec![Circle::new(c[0], c[1], r)], &zero_only());
        assert_eq!((m.medial_vertices, m.medial_arcs), (2, 3));
        assert_eq!(m.collapsed_arcs, 1, "hole at {c:?}");
        assert_eq!(m.layout.blocks.len(), 4);
        assert_groups(&m, [1.0, 1.0], [1.0, 1.0], c, r);
        assert_eq!(m.cocircular_groups[0].holes, vec![0, 0, 0, 0]);
    }
}

#[test]
fn one_hole_in_rectangular_boxes() {
    for (size, c, r) in [
        ([2.0, 1.0], [1.0, 0.5], 0.3),
        ([2.0, 1.0], [0.0, 0.0], 0.45),
        ([1.0, 1.5], [0.5, 0.0], 0.4),
        ([1.0, 0.4], [0.0, 0.2], 0.15),
        ([3.0, 1.0], [1.5, 1.0 - 1.0 / 1024.0], 0.2),
    ] {
        let (_, m) = mesh(size, vec![Circle::new(c[0], c[1], r)], &zero_only());
        assert_eq!((m.medial_vertices, m.medial_arcs), (2, 3));
        assert_eq!(m.collapsed_arcs, 1, "{size:?} {c:?}");
        assert_eq!(m.layout.blocks.len(), 4);
        assert_groups(&m, size, size, c, r);
    }
}

#[test]
fn square_lattices_collapse_one_arc_per_cell() {
    // n x n holes in an n x n box: n^2 empty circles on the torus, each touching 4 holes
    // (2 interior triangles, 1 zero-length arc): collapsed = n^2, blocks = 6n^2 - 2n^2.
    for n in 1..=4usize {
        // Offsets on cell centres, corners, edges, and ones whose copies are inexact float
        // sums (the groups stay exact rectangles of equal circles).
        for offset in [[0.5, 0.5], [0.0, 0.0], [0.5, 0.0], [0.1, 0.7]] {
            for (r, opts) in [(0.3, zero_only()), (0.2, Options::default())] {
                let size = [n as f64, n as f64];
                let (_, m) = mesh(size, square_lattice(n, r, offset), &opts);
                let h = n * n;
                assert_eq!((m.medial_vertices, m.medial_arcs), (2 * h, 3 * h));
                assert_eq!(m.collapsed_arcs, h, "n = {n}, offset {offset:?}");
                assert_eq!(m.layout.blocks.len(), 4 * h);
                assert_groups(&m, size, [1.0, 1.0], offset, r);
            }
        }
    }
}

#[test]
fn rectangular_lattice() {
    // 3 x 2 cells of 1 x 1.5: still four holes on every empty circle.
    let mut holes = Vec::new();
    for i in 0..3 {
        for j in 0..2 {
            holes.push(Circle::new(i as f64 + 0.5, 1.5 * j as f64 + 0.75, 0.35));
        }
    }
    let (_, m) = mesh([3.0, 3.0], holes, &zero_only());
    assert_eq!(m.collapsed_arcs, 6);
    assert_eq!(m.layout.blocks.len(), 24);
    assert_groups(&m, [3.0, 3.0], [1.0, 1.5], [0.5, 0.75], 0.35);
}

#[test]
fn hexagonal_packing_has_no_group() {
    let s = 3.0_f64.sqrt();
    for (r, offset) in [(0.3, [0.25, 0.25]), (0.45, [0.0, 0.0]), (0.2, [0.5, 0.1])] {
        let holes = vec![
            Circle::new(offset[0], offset[1], r),
            Circle::new(offset[0] + 0.5, offset[1] + 0.5 * s, r),
        ];
        for opts in [zero_only(), Options::default()] {
            let (_, m) = mesh([1.0, s], holes.clone(), &opts);
            assert!(m.cocircular_groups.is_empty(), "{:?}", m.cocircular_groups);
            assert_eq!(m.collapsed_arcs, 0);
            assert_eq!(m.layout.blocks.len(), 12, "six blocks per hole");
        }
    }
}

/// `x > 0` moved by `ulps` units in the last place.
fn nudge(x: f64, ulps: i64) -> f64 {
    f64::from_bits((x.to_bits() as i64 + ulps) as u64)
}

#[test]
fn ulp_nudged_lattices_have_no_exact_group_but_short_arcs() {
    // A lattice moved by a few ulps: no exact co-circular group, but arcs far shorter than
    // the local radius, which the default collapse fraction collapses (one per cell).
    for n in 2..=3usize {
        let mut holes = square_lattice(n, 0.3, [0.5, 0.5]);
        for (k, h) in holes.iter_mut().enumerate() {
            h.center[0] = nudge(h.center[0], (k % 3) as i64 - 1);
            h.center[1] = nudge(h.center[1], (k % 5) as i64 - 2);
        }
        let size = [n as f64, n as f64];
        let (_, m) = mesh(size, holes, &Options::default());
        let h = n * n;
        assert!(m.cocircular_groups.is_empty(), "{:?}", m.cocircular_groups);
        assert_eq!((m.medial_vertices, m.medial_arcs), (2 * h, 3 * h));
        assert_eq!(m.collapsed_arcs, h, "n = {n}");
        assert_eq!(m.layout.blocks.len(), 4 * h);
    }
}

#[test]
fn shifted_by_whole_periods_is_the_same_mesh_up_to_translation() {
    // Exactly periodic: the hole given one period away yields the same block structure and
    // the same counts.
    let a = mesh([1.0, 1.0], vec![Circle::new(0.5, 0.5, 0.25)], &zero_only()).1;
    let b = mesh([1.0, 1.0], vec![Circle::new(2.5, -1.5, 0.25)], &zero_only()).1;
    assert_eq!(a.layout.blocks.len(), b.layout.blocks.len());
    assert_eq!(a.collapsed_arcs, b.collapsed_arcs);
    assert_eq!(a.cocircular_groups, b.cocircular_groups);
}

#[test]
fn invalid_collapse_fraction_is_refused() {
    let pd = PeriodicDomain::new([1.0, 1.0], vec![Circle::new(0.5, 0.5, 0.25)]).unwrap();
    for f in [-0.1, f64::NAN, f64::INFINITY] {
        let e = mesh_periodic(
            &pd,
            &Options {
                collapse_fraction: f,
                ..Options::default()
            },
        )
        .expect_err("refused");
        assert!(
            matches!(e, medial_blocks::MeshError::Options(_)),
            "{f}: {e}"
        );
    }
}
