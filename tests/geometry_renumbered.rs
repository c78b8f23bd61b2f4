//! Issue #8: `Triangulation::extended_renumbered` takes an earlier triangulation whose points
//! sit at other indices of the new point list (a resampling that made some circles denser:
//! every earlier sample is still there, but the later circles' samples move), renumbers it and
//! inserts the other points. Oracle: the triangulation of the whole list from scratch, which
//! has the same triangle *set* (the Delaunay triangulation under the lexicographic simulation
//! of simplicity is a function of the point set); and the exact verifier. Maps that do not say
//! where the earlier points are give `None`, never a wrong triangulation.
//!
//! In the pipeline: macro refinement of a square lattice resamples the bounding circle and the
//! holes next to the inserted ones (every earlier sample kept), and its final triangulation,
//! built by renumbering, has the triangles of the one triangulated afresh.

use medial_blocks::geometry::verify::verify_exact;
use medial_blocks::geometry::{Point, Triangulation};
use medial_blocks::layouts;
use medial_blocks::refine::refine;
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
use proptest::prelude::*;

/// The triangles as sorted point triples (coordinates' bits), independent of numbering.
fn triangle_set(t: &Triangulation) -> Vec<[[u64; 2]; 3]> {
    let p = t.points();
    let mut out: Vec<[[u64; 2]; 3]> = (0..t.len())
        .map(|k| {
            let mut v = t.triangle(k).map(|i| p[i as usize].map(f64::to_bits));
            v.sort_unstable();
            v
        })
        .collect();
    out.sort_unstable();
    out
}

/// A deterministic shuffle of `0..n` from `seed` (Fisher-Yates on SplitMix64).
fn shuffled(n: usize, seed: u64) -> Vec<usize> {
    let mut r = layouts::SplitMix64(seed);
    let mut v: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = (r.next_u64() % (i as u64 + 1)) as usize;
        v.swap(i, j);
    }
    v
}

/// Points on a coarse lattice (co-circular quadruples, collinear runs) or spread at random,
/// without duplicates (the renumbering refuses those).
fn points_strategy() -> impl Strategy<Value = Vec<Point>> {
    let lattice = (0i32..9, 0i32..9).prop_map(|(x, y)| [f64::from(x) * 0.5, f64::from(y) * 0.5]);
    let spread = (0.0f64..4.0, 0.0f64..4.0).prop_map(|(x, y)| [x, y]);
    proptest::collection::vec(prop_oneof![1 => lattice, 1 => spread], 4..90).prop_map(|mut v| {
        let mut seen = std::collections::HashSet::new();
        v.retain(|p| seen.insert(p.map(f64::to_bits)));
        v
    })
}

