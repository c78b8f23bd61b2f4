//! Certified double-double "ball" arithmetic for the fast Apollonius path ([`super::fast`]).
//!
//! A [`Ball`] is a midpoint `m = hi + lo` (a double-double, about 106 bits) and a radius
//! `r >= 0` (an `f64`) such that the exact real value `v` of the expression it stands for
//! satisfies `|v - m| <= r`. Invariant kept by every operation:
//!
//! - **add/sub**: `m = AccurateDWPlusDW(mx, ±my)` (Joldes, Muller, Popescu 2017, Algorithm 6),
//!   whose relative error is at most `3u^2 / (1 - 4u)`, `u = 2^-53`; **mul**:
//!   `m = DWTimesDW1` (ibid. Algorithm 10, error at most `7u^2`), and
//!   `r = |mx| ry + |my| rx + rx ry` for the inputs' uncertainty. Both algorithms' errors are
//!   bounded here by `2^-100 |m|` (64 `u^2`, a margin of 9x or more).
//! - **div** and **sqrt** are *self-validating*: the midpoint is any approximation `q`, and
//!   the radius bounds `|x / y - q| = |x - q y| / |y|` (resp. `|sqrt(x) - s| <= |x - s^2| / s`)
//!   with the residual itself evaluated in balls, so no property of the approximation is used.
//! - Every radius is computed in round-to-nearest from non-negative terms (at most six, so a
//!   relative error below `6u < 2^-50`), then multiplied by `1 + 2^-48` and increased by
//!   `2^-1000`, which makes it an upper bound; the absolute term also covers the error of an
//!   underflowing product or sum (at most `2^-1074` per rounding).
//! - `|m| <= |hi| (1 + 2^-53)`: [`mag`] bounds it by `|hi| (1 + 2^-50)`.
//! - Two-products are Dekker's (Veltkamp splitting), exact without overflow or underflow. An
//!   overflow produces an infinite or `NaN` midpoint or radius; every decision ([`Ball::sign`],
//!   [`Ball::round`]) is written so that `NaN` and infinities decide nothing.
//!
//! Callers keep the inputs in a moderate range (the fast path checks `2^-200 <= |v| <= 2^200`
//! for every non-zero input) so that intermediate values stay far from overflow.

use super::exact::Sign;

/// Relative error bound of one double-double addition or multiplication (see module docs).
const REL: f64 = 7.888609052210118e-31; // 2^-100
/// Factor making a round-to-nearest radius computation an upper bound.
const UP: f64 = 1.0 + 3.552713678800501e-15; // 1 + 2^-48
/// Absolute slack per operation (underflow).
const TINY: f64 = 9.332636185032189e-302; // 2^-1000

/// `|hi + lo| <= mag`: an upper bound of the magnitude of a double-double.
fn mag(hi: f64) -> f64 {
    hi.abs() * (1.0 + 8.881784197001252e-16) // 1 + 2^-50
}

/// `x > 0`, false for `NaN` (an undecided bound).
fn positive(x: f64) -> bool {
    x > 0.0
}

/// `(s, e)` with `s = fl(a + b)` and `s + e = a + b` exactly.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// [`two_sum`] for `|a| >= |b|` (or `a = 0`).
fn fast_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

/// Veltkamp split: `a = h + l` with `h`, `l` of at most 26 significant bits.
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let h = c - (c - a);
    (h, a - h)
}

/// `(p, e)` with `p = fl(a b)` and `p + e = a b` exactly (Dekker), barring over/underflow.
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    (p, e)
}

/// A certified enclosure `|v - (hi + lo)| <= r` (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Ball {
    pub hi: f64,
    pub lo: f64,
    pub r: f64,
}

impl Ball {
    /// The exact value `x`.
    pub fn exact(x: f64) -> Ball {
        Ball {
            hi: x,
            lo: 0.0,
            r: 0.0,
        }
    }

    /// The exact difference `a - b` (a double-double holds it exactly, barring overflow).
    pub fn diff(a: f64, b: f64) -> Ball {
        let (hi, lo) = two_sum(a, -b);
        Ball { hi, lo, r: 0.0 }
    }

    fn radius(r: f64) -> f64 {
        r * UP + TINY
    }

    pub fn neg(self) -> Ball {
        Ball {
            hi: -self.hi,
            lo: -self.lo,
            r: self.r,
        }
    }

    pub fn add(self, o: Ball) -> Ball {
        let (sh, sl) = two_sum(self.hi, o.hi);
        let (th, tl) = two_sum(self.lo, o.lo);
        let c = sl + th;
        let (vh, vl) = fast_two_sum(sh, c);
        let w = tl + vl;
        let (hi, lo) = fast_two_sum(vh, w);
        Ball {
            hi,
            lo,
            r: Ball::radius(self.r + o.r + mag(hi) * REL),
        }
    }

