//! The per-cell kernel of [`super`]: the pieces of the reference formulas
//! ([`super::cell_corners`], [`super::cell_metrics`]) that the per-block pass
//! ([`super::rows`]) shares with them, so that both give the same bits, and exact histogram
//! bins without a search (arithmetic or one comparison per edge, vectorised).

use super::{cell_metrics, fold};
use crate::geometry::Point;
use crate::lanes::Lanes;

/// Squared edge lengths inside this range take `sqrt(x² + y²)` (no underflow or overflow in
/// the squares or in the products of two lengths); outside it, and for NaN, `hypot`.
pub(super) const SQ_MIN: f64 = crate::geometry::LENGTH_SQ_MIN;
pub(super) const SQ_MAX: f64 = crate::geometry::LENGTH_SQ_MAX;

/// Cross and dot products at the four corners, with the reference expressions.
#[inline]
pub(super) fn corner_products(p: &[Point; 4]) -> ([f64; 4], [f64; 4]) {
    let mut cross = [0.0; 4];
    let mut dot = [0.0; 4];
    for k in 0..4 {
        let o = p[k];
        let a = p[(k + 1) % 4];
        let b = p[(k + 3) % 4];
        let e1 = [a[0] - o[0], a[1] - o[1]];
        let e2 = [b[0] - o[0], b[1] - o[1]];
        cross[k] = e1[0] * e2[1] - e1[1] * e2[0];
        dot[k] = e1[0] * e2[0] + e1[1] * e2[1];
    }
    (cross, dot)
}

/// Corner angles closer than this (degrees) to 0, 180 or 360 are not taken from the edge
/// directions ([`corner_candidates`], whose error is below `4e-13` degrees) but from the
/// corner's cross and dot products ([`settled`]).
pub(super) const DIRECTION_MARGIN_DEG: f64 = 1e-9;

/// The four corner angles of a cell from the directions (degrees, [`super::angle_deg`] of each
/// edge vector) of its edges `p0 -> p1` (`b`), `p1 -> p2` (`q`), `p3 -> p2` (`t`) and
/// `p0 -> p3` (`a`): corner `k` turns counter-clockwise from `p[k+1] - p[k]` to
/// `p[k-1] - p[k]`, so its angle is the difference of those two directions (an edge taken
/// the other way adds 180), brought into `[0, 360)` by [`wrap`]. Each difference is of two
/// directions in `[0, 360]`, so the result is within a few units in the last place of 360
/// (below `4e-13` degrees) of the exact angle between the two edge vectors.
#[inline(always)]
pub(super) fn corner_candidates(b: f64, q: f64, t: f64, a: f64) -> [f64; 4] {
    [
        wrap(a - b),
        wrap((b - q) + 180.0),
        wrap(q - t),
        wrap((t - a) - 180.0),
    ]
}

/// `x` brought into `[0, 360)` by adding or subtracting 360, for `x` in `(-720, 720)` (NaN
/// stays NaN).
#[inline(always)]
pub(super) fn wrap(x: f64) -> f64 {
    let x = if x < 0.0 { x + 360.0 } else { x };
    let x = if x < 0.0 { x + 360.0 } else { x };
    if x >= 360.0 {
        x - 360.0
    } else {
        x
    }
}

/// Whether the direction-difference angle `a` of a corner with cross product `cross` is the
/// corner's angle: on the side of 180 that the cross product's sign gives and more than
/// [`DIRECTION_MARGIN_DEG`] away from 0, 180 and 360. Otherwise (a corner within a
/// billionth of a degree of flat, a zero or non-finite product, a NaN direction) the angle
/// is `angle_deg(cross, dot)`. Since the difference is within `4e-13` degrees of the true
/// angle, a settled angle is below 180 exactly where the Jacobian is positive.
#[inline(always)]
pub(super) fn settled(a: f64, cross: f64) -> bool {
    const M: f64 = DIRECTION_MARGIN_DEG;
    ((cross > 0.0) & (M..=180.0 - M).contains(&a))
        | ((cross < 0.0) & (180.0 + M..=360.0 - M).contains(&a))
}

