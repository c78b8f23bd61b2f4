//! Insertion order: biased randomized insertion order (BRIO) rounds, each round sorted along a
//! Hilbert curve. Only affects speed: the triangulation itself does not depend on the order.
//!
//! Rounds are drawn from a hash of the point's *coordinates*, so exact duplicates share a round
//! and a Hilbert cell and are ordered by input index: the first occurrence is inserted first.

use super::Point;
use rayon::prelude::*;

/// Fewest points keyed and sorted on several threads (a pipeline's 1e3 particles give some
/// 33 000 sample points).
const PARALLEL_MIN: usize = 1 << 14;

const HILBERT_ORDER: u32 = 14;
const MAX_LEVEL: u32 = 15;

/// Hilbert curve index of cell `(x, y)` on a `2^order` grid: the classic `xy2d` loop (one
/// quadrant per bit level, rotating the remaining low bits), kept as the reference for
/// [`hilbert_fast`].
#[cfg(test)]
fn hilbert(mut x: u32, mut y: u32, order: u32) -> u32 {
    let n = 1u32 << order;
    let mut d = 0u32;
    let mut s = n >> 1;
    while s > 0 {
        let rx = u32::from(x & s != 0);
        let ry = u32::from(y & s != 0);
        d += s * s * ((3 * rx) ^ ry);
        if ry == 0 {
            if rx == 1 {
                x = n - 1 - x;
                y = n - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s >>= 1;
    }
    d
}

/// Spreads the low 16 bits of `x` to the even bit positions.
#[inline(always)]
fn interleave(mut x: u32) -> u32 {
    x = (x | (x << 8)) & 0x00ff_00ff;
    x = (x | (x << 4)) & 0x0f0f_0f0f;
    x = (x | (x << 2)) & 0x3333_3333;
    x = (x | (x << 1)) & 0x5555_5555;
    x
}

/// `hilbert` (the reference loop, kept for the tests) without a loop over the bit levels, for
/// `order <= 16` (the same index: checked against it exhaustively at the order used,
/// [`HILBERT_ORDER`]).
///
/// The rotation state of every level is a prefix of the quadrant transforms above it; that
/// prefix is a composition of the four transforms (identity, swap, complement, both), written
/// as bit planes `a, b` (the transform) and `c, d` (its effect) and combined in `log2(16)`
/// doubling rounds (a parallel prefix scan over the 16 levels, one bit per level per word).
/// After the scan the quadrant digit of each level is read off at once and the digits are
/// interleaved into the index. (Public-domain formulation of the Hilbert prefix scan by
/// rawrunprotected, `hilbert_curves`.)
#[inline]
fn hilbert_fast(x: u32, y: u32, order: u32) -> u32 {
    debug_assert!((1..=16).contains(&order) && x >> order == 0 && y >> order == 0);
    let x = x << (16 - order);
    let y = y << (16 - order);
    // First round, from the quadrant bits of each level.
    let a0 = x ^ y;
    let b0 = 0xffff ^ a0;
    let c0 = 0xffff ^ (x | y);
    let d0 = x & (y ^ 0xffff);
    let mut a = a0 | (b0 >> 1);
    let mut b = (a0 >> 1) ^ a0;
    let mut c = ((c0 >> 1) ^ (b0 & (d0 >> 1))) ^ c0;
    let mut d = ((a0 & (c0 >> 1)) ^ (d0 >> 1)) ^ d0;
    // Doubling rounds: compose with the prefix 2, 4, 8 levels up.
    for sh in [2u32, 4] {
        let (pa, pb, pc, pd) = (a, b, c, d);
        a = (pa & (pa >> sh)) ^ (pb & (pb >> sh));
        b = (pa & (pb >> sh)) ^ (pb & ((pa ^ pb) >> sh));
        c ^= (pa & (pc >> sh)) ^ (pb & (pd >> sh));
        d ^= (pb & (pc >> sh)) ^ ((pa ^ pb) & (pd >> sh));
    }
    let (pa, pb, pc, pd) = (a, b, c, d);
    c ^= (pa & (pc >> 8)) ^ (pb & (pd >> 8));
    d ^= (pb & (pc >> 8)) ^ ((pa ^ pb) & (pd >> 8));
    // Undo the scan's encoding, then the two digit bits per level.
    let a = c ^ (c >> 1);
    let b = d ^ (d >> 1);
    let i0 = x ^ y;
    let i1 = b | (0xffff ^ (i0 | a));
    ((interleave(i1) << 1) | interleave(i0)) >> (32 - 2 * order)
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Point indices in insertion order. Points must be finite and fewer than 2^32.
pub(crate) fn insertion_order(pts: &[Point]) -> Vec<u32> {
    insertion_order_on(
        pts,
        pts.len() >= PARALLEL_MIN && rayon::current_num_threads() > 1,
    )
}

/// Point indices along a Hilbert curve over the points' bounding box (ties, points in one
/// cell of the `2^14 x 2^14` grid, by index): the order alone, without [`insertion_order`]'s
/// rounds. Points must be finite and fewer than 2^32.
///
/// Keyed and sorted on the thread pool (the keys are distinct: any pool gives this order).
pub(crate) fn hilbert_order(pts: &[Point]) -> Vec<u32> {
    let cell = hilbert_cells(pts);
    let mut keys: Vec<u64> = pts
        .par_iter()
        .enumerate()
        .map(|(i, p)| (u64::from(cell(p)) << 32) | i as u64)
        .collect();
    keys.par_sort_unstable();
    keys.into_par_iter().map(|k| k as u32).collect()
}

/// The Hilbert index (`2 HILBERT_ORDER` bits) of a point's cell on the grid over the bounding
/// box of `pts`.
fn hilbert_cells(pts: &[Point]) -> impl Fn(&Point) -> u32 {
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in pts {
        x0 = x0.min(p[0]);
        y0 = y0.min(p[1]);
        x1 = x1.max(p[0]);
        y1 = y1.max(p[1]);
    }
    let cells = f64::from(1u32 << HILBERT_ORDER);
    let max_cell = (1u32 << HILBERT_ORDER) - 1;
    // Scale each axis separately; halve first so the extent never overflows.
    let sx = cells / ((0.5 * x1 - 0.5 * x0) * 2.0).max(f64::MIN_POSITIVE);
    let sy = cells / ((0.5 * y1 - 0.5 * y0) * 2.0).max(f64::MIN_POSITIVE);
    let quantize = move |v: f64, lo: f64, s: f64| -> u32 {
        // `as` truncates, which is `floor` for the positive values kept (no libm call).
        let q = (0.5 * v - 0.5 * lo) * 2.0 * s;
        if q.is_finite() && q > 0.0 {
            (q as u32).min(max_cell)
        } else {
            0
        }
    };
    move |p: &Point| {
        hilbert_fast(
            quantize(p[0], x0, sx),
            quantize(p[1], y0, sy),
            HILBERT_ORDER,
        )
    }
}

/// [`insertion_order`], keyed on the thread pool when `parallel` (the keys do not depend on
/// the pool, so neither does the order).
///
/// The order is that of the 64-bit keys `round (4 bits) | hilbert (28 bits) | index (32
/// bits)` sorted ascending; since the index only breaks ties and the points start in index
/// order, a stable sort on the upper 32 bits gives it: up to [`RADIX_MAX`] points, three
/// counting-sort passes over 11, 11 and 10-bit digits (least significant first, each
/// stable, [`stable_order`]); issue 8: at 1e3 particles (25 000 sample points) the parallel
/// comparison sort of the 64-bit keys and their conversion to indices took 0.7 ms of the
/// order's 1.1 ms.
fn insertion_order_on(pts: &[Point], parallel: bool) -> Vec<u32> {
    let cell = hilbert_cells(pts);
    let key = |p: &Point| -> u32 {
        // `+ 0.0` maps -0.0 to 0.0 so that duplicates hash alike.
        let h = splitmix((p[0] + 0.0).to_bits() ^ splitmix((p[1] + 0.0).to_bits()));
        let level = (h.trailing_zeros()).min(MAX_LEVEL);
        // round (4 bits) | hilbert (28 bits)
        ((MAX_LEVEL - level) << 28) | cell(p)
    };
    if pts.len() > RADIX_MAX && parallel {
        // round (4 bits) | hilbert (28 bits) | index (32 bits): distinct keys, so the unstable
        // parallel sort gives the one order.
        let mut keys: Vec<u64> = pts
            .par_iter()
            .enumerate()
            .map(|(i, p)| (u64::from(key(p)) << 32) | i as u64)
            .collect();
        keys.par_sort_unstable();
        return keys.into_par_iter().map(|k| k as u32).collect();
    }
    let keys: Vec<u32> = if parallel {
        pts.par_iter().map(key).collect()
    } else {
        pts.iter().map(key).collect()
    };
    stable_order(&keys)
}

/// Most points ordered by [`stable_order`] on one thread when a pool is at hand; above, the
/// 64-bit keys are sorted on the pool (the same order). At 1e5 particles (2.5 M points) the
/// passes and their 50 MB of fresh memory on one thread took 40 ms more than the parallel
/// sort; at 1e3 (25 000 points) they save a third of the order's 1 ms.
const RADIX_MAX: usize = 1 << 18;

/// The digits of [`stable_order`]'s passes, least significant first: `(shift, bits)`.
const DIGITS: [(u32, u32); 3] = [(0, 11), (11, 11), (22, 10)];

/// Indices `0..keys.len()` sorted by `keys[i]`, equal keys by index (a stable LSD radix sort
/// of `(key, index)` pairs; a pass whose digit is the same for every key is skipped).
fn stable_order(keys: &[u32]) -> Vec<u32> {
    let n = keys.len();
    let mut counts = [[0u32; 1 << 11]; 3];
    for &k in keys {
        for (c, &(shift, bits)) in counts.iter_mut().zip(&DIGITS) {
            c[((k >> shift) & ((1 << bits) - 1)) as usize] += 1;
        }
    }
    // Every pass turns its counts into starting positions, then scatters stably.
    let starts = |c: &[u32; 1 << 11]| -> Option<[u32; 1 << 11]> {
        if c.iter().any(|&x| x as usize == n) {
            return None;
        }
        let mut s = [0u32; 1 << 11];
        let mut at = 0;
        for (s, &x) in s.iter_mut().zip(c) {
            *s = at;
            at += x;
        }
        Some(s)
    };
    let pack = |i: usize, k: u32| (u64::from(k) << 32) | i as u64;
    let digit =
        |v: u64, (shift, bits): (u32, u32)| ((v >> (32 + shift)) & ((1 << bits) - 1)) as usize;
    // `(key, index)` pairs, in the order of the passes so far (`None`: index order, read from
    // `keys` directly by the first pass that runs).
    let mut sorted: Option<Vec<u64>> = None;
    let mut spare: Vec<u64> = Vec::new();
    for (c, &d) in counts.iter().zip(&DIGITS) {
        let Some(mut at) = starts(c) else {
            continue;
        };
        spare.resize(n, 0);
        let mut put = |v: u64| {
            let b = digit(v, d);
            spare[at[b] as usize] = v;
            at[b] += 1;
        };
        match &sorted {
            None => keys.iter().enumerate().for_each(|(i, &k)| put(pack(i, k))),
            Some(p) => p.iter().for_each(|&v| put(v)),
        }
        let done = std::mem::take(&mut spare);
        spare = sorted.replace(done).unwrap_or_default();
    }
    drop(spare);
    match sorted {
        Some(p) => p.into_iter().map(|v| v as u32).collect(),
        None => (0..n as u32).collect(),
    }
}

/// The sort [`insertion_order_on`] replaced: the 64-bit keys sorted ascending (the
/// reference of the tests).
#[cfg(test)]
fn insertion_order_reference(pts: &[Point]) -> Vec<u32> {
    let cell = hilbert_cells(pts);
    let mut keys: Vec<u64> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let h = splitmix((p[0] + 0.0).to_bits() ^ splitmix((p[1] + 0.0).to_bits()));
            let level = (h.trailing_zeros()).min(MAX_LEVEL);
            let round = u64::from(MAX_LEVEL - level);
            (round << 60) | (u64::from(cell(p)) << 32) | i as u64
        })
        .collect();
    keys.sort_unstable();
    keys.into_iter().map(|k| k as u32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_is_a_bijection_on_small_grid() {
        let mut seen = [false; 64];
        for x in 0..8 {
            for y in 0..8 {
                seen[hilbert(x, y, 3) as usize] = true;
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn scan_hilbert_matches_the_loop() {
        for order in 1..=8 {
            for x in 0..1u32 << order {
                for y in 0..1u32 << order {
                    assert_eq!(hilbert_fast(x, y, order), hilbert(x, y, order));
                }
            }
        }
        let mut r = 0x2545_f491u32;
        for _ in 0..300_000 {
            r ^= r << 13;
            r ^= r >> 17;
            r ^= r << 5;
            let (x, y) = (r & 0x3fff, (r >> 14) & 0x3fff);
            assert_eq!(
                hilbert_fast(x, y, HILBERT_ORDER),
                hilbert(x, y, HILBERT_ORDER)
            );
        }
    }

    #[test]
    fn parallel_order_equals_the_serial_one() {
        let mut r = 0x2545_f491u32;
        let mut unit = || {
            r ^= r << 13;
            r ^= r >> 17;
            r ^= r << 5;
            f64::from(r) / f64::from(u32::MAX)
        };
        let mut pts: Vec<Point> = (0..40_000).map(|_| [unit(), unit() - 0.5]).collect();
        // Duplicates (also through -0.0) and a coarse lattice share keys but for the index.
        pts.extend_from_within(..500);
        pts.extend((0..2_000).map(|i| [f64::from(i % 7) * -0.0, f64::from(i / 7)]));
        assert_eq!(
            insertion_order_on(&pts, true),
            insertion_order_on(&pts, false)
        );
    }

    /// The radix passes give the order of the 64-bit keys sorted (the sort they replaced):
    /// random points, duplicates (also through -0.0), a lattice (many equal cells), points
    /// in one cell, and the smallest inputs.
    #[test]
    fn radix_order_equals_the_sorted_keys() {
        let mut rng = crate::layouts::SplitMix64(0x9e37_79b9);
        let mut unit = || rng.next_f64();
        let mut pts: Vec<Point> = (0..30_000).map(|_| [unit() * 1e3, unit() - 0.5]).collect();
        pts.extend_from_within(..700);
        pts.extend((0..3_000).map(|i| [f64::from(i % 11) * -0.0, f64::from(i / 11)]));
        pts.extend((0..500).map(|i| [1.0 + f64::from(i) * 1e-12, 2.0]));
        for n in [0, 1, 2, 3, 17, 2_048, 2_049, pts.len()] {
            let p = &pts[..n];
            let want = insertion_order_reference(p);
            assert_eq!(insertion_order_on(p, false), want, "{n} points");
            assert_eq!(insertion_order_on(p, true), want, "{n} points");
        }
        // Above `RADIX_MAX` the parallel build sorts the 64-bit keys, the serial one still
        // takes the passes: the same order.
        let big: Vec<Point> = (0..RADIX_MAX + 1_500)
            .map(|i| pts[i % pts.len()].map(|c| c + (i / pts.len()) as f64))
            .collect();
        let want = insertion_order_reference(&big);
        assert_eq!(insertion_order_on(&big, true), want);
        assert_eq!(insertion_order_on(&big, false), want);
        // Every key equal: every pass is skipped, the order is the index order.
        let same = vec![[5.0, 5.0]; 1_000];
        assert_eq!(
            insertion_order_on(&same, false),
            insertion_order_reference(&same)
        );
    }

    /// `stable_order` against a stable comparison sort, on keys drawn to fill few and many
    /// buckets of each digit.
    #[test]
    fn stable_order_is_a_stable_sort() {
        let mut rng = crate::layouts::SplitMix64(0x2545_f491);
        let mut next = || rng.next_u64() as u32;
        for mask in [
            0u32,
            0x7,
            0x7ff,
            0x3f_f800,
            0xffc0_0000,
            0x8000_0001,
            u32::MAX,
        ] {
            let keys: Vec<u32> = (0..5_000).map(|_| next() & mask).collect();
            let mut want: Vec<u32> = (0..keys.len() as u32).collect();
            want.sort_by_key(|&i| keys[i as usize]);
            assert_eq!(stable_order(&keys), want, "mask {mask:#x}");
        }
    }

    #[test]
    fn order_is_a_permutation() {
        let pts: Vec<Point> = (0..1000)
            .map(|i| [(i % 37) as f64, (i / 37) as f64])
            .collect();
        let mut o = insertion_order(&pts);
        o.sort_unstable();
        assert!(o.iter().enumerate().all(|(i, &v)| v as usize == i));
    }
}
