//! Three-valued geometric predicates: Shewchuk's adaptive `orient2d` / `incircle` (crate
//! `robust`) on the fast path, exact `rug` evaluation when a coordinate lies outside the range in
//! which the adaptive code is exact, and simulation of simplicity (SoS) for in-circle ties.
//!
//! Signs are [`Ordering`]s: `Greater` = positive, `Equal` = exactly zero, `Less` = negative.
//!
//! # Why a range check
//! Shewchuk's expansions are exact as long as nothing overflows or underflows. With every
//! coordinate either zero or of magnitude in `[2^-150, 2^200]`, every term of the in-circle
//! determinant (degree 4) is a multiple of `2^-808` and below `2^840`, so the adaptive code is
//! exact. Outside that range the call is evaluated with integers ([`super::exact`]).
//!
//! # Simulation of simplicity
//! The lifted coordinate `x² + y²` of a point of lexicographic rank `r` (by `(x, y)`, smallest
//! first) is perturbed to `x² + y² + ε^(r+1)`, `ε → 0+`. The in-circle determinant
//! `det[x y x²+y² 1]` (rows `a, b, c, d`) is linear in each lift, so when it is exactly zero its
//! sign is that of the first non-zero lift cofactor, walking the points from the smallest rank:
//! `+orient(b,c,d)` for `a`, `-orient(a,c,d)` for `b`, `+orient(a,b,d)` for `c` and
//! `-orient(a,b,c)` for `d`. Orientation itself is never perturbed.

use super::exact::{incircle_exact, orient2d_exact};
use super::Point;
use std::cmp::Ordering;

/// Smallest non-zero magnitude (2^-150) for which the adaptive predicates are trusted.
pub(crate) const SAFE_MIN: f64 = 7.006_492_321_624_085e-46;
/// Largest magnitude (2^200) for which the adaptive predicates are trusted.
pub(crate) const SAFE_MAX: f64 = 1.606_938_044_258_990_3e60;

/// True when `x` is zero or its magnitude lies in `[SAFE_MIN, SAFE_MAX]` (false for NaN/inf).
#[inline(always)]
pub(crate) fn in_safe_range(x: f64) -> bool {
    let a = x.abs();
    a == 0.0 || (SAFE_MIN..=SAFE_MAX).contains(&a)
}

/// True when both coordinates of `p` are in the safe range (see [`in_safe_range`]).
#[inline(always)]
pub(crate) fn safe(p: &Point) -> bool {
    in_safe_range(p[0]) & in_safe_range(p[1])
}

#[inline(always)]
fn sign(x: f64) -> Ordering {
    if x > 0.0 {
        Ordering::Greater
    } else if x < 0.0 {
        Ordering::Less
    } else {
        Ordering::Equal
    }
}

#[inline(always)]
fn coord(p: Point) -> robust::Coord<f64> {
    robust::Coord { x: p[0], y: p[1] }
}

/// Exact orientation of `a, b, c`: `Greater` when counter-clockwise, `Equal` when collinear.
/// Coordinates must be finite.
#[inline]
pub fn orient2d(a: Point, b: Point, c: Point) -> Ordering {
    if safe(&a) & safe(&b) & safe(&c) {
        orient2d_safe(a, b, c)
    } else {
        orient2d_exact(a, b, c)
    }
}

/// [`orient2d`] for points whose coordinates are all in the safe range (unchecked; the caller
/// knows it, e.g. for every point of a triangulation).
#[inline]
pub(crate) fn orient2d_safe(a: Point, b: Point, c: Point) -> Ordering {
    debug_assert!(safe(&a) & safe(&b) & safe(&c));
    sign(robust::orient2d(coord(a), coord(b), coord(c)))
}

/// Exact in-circle test: `Greater` when `d` lies strictly inside the circle through the
/// counter-clockwise triangle `a, b, c`, `Equal` when the four points are co-circular.
/// Coordinates must be finite.
///
/// Evaluation: a floating-point filter (Shewchuk's first-stage error bound); when it cannot
/// decide, fixed-width integer arithmetic if the coordinate differences allow it
/// (module `wide`), else robust's adaptive stages; `rug` outside the safe range.
#[inline]
pub fn incircle(a: Point, b: Point, c: Point, d: Point) -> Ordering {
    if !(safe(&a) & safe(&b) & safe(&c) & safe(&d)) {
        return incircle_exact(a, b, c, d);
    }
    incircle_safe(a, b, c, d)
}

/// [`incircle`] for points whose coordinates are all in the safe range (unchecked).
#[inline]
pub(crate) fn incircle_safe(a: Point, b: Point, c: Point, d: Point) -> Ordering {
    incircle_filter(&a, &b, &c, &d).unwrap_or_else(|| incircle_safe_exact(a, b, c, d))
}