/// Scaled Jacobian, edge ratio and aspect ratio from the corner cross products and the edge
/// lengths (`edges[k]` from `p[k]` to `p[k + 1]`), the expressions of [`cell_metrics`].
#[inline(always)]
pub(super) fn length_figures(cross: &[f64; 4], edges: &[f64; 4]) -> (f64, f64, f64) {
    let mut scaled_jacobian = f64::INFINITY;
    for k in 0..4 {
        // Corner k is between edge k (to p[k+1]) and edge k-1 (to p[k-1]).
        let (la, lb) = (edges[k], edges[(k + 3) % 4]);
        let s = if la > 0.0 && lb > 0.0 {
            cross[k] / (la * lb)
        } else {
            0.0
        };
        if s.is_nan() || s < scaled_jacobian {
            scaled_jacobian = s;
        }
    }
    let (lo, hi) = (fold(*edges, f64::min), fold(*edges, f64::max));
    let li = 0.5 * (edges[0] + edges[2]);
    let lj = 0.5 * (edges[1] + edges[3]);
    (
        scaled_jacobian,
        super::ratio(hi, lo),
        super::ratio(li.max(lj), li.min(lj)),
    )
}

/// The smallest scaled Jacobian of a cell with positive edge lengths `edges` (in range: the
/// products of two are finite and positive) and non-zero finite cross products `cross`, with
/// one division: that of [`length_figures`] at the corner it picks, so the same bits when the
/// flag returned with it is true (the pick is certain).
///
/// Why: the reference figure is `min_k fl(c_k / P_k)` with `P_k = fl(la lb)` (see
/// [`length_figures`]). Rounding is monotone, so the exact quotient order gives the order of
/// the rounded quotients (ties may round together, never cross), and `c_a / P_a < c_b / P_b`
/// exactly iff `c_a P_b < c_b P_a` (`P > 0`). The computed products are rounded too, but again
/// monotonically: `fl(c_a P_b) < fl(c_b P_a)` implies `c_a P_b < c_b P_a`. So a strict
/// comparison of the computed products decides the pair; products that compare equal decide
/// nothing, except when `c_a = c_b` and `P_a = P_b` (the same quotient, either pick). The pick
/// of a 2-round tournament is then a corner whose quotient is the least, and its one division
/// is the reference's minimum, bit for bit, unless it is a zero: `-0.0` and `+0.0` compare
/// equal and the reference keeps the first in corner order, so a zero is not certain either.
#[inline(always)]
pub(super) fn least_scaled_jacobian(cross: &[f64; 4], edges: &[f64; 4]) -> (f64, bool) {
    let p = [
        edges[0] * edges[3],
        edges[1] * edges[0],
        edges[2] * edges[1],
        edges[3] * edges[2],
    ];
    // Pick the lesser of corners a and b: (corner's c, corner's P), certain.
    #[inline(always)]
    fn pick(a: (f64, f64), b: (f64, f64)) -> ((f64, f64), bool) {
        let (x, y) = (a.0 * b.1, b.0 * a.1);
        let same = (a.0 == b.0) & (a.1 == b.1);
        let certain = (x != y) | same;
        (if y < x { b } else { a }, certain)
    }
    let (w01, k01) = pick((cross[0], p[0]), (cross[1], p[1]));
    let (w23, k23) = pick((cross[2], p[2]), (cross[3], p[3]));
    let (w, k) = pick(w01, w23);
    let s = w.0 / w.1;
    (s, k01 & k23 & k & (s != 0.0))
}

/// Equiangle skewness `max((θmax - 90) / 90, (90 - θmin) / 90)` with one division: dividing
/// by 90 is monotone and neither difference of finite angles is `-0.0`, so the larger quotient
/// is the quotient of the larger difference. This expression is the reference (for NaN angles
/// too).
#[inline(always)]
pub(super) fn skewness(min_angle_deg: f64, max_angle_deg: f64) -> f64 {
    (max_angle_deg - 90.0).max(90.0 - min_angle_deg) / 90.0
}

