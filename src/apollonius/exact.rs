//! Exact numbers of a quadratic field `Q(sqrt D)` and correctly rounded conversions to `f64`.
//!
//! A [`QSqrt`] is `a + b sqrt(D)` with rational `a`, `b`; the radicand `D >= 0` is *shared* by all
//! numbers of one computation and is passed to the operations that need it (multiplication,
//! sign, conversion). Addition and subtraction do not depend on `D`.
//!
//! Invariants relied upon:
//! - `D >= 0` always (the solver only builds real roots).
//! - The solver normalises a radicand that is the square of a rational to `D = 0` (folding the
//!   root into `a`), so for every `D > 0` met in practice `sqrt(D)` is irrational and
//!   `Q(sqrt D)` is a field: every non-zero element has an inverse ([`QSqrt::inv`]).
//!   [`QSqrt::sign`] and [`eq_across`] are exact for *any* `D >= 0`, square or not.

use rug::{Integer, Rational};
use std::cmp::Ordering;
use std::ops::{Add, Neg, Sub};

/// A three-valued sign, kept three-valued until the caller decides what a tie means.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Sign {
    Negative,
    Zero,
    Positive,
}

impl Sign {
    /// The sign of an exact rational.
    pub fn of_rational(q: &Rational) -> Sign {
        q.cmp0().into()
    }

    /// The sign of a finite `f64` (`NaN` maps to `Zero`; callers never pass it).
    pub fn of_f64(x: f64) -> Sign {
        if x > 0.0 {
            Sign::Positive
        } else if x < 0.0 {
            Sign::Negative
        } else {
            Sign::Zero
        }
    }

    /// The opposite sign.
    #[must_use]
    pub fn flip(self) -> Sign {
        match self {
            Sign::Negative => Sign::Positive,
            Sign::Zero => Sign::Zero,
            Sign::Positive => Sign::Negative,
        }
    }

    /// The sign of a product.
    #[must_use]
    pub fn times(self, other: Sign) -> Sign {
        match (self, other) {
            (Sign::Zero, _) | (_, Sign::Zero) => Sign::Zero,
            (a, b) if a == b => Sign::Positive,
            _ => Sign::Negative,
        }
    }
}

impl From<Ordering> for Sign {
    fn from(o: Ordering) -> Sign {
        match o {
            Ordering::Less => Sign::Negative,
            Ordering::Equal => Sign::Zero,
            Ordering::Greater => Sign::Positive,
        }
    }
}

impl From<Sign> for Ordering {
    fn from(s: Sign) -> Ordering {
        match s {
            Sign::Negative => Ordering::Less,
            Sign::Zero => Ordering::Equal,
            Sign::Positive => Ordering::Greater,
        }
    }
}

/// The number `a + b sqrt(D)` for a radicand `D >= 0` held by the caller.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct QSqrt {
    pub a: Rational,
    pub b: Rational,
}

impl QSqrt {
    /// `a + b sqrt(D)`.
    pub fn new(a: Rational, b: Rational) -> QSqrt {
        QSqrt { a, b }
    }

    /// The rational number `a` (with `b = 0`).
    pub fn rational(a: Rational) -> QSqrt {
        QSqrt {
            a,
            b: Rational::new(),
        }
    }

    /// True when the number is rational whatever `D` is (`b == 0`).
    pub fn is_rational(&self) -> bool {
        self.b.cmp0() == Ordering::Equal
    }

    /// Exact sign of `a + b sqrt(D)`: the signs of `a` and `b sqrt(D)` when they agree, otherwise
    /// the sign of the larger magnitude, decided by comparing `a^2` with `b^2 D`.
    pub fn sign(&self, d: &Rational) -> Sign {
        debug_assert!(d.cmp0() != Ordering::Less, "negative radicand");
        let sa = Sign::of_rational(&self.a);
        let sb = if d.cmp0() == Ordering::Greater {
            Sign::of_rational(&self.b)
        } else {
            Sign::Zero
        };
        match (sa, sb) {
            (s, Sign::Zero) | (Sign::Zero, s) => s,
            (x, y) if x == y => x,
            _ => {
                let a2 = Rational::from(self.a.square_ref());
                let b2d = Rational::from(self.b.square_ref()) * d;
                match a2.cmp(&b2d) {
                    Ordering::Greater => sa,
                    Ordering::Less => sb,
                    Ordering::Equal => Sign::Zero,
                }
            }
        }
    }

