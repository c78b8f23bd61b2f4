//! The corner angle of the quality figures: `atan2` in degrees, in `[0, 360]`, written here so
//! that it is cheap, branch-light (a row loop vectorises it) and the same bits on every
//! platform (IEEE additions, multiplications and divisions only, no fused multiply-add, no
//! libm).
//!
//! Reduction: with `ax = |x|`, `ay = |y|`, the first-quadrant angle is `atan(ay / ax)` when
//! `ay < tan(π/8) ax`, `90° - atan(ax / ay)` when `ax < tan(π/8) ay`, and
//! `45° + atan((ay - ax) / (ay + ax))` in between: one division gives an argument `|t| <=
//! tan(π/8)` (up to rounding). `atan(t) = t + t z S(z) / Q(z)`, `z = t²`, is the rational
//! approximation 5077 of Hart & Cheney (`t P(z) / Q(z)`, 19.6 digits on `[-tan(π/8),
//! tan(π/8)]`) rewritten so that only the small correction term carries rounding. The
//! quadrant then makes the result `M + s atan(t) · 180/π` with `M` an exact multiple of 45
//! and `s = ±1`: one rounding after the polynomial.
//!
//! Error (measured against a 120-bit evaluation on 2·10⁵ random, near-octant-boundary and
//! wide-exponent inputs): at most 2.3 ulp of the result in degrees, against 1.7 ulp for libm's
//! `atan2(y, x).to_degrees()` (+360 when negative), the formula this replaces; the two differ
//! by at most 2 ulp on the 3·10⁶ random and the hard inputs of `tests/perf_quality_atan.rs`,
//! which holds them within 4 ulp. Exact at the axes and diagonals (0, 45, 90, ..., 315).
//!
//! Zeros: `-0.0` is taken as `+0.0` in both arguments (`x < 0.0` and `y < 0.0` decide the
//! quadrant), so the angle of a corner does not depend on the sign of a zero cross or dot
//! product; `(0, 0)` gives 0. A result of 360 is possible for `y` negative and far smaller than
//! `x` (as with libm's formula). NaN in either argument gives NaN; `(±∞, ±∞)` the diagonals.

/// `tan(π/8)`, the reduction threshold (any nearby value works: the approximation holds a
/// little beyond it).
const TAN_PI_8: f64 = 0.414_213_562_373_095_03;
/// Hart & Cheney 5077: `Q(z)` coefficients from `z⁰` to `z⁴` (`z⁵` has coefficient 1).
const Q: [f64; 5] = [
    896.785_974_036_638_7,
    2_079.334_974_445_41,
    1_666.783_814_881_633_8,
    536.265_374_031_215_3,
    58.956_970_508_444_62,
];
/// `(P(z) - Q(z)) / z` from `z⁰` to `z³` (`z⁴` has coefficient -1; `P(0) - Q(0)` is
/// `-2.5e-17`, a relative `3e-20`, dropped), the differences taken in 40 digits.
const S: [f64; 4] = [
    -298.928_658_012_212_85,
    -513.754_463_341_148_7,
    -267.839_892_076_175_6,
    -42.803_329_210_221_6,
];

/// `atan(t)` in radians for `|t| <= tan(π/8)` (a little beyond is fine).
#[inline(always)]
fn atan_reduced(t: f64) -> f64 {
    let z = t * t;
    let s = (((-z + S[3]) * z + S[2]) * z + S[1]) * z + S[0];
    let q = ((((z + Q[4]) * z + Q[3]) * z + Q[2]) * z + Q[1]) * z + Q[0];
    t + t * (z * s / q)
}

/// The counter-clockwise angle from the direction `(1, 0)` to `(x, y)`, in degrees, in
/// `[0, 360]`: `atan2(y, x)` taken in `[0, 360)` (see the module doc for the error bound and
/// the zeros). A corner angle is `angle_deg(cross, dot)`; the unsigned angle between two
/// directions, in `[0, 180]`, is `angle_deg(|cross|, dot)`.
#[inline(always)]
pub fn angle_deg(y: f64, x: f64) -> f64 {
    angle_deg_with::<true>(y, x)
}

/// [`angle_deg`] for arguments of magnitude at most `1e300` (bit for bit its result there),
/// without its guard for larger ones: the cell pass's edges, whose squared lengths are at
/// most [`super::kernel::SQ_MAX`] where they are used (issue 8: six of the edge loop's
/// operations per edge).
#[inline(always)]
pub(super) fn angle_deg_bounded(y: f64, x: f64) -> f64 {
    angle_deg_with::<false>(y, x)
}

