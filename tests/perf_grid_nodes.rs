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

/// The inverted-cell test of the exact grid loop (`exact_mode::inverted`) against
/// `quality::inverted_cells` of the same grid, computed alongside: blocks made by the row
/// builder (valid ones), the same with random nodes moved (folded cells), with nodes merged
/// (zero products), with NaN and infinite coordinates, random node clouds, thin and empty
/// grids and malformed ones (node count not `(ni + 1)(nj + 1)`); every vector build agrees.
#[test]
fn inverted_cells_match_the_quality_count() {
    use medial_blocks::exact_mode::inverted::has_inverted_cell_every_build;
    use medial_blocks::quality::inverted_cells;
    use medial_blocks::BlockGrid;
    let mut rng = SplitMix64(29);
    let (mut inverted, mut valid) = (0, 0);
    for case in 0..6000u64 {
        let ni = (case % 19) as usize;
        let nj = (case % 17) as usize;
        let mut nodes: Vec<Point> = if case % 5 == 4 {
            (0..(ni + 1) * (nj + 1))
                .map(|_| [rng.next_f64(), rng.next_f64()])
                .collect()
        } else {
            // A block around an annulus sector: walls at radius 1, medial points further out.
            let ends: Vec<(Point, Point)> = (0..=ni)
                .map(|i| {
                    let a = -(i as f64) * 0.05;
                    let r = 1.5 + 0.3 * rng.next_f64();
                    ([a.cos(), a.sin()], [r * a.cos(), r * a.sin()])
                })
                .collect();
            block_nodes(&ends, nj, None, 1.2).expect("the vector builds differ")
        };
        let k = nodes.len();
        if k > 1 {
            match case % 7 {
                1 => {
                    let at = (rng.next_u64() % k as u64) as usize;
                    nodes[at][0] += 0.3 * (rng.next_f64() - 0.5);
                    nodes[at][1] += 0.3 * (rng.next_f64() - 0.5);
                }
                2 => {
                    let at = (rng.next_u64() % (k as u64 - 1)) as usize;
                    nodes[at] = nodes[at + 1];
                }
                3 => {
                    let at = (rng.next_u64() % k as u64) as usize;
                    nodes[at][(case % 2) as usize] = if case % 3 == 0 {
                        f64::NAN
                    } else {
                        f64::INFINITY
                    };
                }
                5 => {
                    nodes.pop();
                }
                _ => {}
            }
        }
        let g = BlockGrid { ni, nj, nodes };
        let want = inverted_cells(std::slice::from_ref(&g)) > 0;
        let got = has_inverted_cell_every_build(&g).expect("the vector builds differ");
        assert_eq!(got, want, "case {case} ni {ni} nj {nj}");
        inverted += usize::from(want);
        valid += usize::from(!want && ni > 0 && nj > 0);
    }
    assert!(inverted > 1000 && valid > 1000, "{inverted} {valid}");
}