    pub fn sub(self, o: Ball) -> Ball {
        self.add(o.neg())
    }

    pub fn mul(self, o: Ball) -> Ball {
        let (ch, cl1) = two_prod(self.hi, o.hi);
        let tl1 = self.hi * o.lo;
        let tl2 = self.lo * o.hi;
        let cl2 = tl1 + tl2;
        let cl3 = cl1 + cl2;
        let (hi, lo) = fast_two_sum(ch, cl3);
        let r = mag(self.hi) * o.r + mag(o.hi) * self.r + self.r * o.r + mag(hi) * REL;
        Ball {
            hi,
            lo,
            r: Ball::radius(r),
        }
    }

    pub fn square(self) -> Ball {
        self.mul(self)
    }

    /// Midpoint and radius finite (an overflow leaves an infinity or `NaN` somewhere).
    fn finite(self) -> bool {
        self.hi.is_finite() && self.lo.is_finite() && self.r.is_finite()
    }

    /// An upper bound of `|v|` for every `v` in the ball.
    fn upper(self) -> f64 {
        (mag(self.hi) + self.r) * UP
    }

    /// A lower bound of `|v|` for every `v` in the ball (`<= 0` or `NaN` when it may be 0).
    fn lower(self) -> f64 {
        // |m| >= |hi| (1 - 2^-53); the subtraction is rounded down by the factor.
        (self.hi.abs() * (1.0 - 8.881784197001252e-16) - self.r) * (1.0 - 3.552713678800501e-15)
    }

    /// The quotient, self-validating: `q ~ m_x / m_y`, then for every `x`, `y` of the balls
    /// `|x / y - q| <= (|m_x - q m_y| + r_x + |q| r_y) / (|m_y| - r_y)`, the residual
    /// `m_x - q m_y` bounded in ball arithmetic. `None` when the divisor may be 0.
    pub fn div(self, o: Ball) -> Option<Ball> {
        let low = o.lower();
        if !positive(low) {
            return None;
        }
        let qh = self.hi / o.hi;
        // One correction step towards the double-double quotient (only the width depends on it).
        let q0 = Ball::exact(qh);
        let res = Ball { r: 0.0, ..self }.sub(q0.mul(Ball { r: 0.0, ..o }));
        let ql = res.hi / o.hi;
        let (hi, lo) = two_sum(qh, ql);
        let q = Ball { hi, lo, r: 0.0 };
        let e = Ball { r: 0.0, ..self }.sub(q.mul(Ball { r: 0.0, ..o }));
        let num = (e.upper() + self.r + mag(hi) * o.r) * UP;
        let r = num / low * UP + TINY;
        r.is_finite().then_some(Ball { hi, lo, r })
    }

    /// The square root, self-validating: `s ~ sqrt(m)`, then `|sqrt(x) - s| = |x - s^2| /
    /// (sqrt(x) + s) <= (|m - s^2| + r) / s`. `None` unless the ball is certainly positive.
    pub fn sqrt(self) -> Option<Ball> {
        if !positive(self.lower()) || self.hi <= 0.0 {
            return None;
        }
        let sh = self.hi.sqrt();
        // One Newton step: s = sh + (m - sh^2) / (2 sh).
        let s0 = Ball::exact(sh);
        let res = Ball { r: 0.0, ..self }.sub(s0.square());
        let (hi, lo) = two_sum(sh, res.hi / (2.0 * sh));
        let s = Ball { hi, lo, r: 0.0 };
        let e = Ball { r: 0.0, ..self }.sub(s.square());
        let slow = s.lower();
        if !positive(slow) {
            return None;
        }
        let r = (e.upper() + self.r) * UP / slow * UP + TINY;
        r.is_finite().then_some(Ball { hi, lo, r })
    }

    /// The sign of every value in the ball; `None` when it may contain 0 (or is not finite).
    pub fn sign(self) -> Option<Sign> {
        if !positive(self.lower()) || !self.finite() {
            return None;
        }
        Some(if self.hi > 0.0 {
            Sign::Positive
        } else {
            Sign::Negative
        })
    }

    /// The `f64` nearest to every value of the ball, when that is one non-zero normal `f64`:
    /// `hi` when `|lo| + r` is below half the gap to both neighbours of `hi` (strictly, so no
    /// value is a rounding midpoint). `None` otherwise.
    pub fn round(self) -> Option<f64> {
        let h = self.hi;
        if h.abs() < f64::MIN_POSITIVE || !self.finite() {
            return None;
        }
        let up = h.next_up() - h;
        let down = h - h.next_down();
        if !up.is_finite() {
            return None;
        }
        // Half gaps are exact; the smaller of the two is the binding one.
        let half = 0.5 * up.min(down);
        ((self.lo.abs() + self.r) * UP < half).then_some(h)
    }