/// [`angle_deg`], with (`GUARD`) or without the scaling of arguments above `1e300`.
#[inline(always)]
fn angle_deg_with<const GUARD: bool>(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let small = (ay < TAN_PI_8 * ax) | (ay == 0.0);
    let large = !small & ((ax < TAN_PI_8 * ay) | (ax == 0.0));
    // The middle branch's sum could overflow: scale huge arguments by 1/4 (exact there; both
    // are within a factor 2.5 of each other, so neither is subnormal). At most `1e300`, `k`
    // is 1 and the products are the arguments themselves.
    let (n, d) = if small {
        (ay, ax)
    } else if large {
        (ax, ay)
    } else if GUARD {
        let k = if ay > 1e300 { 0.25 } else { 1.0 };
        (ay * k - ax * k, ay * k + ax * k)
    } else {
        (ay - ax, ay + ax)
    };
    // ax == ay: (0, 0), the diagonals and (inf, inf); t = 0 without a 0/0 or inf/inf.
    let t = if ax == ay { 0.0 } else { n / d };
    placed(atan_reduced(t).to_degrees(), small, large, y, x)
}

/// The angle of `(x, y)` from the reduced angle `a` (degrees) of the octant branch taken
/// (`small`: `|y| < tan(π/8) |x|`, `large`: `|x| < tan(π/8) |y|`, else the diagonal one):
/// first `c + sa * a` in the first quadrant, then mirrored into the quadrant of `(x, y)`.
#[inline(always)]
fn placed(a: f64, small: bool, large: bool, y: f64, x: f64) -> f64 {
    // First quadrant: c + sa * a.
    let c = if small {
        0.0
    } else if large {
        90.0
    } else {
        45.0
    };
    let sa = if large { -1.0 } else { 1.0 };
    // Quadrant: base + φ or base - φ.
    let (xn, yn) = (x < 0.0, y < 0.0);
    let base = if xn {
        180.0
    } else if yn {
        360.0
    } else {
        0.0
    };
    let neg = xn != yn;
    let m = if neg { base - c } else { base + c };
    let s = if neg { -sa } else { sa };
    m + s * a
}

#[cfg(test)]
mod tests {
    use super::angle_deg;

    /// The cell pass's form gives `angle_deg`'s bits wherever both arguments are at most
    /// `1e300` in magnitude: random directions over many scales, the axes and diagonals,
    /// zeros of both signs and the octant boundaries.
    #[test]
    fn bounded_form_equals_angle_deg() {
        let mut rng = crate::layouts::SplitMix64(0x2545_f491_9e37_79b9);
        let mut next = || rng.next_u64();
        let t8 = super::TAN_PI_8;
        let mut cases: Vec<(f64, f64)> = vec![
            (0.0, 0.0),
            (-0.0, 0.0),
            (0.0, -0.0),
            (1.0, 1.0),
            (-1.0, 1.0),
            (1e300, 1e300),
            (-1e300, 1e299),
            (t8, 1.0),
            (1.0, t8),
            (-t8, -1.0),
            (5e-324, 1.0),
            (1.0, -5e-324),
        ];
        for _ in 0..200_000 {
            let (a, b) = (next(), next());
            let scale = 10f64.powi((a % 601) as i32 - 300);
            let unit = |v: u64| (v >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            cases.push((unit(a) * scale, unit(b) * scale));
            cases.push((unit(a) * scale, unit(a) * scale * t8));
        }
        for (y, x) in cases {
            assert_eq!(
                super::angle_deg_bounded(y, x).to_bits(),
                angle_deg(y, x).to_bits(),
                "({y}, {x})"
            );
        }
    }

    #[test]
    fn axes_and_diagonals_are_exact() {
        let cases = [
            ((0.0, 1.0), 0.0),
            ((1.0, 1.0), 45.0),
            ((1.0, 0.0), 90.0),
            ((1.0, -1.0), 135.0),
            ((0.0, -1.0), 180.0),
            ((-1.0, -1.0), 225.0),
            ((-1.0, 0.0), 270.0),
            ((-1.0, 1.0), 315.0),
            ((0.0, 0.0), 0.0),
            ((-0.0, 0.0), 0.0),
            ((0.0, -0.0), 0.0),
            ((-0.0, -0.0), 0.0),
            ((-0.0, -3.0), 180.0),
            ((f64::INFINITY, f64::INFINITY), 45.0),
            ((f64::INFINITY, 2.0), 90.0),
            ((2.0, f64::NEG_INFINITY), 180.0),
        ];
        for ((y, x), want) in cases {
            let got = angle_deg(y, x);
            assert_eq!(got.to_bits(), f64::to_bits(want), "({y}, {x}): {got}");
        }
        assert!(angle_deg(f64::NAN, 1.0).is_nan());
        assert!(angle_deg(1.0, f64::NAN).is_nan());
    }
}