/// The angle histogram's bin of an angle `x >= +0` (degrees), as a float: the rule of the
/// tests' oracle `bin` for [`super::ANGLE_EDGES`] (0, 10, ..., 130, 135, 140, ..., 180): the
/// inner edges at or below `x` are the multiples of 10 from 10 up (`floor(x / 10)` of them) and
/// 135 when `x >= 135`, at most 18 in all (the last bin):
/// `min(floor(x / 10) + [x >= 135], 18)`, by arithmetic rather than a search, so that the
/// vectorised row loop computes it; and without a division (the row loop's costliest
/// operation): `floor(x / 10)` is `q = floor(fl(x · 0.1))`, less one when `10 q > x`.
///
/// Why: let `k = floor(x / 10)` (exact quotient), `x` finite, `0 <= x < 2⁵⁰`. The float `0.1`
/// is above `1/10` by a relative `δ = 5.6e-17`, so `x · 0.1 >= x / 10 >= k`, and `k` is a
/// float: rounding keeps `fl(x · 0.1) >= k`. Above, `x · 0.1 < (k + 1)(1 + δ)`, which is
/// below the midpoint between `k + 1` and the next float, so `fl(x · 0.1) <= k + 1`. So
/// `q` is `k` or `k + 1`, and since `10 k <= x < 10 (k + 1)` (both products exact, `q < 2⁵⁰`)
/// the test `10 q > x` tells which. For `x >= 2⁵⁰` either way gives a count above 18, so the
/// last bin; infinity gives 18; NaN (not on the path that counts the bin) gives 18 too.
#[inline(always)]
pub(super) fn angle_bin_unsigned(x: f64) -> f64 {
    let q = (x * 0.1).floor();
    let q = if q * 10.0 > x { q - 1.0 } else { q };
    let b = if x >= 135.0 { q + 1.0 } else { q };
    if b < 18.0 {
        b
    } else {
        18.0
    }
}

/// `weight` times the number of inner edges `edges[1..N - 1]` at or below `x`: for a finite
/// `x`, the rule of the tests' oracle `bin` (the number of `edges[1..]` at or below `x`, at
/// most `N - 2`: the last edge is at or below `x` only when every inner edge is), scaled. With
/// weights `32ᵏ` the bins of several values add up, exactly (integers below `2⁵³`), into one
/// packed word of 5-bit fields, see [`PACK`], no packing.
///
/// One comparison and one select of a constant per edge (no addition): the edges ascend, so
/// the edges at or below `x` are the first ones, and the last edge `x` passes (in edge order)
/// gives the count, `k + 1` for edge `k` (NaN passes none: 0, as counting does).
#[inline(always)]
pub(super) fn weighted_bin<const N: usize>(x: f64, edges: &[f64; N], weight: f64) -> f64 {
    let mut b = 0.0;
    for (k, &e) in edges[1..N - 1].iter().enumerate() {
        b = if x >= e { (k + 1) as f64 * weight } else { b };
    }
    b
}

/// The ratio histogram's bin of `x` ([`super::RATIO_EDGES`]) from a table rather than nine
/// comparisons: every edge has at most four significant bits (1.25 = 1.01b, 50 = 1.1001b · 2⁵,
/// ...), so for `x >= +0` the comparison `x >= e` is that of the top 16 bits of their
/// representations (sign, exponent and four fraction bits; `e`'s lower bits are zero), and
/// every float with the same top 16 bits falls in the same bin: the table has the bin of each
/// such group from `1.0` (below: bin 0) to `1.9375 · 2⁷` (above: the last bin, `x >= 50`).
/// Negative `x` (top bits negative as a signed integer) give bin 0, as the rule does.
pub(super) struct RatioBins {
    /// Bin of the group `k` (top 16 bits of `1.0` plus `k`), times the weight.
    table: [f64; RATIO_GROUPS],
    /// The inner edges' representations as signed integers, ascending, and their weighted
    /// bins (`(k + 1) · weight` from the edge `k + 1` on), for [`RatioBins::bin_by_compares`].
    inner: [(i64, f64); RATIO_INNER],
}

/// Inner edges of [`super::RATIO_EDGES`] (all but the first and the last).
const RATIO_INNER: usize = 9;

/// Groups of 16 top bits covered by [`RatioBins`] (seven binades from 1, 16 groups each, and
/// up to 128 in all).
const RATIO_GROUPS: usize = 128;

/// The top 16 bits of `1.0`.
const ONE_TOP: i64 = (0x3ff0_0000_0000_0000_u64 >> 48) as i64;

