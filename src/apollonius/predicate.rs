//! The exact tangency predicate of a fourth site against an Apollonius circle, behind a
//! floating-point filter.
//!
//! For a root `(p, rho)` and a site `l = (c_l, s_l)` let `sigma = rho + s_l` and
//!
//! ```text
//! f = |p - c_l|^2 - sigma^2 = A + B sqrt(D)      (A, B rational).
//! ```
//!
//! The answer is a *clearance* sign, uniform for holes and the bounding circle:
//! - hole (`s_l >= 0`, so `sigma >= 0`): `sign(f) = sign(|p - c_l| - (rho + r_l))`:
//!   `Positive` = the hole lies outside the circle, `Zero` = externally tangent,
//!   `Negative` = the hole cuts into the open disc;
//! - bounding circle (`s_l = -R`): if `sigma > 0` (`rho > R`) the disc cannot fit: `Negative`;
//!   otherwise `-sign(f) = sign(R - rho - |p - c_l|)`: `Positive` = the disc lies strictly inside,
//!   `Zero` = internally tangent, `Negative` = it pokes out.
//!
//! ## Filter
//! The root caches correctly rounded `f64` values of `x`, `y`, `rho`, so each exact value lies in
//! `[v.next_down(), v.next_up()]`. `f` (and `sigma`) are evaluated in interval arithmetic with every
//! operation widened outward by one ulp (see `interval.rs`): the resulting interval provably
//! contains the exact value, so a sign decided by the interval is the exact sign. Only when the
//! interval contains 0 (or overflowed to `NaN`) is the exact `Q(sqrt D)` evaluation run. The
//! filter never certifies `Zero`. Its relative width is a few ulps of `|p - c_l|^2 + sigma^2`, so
//! on random input the exact path essentially never runs.

use super::exact::{eq_across, QSqrt, Sign, ZSqrt};
use super::interval::Interval;
use super::solve::{apollonius_roots, ApolloniusError, ExactApollonius};
use super::Site;
use rug::Integer;

/// Which evaluation decided a predicate (for tests and statistics).
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Path {
    Filter,
    Exact,
}

/// Clearance sign of site `l` against the Apollonius circle `root` (see the module docs):
/// `Positive` clear, `Zero` tangent (with the site's sense), `Negative` intruding.
///
/// Exact for every finite input; `Err(NonFinite)` when `l` is not finite.
pub fn tangency(root: &ExactApollonius, l: &Site) -> Result<Sign, ApolloniusError> {
    tangency_sign_filtered(root, l).map(|(s, _)| s)
}

/// True when `l` is tangent to `root` with its sense (externally for a hole, internally for the
/// bounding circle): `root`'s sites and `l` are then co-circular.
pub fn is_tangent(root: &ExactApollonius, l: &Site) -> Result<bool, ApolloniusError> {
    Ok(tangency(root, l)? == Sign::Zero)
}

/// [`tangency`] with the path that decided it.
#[doc(hidden)]
pub fn tangency_sign_filtered(
    root: &ExactApollonius,
    l: &Site,
) -> Result<(Sign, Path), ApolloniusError> {
    if !l.is_finite() {
        return Err(ApolloniusError::NonFinite);
    }
    match tangency_filter(root, l) {
        Some(s) => Ok((s, Path::Filter)),
        None => tangency_exact(root, l).map(|s| (s, Path::Exact)),
    }
}

/// The filter alone: `Some(sign)` when the interval evaluation decides, else `None`.
#[doc(hidden)]
pub fn tangency_filter(root: &ExactApollonius, l: &Site) -> Option<Sign> {
    if !l.is_finite() {
        return None;
    }
    let [x, y] = root.center_f64();
    let dx = Interval::around(x).sub(Interval::point(l.center[0]));
    let dy = Interval::around(y).sub(Interval::point(l.center[1]));
    let sigma = Interval::around(root.radius_f64()).add(Interval::point(l.s));
    let f = dx.square().add(dy.square()).sub(sigma.square());
    if l.is_bounding() {
        match sigma.sign()? {
            Sign::Positive => Some(Sign::Negative),
            _ => f.sign().map(Sign::flip),
        }
    } else {
        f.sign()
    }
}

/// The exact evaluation in `Q(sqrt D)`, no filter.
///
/// In the root's integer frame rescaled to the site's exponent `e`:
/// `den (p - c_l) / 2^e` and `den sigma / 2^e` are integer `a + b sqrt(disc)`, so
/// `den^2 f / 4^e` is one too, with the sign of `f` (`den > 0`).
#[doc(hidden)]
pub fn tangency_exact(root: &ExactApollonius, l: &Site) -> Result<Sign, ApolloniusError> {
    let (num, ints, _) = root
        .rescaled(&[l.center[0], l.center[1], l.s])
        .ok_or(ApolloniusError::NonFinite)?;
    let (_, d, den, _) = root.frame();
    let shifted = |z: &ZSqrt, v: &Integer| z.add_int(&Integer::from(den * v));
    let dx = shifted(&num[0], &Integer::from(-&ints[0]));
    let dy = shifted(&num[1], &Integer::from(-&ints[1]));
    let sigma = shifted(&num[2], &ints[2]);
    let f = &(&dx.square(d) + &dy.square(d)) - &sigma.square(d);
    Ok(if l.is_bounding() {
        match sigma.sign(d) {
            Sign::Positive => Sign::Negative,
            _ => f.sign(d).flip(),
        }
    } else {
        f.sign(d)
    })
}

/// Do four sites touch one circle with their senses? True when some valid Apollonius circle of
/// the first three is tangent to the fourth (then every triple of the four has that circle among
/// its roots).
pub fn cocircular(sites: [Site; 4]) -> Result<bool, ApolloniusError> {
    let [a, b, c, l] = sites;
    if !l.is_finite() {
        return Err(ApolloniusError::NonFinite);
    }
    for root in apollonius_roots(&[a, b, c])? {
        if is_tangent(&root, &l)? {
            return Ok(true);
        }
    }
    Ok(false)
}

/// Exact equality of two Apollonius circles, possibly from different triples and quadratic
/// fields: equal centres and radii as real numbers.
pub fn same_circle(x: &ExactApollonius, y: &ExactApollonius) -> bool {
    // Cheap rejection on the rounded values: equal reals round to equal floats (to within one
    // ulp even if a conversion hit its precision cap). Before any exact value is read: a root
    // of the fast path builds its exact frame only when asked.
    let near = |a: f64, b: f64| a == b || a.next_up() == b || a.next_down() == b;
    let (cx, cy) = (x.center_f64(), y.center_f64());
    if !(near(cx[0], cy[0]) && near(cx[1], cy[1]) && near(x.radius_f64(), y.radius_f64())) {
        return false;
    }
    let (dx, dy) = (x.d(), y.d());
    let eq = |a: &QSqrt, b: &QSqrt| eq_across(a, &dx, b, &dy);
    eq(&x.rho(), &y.rho()) && eq(&x.x(), &y.x()) && eq(&x.y(), &y.y())
}