    /// `self * other = (a1 a2 + b1 b2 D) + (a1 b2 + a2 b1) sqrt(D)`.
    pub fn mul(&self, other: &QSqrt, d: &Rational) -> QSqrt {
        let bb = Rational::from(&self.b * &other.b) * d;
        let a = Rational::from(&self.a * &other.a) + bb;
        let b = Rational::from(&self.a * &other.b) + Rational::from(&other.a * &self.b);
        QSqrt { a, b }
    }

    /// `self^2`.
    pub fn square(&self, d: &Rational) -> QSqrt {
        let a = Rational::from(self.a.square_ref()) + Rational::from(self.b.square_ref()) * d;
        let b = Rational::from(&self.a * &self.b) * 2u32;
        QSqrt { a, b }
    }

    /// `q * self` for a rational `q`.
    pub fn scale(&self, q: &Rational) -> QSqrt {
        QSqrt {
            a: Rational::from(&self.a * q),
            b: Rational::from(&self.b * q),
        }
    }

    /// `self + q` for a rational `q`.
    pub fn add_rational(&self, q: &Rational) -> QSqrt {
        QSqrt {
            a: Rational::from(&self.a + q),
            b: self.b.clone(),
        }
    }

    /// The conjugate `a - b sqrt(D)`.
    pub fn conj(&self) -> QSqrt {
        QSqrt {
            a: self.a.clone(),
            b: Rational::from(-&self.b),
        }
    }

    /// The field norm `a^2 - b^2 D = self * conj(self)`.
    pub fn norm(&self, d: &Rational) -> Rational {
        Rational::from(self.a.square_ref()) - Rational::from(self.b.square_ref()) * d
    }

    /// `1 / self = conj(self) / norm(self)`; `None` when the norm vanishes (the number is zero,
    /// or `D` is the square of a rational and `self` a zero divisor of the ring).
    pub fn inv(&self, d: &Rational) -> Option<QSqrt> {
        let n = self.norm(d);
        if n.cmp0() == Ordering::Equal {
            return None;
        }
        let r = n.recip();
        Some(self.conj().scale(&r))
    }

    /// The `f64` nearest to `a + b sqrt(D)` (ties to even).
    ///
    /// Computed by bracketing `sqrt(D)` between two rationals with an integer square root, so
    /// the number lies between two rationals `lo <= x <= hi`; when both round to the same
    /// `f64`, that is the correctly rounded value (rounding is monotone). The bracket is refined
    /// until this happens. An irrational `x` is never a rounding midpoint, so this terminates;
    /// a cap of 2^16 bits (reached only after cancellation of thousands of bits) returns the
    /// rounding of `lo`, which is then still within one ulp.
    pub fn to_f64(&self, d: &Rational) -> f64 {
        if self.is_rational() || d.cmp0() != Ordering::Greater {
            return round_rational(&self.a);
        }
        let mut bits = 128u32;
        loop {
            let (slo, shi) = sqrt_bounds(d, bits);
            let mut lo = Rational::from(&self.b * &slo) + &self.a;
            let mut hi = Rational::from(&self.b * &shi) + &self.a;
            if lo > hi {
                std::mem::swap(&mut lo, &mut hi);
            }
            let (fl, fh) = (round_rational(&lo), round_rational(&hi));
            if fl == fh || bits >= 1 << 16 {
                return fl;
            }
            bits *= 2;
        }
    }
}

impl Add for &QSqrt {
    type Output = QSqrt;
    fn add(self, o: &QSqrt) -> QSqrt {
        QSqrt {
            a: Rational::from(&self.a + &o.a),
            b: Rational::from(&self.b + &o.b),
        }
    }
}

impl Sub for &QSqrt {
    type Output = QSqrt;
    fn sub(self, o: &QSqrt) -> QSqrt {
        QSqrt {
            a: Rational::from(&self.a - &o.a),
            b: Rational::from(&self.b - &o.b),
        }
    }
}

impl Add<&QSqrt> for QSqrt {
    type Output = QSqrt;
    fn add(self, o: &QSqrt) -> QSqrt {
        &self + o
    }
}

impl Sub<&QSqrt> for QSqrt {
    type Output = QSqrt;
    fn sub(self, o: &QSqrt) -> QSqrt {
        &self - o
    }
}

impl Neg for &QSqrt {
    type Output = QSqrt;
    fn neg(self) -> QSqrt {
        QSqrt {
            a: Rational::from(-&self.a),
            b: Rational::from(-&self.b),
        }
    }
}