impl RatioBins {
    /// The table of weighted bins for `edges` (each edge with its lower 48 bits zero,
    /// ascending, `edges[0] <= 1`), weight `weight`.
    pub fn new<const N: usize>(edges: &[f64; N], weight: f64) -> RatioBins {
        assert!(edges.iter().all(|e| e.to_bits() << 16 == 0) && edges[0] <= 1.0);
        assert!(N == RATIO_INNER + 2 && edges.iter().all(|&e| e > 0.0));
        RatioBins {
            table: std::array::from_fn(|k| {
                let x = f64::from_bits(((ONE_TOP + k as i64) as u64) << 48);
                weighted_bin(x, edges, weight)
            }),
            inner: std::array::from_fn(|k| {
                (edges[k + 1].to_bits() as i64, (k + 1) as f64 * weight)
            }),
        }
    }

    /// [`RatioBins::bin`] (the same bits for every `x`, NaN included) by comparing
    /// representations rather than loading from the table: for the 4-lane (AVX2) row loop,
    /// where the table load is a gather, slower than nine integer comparisons on an AMD EPYC
    /// (Zen 3: the quality pass 16% faster at 1e3 bubbles); the 8-lane build keeps the table.
    ///
    /// Why the same: the edges are positive, so as signed integers their representations
    /// ascend with them; for `x >= +0`, `+inf` and positive NaN, `x`'s representation
    /// compares with theirs as `x` with the edges (NaN above all: the last bin, as the table's
    /// clamp gives), and every negative representation (negative numbers, `-0.0`, negative
    /// NaN) is below all of them: bin 0, as the table's clamp gives.
    #[inline(always)]
    pub fn bin_by_compares(&self, x: f64) -> f64 {
        let xb = x.to_bits() as i64;
        let mut b = 0.0;
        for &(e, w) in &self.inner {
            b = if xb >= e { w } else { b };
        }
        b
    }

    /// `weighted_bin(x, edges, weight)` for `x >= +0` or negative (NaN with the sign clear: the
    /// last bin).
    #[inline(always)]
    pub fn bin(&self, x: f64) -> f64 {
        let k = ((x.to_bits() as i64 >> 48) - ONE_TOP).clamp(0, RATIO_GROUPS as i64 - 1);
        self.table[k as usize & (RATIO_GROUPS - 1)]
    }
}

/// The weights `32ᵏ` of the 5-bit fields of a packed word of bins (field `k` in bits
/// `5k..5k + 5`): the float `ROUND + Σ binₖ 32ᵏ` (every term an integer, the sum below `2⁵³`
/// for 8 fields of bins below 32, so exact in any order) holds the word in the low bits of
/// its representation ([`packed_bins`]).
pub(super) const PACK: [f64; 8] = [
    1.0,
    32.0,
    1024.0,
    32768.0,
    1_048_576.0,
    33_554_432.0,
    1_073_741_824.0,
    34_359_738_368.0,
];

/// The packed word of bins (40 bits) held by `ROUND + Σ binₖ 32ᵏ` (see [`PACK`]).
#[inline(always)]
pub(super) fn packed_bins(sum: f64) -> u64 {
    (sum + ROUND).to_bits() & ((1 << 40) - 1)
}

/// Histogram bin of `x`, the rule of [`super::Histogram::add`] (NaN in the last bin): the
/// oracle of [`angle_bin_unsigned`] and [`weighted_bin`].
#[cfg(test)]
pub(super) fn bin(edges: &[f64], x: f64) -> usize {
    let last = edges.len().saturating_sub(2);
    if x.is_nan() {
        return last;
    }
    edges[1..].partition_point(|&e| e <= x).min(last)
}

/// `2⁵²`: adding it to an integer float in `[0, 2⁵²)` gives a float whose low bits hold that
/// integer.
const ROUND: f64 = 4_503_599_627_370_496.0;

