//! Exact re-check (integer arithmetic, `geometry::verify`) of triangulations of generic and
//! degenerate point sets.

use medial_blocks::geometry::verify::verify_exact;
use medial_blocks::geometry::{Point, Triangulation, TriangulationError};

use crate::common;
use common::XorShift as Rng;

/// Deterministic xorshift generator.
fn check(pts: &[Point]) -> Triangulation {
    let dt = Triangulation::new(pts).expect("triangulation");
    if let Err(e) = verify_exact(&dt) {
        panic!("verification failed: {e}");
    }
    dt
}

fn grid(k: usize, scale: f64) -> Vec<Point> {
    let mut v = Vec::new();
    for i in 0..k {
        for j in 0..k {
            v.push([i as f64 * scale, j as f64 * scale]);
        }
    }
    v
}

#[test]
fn uniform_random() {
    let mut r = Rng(7);
    for n in [3, 4, 5, 10, 100, 1000, 20_000] {
        let pts: Vec<Point> = (0..n).map(|_| [r.unit(), r.unit()]).collect();
        let dt = check(&pts);
        assert!(!dt.is_empty());
    }
}

#[test]
fn square_grid_has_one_group_per_cell() {
    for k in [2usize, 3, 5, 12] {
        let dt = check(&grid(k, 1.0));
        assert_eq!(dt.len(), 2 * (k - 1) * (k - 1));
        let groups = dt.cocircular_groups();
        let mut expected: Vec<Vec<u32>> = Vec::new();
        for i in 0..k - 1 {
            for j in 0..k - 1 {
                let id = |a: usize, b: usize| (a * k + b) as u32;
                let mut g = vec![id(i, j), id(i, j + 1), id(i + 1, j), id(i + 1, j + 1)];
                g.sort_unstable();
                expected.push(g);
            }
        }
        expected.sort();
        assert_eq!(groups, expected, "k = {k}");
    }
}

#[test]
fn tilted_and_scaled_grids() {
    // Power-of-two scales keep the lattice exact; 1e-9 and 1e9 round it (validity only).
    for (scale, exact) in [
        (1e-9, false),
        (0.125, true),
        (1.0, true),
        (3.0, true),
        (1e9, true),
        (0.1, false),
    ] {
        let k = 9;
        let mut pts = Vec::new();
        for i in 0..k {
            for j in 0..k {
                let (i, j) = (i as f64, j as f64);
                // A lattice with basis (2, 1), (-1, 2): integer, tilted, exact.
                pts.push([(2.0 * i - j) * scale, (i + 2.0 * j) * scale]);
            }
        }
        let dt = check(&pts);
        if exact {
            assert_eq!(dt.cocircular_groups().len(), (k - 1) * (k - 1));
        }
    }
}

fn pythagorean_circle(r: f64, cx: f64, cy: f64) -> Vec<Point> {
    // All lattice points on the circle of radius 25 (x² + y² = 625).
    let base = [
        (25.0, 0.0),
        (24.0, 7.0),
        (20.0, 15.0),
        (15.0, 20.0),
        (7.0, 24.0),
    ];
    let mut v = Vec::new();
    for (x, y) in base {
        for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
            let p = [cx + r * sx * x / 25.0, cy + r * sy * y / 25.0];
            if !v.contains(&p) {
                v.push(p);
            }
            let q = [cx + r * sy * y / 25.0, cy + r * sx * x / 25.0];
            if !v.contains(&q) {
                v.push(q);
            }
        }
    }
    v
}

#[test]
fn cocircular_points_form_one_group() {
    for (r, c) in [(25.0, 0.0), (25.0 * 1024.0, 3.0), (6.25, -7.5)] {
        let pts = pythagorean_circle(r, c, c);
        assert_eq!(pts.len(), 20);
        let dt = check(&pts);
        let all: Vec<u32> = (0..pts.len() as u32).collect();
        assert_eq!(dt.cocircular_groups(), vec![all]);
        assert_eq!(dt.hull().len(), 20);
    }
}

#[test]
fn duplicates_are_reported_not_lost() {
    let mut r = Rng(11);
    let base: Vec<Point> = (0..200).map(|_| [r.unit(), r.unit()]).collect();
    let mut pts = base.clone();
    for i in 0..600 {
        pts.push(base[(r.next() % 200) as usize]);
        if i % 7 == 0 {
            pts.push([0.0, -0.0]);
        }
    }
    pts.push([-0.0, 0.0]);
    let dt = check(&pts);
    assert_eq!(dt.vertex_count(), 201);
    assert_eq!(dt.duplicates().len(), pts.len() - 201);
}

