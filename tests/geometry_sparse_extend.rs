//! Issue #8: `Triangulation::extended` inserts the new points by a sparse replay of the
//! resumed builder on copies of the finished arrays (`geometry::sparse`). It must give exactly
//! the builder's triangulation (`extended_full`, the reference computed alongside): the same
//! triangles in the same order, the same neighbours, vertex triangles and duplicates; and pass
//! the exact verifier. Where it gives up (points outside the hull, duplicates), `extended`
//! still equals the reference. `extended_taking` (the replay on the taken arrays themselves)
//! gives the same triangulation, leaves the original unchanged where it gives up, gives it back
//! by `Changes::undo`, and its changes give the same `Kept` as comparing both triangulations.

use crate::common;

use medial_blocks::geometry::verify::verify_exact;
use medial_blocks::geometry::{Point, Triangulation};
use medial_blocks::layouts;
use medial_blocks::medial::reuse::Kept;
use medial_blocks::refine::refine;
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
use proptest::prelude::*;

/// `extended_taking` of a copy of `prefix` against `extended_sparse` of `prefix` (the
/// replay on copies), the `Kept` of its changes against the comparison of both
/// triangulations, and its undo against `prefix`. True when it applied.
fn taking_agrees(prefix: &Triangulation, pts: &[Point]) -> bool {
    let mut taken = prefix.clone();
    let sparse = prefix.extended_sparse(pts).unwrap();
    match taken.extended_taking(pts).unwrap() {
        Some((after, changes)) => {
            common::assert_same_triangulation(
                &after,
                sparse.as_ref().expect("the replay on copies applies too"),
            );
            assert_eq!(taken.len(), 0, "the arrays were taken");
            assert_eq!(
                Kept::from_changes(&changes, &after),
                Kept::new(prefix, &after)
            );
            common::assert_same_triangulation(&changes.undo(after), prefix);
            true
        }
        None => {
            assert!(sparse.is_none());
            common::assert_same_triangulation(&taken, prefix);
            false
        }
    }
}

/// Points on a coarse lattice (co-circular quadruples, collinear points, duplicates) or spread
/// at random inside a box, then new points mostly inside it.
fn points_strategy() -> impl Strategy<Value = Vec<Point>> {
    let lattice = (0i32..8, 0i32..8).prop_map(|(x, y)| [f64::from(x) * 0.5, f64::from(y) * 0.5]);
    let spread = (0.0f64..3.5, 0.0f64..3.5).prop_map(|(x, y)| [x, y]);
    let outside = (-2.0f64..6.0, -2.0f64..6.0).prop_map(|(x, y)| [x, y]);
    proptest::collection::vec(prop_oneof![4 => lattice, 4 => spread, 1 => outside], 3..80)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    #[test]
    fn sparse_extension_is_the_builders(pts in points_strategy(), cut in 0.2f64..1.0) {
        let n0 = ((pts.len() as f64 * cut) as usize).max(3);
        let Ok(prefix) = Triangulation::new(&pts[..n0]) else { return Ok(()); };
        let full = prefix.extended_full(&pts).unwrap();
        let auto = prefix.extended(&pts).unwrap();
        prop_assert_eq!(full.is_some(), auto.is_some());
        if let (Some(full), Some(auto)) = (full, auto) {
            common::assert_same_triangulation(&auto, &full);
            prop_assert!(verify_exact(&auto).is_ok(), "{:?}", verify_exact(&auto));
            if let Some(sparse) = prefix.extended_sparse(&pts).unwrap() {
                common::assert_same_triangulation(&sparse, &full);
            }
        }
        taking_agrees(&prefix, &pts);
    }
}

/// Random points in the unit square, then more inside: the replay applies, and agrees.
#[test]
fn sparse_extension_applies_inside_the_hull() {
    let mut rng = layouts::SplitMix64(7);
    let mut applied = 0;
    for round in 0..20 {
        let n0 = 200 + 50 * round;
        let mut pts: Vec<Point> = (0..n0).map(|_| [rng.next_f64(), rng.next_f64()]).collect();
        pts.extend([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let prefix = Triangulation::new(&pts).unwrap();
        pts.extend(
            (0..1 + round * 7).map(|_| [0.01 + 0.98 * rng.next_f64(), 0.5 * rng.next_f64()]),
        );
        let full = prefix.extended_full(&pts).unwrap().unwrap();
        if let Some(sparse) = prefix.extended_sparse(&pts).unwrap() {
            common::assert_same_triangulation(&sparse, &full);
            applied += 1;
        }
        common::assert_same_triangulation(&prefix.extended(&pts).unwrap().unwrap(), &full);
        taking_agrees(&prefix, &pts);
    }
    assert!(applied >= 18, "the replay applied {applied} times of 20");
}

/// The samples of refined layouts (new holes' samples appended), as refinement meets them.
#[test]
fn sparse_extension_on_refinement_samples() {
    let sampling = SamplingOptions {
        soft_rounds: false,
        ..SamplingOptions::default()
    };
    let mut applied = 0;
    for (n, seed) in [(200, 3), (300, 1), (500, 2)] {
        let d = layouts::bubbles(n, seed).unwrap();
        let Ok(r) = refine(&d, Some(2.0), 10_000, &sampling) else {
            continue;
        };
        let s0 = sample_and_triangulate(&d, &sampling).unwrap();
        let p1 = &r.sampled.samples.points;
        let Some(full) = s0.triangulation.extended_full(p1).unwrap() else {
            continue;
        };
        if let Some(sparse) = s0.triangulation.extended_sparse(p1).unwrap() {
            common::assert_same_triangulation(&sparse, &full);
            verify_exact(&sparse).unwrap();
            assert!(taking_agrees(&s0.triangulation, p1));
            applied += usize::from(p1.len() > s0.samples.points.len());
        }
    }
    assert!(applied >= 1, "no layout exercised the replay");
}
