//! `Triangulation::finish` builds the result in the builder's own arrays (issue 8: fewer fresh
//! pages): the neighbours compacted inside the half-edge array, the slot map in the builder's
//! scratch, the vertex table in a scratch array or the slot map again, the points in the
//! working copy. These tests check the result against facts computed independently of that
//! reuse, on the inputs where the reuse has edge cases: far more duplicates than triangle
//! slots (the slot map is shorter than the vertex table it becomes), coordinates the
//! predicates rescale (the working copy differs from the points), and the resumed builder of
//! `extended_full` (identity vertex order, the vertex table in the per-vertex scratch).

use medial_blocks::geometry::{Point, Triangulation};

use crate::common;
use common::XorShift;

/// Every public fact of `dt` checked against `points` alone: the points bit for bit, each
/// point's triangle has the point (or the point it duplicates), the neighbour relation is
/// symmetric and shares an edge, and the triangle count is `2 V - 2 - hull`.
fn check_against_points(dt: &Triangulation, points: &[Point]) {
    assert_eq!(dt.points().len(), points.len());
    for (a, b) in dt.points().iter().zip(points) {
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
    }
    // Duplicates: (first, duplicate), the first the smallest index of its equal points.
    let mut first_of: Vec<usize> = (0..points.len()).collect();
    for &(f, d) in dt.duplicates() {
        assert_eq!(points[f as usize], points[d as usize]);
        assert!(f < d);
        first_of[d as usize] = f as usize;
    }
    for (v, &f) in first_of.iter().enumerate() {
        let t = dt.vertex_triangle(v).expect("every point has a triangle");
        assert!(dt.triangle(t).contains(&(f as u32)), "point {v}");
    }
    assert_eq!(dt.vertex_triangle(points.len()), None);
    let mut hull_edges = 0;
    for t in 0..dt.len() {
        let v = dt.triangle(t);
        for (k, nb) in dt.neighbors(t).iter().enumerate() {
            let Some(m) = nb else {
                hull_edges += 1;
                continue;
            };
            let w = dt.triangle(*m as usize);
            let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            assert!(w.contains(&a) && w.contains(&b), "edge {t}.{k}");
            assert!(dt.neighbors(*m as usize).contains(&Some(t as u32)));
        }
    }
    assert_eq!(dt.len(), 2 * dt.vertex_count() - 2 - hull_edges);
}

/// The triangles as a sorted list of vertex sets (the Delaunay set is a function of the
/// point set: the numbering may differ).
fn triangle_set(dt: &Triangulation) -> Vec<[u32; 3]> {
    let mut out: Vec<[u32; 3]> = (0..dt.len())
        .map(|t| {
            let mut v = dt.triangle(t);
            v.sort_unstable();
            v
        })
        .collect();
    out.sort_unstable();
    out
}

/// `base` distinct random points (scaled by `scale`) followed by `dups` copies of them.
fn with_duplicates(rng: &mut XorShift, base: usize, dups: usize, scale: f64) -> Vec<Point> {
    let mut pts: Vec<Point> = (0..base)
        .map(|_| [rng.unit() * scale, rng.unit() * scale])
        .collect();
    for _ in 0..dups {
        let p = pts[rng.below(base as u64) as usize];
        pts.push(p);
    }
    pts
}

#[test]
fn finish_in_place_with_many_duplicates_and_rescaled_points() {
    let mut rng = XorShift(0x9e37_79b9_7f4a_7c15);
    for (base, dups, scale) in [
        (50, 400, 1.0),
        (300, 0, 1.0),
        (120, 900, 1e-200),
        (200, 50, 1e200),
        (8, 100, 3.0),
    ] {
        let pts = with_duplicates(&mut rng, base, dups, scale);
        let dt = Triangulation::new(&pts).unwrap();
        assert_eq!(dt.duplicates().len(), dups);
        check_against_points(&dt, &pts);
    }
}

#[test]
fn resumed_builder_finish_matches_a_fresh_triangulation() {
    let mut rng = XorShift(77);
    for (base, extra, dups, scale) in [(200, 150, 300, 1.0), (60, 40, 500, 1e-150)] {
        let first = with_duplicates(&mut rng, base, 0, scale);
        let mut all = first.clone();
        all.extend(with_duplicates(&mut rng, extra, 0, scale));
        for _ in 0..dups {
            let p = all[rng.below(all.len() as u64) as usize];
            all.push(p);
        }
        let dt = Triangulation::new(&first).unwrap();
        let ext = dt
            .extended_full(&all)
            .unwrap()
            .expect("same scaling: extensible");
        check_against_points(&ext, &all);
        let fresh = Triangulation::new(&all).unwrap();
        assert_eq!(triangle_set(&ext), triangle_set(&fresh));
        assert_eq!(ext.duplicates(), fresh.duplicates());
    }
}
