//! The triangulation's *structure* (triangle numbering and vertex order, adjacency, duplicates,
//! vertex triangles) is what downstream code numbers everything by. These hashes were computed
//! by the engine of main 1d23c7f (before the `trifast` speed-ups) on the same inputs: every
//! change to the engine must keep them, not only the triangle set. Except on purpose: the
//! fifteenth session split sets from 2^13 points in halves (was 2^15), which renumbers
//! "bubbles 300" (some 25 000 samples) and its extension; their hashes are the new engine's
//! (the triangle set is checked unchanged by the split tests and `verify_exact` here).

use medial_blocks::geometry::verify::verify_exact;
use medial_blocks::geometry::{Point, Triangulation};
use medial_blocks::layouts;
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};

use crate::common;
use common::structure_hash;

fn samples(holes: usize, seed: u64) -> Vec<Point> {
    let domain = layouts::bubbles(holes, seed).unwrap();
    sample_and_triangulate(&domain, &SamplingOptions::default())
        .unwrap()
        .samples
        .points
}

/// A half-unit lattice (co-circular quadruples, collinear hull points) with every seventh point
/// repeated, in a scrambled order.
fn lattice() -> Vec<Point> {
    let mut pts: Vec<Point> = (0..900)
        .map(|i| [f64::from(i % 30) * 0.5, f64::from(i / 30) * 0.5])
        .collect();
    let dups: Vec<Point> = pts.iter().step_by(7).copied().collect();
    pts.extend(dups);
    let n = pts.len();
    (0..n).map(|i| pts[(i * 337) % n]).collect()
}

/// Every `(name, triangulation, expected hash)` is exactly valid and hashes as expected (all
/// hashes reported before failing).
fn check(cases: &[(&str, Triangulation, u64)]) {
    let mut wrong = Vec::new();
    for (name, dt, want) in cases {
        verify_exact(dt).unwrap();
        let got = structure_hash(dt);
        if got != *want {
            wrong.push(format!("{name}: structure hash {got:#018x}"));
        }
    }
    assert!(wrong.is_empty(), "{wrong:?}");
}

#[test]
fn pipeline_samples_keep_their_structure() {
    let pts = samples(300, 1);
    // The prefix extended by the remaining points (numbering of `extended`).
    let cut = pts.len() - pts.len() / 20;
    let prefix = Triangulation::new(&pts[..cut]).unwrap();
    let ext = prefix.extended(&pts).unwrap().unwrap();
    check(&[
        (
            "bubbles 300",
            Triangulation::new(&pts).unwrap(),
            0x86ac_588f_d43a_e702,
        ),
        ("bubbles 300 extended", ext, 0x6dcc_f550_9d20_4d65),
    ]);
}

#[test]
fn degenerate_sets_keep_their_structure() {
    let pts = lattice();
    // Scaled out of the predicates' range (the shift path) and mixed magnitudes (the checked,
    // partly rug-evaluated predicates).
    let tiny: Vec<Point> = pts.iter().map(|p| [p[0] * 1e-200, p[1] * 1e-200]).collect();
    let mut mixed = pts.clone();
    mixed.push([1e-160, 3.0]);
    mixed.push([7.25, 1e250]);
    let cut = pts.len() * 2 / 3;
    let prefix = Triangulation::new(&pts[..cut]).unwrap();
    let ext = prefix.extended(&pts).unwrap().unwrap();
    let tiny_prefix = Triangulation::new(&tiny[..cut]).unwrap();
    let tiny_ext = tiny_prefix.extended(&tiny).unwrap().unwrap();
    check(&[
        (
            "lattice",
            Triangulation::new(&pts).unwrap(),
            0x57ad_5c81_d573_3567,
        ),
        (
            "lattice tiny",
            Triangulation::new(&tiny).unwrap(),
            0x93f3_cd02_2e6d_f559,
        ),
        (
            "lattice mixed",
            Triangulation::new(&mixed).unwrap(),
            0x7978_0b63_46dc_e3cc,
        ),
        ("lattice extended", ext, 0xfb2b_0c3b_16b7_3ac9),
        ("lattice tiny extended", tiny_ext, 0xf453_db86_515b_9331),
    ]);
}