/// The smallest float `x` (in the order of [`f64::total_cmp`], `-inf` to `+inf`, NaN
/// excluded) with `pred(x)`, for a `pred` that is monotone in that order (false up to some
/// point, true from there on; `+inf` if it is never true). A bisection over the ordered bit
/// patterns: exact, whatever the rounding inside `pred`.
pub(super) fn first_where(pred: impl Fn(f64) -> bool) -> f64 {
    // Keys ordered as the floats: negative floats mirrored below zero.
    let key = |x: f64| -> i64 {
        let b = x.to_bits() as i64;
        b ^ (((b >> 63) as u64) >> 1) as i64
    };
    let float = |k: i64| f64::from_bits((k ^ (((k >> 63) as u64) >> 1) as i64) as u64);
    let (mut lo, mut hi) = (key(f64::NEG_INFINITY), key(f64::INFINITY));
    if pred(f64::NEG_INFINITY) {
        return f64::NEG_INFINITY;
    }
    // Invariant: !pred(float(lo)), and pred(float(hi)) or hi is +inf's key.
    while i128::from(hi) - i128::from(lo) > 1 {
        // The midpoint without overflow (the keys span more than `i64`'s half range).
        let mid = ((i128::from(lo) + i128::from(hi)) / 2) as i64;
        if pred(float(mid)) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    float(hi)
}

/// The number of ascending thresholds `t[0] < t[1] < ... < t[n - 1]` that `x` reaches
/// (`x >= t[k]`; NaN reaches none), for thresholds close to
/// the multiples of a step, by one product instead of one comparison per threshold (issue 8:
/// the skewness's and the scaled Jacobian's bins took twenty of the cell loop's operations
/// each): `clamp(floor(x · scale) + offset, 0, n)`, plus `delta` (±1) at the single float
/// `fix` where the rounded product falls on the wrong side of a threshold.
///
/// Why it is the count: `f(x) = clamp(floor(fl(x · scale)) + offset, 0, n)` is monotone in
/// `x` (each step is a rounded monotone operation, overflow to infinity included) and so is
/// the count `c(x)`, which is `k` from `t[k - 1]` to `pred(t[k])` (`pred`: the float below).
/// The tests' constructor `StepBins::new` checks `f(t[k - 1]) >= k` and
/// `f(pred(t[k - 1])) <= k - 1` for every `k`; then from `t[k - 1]` to `pred(t[k])`,
/// `k <= f(t[k - 1]) <= f(x) <= f(pred(t[k])) <= k`, and below `t[0]` (where `f >= 0`) and
/// from `t[n - 1]` on (where `f <= n`) the clamp gives 0 and `n`. Where one of those checks
/// fails by one at a single float (the check then holds at its neighbour: `f(succ(t)) >= k`,
/// or `f(pred(pred(t))) <= k - 1`), that float is `fix` and the same argument holds for `f`
/// corrected there. NaN: `floor` gives NaN, the clamp 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StepBins {
    scale: f64,
    offset: f64,
    n: f64,
    /// The float where `f` is off by `delta`'s opposite (NaN when there is none: no `x`
    /// equals it).
    fix: f64,
    delta: f64,
}

impl StepBins {
    /// The skewness's bin from its dividend `D` (see [`SkewThresholds`]): the number of its
    /// thresholds `D` reaches (the multiples of 9 from 9 to 90, but 63 less one unit in the
    /// last place), as `StepBins::new` finds it (a unit test). A constant, so that the cell
    /// loop holds no register for it.
    pub const SKEW: StepBins = StepBins {
        scale: 1.0 / 9.0,
        offset: 0.0,
        n: 10.0,
        fix: 62.999_999_999_999_99,
        delta: 1.0,
    };

    /// The scaled Jacobian's bin: the number of inner edges of [`super::JACOBIAN_EDGES`] (0,
    /// 0.1, ..., 0.9) at or below it, `floor(10 x) + 1` but at the float below 0.9, as
    /// `StepBins::new` finds it (a unit test).
    pub const JACOBIAN: StepBins = StepBins {
        scale: 10.0,
        offset: 1.0,
        n: 10.0,
        fix: 0.899_999_999_999_999_9,
        delta: -1.0,
    };

