//! Exact mode collapses the same short arcs whatever the sampling density.
//!
//! The sampling only finds the combinatorics of the medial axis (which circles meet at a
//! medial vertex); exact mode builds its blocks on the exact Apollonius centres. An arc is
//! short when its length is below a fraction of the empty-circle radius, and exact mode
//! measures it by the chord between its ends' exact centres
//! (`collapse::ArcLength::Chord`), a function of the arc's circles alone. The sampled
//! polyline through the circumcentres of the sampled triangles (`ArcLength::Polyline`, the
//! paper pipeline's measure) moves with the samples: an arc near the threshold was collapsed
//! at one density and kept at another (on 1 000 bubbles, 16 samples per circle instead of 32
//! kept one truly short arc and left cells with aspect ratios above 100).
//!
//! The oracle: two samplings of the same layout (exact mode's own, 24 samples per circle at
//! least, and one with 128 and a quarter of its spacing) must choose the same arcs to
//! collapse, named by their circles (which survive resampling); in periodic boxes, as many
//! arcs and blocks.

use crate::common;

use medial_blocks::blocking::arc_key;
use medial_blocks::cocircular::cocircular_groups;
use medial_blocks::collapse::{ArcLength, Selection};
use medial_blocks::domain::{CircleId, Domain};
use medial_blocks::layouts::bubbles;
use medial_blocks::periodic::periodic_layout_with;
use medial_blocks::refine::refine;
use medial_blocks::sampling::SamplingOptions;
use medial_blocks::{Mode, Options, PeriodicDomain};
use std::collections::BTreeSet;

type Keys = BTreeSet<Vec<CircleId>>;

/// Every sampled arc's key, and the keys of the arcs chosen for collapse with `how`.
fn arcs_and_collapses(d: &Domain, sampling: &SamplingOptions, how: ArcLength) -> (Keys, Keys) {
    let options = Options::default();
    let refined = refine(
        d,
        options.refine_ratio,
        options.max_inserted_holes,
        sampling,
    )
    .unwrap();
    let s = &refined.sampled;
    let groups = cocircular_groups(&s.medial, &refined.circles);
    let selection = Selection::new(
        &s.medial,
        &s.triangulation,
        &refined.circles,
        &groups,
        &s.samples.points,
        options.collapse_fraction,
        how,
    );
    let all = (0..s.medial.arcs.len())
        .map(|e| arc_key(&s.medial, e))
        .collect();
    let chosen = selection
        .select(&[], &[])
        .iter()
        .map(|c| arc_key(&s.medial, c.arc as usize))
        .collect();
    (all, chosen)
}

/// Exact mode's own first sampling.
fn coarse() -> SamplingOptions {
    medial_blocks::mesher::exact_sampling()
}

fn fine() -> SamplingOptions {
    SamplingOptions {
        min_per_circle: 128,
        spacing_per_gap: 0.25,
        ..coarse()
    }
}

/// Layouts whose short arcs the sampled polylines measure differently at the two densities
/// (the test checks that at least three still do, so that it keeps its power).
const LAYOUTS: [(usize, u64); 6] = [(300, 1), (300, 3), (400, 4), (400, 5), (500, 6), (500, 7)];

#[test]
fn exact_mode_collapses_the_same_arcs_at_every_sampling_density() {
    let mut polyline_differs = 0;
    let mut flipped_diagonals = 0;
    for (holes, seed) in LAYOUTS {
        let d = bubbles(holes, seed).unwrap();
        let (arcs_coarse, chord_coarse) = arcs_and_collapses(&d, &coarse(), ArcLength::Chord);
        let (arcs_fine, chord_fine) = arcs_and_collapses(&d, &fine(), ArcLength::Chord);
        // The two samplings find the same medial axis up to the diagonal of nearly
        // co-circular quadruples (same arc count, keys may differ there).
        assert_eq!(
            arcs_coarse.len(),
            arcs_fine.len(),
            "{holes} holes, seed {seed}"
        );
        flipped_diagonals += usize::from(arcs_coarse != arcs_fine);
        assert!(
            !chord_coarse.is_empty(),
            "{holes} holes, seed {seed}: nothing collapsed"
        );
        // A collapsed arc is named by the four circles of its ends, the same for either
        // diagonal of a quadruple: the chosen collapses agree even where the diagonals differ.
        assert_eq!(chord_coarse, chord_fine, "{holes} holes, seed {seed}");
        let (_, poly_coarse) = arcs_and_collapses(&d, &coarse(), ArcLength::Polyline);
        let (_, poly_fine) = arcs_and_collapses(&d, &fine(), ArcLength::Polyline);
        polyline_differs += usize::from(poly_coarse != poly_fine);
    }
    assert!(
        polyline_differs >= 3,
        "the sampled polylines agreed on {polyline_differs} only"
    );
    assert!(
        flipped_diagonals >= 1,
        "no layout exercised a flipped diagonal"
    );
}

/// The same in periodic boxes (`periodic::select_collapse`, the arcs chosen once per orbit):
/// exact mode measures by the chords, paper mode by the polylines. Fifteen random boxes of 14
/// holes with a collapse fraction of 0.05 (periodic exact mode's own is 1e-3, where only
/// nearly co-circular arcs qualify): exact mode collapses as many arcs and gets as many blocks
/// at both densities on every box; the polylines disagree on at least one (seed 13).
#[test]
fn periodic_exact_mode_collapses_the_same_arcs_at_every_sampling_density() {
    let mut polyline_differs = 0;
    for seed in 1..=15u64 {
        let mut rng = medial_blocks::layouts::SplitMix64(seed);
        let holes = common::random_holes(&mut rng, 14, 0.5, [0.5, 0.5], 0.02);
        let pd = PeriodicDomain::new([1.0, 1.0], holes).unwrap();
        let counts = |mode: Mode, sampling: &SamplingOptions| {
            let options = Options {
                mode,
                collapse_fraction: 0.05,
                ..Options::default()
            };
            let p = periodic_layout_with(&pd, &options, sampling).unwrap();
            (p.collapsed_arcs, p.layout.blocks.len())
        };
        let exact = counts(Mode::Exact, &coarse());
        assert_eq!(exact, counts(Mode::Exact, &fine()), "seed {seed}");
        polyline_differs +=
            usize::from(counts(Mode::Paper, &coarse()) != counts(Mode::Paper, &fine()));
    }
    assert!(
        polyline_differs >= 1,
        "the sampled polylines agreed on every box"
    );
}