/// Exact equality of `x = ax + bx sqrt(dx)` and `y = ay + by sqrt(dy)` living in two possibly
/// different quadratic fields.
///
/// With `u = ax - ay`, `x == y` iff `u + bx sqrt(dx) == by sqrt(dy)`: both sides have the same
/// sign and equal squares, and the difference of squares
/// `(u^2 + bx^2 dx - by^2 dy) + 2 u bx sqrt(dx)` is an element of `Q(sqrt dx)` whose sign is exact.
pub fn eq_across(x: &QSqrt, dx: &Rational, y: &QSqrt, dy: &Rational) -> bool {
    let u = Rational::from(&x.a - &y.a);
    let left = QSqrt::new(u, x.b.clone());
    let right_sign = if dy.cmp0() == Ordering::Greater {
        Sign::of_rational(&y.b)
    } else {
        Sign::Zero
    };
    if left.sign(dx) != right_sign {
        return false;
    }
    if right_sign == Sign::Zero {
        return true; // both sides are zero
    }
    let by2dy = Rational::from(y.b.square_ref()) * dy;
    let diff = left.square(dx).add_rational(&(-by2dy));
    diff.sign(dx) == Sign::Zero
}

/// Rationals `lo <= sqrt(d) <= hi` with `hi - lo <= 2^-(bits-1) * sqrt(d)` (both equal to
/// `sqrt(d)` when `d` is a square of a rational). `d` must be `>= 0`.
///
/// `sqrt(n/m) = sqrt(n m) / m`; with `t = isqrt(n m 4^k)`, `t <= sqrt(n m) 2^k < t + 1`.
pub fn sqrt_bounds(d: &Rational, bits: u32) -> (Rational, Rational) {
    if d.cmp0() != Ordering::Greater {
        return (Rational::new(), Rational::new());
    }
    let p = Integer::from(d.numer() * d.denom());
    let half = p.significant_bits() / 2;
    let k = bits.saturating_sub(half) + 1;
    let scaled = Integer::from(&p << (2 * k));
    let (t, rem) = scaled.sqrt_rem(Integer::new());
    let den = Integer::from(d.denom() << k);
    let lo = Rational::from((t.clone(), den.clone()));
    let hi = if rem.cmp0() == Ordering::Equal {
        lo.clone()
    } else {
        Rational::from((t + 1u32, den))
    };
    (lo, hi)
}

/// `2^k` as an `f64` for `-1074 <= k <= 1023`.
fn pow2(k: i64) -> f64 {
    debug_assert!((-1074..=1023).contains(&k));
    if k >= -1022 {
        f64::from_bits(((k + 1023) as u64) << 52)
    } else {
        f64::from_bits(1u64 << (k + 1074))
    }
}

/// The `f64` nearest to the rational `q`, ties to even (IEEE round-to-nearest), with overflow to
/// `±inf` and gradual underflow. (`rug`'s own `to_f64` truncates.)
pub fn round_rational(q: &Rational) -> f64 {
    let negative = q.cmp0() == Ordering::Less;
    let n = Integer::from(q.numer().abs_ref());
    let m = q.denom();
    if n.cmp0() == Ordering::Equal {
        return 0.0;
    }
    // e = floor(log2(n/m)): start from the bit lengths, correct by one.
    let mut e = i64::from(n.significant_bits()) - i64::from(m.significant_bits());
    let ge = if e >= 0 {
        n >= Integer::from(m << (e as u32))
    } else {
        Integer::from(&n << ((-e) as u32)) >= *m
    };
    if !ge {
        e -= 1;
    }
    let mag = if e > 1023 {
        f64::INFINITY
    } else {
        let e_eff = e.max(-1022);
        let shift = 52 - e_eff; // m_int = floor(n/m * 2^shift), 2^52 <= m_int < 2^53 when normal
        let (num, den) = if shift >= 0 {
            (Integer::from(&n << (shift as u32)), m.clone())
        } else {
            (n, Integer::from(m << ((-shift) as u32)))
        };
        let (mut mi, r) = num.div_rem(den.clone());
        let twice_r = r * 2u32;
        match twice_r.cmp(&den) {
            Ordering::Greater => mi += 1u32,
            Ordering::Equal if mi.is_odd() => mi += 1u32,
            _ => {}
        }
        // mi <= 2^53, exactly representable; the product below is exact unless it overflows.
        let mf = mi.to_f64();
        mf * pow2(e_eff - 52)
    };
    if negative {
        -mag
    } else {
        mag
    }
}