    /// The counting rule for `thresholds` (ascending) with `scale` and `offset`, checked at
    /// every threshold (see the type's doc), or `None` when the rule does not give the count
    /// (a threshold where it fails by more than one float, or more than one such float).
    #[cfg(test)]
    pub fn new(thresholds: &[f64], scale: f64, offset: f64) -> Option<StepBins> {
        let n = thresholds.len() as f64;
        let ordered = thresholds.windows(2).all(|w| w[0] < w[1]);
        if !ordered || thresholds.iter().any(|t| t.is_nan()) || !scale.is_finite() {
            return None;
        }
        let mut rule = StepBins {
            scale,
            offset,
            n,
            fix: f64::NAN,
            delta: 0.0,
        };
        let mut fixes = Vec::new();
        for (k, &t) in thresholds.iter().enumerate() {
            let k = (k + 1) as f64;
            let f = |x: f64| rule.count(x);
            if f(t) < k {
                if f(t) != k - 1.0 || f(t.next_up()) < k {
                    return None;
                }
                fixes.push((t, 1.0));
            }
            let p = t.next_down();
            if f(p) > k - 1.0 {
                if f(p) != k || f(p.next_down()) > k - 1.0 {
                    return None;
                }
                fixes.push((p, -1.0));
            }
        }
        match fixes[..] {
            [] => {}
            [(fix, delta)] => {
                rule.fix = fix;
                rule.delta = delta;
            }
            _ => return None,
        }
        // The fix's own interval holds its float and its neighbour (checked above), so the
        // corrected rule is the count; confirm it at every threshold and its neighbours.
        let exact = thresholds.iter().enumerate().all(|(k, &t)| {
            let k = (k + 1) as f64;
            rule.count(t) == k && rule.count(t.next_down()) == k - 1.0
        });
        exact.then_some(rule)
    }

    /// The number of thresholds `x` reaches, as a float (see the type's doc).
    #[inline(always)]
    pub fn count(&self, x: f64) -> f64 {
        let q = (x * self.scale).floor() + self.offset;
        let q = if q > 0.0 { q } else { 0.0 };
        let q = if q < self.n { q } else { self.n };
        if x == self.fix {
            q + self.delta
        } else {
            q
        }
    }
}

/// The skewness figures as thresholds on `D = max(θmax - 90, 90 - θmin)`, the dividend of
/// [`skewness`]: `D / 90` is a correctly rounded division by a positive constant, so it is
/// monotone in `D`, and `D / 90 >= e` holds exactly from the first `D` where it holds
/// ([`first_where`] of the very expression). Comparing `D` with these thresholds gives the
/// acceptance of the skewness without dividing (its bins: [`StepBins::SKEW`], a rule on the
/// same kind of thresholds), and the extremes of the skewness are the quotients of the
/// extremes of `D` (monotone: `min(D) / 90 = min(D / 90)`).
pub(super) struct SkewThresholds {
    /// The least `D` with `D / 90 >= 0` (the acceptable range's low end).
    pub lo: f64,
    /// The least `D` with `D / 90 > 0.5` (above the acceptable range's high end).
    pub above: f64,
}

impl SkewThresholds {
    pub fn new() -> SkewThresholds {
        let at_least = |e: f64| first_where(|d| d / 90.0 >= e);
        let [lo, hi] = super::SKEWNESS_ACCEPTABLE;
        SkewThresholds {
            lo: at_least(lo),
            above: first_where(|d| d / 90.0 > hi),
        }
    }
}

/// Per inner edge `e` of [`super::SKEWNESS_EDGES`] (0.1 to 1.0): the least `D` with `D / 90 >=
/// e` (the skewness's bins as thresholds on its dividend, see [`SkewThresholds`]).
#[cfg(test)]
pub(super) fn skew_bin_thresholds() -> [f64; 10] {
    std::array::from_fn(|k| first_where(|d| d / 90.0 >= super::SKEWNESS_EDGES[k + 1]))
}

/// The thresholds of [`StepBins::JACOBIAN`]: the inner edges of [`super::JACOBIAN_EDGES`]
/// as the least `x` with `x >= e` (`-0.0` for the edge 0).
#[cfg(test)]
pub(super) fn jacobian_bin_thresholds() -> Vec<f64> {
    let edges = &super::JACOBIAN_EDGES;
    edges[1..edges.len() - 1]
        .iter()
        .map(|&e| first_where(|x| x >= e))
        .collect()
}

