//! Exact mode's attempt loop (issue #8, "repetition in exact mode"): one sampling and one
//! triangulation when the first sampling is good, local fixes on that triangulation.
//!
//! Oracles independent of the code under test: cell orientation recomputed here from the grid
//! nodes (cross products at the four corners of every cell), triangulation counts from
//! [`timings::Recording`], and collapse sets compared by plain set arithmetic.

use crate::common;

use medial_blocks::blocking::{arc_key, collapsed_blocking_excluding, collapsed_blocking_with};
use medial_blocks::domain::CircleId;
use medial_blocks::layouts::bubbles;
use medial_blocks::mesh::Geometry;
use medial_blocks::mesher::{exact_sampling, mesh_timed, Options};
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
use medial_blocks::{refine, timings};
use std::collections::BTreeSet;

fn calls(t: &timings::Timings, stage: &str) -> u64 {
    t.calls
        .iter()
        .find(|(s, _)| s == stage)
        .map_or(0, |&(_, n)| n)
}

/// Random bubbles: exact geometry, no inverted cell, and exactly one triangulation on the
/// layouts whose first sampling meets the hard invariants and need no inserted hole.
#[test]
fn random_bubbles_are_exact_in_one_triangulation() {
    let _turn = common::turn();
    let options = Options {
        block_cells: Some(4),
        ..Options::default()
    };
    let mut single = 0;
    for seed in 1..=8u64 {
        let domain = bubbles(40, seed).unwrap();
        let (mesh, t) = mesh_timed(&domain, &options).unwrap();
        assert_eq!(mesh.geometry, Geometry::Exact, "seed {seed}");
        assert_eq!(common::count_inverted_cells(&mesh.grids), 0, "seed {seed}");
        // No hard resampling and no inserted hole: one sampling, one triangulation.
        let sampled = sample_and_triangulate(&domain, &exact_sampling()).unwrap();
        let refined = refine::refine(
            &domain,
            options.refine_ratio,
            options.max_inserted_holes,
            &exact_sampling(),
        )
        .unwrap();
        if sampled.rounds == 0 && refined.inserted.is_empty() {
            single += 1;
            assert_eq!(calls(&t, "triangulation"), 1, "seed {seed}");
            assert_eq!(calls(&t, "sampling"), 1, "seed {seed}");
        }
    }
    assert!(single >= 4, "only {single} layouts needed no resampling");
}

/// The soft invariant (d) costs exact mode nothing: without its rounds the sampling stops at
/// the first triangulation where the paper pipeline's sampling resamples.
#[test]
fn exact_sampling_skips_the_soft_rounds() {
    let _turn = common::turn();
    let domain = bubbles(200, 1).unwrap();
    let rec = timings::Recording::start();
    let paper = sample_and_triangulate(&domain, &SamplingOptions::default()).unwrap();
    let t_paper = rec.finish();
    let rec = timings::Recording::start();
    let exact = sample_and_triangulate(&domain, &exact_sampling()).unwrap();
    let t_exact = rec.finish();
    assert!(paper.rounds >= 1, "the layout should have thin walls");
    assert_eq!(exact.rounds, 0);
    assert!(
        !exact.thin_walls.is_empty(),
        "the violations are still listed"
    );
    assert_eq!(calls(&t_exact, "triangulation"), 1);
    assert_eq!(
        calls(&t_paper, "triangulation"),
        1 + paper.rounds as u64,
        "one triangulation per round"
    );
}

