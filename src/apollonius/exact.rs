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

use super::interval::Interval;
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
///
/// Always the exact integer path ([`round_scaled_exact`]): this is the test oracle of the
/// filtered [`round_scaled`].
pub fn round_rational(q: &Rational) -> f64 {
    round_scaled_exact(q.numer(), q.denom(), 0)
}

/// The `f64` nearest to `num / den * 2^exp` (`den > 0`, the fraction need not be reduced),
/// ties to even, with overflow to `±inf` and gradual underflow.
///
/// A filter first brackets the value between two `u128` quotients of the top 64 bits of `num`
/// and `den` ([`round_scaled_filter`]); when both round to the same normal `f64`, that is the
/// answer (rounding is monotone). Otherwise (near a rounding midpoint, or outside the normal
/// range) the exact integer division decides ([`round_scaled_exact`]). Same value either way.
pub fn round_scaled(num: &Integer, den: &Integer, exp: i64) -> f64 {
    round_scaled_filter(num, den, exp).unwrap_or_else(|| round_scaled_exact(num, den, exp))
}

/// `m` and `s` with `2^63 <= m < 2^64` and `m <= |v| / 2^s < m + 1` (`v != 0`), read from the
/// top limbs without allocating; `exact` when `|v| = m 2^s`.
fn top64(v: &Integer) -> (u64, i64, bool) {
    // 64-bit limbs (x86_64, aarch64): a 32-bit limb target fails to compile here.
    let limbs: &[u64] = v.as_limbs();
    let n = limbs.len();
    let top = limbs[n - 1];
    let lz = top.leading_zeros();
    let below = if n >= 2 { limbs[n - 2] } else { 0 };
    let m = if lz == 0 {
        top
    } else {
        (top << lz) | (below >> (64 - lz))
    };
    let s = 64 * (n as i64 - 1) - i64::from(lz);
    // Bits below the 64 kept ones: the low `64 - lz` bits of `below` (when lz > 0: its low
    // `64 - lz`; when lz == 0: all of it) and every lower limb.
    let dropped_below = if n >= 2 {
        let mask = if lz == 0 {
            u64::MAX
        } else {
            (1u64 << (64 - lz)) - 1
        };
        below & mask != 0
    } else {
        false
    };
    let exact = !dropped_below && limbs[..n.saturating_sub(2)].iter().all(|&l| l == 0);
    (m, s, exact)
}

/// The filter of [`round_scaled`]: `Some` only when the correctly rounded value is certain and
/// normal. With `|num| / 2^sn` in `[N, N + 1)` and `den / 2^sd` in `[D, D + 1)` (top 64 bits),
/// `|num| / den` lies in `[N / (D + 1), (N + 1) / D] 2^(sn - sd)`; the quotients times `2^64`
/// are bracketed by `u128` floor/ceiling divisions, whose roundings (`u128 as f64` rounds to
/// nearest, ties to even; the power-of-two scale is exact for normal results) must agree.
pub fn round_scaled_filter(num: &Integer, den: &Integer, exp: i64) -> Option<f64> {
    if num.cmp0() == Ordering::Equal {
        return Some(0.0);
    }
    if den.cmp0() != Ordering::Greater {
        return None;
    }
    let (n, sn, n_exact) = top64(num);
    let (d, sd, d_exact) = top64(den);
    let (n, d) = (u128::from(n), u128::from(d));
    let n_hi = if n_exact { n } else { n + 1 };
    if n_hi >> 64 != 0 {
        return None; // (N + 1) 2^64 would not fit
    }
    let d_hi = if d_exact { d } else { d + 1 };
    // lo <= |num| / den * 2^(64 - sn + sd) <= hi.
    let lo = (n << 64) / d_hi;
    let hi = (n_hi << 64).div_ceil(d);
    let e = exp.checked_add(sn)?.checked_sub(sd)?.checked_sub(64)?;
    // lo >= 2^62 and hi < 2^66: results in [2^(e+62), 2^(e+66)) are normal and finite.
    if !(-1022..=1023 - 66).contains(&e) {
        return None;
    }
    let scale = pow2(e);
    let (fl, fh) = (lo as f64 * scale, hi as f64 * scale);
    if fl != fh {
        return None;
    }
    Some(if num.cmp0() == Ordering::Less {
        -fl
    } else {
        fl
    })
}

