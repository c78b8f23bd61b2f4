//! A fast exact in-circle evaluation for the common near-degenerate case, in fixed-width
//! integer arithmetic (no allocation, no expansions).
//!
//! When the six coordinate differences `a - d, b - d, c - d`, written as integers at a common
//! power of two, fit in 62 bits (see [`incircle_small`] for the two ways of getting them), the
//! determinant is computed exactly: 2x2 minors and lifts in `i128` (< 2^125), the three lift x
//! minor products in 256-bit two's complement (< 2^252). Otherwise the caller falls back to the
//! adaptive predicate.

use super::exact::decompose;
use super::Point;
use std::cmp::Ordering;

/// `a - b` if it is exact in `f64` (Shewchuk's two-diff tail is zero).
#[inline(always)]
fn exact_diff(a: f64, b: f64) -> Option<f64> {
    let x = a - b;
    let bvirt = a - x;
    let avirt = x + bvirt;
    let bround = bvirt - b;
    let around = a - avirt;
    (around + bround == 0.0).then_some(x)
}

/// A signed 256-bit integer as `(hi, lo)` in two's complement.
#[derive(Clone, Copy, Debug, PartialEq)]
struct I256 {
    hi: u128,
    lo: u128,
}

impl I256 {
    const ZERO: I256 = I256 { hi: 0, lo: 0 };

    /// Exact product of two `i128`.
    fn mul(a: i128, b: i128) -> I256 {
        let negative = (a < 0) != (b < 0);
        let (a, b) = (a.unsigned_abs(), b.unsigned_abs());
        let (a1, a0) = (a >> 64, a & u128::from(u64::MAX));
        let (b1, b0) = (b >> 64, b & u128::from(u64::MAX));
        let p00 = a0 * b0;
        let p01 = a0 * b1;
        let p10 = a1 * b0;
        let p11 = a1 * b1;
        let (mid, c1) = p01.overflowing_add(p10);
        let (lo, c2) = p00.overflowing_add(mid << 64);
        let hi = p11
            .wrapping_add(mid >> 64)
            .wrapping_add(u128::from(c1) << 64)
            .wrapping_add(u128::from(c2));
        let m = I256 { hi, lo };
        if negative {
            m.neg()
        } else {
            m
        }
    }

    fn neg(self) -> I256 {
        let (lo, carry) = (!self.lo).overflowing_add(1);
        I256 {
            hi: (!self.hi).wrapping_add(u128::from(carry)),
            lo,
        }
    }

    fn add(self, o: I256) -> I256 {
        let (lo, carry) = self.lo.overflowing_add(o.lo);
        I256 {
            hi: self.hi.wrapping_add(o.hi).wrapping_add(u128::from(carry)),
            lo,
        }
    }

    fn sign(self) -> Ordering {
        if (self.hi as i128) < 0 {
            Ordering::Less
        } else if self.hi == 0 && self.lo == 0 {
            Ordering::Equal
        } else {
            Ordering::Greater
        }
    }
}

/// Exact in-circle sign (as [`super::predicates::incircle`]) or `None` when neither integer
/// form below applies. Coordinates must be finite.
///
/// Tried in turn: the coordinates themselves as integers at their lowest exponent (needs
/// exponents within 73 of each other, so that they fit `i128`; the differences are then exact
/// integers whatever their `f64` rounding), then the `f64` differences when those are exact.
/// Either way the differences must fit 62 bits for the 256-bit evaluation.
#[inline]
pub(crate) fn incircle_small(a: Point, b: Point, c: Point, d: Point) -> Option<Ordering> {
    incircle_integer_coords(a, b, c, d).or_else(|| incircle_exact_diffs(a, b, c, d))
}

/// `x = m * 2^(e - 1075)` with `m` the full significand (implicit bit included, `0 <= m < 2^53`,
/// not reduced by trailing zeros) and `e` the biased exponent, `1` for subnormals; `m = 0` for
/// zero. Branch-free; `x` must be finite.
#[inline(always)]
fn raw_parts(x: f64) -> (i64, i32) {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let m = (bits & ((1u64 << 52) - 1)) | (u64::from(biased != 0) << 52);
    let m = m as i64;
    (if bits >> 63 == 1 { -m } else { m }, biased.max(1))
}