/// Giving up the short collapses of one cluster keeps every other collapse, on the same
/// triangulation, and the given-up arcs stay given up after a new front end is built from
/// their keys (which survive resampling).
#[test]
fn local_uncollapse_keeps_the_collapses_outside_the_cluster() {
    let _turn = common::turn();
    let options = Options::default();
    let domain = bubbles(300, 1).unwrap();
    let cb = collapsed_blocking_with(&domain, &options, &exact_sampling(), false).unwrap();
    let medial = &cb.refined.sampled.medial;
    let cluster_of =
        |arc: u32| cb.contracted.cluster_of[medial.arcs[arc as usize].ends[0] as usize];
    let all: BTreeSet<u32> = cb.chosen.iter().map(|c| c.arc).collect();
    let mut clusters: Vec<u32> = cb
        .chosen
        .iter()
        .filter(|c| !c.zero)
        .map(|c| cluster_of(c.arc))
        .collect();
    clusters.sort_unstable();
    clusters.dedup();
    assert!(
        clusters.len() >= 3,
        "the layout should have short collapses"
    );
    for &k in clusters.iter().take(4) {
        let give_up: Vec<u32> = cb
            .chosen
            .iter()
            .filter(|c| !c.zero && cluster_of(c.arc) == k)
            .map(|c| c.arc)
            .collect();
        let mut local = cb.clone();
        local.recollapse(&options, &give_up, &[]).unwrap();
        let kept: BTreeSet<u32> = local.chosen.iter().map(|c| c.arc).collect();
        let expected: BTreeSet<u32> = all
            .iter()
            .copied()
            .filter(|e| !give_up.contains(e))
            .collect();
        assert_eq!(kept, expected, "cluster {k}");
        assert_eq!(local.collapsed, expected.len());
        assert!(give_up.iter().all(|&e| local.excluded[e as usize]));
        // Same sampling, same triangulation: the sampled graph is untouched.
        assert_eq!(local.refined.sampled.medial, *medial);
        // Sticky: a new front end told the keys never collapses those arcs, keeps the rest.
        let mut keys: Vec<Vec<CircleId>> = give_up
            .iter()
            .map(|&e| arc_key(medial, e as usize))
            .collect();
        keys.sort();
        let fresh =
            collapsed_blocking_excluding(&domain, &options, &exact_sampling(), false, &keys)
                .unwrap();
        let fresh_set: BTreeSet<u32> = fresh.chosen.iter().map(|c| c.arc).collect();
        assert_eq!(fresh_set, expected, "cluster {k}, from keys");
    }
}

/// An arc running backwards (the sampled Delaunay diagonal of four nearly co-circular circles
/// is not the exact one) with no short collapse to give up: exact mode collapses it into a
/// degree-4 vertex on the same triangulation instead of resampling.
#[test]
fn backwards_arc_is_collapsed_without_resampling() {
    let _turn = common::turn();
    let options = Options {
        collapse_fraction: 0.0,
        block_cells: Some(2),
        ..Options::default()
    };
    // (150, 2) had one with 32 samples per circle, not with exact mode's 24.
    let domain = bubbles(150, 5).unwrap();
    // Precondition, checked: the first exact build has an inconsistent arc.
    let cb = collapsed_blocking_with(&domain, &options, &exact_sampling(), false).unwrap();
    assert!(cb.chosen.iter().all(|c| c.zero));
    let first = medial_blocks::exact_mode::collapsed::build_collapsed(&cb, &options).unwrap();
    assert!(!first.inconsistent_arcs.is_empty());
    let (mesh, t) = mesh_timed(&domain, &options).unwrap();
    assert_eq!(mesh.geometry, Geometry::Exact);
    assert_eq!(common::count_inverted_cells(&mesh.grids), 0);
    assert_eq!(calls(&t, "triangulation"), 1);
    assert_eq!(calls(&t, "sampling"), 1);
    assert_eq!(
        mesh.collapsed_arcs,
        cb.collapsed + first.inconsistent_arcs.len()
    );
}

/// Exact mode takes its sampled graph's exact vertices from the refinement's Apollonius
/// circles instead of solving them again: the same vertices, bit for bit, as solving afresh.
#[test]
fn exact_vertices_from_the_refinement_are_the_solved_ones() {
    let _turn = common::turn();
    use medial_blocks::exact_mode::{exact_vertices, exact_vertices_with};
    for (n, seed) in [(60, 3), (150, 2)] {
        let domain = bubbles(n, seed).unwrap();
        let refined = refine::refine(&domain, Some(2.0), 10_000, &exact_sampling()).unwrap();
        let medial = &refined.sampled.medial;
        assert!(refined.circles.iter().filter(|c| c.is_some()).count() > medial.vertices.len() / 2);
        let solved = exact_vertices(&refined.domain, medial).unwrap();
        let reused = exact_vertices_with(&refined.domain, medial, &refined.circles).unwrap();
        let bits = |v: &medial_blocks::exact_mode::ExactVertex| {
            let mut b = vec![
                v.center[0].to_bits(),
                v.center[1].to_bits(),
                v.radius.to_bits(),
            ];
            b.extend(
                v.tangent
                    .iter()
                    .flat_map(|t| [t[0].to_bits(), t[1].to_bits()]),
            );
            (b, v.circles.clone())
        };
        assert_eq!(solved.len(), reused.len());
        for (a, b) in solved.iter().zip(&reused) {
            assert_eq!(bits(a), bits(b));
        }
    }
}