#[test]
fn collinear_lines_plus_one_point() {
    let mut pts: Vec<Point> = (0..50).map(|i| [i as f64, 0.0]).collect();
    pts.push([3.0, 1.0]);
    let dt = check(&pts);
    assert_eq!(dt.len(), 49);
    let mut pts: Vec<Point> = (0..30).map(|i| [i as f64 * 0.1, i as f64 * 0.3]).collect();
    pts.extend((0..30).map(|i| [i as f64 * 0.1 + 1.0, i as f64 * 0.3]));
    check(&pts);
    // Points on all four sides of a square, and on its diagonals.
    let mut pts = Vec::new();
    for i in 0..=10 {
        let t = i as f64;
        pts.extend([
            [t, 0.0],
            [t, 10.0],
            [0.0, t],
            [10.0, t],
            [t, t],
            [t, 10.0 - t],
        ]);
    }
    check(&pts);
}

#[test]
fn extreme_magnitudes() {
    let mut r = Rng(5);
    for scale in [1e300, 1e-300, 5e-324, 1e-310, 1e150, f64::MAX / 128.0] {
        let pts: Vec<Point> = (0..300)
            .map(|_| {
                [
                    (r.next() % 64) as f64 * scale,
                    (r.next() % 64) as f64 * scale,
                ]
            })
            .collect();
        check(&pts);
    }
    // Clusters at 1e300 with ulp offsets, and tiny clusters, in one set (no common scaling).
    let mut pts = Vec::new();
    for i in 0..6 {
        for j in 0..6 {
            let up = |v: f64, k: u64| f64::from_bits(v.to_bits() + k);
            pts.push([up(1e300, i), up(1e300, j)]);
            pts.push([up(-1e300, i), up(2e300, j)]);
            pts.push([i as f64 * 5e-324, j as f64 * 5e-324]);
            pts.push([1.0 + i as f64 * 1e-300, j as f64]);
        }
    }
    check(&pts);
}

#[test]
fn errors_are_typed() {
    assert_eq!(
        Triangulation::new(&[]).unwrap_err(),
        TriangulationError::TooFewPoints { distinct: 0 }
    );
    assert_eq!(
        Triangulation::new(&[[1.0, 1.0], [1.0, 1.0], [2.0, 1.0], [2.0, 1.0]]).unwrap_err(),
        TriangulationError::TooFewPoints { distinct: 2 }
    );
    assert_eq!(
        Triangulation::new(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [1.0, 1.0]]).unwrap_err(),
        TriangulationError::AllCollinear { distinct: 3 }
    );
    assert_eq!(
        Triangulation::new(&[[0.0, 0.0], [1.0, f64::NAN], [2.0, 1.0]]).unwrap_err(),
        TriangulationError::NonFinite { index: 1 }
    );
    assert_eq!(
        Triangulation::new(&[[0.0, 0.0], [1.0, 0.0], [f64::INFINITY, 1.0]]).unwrap_err(),
        TriangulationError::NonFinite { index: 2 }
    );
}

#[test]
fn many_sampled_circles_near_ties() {
    // 625 circles of 32 samples (cos/sin rounding: thousands of near co-circular tests).
    let mut r = Rng(9);
    let mut pts = Vec::new();
    for c in 0..625 {
        let (cx, cy) = ((c % 25) as f64 + 0.5, (c / 25) as f64 + 0.5);
        let rad = 0.3 + 0.15 * r.unit();
        for k in 0..32 {
            let a = std::f64::consts::TAU * k as f64 / 32.0;
            pts.push([cx + rad * a.cos(), cy + rad * a.sin()]);
        }
    }
    check(&pts);
}

#[test]
fn ulp_perturbed_grid() {
    // A 40 x 40 grid whose points are moved by a few ulps: nearly every test is a near tie.
    let mut r = Rng(10);
    let mut pts = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            let jitter = |v: f64, r: &mut Rng| f64::from_bits(v.to_bits() + r.next() % 4);
            pts.push([
                jitter(1.0 + i as f64 * 0.25, &mut r),
                jitter(1.0 + j as f64 * 0.25, &mut r),
            ]);
        }
    }
    check(&pts);
}