/// The coordinates as `i128` at the lowest exponent among them; `None` when the exponents span
/// more than 73 (the integers would not fit below 2^126, so that every difference fits `i128`)
/// or a difference needs more than 62 bits.
#[inline]
fn incircle_integer_coords(a: Point, b: Point, c: Point, d: Point) -> Option<Ordering> {
    let parts = [a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]].map(raw_parts);
    let mut emin = i32::MAX;
    let mut emax = i32::MIN;
    for &(m, e) in &parts {
        // Zero coordinates fit any exponent.
        emin = emin.min(if m == 0 { i32::MAX } else { e });
        emax = emax.max(if m == 0 { i32::MIN } else { e });
    }
    if emin == i32::MAX {
        return Some(Ordering::Equal); // every coordinate is zero: the four points coincide
    }
    if emax - emin > 73 {
        return None;
    }
    // m < 2^53 shifted by at most 73: every value below 2^126.
    let v = parts.map(|(m, e)| i128::from(m) << (e.max(emin) - emin));
    let diffs = [
        v[0] - v[6],
        v[1] - v[7],
        v[2] - v[6],
        v[3] - v[7],
        v[4] - v[6],
        v[5] - v[7],
    ];
    let span = diffs.iter().fold(0u128, |acc, x| acc | x.unsigned_abs());
    if span >> 62 != 0 {
        return None;
    }
    Some(det_sign(diffs.map(|x| x as i64)))
}

/// The `f64` differences `a - d, b - d, c - d` as integers at their common lowest power of two,
/// when all six are exact and span at most 62 bits.
fn incircle_exact_diffs(a: Point, b: Point, c: Point, d: Point) -> Option<Ordering> {
    let diffs = [
        exact_diff(a[0], d[0])?,
        exact_diff(a[1], d[1])?,
        exact_diff(b[0], d[0])?,
        exact_diff(b[1], d[1])?,
        exact_diff(c[0], d[0])?,
        exact_diff(c[1], d[1])?,
    ];
    let parts = diffs.map(decompose);
    let mut emin = i32::MAX;
    let mut top = i32::MIN;
    for &(m, e) in &parts {
        if m != 0 {
            emin = emin.min(e);
            top = top.max(e + 64 - m.unsigned_abs().leading_zeros() as i32);
        }
    }
    if emin == i32::MAX {
        return Some(Ordering::Equal); // all four points coincide
    }
    if top - emin > 62 {
        return None;
    }
    Some(det_sign(parts.map(|(m, e)| {
        if m == 0 {
            0
        } else {
            m << (e - emin)
        }
    })))
}