/// [`round_scaled`] by exact integer division (the reference path).
pub fn round_scaled_exact(num: &Integer, den: &Integer, exp: i64) -> f64 {
    debug_assert!(den.cmp0() == Ordering::Greater);
    let negative = num.cmp0() == Ordering::Less;
    let n = Integer::from(num.abs_ref());
    if n.cmp0() == Ordering::Equal {
        return 0.0;
    }
    // e0 = floor(log2(n/den)): start from the bit lengths, correct by one.
    let mut e0 = i64::from(n.significant_bits()) - i64::from(den.significant_bits());
    let ge = if e0 >= 0 {
        n >= Integer::from(den << (e0 as u32))
    } else {
        Integer::from(&n << ((-e0) as u32)) >= *den
    };
    if !ge {
        e0 -= 1;
    }
    let e = e0.saturating_add(exp);
    let mag = if e > 1023 {
        f64::INFINITY
    } else if e < -1080 {
        0.0 // below half the smallest subnormal
    } else {
        let e_eff = e.max(-1022);
        // mi = floor(n/den * 2^sh) with 2^52 <= mi < 2^53 when normal.
        let sh = exp + 52 - e_eff;
        let (scaled_num, scaled_den) = if sh >= 0 {
            (n << (sh as u32), den.clone())
        } else {
            (n, Integer::from(den << ((-sh) as u32)))
        };
        let (mut mi, r) = scaled_num.div_rem(scaled_den.clone());
        let twice_r = r * 2u32;
        match twice_r.cmp(&scaled_den) {
            Ordering::Greater => mi += 1u32,
            Ordering::Equal if mi.is_odd() => mi += 1u32,
            _ => {}
        }
        // mi <= 2^53, exactly representable; the product below is exact unless it overflows.
        mi.to_f64() * pow2(e_eff - 52)
    };
    if negative {
        -mag
    } else {
        mag
    }
}

/// Bits of the first bracket of [`ZSqrt::to_f64`] (doubled until the rounding is decided).
const FIRST_BRACKET_BITS: u32 = 128;

/// The first bracket of `sqrt(D)` that [`ZSqrt::to_f64`] uses for a radicand `D > 0`:
/// `t = floor(sqrt(D 4^k))` and whether it is exact. Every rounding of one Apollonius root
/// (centre, radius, tangent points) brackets the same `sqrt(D)`: computed once, shared.
#[derive(Debug, Clone)]
pub struct SqrtBracket {
    k: u32,
    t: Integer,
    exact: bool,
}

impl SqrtBracket {
    /// The first bracket for `d` (`None` when `d <= 0`: no square root is taken then).
    pub fn new(d: &Integer) -> Option<SqrtBracket> {
        if d.cmp0() != Ordering::Greater {
            return None;
        }
        let half = d.significant_bits() / 2;
        let k = FIRST_BRACKET_BITS.saturating_sub(half) + 1;
        let (t, rem) = Integer::from(d << (2 * k)).sqrt_rem(Integer::new());
        Some(SqrtBracket {
            k,
            t,
            exact: rem.cmp0() == Ordering::Equal,
        })
    }
}

/// The number `a + b sqrt(D)` with integer parts, `D` an integer held by the caller. The solver
/// works with these over a shared positive denominator, which avoids the gcd of every rational
/// operation (the dominant cost otherwise).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct ZSqrt {
    pub a: Integer,
    pub b: Integer,
}

impl ZSqrt {
    /// `a + b sqrt(D)`.
    pub fn new(a: Integer, b: Integer) -> ZSqrt {
        ZSqrt { a, b }
    }

    /// The integer `a`.
    pub fn int(a: Integer) -> ZSqrt {
        ZSqrt {
            a,
            b: Integer::new(),
        }
    }

    /// Exact sign, as [`QSqrt::sign`]. When the signs of `a` and `b` differ, an interval
    /// evaluation of `a + b sqrt(D)` decides first (every interval contains the exact value, so
    /// a decided sign is exact); the squares are compared only when it contains 0.
    pub fn sign(&self, d: &Integer) -> Sign {
        let sa: Sign = self.a.cmp0().into();
        let sb = if d.cmp0() == Ordering::Greater {
            self.b.cmp0().into()
        } else {
            Sign::Zero
        };
        if sa != sb && sa != Sign::Zero && sb != Sign::Zero {
            if let Some(s) = self.sign_filter(d) {
                return s;
            }
        }
        self.sign_exact(d)
    }