/// The vector builds the CPU can run, detected once per measurement.
pub(super) struct Tables {
    /// The CPU has AVX2: the row loop runs in 4-lane vectors (same bits, see
    /// [`super::rows`]).
    pub wide: bool,
    /// The CPU has AVX-512 (F, DQ, VL): the row loop runs in 8-lane vectors (same bits).
    pub wider: bool,
    /// The skewness thresholds.
    pub skew: SkewThresholds,
    /// The edge ratio's and the aspect ratio's bins, weighted for their fields.
    pub ratios: [RatioBins; 2],
}

impl Tables {
    pub fn new() -> Tables {
        Tables {
            wide: wide(),
            wider: wider(),
            skew: SkewThresholds::new(),
            ratios: [
                RatioBins::new(&super::RATIO_EDGES, PACK[6]),
                RatioBins::new(&super::RATIO_EDGES, PACK[7]),
            ],
        }
    }
}

/// True when the CPU has AVX-512 F, DQ and VL (x86-64 only).
pub(super) fn wider() -> bool {
    Lanes::Avx512.available()
}

/// True when the CPU has AVX2 (x86-64 only).
pub(super) fn wide() -> bool {
    Lanes::Avx2.available()
}

/// Per-block partial results of [`super::measure`] (small; the metrics of
/// [`super::quality_metrics`] are accumulated per chunk of blocks, see [`super::rows::Chunk`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct BlockFigures {
    /// The grid's node count does not match `ni`, `nj` (no cell measured).
    pub malformed: bool,
    pub cells: usize,
    pub sum_min: f64,
    pub sum_max: f64,
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    pub inverted: usize,
    /// NaN-sticky minimum of the cells' scaled Jacobians.
    pub min_scaled_jacobian: f64,
}

/// Per-cell figures of [`super::CellFields`] for one cell: (min angle, max angle, min
/// Jacobian, skewness, edge ratio, scaled Jacobian, aspect ratio), those of the reference.
#[inline]
pub(super) fn cell_field_values(p: &[Point; 4]) -> [f64; 7] {
    let m = cell_metrics(*p);
    let (jacobian, _) = corner_products(p);
    // NaN-propagating minimum: a NaN Jacobian must not look valid.
    let mut mj = jacobian[0];
    for &x in &jacobian[1..] {
        if x.is_nan() || x < mj {
            mj = x;
        }
    }
    [
        m.min_angle_deg,
        m.max_angle_deg,
        mj,
        m.equiangle_skewness,
        m.edge_ratio,
        m.scaled_jacobian,
        m.aspect_ratio,
    ]
}

/// The four edges of cell `i` between node lines `lo` and `hi`: `p0 -> p1`, `p3 -> p2`,
/// `p0 -> p3`, `p1 -> p2` (each edge one difference of its two nodes).
#[inline(always)]
pub(super) fn row_edges(lo: &[Point], hi: &[Point], i: usize) -> [[f64; 2]; 4] {
    [
        [lo[i + 1][0] - lo[i][0], lo[i + 1][1] - lo[i][1]],
        [hi[i + 1][0] - hi[i][0], hi[i + 1][1] - hi[i][1]],
        [hi[i][0] - lo[i][0], hi[i][1] - lo[i][1]],
        [hi[i + 1][0] - lo[i + 1][0], hi[i + 1][1] - lo[i + 1][1]],
    ]
}

/// Corner cross and dot products of a cell from its edges `[h, u, v, w]` (`p0 -> p1`,
/// `p3 -> p2`, `p0 -> p3`, `p1 -> p2`): corner `k` takes `e1 = p[k+1] - p[k]`,
/// `e2 = p[k-1] - p[k]` (see [`corner_products`]), an edge running the other way negated.
/// Shared by the row passes so they all form the same products.
#[inline(always)]
pub(super) fn cell_products(e: [[f64; 2]; 4]) -> ([f64; 4], [f64; 4]) {
    let [[hx, hy], [ux, uy], [vx, vy], [wx, wy]] = e;
    let c = [
        hx * vy - hy * vx,
        wx * (-hy) - wy * (-hx),
        (-ux) * (-wy) - (-uy) * (-wx),
        (-vx) * uy - (-vy) * ux,
    ];
    let d = [
        hx * vx + hy * vy,
        wx * (-hx) + wy * (-hy),
        (-ux) * (-wx) + (-uy) * (-wy),
        (-vx) * ux + (-vy) * uy,
    ];
    (c, d)
}