/// Sign of the in-circle determinant from the integer differences
/// `[adx, ady, bdx, bdy, cdx, cdy]`, each of magnitude below 2^62: 2x2 minors and lifts in
/// `i128` (< 2^125), the three lift x minor products in 256-bit two's complement (< 2^252).
#[inline]
fn det_sign(d: [i64; 6]) -> Ordering {
    let [adx, ady, bdx, bdy, cdx, cdy] = d.map(i128::from);
    let alift = adx * adx + ady * ady;
    let blift = bdx * bdx + bdy * bdy;
    let clift = cdx * cdx + cdy * cdy;
    let bc = bdx * cdy - cdx * bdy;
    let ca = cdx * ady - adx * cdy;
    let ab = adx * bdy - bdx * ady;
    I256::ZERO
        .add(I256::mul(alift, bc))
        .add(I256::mul(blift, ca))
        .add(I256::mul(clift, ab))
        .sign()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rug::Integer;

    fn to_rug(x: I256) -> Integer {
        let v = (Integer::from(x.hi) << 128) + Integer::from(x.lo);
        if (x.hi as i128) < 0 {
            v - (Integer::from(1) << 256)
        } else {
            v
        }
    }

    #[test]
    fn wide_multiply_matches_rug() {
        let vals: [i128; 9] = [
            0,
            1,
            -1,
            (1 << 124) - 1,
            -(1 << 124) + 3,
            0x1234_5678_9abc_def0_1234_5678,
            -0x0fed_cba9_8765_4321_0fed_cba9,
            i128::from(u64::MAX),
            -(i128::from(u64::MAX) << 60),
        ];
        for &a in &vals {
            for &b in &vals {
                let p = I256::mul(a, b);
                assert_eq!(to_rug(p), Integer::from(a) * Integer::from(b), "{a} * {b}");
                let s = p.add(I256::mul(b, -a));
                assert_eq!(s.sign(), Ordering::Equal);
            }
        }
    }

    /// Four points near one circle: three on it and a fourth at a tiny radial offset, with
    /// centre and radius spanning magnitudes, so that the `f64` differences are often inexact.
    fn near_cocircular(seed: u64, count: usize) -> Vec<[Point; 4]> {
        let mut x = seed | 1;
        let mut unit = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..count)
            .map(|i| {
                let scale = 2f64.powi((i % 40) as i32 - 20);
                let (cx, cy) = (scale * (unit() - 0.5) * 64.0, scale * (unit() - 0.5) * 64.0);
                let r = scale * (0.01 + unit());
                let mut on = |off: f64| {
                    let a = unit() * std::f64::consts::TAU;
                    let rr = r * (1.0 + off);
                    [cx + rr * a.cos(), cy + rr * a.sin()]
                };
                let off = [0.0, 1e-17, -1e-16, 1e-15, 3e-13][i % 5];
                [on(0.0), on(0.0), on(0.0), on(off)]
            })
            .collect()
    }

    #[test]
    fn both_integer_forms_match_rug() {
        let mut coords_hits = 0;
        let mut diffs_hits = 0;
        for [a, b, c, d] in near_cocircular(0x5eed, 4000) {
            let want = super::super::exact::incircle_exact(a, b, c, d);
            if let Some(s) = incircle_integer_coords(a, b, c, d) {
                assert_eq!(s, want, "{a:?} {b:?} {c:?} {d:?}");
                coords_hits += 1;
            }
            if let Some(s) = incircle_exact_diffs(a, b, c, d) {
                assert_eq!(s, want, "{a:?} {b:?} {c:?} {d:?}");
                diffs_hits += 1;
            }
            if let Some(s) = incircle_small(a, b, c, d) {
                assert_eq!(s, want);
            }
        }
        // The coordinate form decides most of these, the difference form far fewer.
        assert!(coords_hits > 3000, "{coords_hits}");
        assert!(diffs_hits < coords_hits, "{diffs_hits} {coords_hits}");
    }

    #[test]
    fn inexact_differences_are_decided() {
        // Pipeline sample points on which the difference form failed (inexact `f64`
        // differences) and the adaptive predicate had to run.
        let (a, b, c, d) = (
            [-14.3718714641731, -0.28327305577793394],
            [-14.46624380935457, -0.2739781910629044],
            [-14.734993510832537, -0.35550252172670876],
            [-14.651361823416803, -1.204629293861882],
        );
        assert_eq!(incircle_exact_diffs(a, b, c, d), None);
        let want = super::super::exact::incircle_exact(a, b, c, d);
        assert_eq!(incircle_integer_coords(a, b, c, d), Some(want));
        // Exponents spanning more than 73 fall through to the difference form.
        let tiny = [1.0, 1e-300];
        assert_eq!(incircle_integer_coords(tiny, b, c, d), None);
        let same = [0.0, 0.0];
        assert_eq!(
            incircle_integer_coords(same, same, same, same),
            Some(Ordering::Equal)
        );
    }

    #[test]
    fn exact_diff_detects_rounding() {
        assert_eq!(exact_diff(1.5, 0.25), Some(1.25));
        assert_eq!(exact_diff(1.0, 1e-30), None);
    }
}