    /// The interval sign of `a + b sqrt(D)` (`None` when undecided).
    #[doc(hidden)]
    pub fn sign_filter(&self, d: &Integer) -> Option<Sign> {
        let iv = Interval::of_integer;
        iv(&self.a)?.add(iv(&self.b)?.mul(iv(d)?.sqrt())).sign()
    }

    /// [`ZSqrt::sign`] by comparing `a^2` with `b^2 D` (the reference).
    #[doc(hidden)]
    pub fn sign_exact(&self, d: &Integer) -> Sign {
        let sa: Sign = self.a.cmp0().into();
        let sb = if d.cmp0() == Ordering::Greater {
            self.b.cmp0().into()
        } else {
            Sign::Zero
        };
        match (sa, sb) {
            (s, Sign::Zero) | (Sign::Zero, s) => s,
            (x, y) if x == y => x,
            _ => {
                let a2 = Integer::from(self.a.square_ref());
                let b2d = Integer::from(self.b.square_ref()) * d;
                match a2.cmp(&b2d) {
                    Ordering::Greater => sa,
                    Ordering::Less => sb,
                    Ordering::Equal => Sign::Zero,
                }
            }
        }
    }

    /// `self * other`.
    ///
    /// Accumulated in place (`+= x * y` is GMP's addmul): two allocations, no temporaries.
    pub fn mul(&self, o: &ZSqrt, d: &Integer) -> ZSqrt {
        let mut a = Integer::from(&self.b * &o.b);
        a *= d;
        a += &self.a * &o.a;
        let mut b = Integer::from(&self.a * &o.b);
        b += &o.a * &self.b;
        ZSqrt { a, b }
    }

    /// `self^2`.
    pub fn square(&self, d: &Integer) -> ZSqrt {
        let mut a = Integer::from(self.b.square_ref());
        a *= d;
        a += &self.a * &self.a;
        let mut b = Integer::from(&self.a * &self.b);
        b <<= 1u32;
        ZSqrt { a, b }
    }

    /// `k * self` for an integer `k`.
    pub fn scale(&self, k: &Integer) -> ZSqrt {
        ZSqrt {
            a: Integer::from(&self.a * k),
            b: Integer::from(&self.b * k),
        }
    }

    /// `self * 2^k`.
    pub fn shl(&self, k: u32) -> ZSqrt {
        ZSqrt {
            a: Integer::from(&self.a << k),
            b: Integer::from(&self.b << k),
        }
    }

    /// `self + k` for an integer `k`.
    pub fn add_int(&self, k: &Integer) -> ZSqrt {
        ZSqrt {
            a: Integer::from(&self.a + k),
            b: self.b.clone(),
        }
    }

    /// The conjugate `a - b sqrt(D)`.
    pub fn conj(&self) -> ZSqrt {
        ZSqrt {
            a: self.a.clone(),
            b: Integer::from(-&self.b),
        }
    }

    /// The norm `a^2 - b^2 D`.
    pub fn norm(&self, d: &Integer) -> Integer {
        Integer::from(self.a.square_ref()) - Integer::from(self.b.square_ref()) * d
    }

    /// The value `2^exp (a + b sqrt(D)) / den` as a [`QSqrt`] (`den != 0`).
    pub fn to_qsqrt(&self, den: &Integer, exp: i64) -> QSqrt {
        let part = |v: &Integer| -> Rational {
            let q = Rational::from((v.clone(), den.clone()));
            shift_rational(q, exp)
        };
        QSqrt::new(part(&self.a), part(&self.b))
    }

    /// The `f64` nearest to `2^exp (a + b sqrt(D)) / den` (`den > 0`), ties to even; see
    /// [`QSqrt::to_f64`] for the bracketing argument and the precision cap.
    pub fn to_f64(&self, d: &Integer, den: &Integer, exp: i64) -> f64 {
        self.to_f64_with(d, den, exp, None)
    }