/// The cells between node lines `lo` and `hi` (same length) with some corner Jacobian
/// `<= 0` or not a number: the cross products of [`corner_products`], each edge taken as a
/// difference of its two nodes in one direction and negated for the other corner. Negation
/// changes at most the sign of a zero product, and `!(cross > 0)` holds for both zeros (and
/// NaN), so the count is that of the reference test.
pub(super) fn row_inverted(lo: &[Point], hi: &[Point]) -> usize {
    #[cfg(target_arch = "x86_64")]
    if wider() {
        // SAFETY: the CPU has the AVX-512 features (checked just above).
        return unsafe { row_inverted_avx512(lo, hi) };
    }
    #[cfg(target_arch = "x86_64")]
    if wide() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { row_inverted_avx2(lo, hi) };
    }
    row_inverted_portable(lo, hi)
}

/// [`row_inverted`] compiled for AVX-512 (the same comparisons of the same products).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
fn row_inverted_avx512(lo: &[Point], hi: &[Point]) -> usize {
    row_inverted_portable(lo, hi)
}

/// [`row_inverted`] compiled for AVX2 (the same comparisons of the same products).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn row_inverted_avx2(lo: &[Point], hi: &[Point]) -> usize {
    row_inverted_portable(lo, hi)
}

/// The body of [`row_inverted`], inlined into each caller's build (the row passes here and
/// `exact_mode::inverted`, which runs it inside its own vector builds).
#[inline(always)]
pub(crate) fn row_inverted_portable(lo: &[Point], hi: &[Point]) -> usize {
    let n = lo.len().min(hi.len()).saturating_sub(1);
    let (lo, hi) = (&lo[..=n], &hi[..=n]);
    let mut count = 0;
    for i in 0..n {
        // p0 -> p1, p3 -> p2, p0 -> p3, p1 -> p2.
        let (c, _) = cell_products(row_edges(lo, hi, i));
        let good = (c[0] > 0.0) & (c[1] > 0.0) & (c[2] > 0.0) & (c[3] > 0.0);
        count += usize::from(!good);
    }
    count
}

/// True when some cell between node lines `lo` and `hi` (same length) has a corner with
/// `cross <= 0` or NaN (inverted, degenerate or not a number) or `dot > 0` and `cross < t dot` (an
/// angle below `atan(t)`): the test of [`super::has_corner_below`] with the products of
/// [`row_inverted`] (shared edges: a product may differ from the reference's only in the sign
/// of a zero, which neither comparison sees).
pub(super) fn row_corner_below(lo: &[Point], hi: &[Point], t: f64) -> bool {
    #[cfg(target_arch = "x86_64")]
    if wider() {
        // SAFETY: the CPU has the AVX-512 features (checked just above).
        return unsafe { row_corner_below_avx512(lo, hi, t) };
    }
    #[cfg(target_arch = "x86_64")]
    if wide() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { row_corner_below_avx2(lo, hi, t) };
    }
    row_corner_below_portable(lo, hi, t)
}

/// [`row_corner_below`] compiled for AVX-512 (the same comparisons of the same products).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
fn row_corner_below_avx512(lo: &[Point], hi: &[Point], t: f64) -> bool {
    row_corner_below_portable(lo, hi, t)
}

/// [`row_corner_below`] compiled for AVX2 (the same comparisons of the same products).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn row_corner_below_avx2(lo: &[Point], hi: &[Point], t: f64) -> bool {
    row_corner_below_portable(lo, hi, t)
}

#[inline(always)]
fn row_corner_below_portable(lo: &[Point], hi: &[Point], t: f64) -> bool {
    let n = lo.len().min(hi.len()).saturating_sub(1);
    let (lo, hi) = (&lo[..=n], &hi[..=n]);
    let mut bad = false;
    for i in 0..n {
        let (c, d) = cell_products(row_edges(lo, hi, i));
        for k in 0..4 {
            bad |= c[k].is_nan() | (c[k] <= 0.0) | ((d[k] > 0.0) & (c[k] < t * d[k]));
        }
    }
    bad
}

#[cfg(test)]
mod tests;
