//! Minimal interval arithmetic on `f64` for the predicate's floating-point filter.
//!
//! Directed rounding is emulated: every operation is done in round-to-nearest and the result is
//! widened outwards by one ulp (`f64::next_down` / `f64::next_up`). Round-to-nearest makes an
//! error of at most half an ulp, so the widened interval contains the exact result of the
//! operation on the interval endpoints; by induction every interval contains the exact value of
//! the expression.
//! Overflow gives infinite endpoints (still valid bounds); `inf - inf` gives `NaN`, and an
//! interval with a `NaN` endpoint decides nothing.

use super::exact::Sign;

/// A closed interval `[lo, hi]` known to contain an exact real value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    /// The exact value `x` (a point interval).
    pub fn point(x: f64) -> Interval {
        Interval { lo: x, hi: x }
    }

    /// An interval containing every real whose nearest `f64` is `x` (or that `x` brackets within
    /// one ulp): `[x.next_down(), x.next_up()]`.
    pub fn around(x: f64) -> Interval {
        Interval {
            lo: x.next_down(),
            hi: x.next_up(),
        }
    }

    fn widen(lo: f64, hi: f64) -> Interval {
        Interval {
            lo: lo.next_down(),
            hi: hi.next_up(),
        }
    }

    pub fn add(self, o: Interval) -> Interval {
        Interval::widen(self.lo + o.lo, self.hi + o.hi)
    }

    pub fn sub(self, o: Interval) -> Interval {
        Interval::widen(self.lo - o.hi, self.hi - o.lo)
    }

    /// An interval containing the integer `v`: its `f64` conversion (within one ulp) widened by
    /// one ulp each way; `None` when `v` is beyond the `f64` range.
    pub fn of_integer(v: &rug::Integer) -> Option<Interval> {
        let x = v.to_f64();
        x.is_finite().then(|| Interval::around(x))
    }

    /// The interval with `NaN` endpoints: decides nothing.
    fn undecided() -> Interval {
        Interval {
            lo: f64::NAN,
            hi: f64::NAN,
        }
    }

    /// The product: the extreme endpoint products, widened (a `NaN` product, from `0 * inf`,
    /// gives the undecided interval rather than being dropped by `min`/`max`).
    pub fn mul(self, o: Interval) -> Interval {
        let p = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        if p.iter().any(|v| v.is_nan()) {
            return Interval::undecided();
        }
        let lo = p.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Interval::widen(lo, hi)
    }

    /// The quotient by an interval of positive numbers (undecided otherwise).
    pub fn div_positive(self, o: Interval) -> Interval {
        if o.lo.is_nan() || o.lo <= 0.0 {
            return Interval::undecided();
        }
        let p = [
            self.lo / o.lo,
            self.lo / o.hi,
            self.hi / o.lo,
            self.hi / o.hi,
        ];
        if p.iter().any(|v| v.is_nan()) {
            return Interval::undecided();
        }
        let lo = p.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Interval::widen(lo, hi)
    }

    /// The square root of the non-negative part (`sqrt` is correctly rounded: one ulp of
    /// widening suffices).
    pub fn sqrt(self) -> Interval {
        if self.hi.is_nan() || self.lo.is_nan() || self.hi < 0.0 {
            return Interval::undecided();
        }
        Interval {
            lo: self.lo.max(0.0).sqrt().next_down().max(0.0),
            hi: self.hi.sqrt().next_up(),
        }
    }

    /// `x^2`, which is `>= 0` also when the interval straddles 0.
    pub fn square(self) -> Interval {
        let (a, b) = (self.lo.abs(), self.hi.abs());
        let (small, big) = if a <= b { (a, b) } else { (b, a) };
        let lo = if self.lo <= 0.0 && self.hi >= 0.0 {
            0.0
        } else {
            (small * small).next_down().max(0.0)
        };
        Interval {
            lo,
            hi: (big * big).next_up(),
        }
    }

    /// The sign when every point of the interval has it; `None` when undecided (contains 0 or
    /// has a `NaN` endpoint). A zero is never certified by the filter.
    pub fn sign(self) -> Option<Sign> {
        if self.lo > 0.0 {
            Some(Sign::Positive)
        } else if self.hi < 0.0 {
            Some(Sign::Negative)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn around_widens_by_one_ulp_each_way() {
        let one = Interval::around(1.0);
        assert_eq!(
            (one.lo, one.hi),
            (1.0 - f64::EPSILON / 2.0, 1.0 + f64::EPSILON)
        );
        let zero = Interval::around(-0.0);
        assert_eq!((zero.lo, zero.hi), (-f64::from_bits(1), f64::from_bits(1)));
        assert_eq!(Interval::around(f64::MAX).hi, f64::INFINITY);
        assert_eq!(Interval::around(f64::INFINITY).lo, f64::MAX);
        assert!(Interval::around(f64::NAN).hi.is_nan());
    }

    #[test]
    fn nan_decides_nothing() {
        let i = Interval::point(f64::INFINITY).sub(Interval::point(f64::INFINITY));
        assert_eq!(i.sign(), None);
        assert_eq!(Interval::around(1.0).sign(), Some(Sign::Positive));
    }
}