    /// [`ZSqrt::to_f64`], taking the first bracket's square root from `first` (computed once
    /// for `d` by [`SqrtBracket::new`]) instead of computing it again: the same value.
    pub fn to_f64_with(
        &self,
        d: &Integer,
        den: &Integer,
        exp: i64,
        first: Option<&SqrtBracket>,
    ) -> f64 {
        if self.b.cmp0() == Ordering::Equal || d.cmp0() != Ordering::Greater {
            return round_scaled(&self.a, den, exp);
        }
        let half = d.significant_bits() / 2;
        let mut bits = FIRST_BRACKET_BITS;
        loop {
            // sqrt(D) in [t, t + 1] / 2^k.
            let k = bits.saturating_sub(half) + 1;
            let computed;
            let (t, exact) = match first {
                Some(f) if f.k == k => (&f.t, f.exact),
                _ => {
                    let (t, rem) = Integer::from(d << (2 * k)).sqrt_rem(Integer::new());
                    computed = t;
                    (&computed, rem.cmp0() == Ordering::Equal)
                }
            };
            // lo = a 2^k + b t, then hi = lo + b, in one buffer.
            let mut bound = Integer::from(&self.a << k);
            bound += &self.b * t;
            let kk = exp - i64::from(k);
            let fl = round_scaled(&bound, den, kk);
            if exact {
                return fl; // D is a square: the bracket is exact
            }
            bound += &self.b;
            let fh = round_scaled(&bound, den, kk);
            if fl == fh || bits >= 1 << 16 {
                return fl;
            }
            bits *= 2;
        }
    }
}

impl Add for &ZSqrt {
    type Output = ZSqrt;
    fn add(self, o: &ZSqrt) -> ZSqrt {
        ZSqrt {
            a: Integer::from(&self.a + &o.a),
            b: Integer::from(&self.b + &o.b),
        }
    }
}

impl Sub for &ZSqrt {
    type Output = ZSqrt;
    fn sub(self, o: &ZSqrt) -> ZSqrt {
        ZSqrt {
            a: Integer::from(&self.a - &o.a),
            b: Integer::from(&self.b - &o.b),
        }
    }
}

impl Sub<&ZSqrt> for ZSqrt {
    type Output = ZSqrt;
    fn sub(self, o: &ZSqrt) -> ZSqrt {
        &self - o
    }
}

/// `q * 2^exp`.
pub fn shift_rational(q: Rational, exp: i64) -> Rational {
    if exp >= 0 {
        q << (exp as u32)
    } else {
        q >> ((-exp) as u32)
    }
}

/// `v = n * 2^e` with integer `n` (`None` for non-finite `v`).
///
/// In lowest terms (`n` odd, or `n = 0` with `e = 0`) when `e < 0`; for integers `e = 0`. Read
/// from the bits of `v` (the same pair as the reduced `Rational::from_f64(v)`, tested against
/// it in `tests/perf_apollonius.rs` via [`dyadic_reference`]).
pub fn dyadic(v: f64) -> Option<(Integer, i64)> {
    if !v.is_finite() {
        return None;
    }
    if v == 0.0 {
        return Some((Integer::new(), 0));
    }
    let bits = v.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i64;
    let frac = bits & ((1u64 << 52) - 1);
    let (mut m, mut e) = if biased == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), biased - 1075)
    };
    let tz = m.trailing_zeros();
    m >>= tz;
    e += i64::from(tz);
    // Integers: the reduced denominator is 1, numerator m 2^e.
    let (n, e) = if e > 0 {
        (Integer::from(m) << (e as u32), 0)
    } else {
        (Integer::from(m), e)
    };
    Some((if v < 0.0 { -n } else { n }, e))
}

/// [`dyadic`] through `Rational::from_f64` (the reference).
pub fn dyadic_reference(v: f64) -> Option<(Integer, i64)> {
    let q = Rational::from_f64(v)?;
    let k = i64::from(q.denom().significant_bits()) - 1; // the denominator is 2^k
    let (n, _) = q.into_numer_denom();
    Some((n, -k))
}

/// Bring dyadics `n_i 2^{e_i}` to one scale: integers `N_i` and `E = min e_i` with
/// `n_i 2^{e_i} = N_i 2^E`.
pub fn common_scale(vals: &[(Integer, i64)]) -> (Vec<Integer>, i64) {
    let e = vals.iter().map(|v| v.1).min().unwrap_or(0);
    let ints = vals
        .iter()
        .map(|(n, ei)| Integer::from(n << ((ei - e) as u32)))
        .collect();
    (ints, e)
}