    /// True when every value of `self` is below every value of `o` (certainly `self < o`).
    pub fn certainly_less(self, o: Ball) -> Option<bool> {
        match o.sub(self).sign()? {
            Sign::Positive => Some(true),
            Sign::Negative => Some(false),
            Sign::Zero => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rug::Rational;

    fn q(x: f64) -> Rational {
        Rational::from_f64(x).expect("finite")
    }

    /// The ball's exact bounds `[m - r, m + r]` as rationals.
    fn bounds(b: Ball) -> (Rational, Rational) {
        let m = q(b.hi) + q(b.lo);
        (&m - q(b.r), m + q(b.r))
    }

    fn contains(b: Ball, v: &Rational) -> bool {
        let (lo, hi) = bounds(b);
        lo <= *v && *v <= hi
    }

    #[test]
    fn constants_are_the_powers_of_two() {
        assert_eq!(REL, 2f64.powi(-100));
        assert_eq!(UP, 1.0 + 2f64.powi(-48));
        assert_eq!(TINY, 2f64.powi(-1000));
        assert_eq!(mag(1.0), 1.0 + 2f64.powi(-50));
    }

    /// Every operation's ball contains the exact result of the operation on every pair of
    /// values of its inputs (checked at the inputs' ends and midpoints, exactly in rationals),
    /// on values spanning many binades, with cancellation.
    #[test]
    fn operations_contain_the_exact_result() {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut rnd = || {
            let m = (next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            let e = (next() % 120) as i32 - 60;
            m * 2f64.powi(e)
        };
        for case in 0..20_000 {
            let (a, b, c, d) = (rnd(), rnd(), rnd(), rnd());
            // Inputs with a double-double midpoint and a radius.
            let x = Ball::diff(a, b).mul(Ball::exact(c));
            let y = if case % 3 == 0 {
                Ball::diff(a, -d) // cancellation against x
            } else {
                Ball::diff(c, d).add(Ball::exact(b))
            };
            let ends = |v: Ball| {
                let (lo, hi) = bounds(v);
                let mid = q(v.hi) + q(v.lo);
                [lo, mid, hi]
            };
            for xv in ends(x) {
                for yv in ends(y) {
                    assert!(contains(x.add(y), &Rational::from(&xv + &yv)));
                    assert!(contains(x.sub(y), &Rational::from(&xv - &yv)));
                    assert!(contains(x.mul(y), &Rational::from(&xv * &yv)));
                    if let Some(z) = x.div(y) {
                        assert!(contains(z, &Rational::from(&xv / &yv)), "{x:?} / {y:?}");
                    }
                }
                // sqrt(v) in [lo, hi] iff lo^2 <= v <= hi^2 (lo >= 0).
                if let Some(z) = x.sqrt() {
                    let (lo, hi) = bounds(z);
                    assert!(lo >= 0);
                    let (l2, h2) = (Rational::from(lo.square_ref()), hi.square());
                    assert!(l2 <= xv && xv <= h2, "sqrt {x:?}");
                }
            }
            // Signs and roundings are certain for every value of the ball.
            for v in [x, y, x.mul(y), x.add(y)] {
                let (lo, hi) = bounds(v);
                match v.sign() {
                    Some(Sign::Positive) => assert!(lo > 0),
                    Some(Sign::Negative) => assert!(hi < 0),
                    _ => {}
                }
                if let Some(f) = v.round() {
                    // Both ends round to f (rug's nearest-even rounding through an f64
                    // conversion of the exact rational).
                    for e in [lo, hi] {
                        assert_eq!(crate::apollonius::exact::round_rational(&e), f);
                    }
                }
            }
        }
    }

    #[test]
    fn undecided_on_overflow_and_zero() {
        let big = Ball::exact(f64::MAX).mul(Ball::exact(4.0));
        assert_eq!(big.sign(), None);
        assert_eq!(big.round(), None);
        assert_eq!(Ball::diff(1.0, 1.0).sign(), None);
        assert_eq!(Ball::exact(0.0).round(), None);
        assert_eq!(Ball::exact(1.0).div(Ball::diff(2.0, 2.0)), None);
        assert_eq!(Ball::exact(-1.0).sqrt(), None);
        assert_eq!(Ball::exact(1.5).round(), Some(1.5));
    }
}
