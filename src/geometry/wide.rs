//! A fast exact in-circle evaluation for the common near-degenerate case, in fixed-width
//! integer arithmetic (no allocation, no expansions).
//!
//! When the six coordinate differences `a - d, b - d, c - d` are exact in `f64` and, written as
//! integers at their smallest common power of two, fit in 62 bits, the determinant is computed
//! exactly: 2x2 minors and lifts in `i128` (< 2^125), the three lift x minor products in 256-bit
//! two's complement (< 2^252). Otherwise the caller falls back to the adaptive predicate.

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

/// Exact in-circle sign (as [`super::predicates::incircle`]) or `None` when the differences are
/// not exact or span more than 62 bits. Coordinates must be finite.
pub(crate) fn incircle_small(a: Point, b: Point, c: Point, d: Point) -> Option<Ordering> {
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
    let [adx, ady, bdx, bdy, cdx, cdy] = parts.map(|(m, e)| {
        if m == 0 {
            0i128
        } else {
            i128::from(m << (e - emin))
        }
    });
    let alift = adx * adx + ady * ady;
    let blift = bdx * bdx + bdy * bdy;
    let clift = cdx * cdx + cdy * cdy;
    let bc = bdx * cdy - cdx * bdy;
    let ca = cdx * ady - adx * cdy;
    let ab = adx * bdy - bdx * ady;
    let det = I256::ZERO
        .add(I256::mul(alift, bc))
        .add(I256::mul(blift, ca))
        .add(I256::mul(clift, ab));
    Some(det.sign())
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

    #[test]
    fn exact_diff_detects_rounding() {
        assert_eq!(exact_diff(1.5, 0.25), Some(1.25));
        assert_eq!(exact_diff(1.0, 1e-30), None);
    }
}