/// The earlier points: those of `pts` that `keep` selects, in the order of a shuffle; and
/// where each one is in `pts`.
fn earlier(pts: &[Point], keep: &[bool], seed: u64) -> (Vec<Point>, Vec<u32>) {
    let chosen: Vec<usize> = shuffled(pts.len(), seed)
        .into_iter()
        .filter(|&i| keep[i % keep.len()])
        .collect();
    (
        chosen.iter().map(|&i| pts[i]).collect(),
        chosen.iter().map(|&i| i as u32).collect(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn renumbered_extension_has_the_triangles_from_scratch(
        pts in points_strategy(),
        keep in proptest::collection::vec(proptest::bool::weighted(0.7), 1..16),
        seed in 0u64..1000,
    ) {
        let (old, map) = earlier(&pts, &keep, seed);
        let Ok(before) = Triangulation::new(&old) else { return Ok(()); };
        let Ok(scratch) = Triangulation::new(&pts) else { return Ok(()); };
        match before.extended_renumbered(&pts, &map).unwrap() {
            Some(after) => {
                prop_assert_eq!(after.points(), &pts[..]);
                prop_assert_eq!(triangle_set(&after), triangle_set(&scratch));
                prop_assert!(verify_exact(&after).is_ok(), "{:?}", verify_exact(&after));
            }
            // Only where there was nothing to renumber (all earlier points collinear).
            None => prop_assert_eq!(before.len(), 0),
        }
    }
}

/// Maps that do not place the earlier points give `None`: a wrong length, an index out of
/// range, a point that differs, an index taken twice. The right map gives the triangulation.
#[test]
fn wrong_maps_are_refused() {
    let mut r = layouts::SplitMix64(3);
    let pts: Vec<Point> = (0..200).map(|_| [r.next_f64(), r.next_f64()]).collect();
    let (old, map) = earlier(&pts, &[true, false, true], 11);
    let before = Triangulation::new(&old).unwrap();
    assert!(!before.is_empty());
    let some = |m: &[u32]| before.extended_renumbered(&pts, m).unwrap().is_some();
    assert!(some(&map));
    assert!(!some(&map[1..]), "short map");
    let mut out_of_range = map.clone();
    out_of_range[5] = pts.len() as u32;
    assert!(!some(&out_of_range));
    // Another point's index: its coordinates differ.
    let mut differs = map.clone();
    let unused = (0..pts.len() as u32).find(|i| !map.contains(i)).unwrap();
    differs[0] = unused;
    assert!(!some(&differs));
    // Two earlier points at one index.
    let mut twice = map.clone();
    twice[1] = twice[0];
    assert!(!some(&twice));
    // A new point equal to an earlier one: duplicates are refused (their kept index could
    // change), the triangulation from scratch handles them.
    let mut with_duplicate = pts.clone();
    with_duplicate.push(old[0]);
    assert!(before
        .extended_renumbered(&with_duplicate, &map)
        .unwrap()
        .is_none());
}

/// Macro refinement of a square lattice: the inserted holes make the bounding circle and their
/// neighbours denser (every earlier sample stays), so each round's triangulation is the
/// earlier one renumbered with the new samples inserted; the final one has the triangles of
/// the same samples triangulated afresh, and a different numbering (the renumbering applied).
#[test]
fn refinement_of_a_lattice_renumbers_with_the_triangles_from_scratch() {
    let domain = layouts::square_lattice(400).unwrap();
    let opts = SamplingOptions {
        soft_rounds: false,
        ..SamplingOptions::default()
    };
    let ratio = medial_blocks::Options::default().refine_ratio;
    let refined = refine(&domain, ratio, 10_000, &opts).unwrap();
    assert!(
        !refined.inserted.is_empty(),
        "the lattice needs inserted holes"
    );
    let scratch = sample_and_triangulate(&refined.domain, &opts).unwrap();
    assert_eq!(
        scratch.samples.points, refined.sampled.samples.points,
        "the same samples"
    );
    let (a, b) = (&refined.sampled.triangulation, &scratch.triangulation);
    assert_eq!(triangle_set(a), triangle_set(b));
    assert!(verify_exact(a).is_ok());
    let order = |t: &Triangulation| (0..t.len()).map(|k| t.triangle(k)).collect::<Vec<_>>();
    assert_ne!(order(a), order(b), "numbered as an extension, not afresh");
}

/// Every new point strictly inside the earlier hull (the corners of the box are earlier
/// points): the case the sparse replay takes, on the renumbered arrays. Many rounds of random
/// subsets, each against the triangulation from scratch.
#[test]
fn new_points_inside_the_hull_give_the_triangles_from_scratch() {
    let mut r = layouts::SplitMix64(19);
    for round in 0..40u64 {
        let mut pts: Vec<Point> = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]];
        // Interior points, on a lattice (co-circular and collinear) or at random.
        while pts.len() < 300 {
            let p = if r.next_u64().is_multiple_of(2) {
                [
                    1.0 + (r.next_u64() % 5) as f64 * 0.5,
                    1.0 + (r.next_u64() % 5) as f64 * 0.5,
                ]
            } else {
                [0.1 + 3.8 * r.next_f64(), 0.1 + 3.8 * r.next_f64()]
            };
            if !pts.contains(&p) {
                pts.push(p);
            }
        }
        // The corners are kept; a third of the others are new.
        let keep: Vec<bool> = (0..pts.len())
            .map(|i| i < 4 || !r.next_u64().is_multiple_of(3))
            .collect();
        let order = shuffled(pts.len(), round);
        let chosen: Vec<usize> = order.into_iter().filter(|&i| keep[i]).collect();
        let old: Vec<Point> = chosen.iter().map(|&i| pts[i]).collect();
        let map: Vec<u32> = chosen.iter().map(|&i| i as u32).collect();
        let before = Triangulation::new(&old).unwrap();
        let after = before
            .extended_renumbered(&pts, &map)
            .unwrap()
            .expect("no duplicates, every earlier point placed");
        let scratch = Triangulation::new(&pts).unwrap();
        assert_eq!(
            triangle_set(&after),
            triangle_set(&scratch),
            "round {round}"
        );
        assert!(verify_exact(&after).is_ok(), "round {round}");
    }
}