/// The first stage of [`incircle_safe`]: the sign when the floating-point determinant clears
/// Shewchuk's first-stage error bound, else `None`. Inlined into its callers (the builder's
/// cavity search makes some ten calls per inserted point; about nine in ten are decided here).
#[inline(always)]
fn incircle_filter(a: &Point, b: &Point, c: &Point, d: &Point) -> Option<Ordering> {
    debug_assert!(safe(a) & safe(b) & safe(c) & safe(d));
    let (adx, ady) = (a[0] - d[0], a[1] - d[1]);
    let (bdx, bdy) = (b[0] - d[0], b[1] - d[1]);
    let (cdx, cdy) = (c[0] - d[0], c[1] - d[1]);
    let (bdxcdy, cdxbdy) = (bdx * cdy, cdx * bdy);
    let (cdxady, adxcdy) = (cdx * ady, adx * cdy);
    let (adxbdy, bdxady) = (adx * bdy, bdx * ady);
    let alift = adx * adx + ady * ady;
    let blift = bdx * bdx + bdy * bdy;
    let clift = cdx * cdx + cdy * cdy;
    let det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
    let permanent = (bdxcdy.abs() + cdxbdy.abs()) * alift
        + (cdxady.abs() + adxcdy.abs()) * blift
        + (adxbdy.abs() + bdxady.abs()) * clift;
    let errbound = ICC_ERRBOUND_A * permanent;
    if det > errbound {
        return Some(Ordering::Greater);
    }
    if -det > errbound {
        return Some(Ordering::Less);
    }
    None
}

/// The exact stages of [`incircle_safe`], out of line: fixed-width integers when they apply,
/// else robust's adaptive stages.
#[inline(never)]
fn incircle_safe_exact(a: Point, b: Point, c: Point, d: Point) -> Ordering {
    match super::wide::incircle_small(a, b, c, d) {
        Some(s) => s,
        None => sign(robust::incircle(coord(a), coord(b), coord(c), coord(d))),
    }
}

/// Shewchuk's first-stage in-circle error bound factor, `(10 + 96 eps) eps`, `eps = 2^-53`.
const ICC_ERRBOUND_A: f64 = (10.0 + 96.0 * F64_EPS) * F64_EPS;
const F64_EPS: f64 = 1.0 / 9_007_199_254_740_992.0;

/// Lexicographic `(x, y)` order of two finite points (`-0.0 == 0.0`).
#[inline]
pub fn lex_cmp(p: &Point, q: &Point) -> Ordering {
    match p[0].partial_cmp(&q[0]) {
        Some(Ordering::Equal) | None => p[1].partial_cmp(&q[1]).unwrap_or(Ordering::Equal),
        Some(o) => o,
    }
}

/// In-circle test with simulation of simplicity (see the module documentation): never `Equal`
/// when `a, b, c` is a proper counter-clockwise triangle and the four points are distinct.
/// Returns `Equal` only for fully degenerate input (all four points collinear).
#[inline]
pub fn incircle_sos(a: Point, b: Point, c: Point, d: Point) -> Ordering {
    match incircle(a, b, c, d) {
        Ordering::Equal => incircle_tie(a, b, c, d),
        s => s,
    }
}

/// [`incircle_sos`] for points whose coordinates are all in the safe range (unchecked).
/// The filter is inlined; the exact stages and the tie-break (a tie is exact) are not.
#[inline(always)]
pub(crate) fn incircle_sos_safe(a: &Point, b: &Point, c: &Point, d: &Point) -> Ordering {
    incircle_filter(a, b, c, d).unwrap_or_else(|| incircle_sos_safe_exact(*a, *b, *c, *d))
}

/// The exact stages of [`incircle_sos_safe`] and its tie-break, out of line.
#[inline(never)]
fn incircle_sos_safe_exact(a: Point, b: Point, c: Point, d: Point) -> Ordering {
    match incircle_safe_exact(a, b, c, d) {
        Ordering::Equal => incircle_tie(a, b, c, d),
        s => s,
    }
}

/// The SoS decision for an exact in-circle tie: the sign of the first non-zero lift cofactor,
/// points taken in increasing lexicographic rank.
pub fn incircle_tie(a: Point, b: Point, c: Point, d: Point) -> Ordering {
    let pts = [a, b, c, d];
    let mut idx = [0usize, 1, 2, 3];
    idx.sort_unstable_by(|&i, &j| lex_cmp(&pts[i], &pts[j]));
    for i in idx {
        let s = match i {
            0 => orient2d(b, c, d),
            1 => orient2d(a, c, d).reverse(),
            2 => orient2d(a, b, d),
            _ => orient2d(a, b, c).reverse(),
        };
        if s != Ordering::Equal {
            return s;
        }
    }
    Ordering::Equal
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn safe_constants_are_powers_of_two() {
        assert_eq!(SAFE_MIN, 2f64.powi(-150));
        assert_eq!(SAFE_MAX, 2f64.powi(200));
    }

    #[test]
    fn square_tie_is_broken() {
        let (a, b, c, d) = ([0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]);
        assert_eq!(incircle(a, b, c, d), Ordering::Equal);
        let s = incircle_sos(a, b, c, d);
        assert_ne!(s, Ordering::Equal);
        // The other diagonal gets the opposite verdict: exactly one diagonal is chosen.
        let t = incircle_sos(b, c, d, a);
        assert_ne!(t, Ordering::Equal);
        assert_ne!(s, t);
    }
}
