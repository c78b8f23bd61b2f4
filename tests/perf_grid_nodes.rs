//! The row-by-row block nodes of exact mode (`exact_mode::grid_nodes`, issue #8) against the
//! spoke-by-spoke build they replaced (`spoke_column` into a zeroed vector), bit for bit:
//! random blocks with uniform and clustered spokes (both clustering regimes, first heights
//! too large to fit, mixed within one block), degenerate spokes (zero, tiny, subnormal,
//! infinite and NaN lengths), and every small count of cells; every vector build the CPU has
//! (baseline, AVX2, AVX-512) gives the same bits.

use medial_blocks::exact_mode::grid_nodes::{block_nodes, block_nodes_reference, SAFE_LEN};
use medial_blocks::layouts::SplitMix64;
use proptest::prelude::*;

type Point = [f64; 2];

fn same(a: &[Point], b: &[Point]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x[0].to_bits() == y[0].to_bits() && x[1].to_bits() == y[1].to_bits())
}

fn check(ends: &[(Point, Point)], nj: usize, first: Option<f64>, growth: f64) {
    let fast = block_nodes(ends, nj, first, growth).expect("the vector builds differ");
    let slow = block_nodes_reference(ends, nj, first, growth);
    assert!(
        same(&fast, &slow),
        "nj {nj} first {first:?} growth {growth} ends {ends:?}"
    );
}

/// A spoke end pair whose length is about `scale` (or degenerate, by `kind`).
fn spoke(rng: &mut SplitMix64, kind: u64, scale: f64) -> (Point, Point) {
    let a = [rng.next_f64() * 4.0 - 2.0, rng.next_f64() * 4.0 - 2.0];
    let dir = [rng.next_f64() - 0.5, rng.next_f64() - 0.5];
    let m = match kind {
        0 => a,
        1 => [a[0] + 1e-300 * dir[0], a[1]],
        2 => [a[0] + SAFE_LEN * (1.0 + dir[0]), a[1] + SAFE_LEN * dir[1]],
        3 => [f64::INFINITY, a[1]],
        4 => [f64::NAN, a[1]],
        5 => [a[0] + 5e-324, a[1]],
        _ => [a[0] + scale * dir[0], a[1] + scale * dir[1]],
    };
    (a, m)
}

#[test]
fn rows_match_the_spokes_on_random_blocks() {
    let mut rng = SplitMix64(17);
    for case in 0..4000u64 {
        let ni = 1 + (case % 23) as usize;
        let nj = (case % 19) as usize;
        let scale = 10f64.powi((case % 13) as i32 - 6);
        let degenerate = case % 3 == 0;
        let ends: Vec<(Point, Point)> = (0..ni)
            .map(|_| {
                let kind = if degenerate { rng.next_u64() % 12 } else { 99 };
                spoke(&mut rng, kind, scale)
            })
            .collect();
        let first = match case % 5 {
            0 | 1 => None,
            2 => Some(1e-4 * scale * (1.0 + rng.next_f64())),
            3 => Some(0.1 * scale * rng.next_f64()),
            _ => Some(2.0 * scale),
        };
        let growth = 1.0 + 0.4 * rng.next_f64();
        check(&ends, nj, first, growth);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Arbitrary coordinates (any magnitude) and counts, uniform spacing.
    #[test]
    fn rows_match_the_spokes_uniform(
        pts in prop::collection::vec((any::<f64>(), any::<f64>(), -1e6f64..1e6, -1e6f64..1e6), 1..12),
        nj in 0usize..40,
    ) {
        let ends: Vec<(Point, Point)> = pts.iter().map(|&(x, y, u, v)| ([x, y], [u, v])).collect();
        let fast = block_nodes(&ends, nj, None, 1.2).expect("the vector builds differ");
        let slow = block_nodes_reference(&ends, nj, None, 1.2);
        prop_assert!(same(&fast, &slow));
    }
}

/// The node parameters from the weights' running sums (`exact_mode::equidistribution`)
/// against the sum-then-scan form, bit for bit: random weights with zeros, runs of zeros,
/// tiny and huge values, negative, infinite and NaN entries, all counts up to 40 and empty
/// weights.
#[test]
fn equidistribution_matches_the_sum_then_scan() {
    use medial_blocks::exact_mode::equidistribution::{
        equidistribute_bits, equidistribute_reference,
    };
    let mut rng = SplitMix64(23);
    for case in 0..20_000u64 {
        let k = (case % 300) as usize;
        let mode = case % 7;
        let w: Vec<f64> = (0..k)
            .map(|i| {
                let r = rng.next_f64();
                match (mode, (i as u64 + case) % 11) {
                    (0, _) => r,
                    (1, 0..=4) => 0.0,
                    (2, 0) => 1e300 * r,
                    (2, 1) => 1e-300 * r,
                    (3, 0) if case % 50 == 3 => -r,
                    (4, 0) if case % 40 == 4 => f64::INFINITY,
                    (5, 0) if case % 30 == 5 => f64::NAN,
                    (6, _) => (r * 4.0).floor(),
                    _ => r * r,
                }
            })
            .collect();
        let n = 1 + (case % 40) as usize;
        let want: Vec<u64> = equidistribute_reference(&w, n)
            .iter()
            .map(|x| x.to_bits())
            .collect();
        assert_eq!(
            equidistribute_bits(&w, n),
            want,
            "case {case} n {n} w {w:?}"
        );
    }
}
