//! The exact Apollonius solve: every circle tangent to three sites with the right senses.
//!
//! For sites `(c_i, s_i)`, `i = 0, 1, 2`, the unknowns are `u = (x, y, rho)` and the squared
//! tangency equations are
//!
//! ```text
//! F_i(u) = (x - x_i)^2 + (y - y_i)^2 - (rho + s_i)^2 = 0.
//! ```
//!
//! `F_j - F_0` is linear: `(x_j - x_0) x + (y_j - y_0) y + (s_j - s_0) rho = (k_j - k_0) / 2` with
//! `k_i = x_i^2 + y_i^2 - s_i^2`, for `j = 1, 2`: a 2x3 system `M u = h` over the rationals (every
//! `f64` is an exact dyadic rational). Its rank is decided exactly from the three 2x2 minors:
//!
//! - rank 2: pick the first non-zero minor in the order `(x, y)`, `(x, rho)`, `(y, rho)`; those two
//!   unknowns are affine in the remaining one `t` (`rho` unless the centres are collinear), so
//!   `u = u0 + t u1`. Substituting into `F_0` gives `A t^2 + B t + C = 0` with rational `A, B, C`;
//!   the roots lie in `Q(sqrt D)`, `D = B^2 - 4AC` (`D` a rational square is folded into the
//!   rational part, so a stored `D > 0` is never a square). `A = B = C = 0` is a continuum.
//! - rank <= 1: either inconsistent (no circle) or a continuum of circles
//!   ([`ApolloniusError::Continuum`]); this covers coincident sites and three equal circles in a
//!   row (whose "tangent circles" are the common tangent lines).
//!
//! A root is *valid* when `rho >= 0` and for every site `sigma_i = rho + s_i` has the site's sense:
//! `sigma_i >= 0` for a hole (`|p - c_i| = rho + r_i`, external tangency) and `sigma_i <= 0` for the
//! bounding circle (`|p - c_0| = R - rho`, internal tangency). All tests are exact.
//!
//! Tangent points: `a_i = p + rho (c_i - p) / sigma_i` (the unit vector `(c_i - p) / sigma_i`
//! points from `p` towards the tangent point, towards `c_i` for a hole and away from `c_0` for the
//! bounding circle), an element of `Q(sqrt D)` too since `|p - c_i| = |sigma_i|`. It is undefined
//! when `sigma_i = 0` and `rho > 0`, which for valid input means the circle *is* the bounding
//! circle. The orientation of a root is the orientation of its three unit vectors (equivalently
//! of its three tangent points when `rho > 0`): with `u_i = c_i - p` it is
//! `sign(sigma_0 sigma_1 sigma_2) * sign(sigma_2 u_0 x u_1 + sigma_0 u_1 x u_2 + sigma_1 u_2 x u_0)`,
//! and `Zero` when some `sigma_i = 0`.

use super::exact::{common_scale, dyadic, QSqrt, Sign, SqrtBracket, ZSqrt};
use super::fast;
use super::interval::Interval;
use super::Site;
use rug::{Integer, Rational};
use std::cmp::Ordering;
use std::sync::OnceLock;

/// Why the Apollonius solve (or a derived query) has no single answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ApolloniusError {
    /// A site has a non-finite centre coordinate or radius.
    #[error("a site has a non-finite centre or radius")]
    NonFinite,
    /// The three sites admit infinitely many tangent circles (coincident sites, or a degenerate
    /// configuration such as three concentric or otherwise dependent circles).
    #[error("the three sites admit a continuum of tangent circles")]
    Continuum,
    /// No circle is tangent to the three sites with the required senses (and orientation).
    #[error("no circle is tangent to the three sites with the required senses")]
    NoCircle,
    /// The circle is the bounding circle itself, so its tangent point there is undefined.
    #[error("tangent point undefined: the circle coincides with the bounding circle")]
    UndefinedTangentPoint,
}

/// One exact Apollonius circle of three sites: centre `(x, y)` and radius `rho` in `Q(sqrt D)`.
///
/// Stored in a common integer frame: each of `x, y, rho` is `2^exp (a + b sqrt(disc)) / den`
/// with integers `a, b`, a shared `den > 0` and an integer `disc >= 0` that is `0` or not a
/// perfect square. Built only by [`apollonius_roots`], so it is always a *valid* root (see the
/// module docs); the `f64` approximations are the correctly rounded values of the exact ones.
///
/// A root found by the certified fast path ([`apollonius`]) holds its rounded values and
/// orientation, and builds its integer frame only when a query needs it (the exact solve's
/// `index`-th valid root: the same root, see `fast.rs`).
#[derive(Debug, Clone)]
pub struct ExactApollonius {
    sites: [Site; 3],
    approx: [f64; 3],
    orientation: Sign,
    /// Position among the valid roots of the sites, by increasing radius.
    index: u8,
    frame: OnceLock<Frame>,
}

/// The integer frame of an exact root (see [`ExactApollonius`]).
#[derive(Debug, Clone, PartialEq)]
struct Frame {
    exp: i64,
    disc: Integer,
    den: Integer,
    num: [ZSqrt; 3],
}

/// Equal sites, rounded values, orientation and exact values (a lazily built frame is built
/// for the comparison).
impl PartialEq for ExactApollonius {
    fn eq(&self, o: &ExactApollonius) -> bool {
        self.sites == o.sites
            && self.approx == o.approx
            && self.orientation == o.orientation
            && self.f() == o.f()
    }
}

impl ExactApollonius {
    /// The three sites, in the order they were given.
    pub fn sites(&self) -> &[Site; 3] {
        &self.sites
    }
    /// The radicand `D >= 0` of [`x`](Self::x), [`y`](Self::y), [`rho`](Self::rho) (`0` when the
    /// root is rational; otherwise not the square of a rational).
    pub fn d(&self) -> Rational {
        Rational::from(&self.f().disc)
    }
    /// Centre x-coordinate, `a + b sqrt(D)`.
    pub fn x(&self) -> QSqrt {
        self.f().num[0].to_qsqrt(&self.f().den, self.f().exp)
    }
    /// Centre y-coordinate.
    pub fn y(&self) -> QSqrt {
        self.f().num[1].to_qsqrt(&self.f().den, self.f().exp)
    }
    /// Radius `rho >= 0`.
    pub fn rho(&self) -> QSqrt {
        self.f().num[2].to_qsqrt(&self.f().den, self.f().exp)
    }
    /// The correctly rounded centre.
    pub fn center_f64(&self) -> [f64; 2] {
        [self.approx[0], self.approx[1]]
    }
    /// The correctly rounded radius.
    pub fn radius_f64(&self) -> f64 {
        self.approx[2]
    }
    /// Orientation of the three tangent directions in site order (`Positive`: counter-clockwise
    /// around the centre); `Zero` when one is undefined.
    pub fn orientation(&self) -> Sign {
        self.orientation
    }

    /// Set the rounded centre and radius (`approx`) from the exact ones.
    fn round(&mut self, sq: Option<&SqrtBracket>) {
        let f = self.f();
        let approx = [0, 1, 2].map(|i| f.num[i].to_f64_with(&f.disc, &f.den, f.exp, sq));
        self.approx = approx;
    }

    /// The integer frame, built on first use for a root of the fast path.
    fn f(&self) -> &Frame {
        self.frame.get_or_init(|| {
            let roots = unrounded_roots(&self.sites).unwrap_or_default();
            let root = roots
                .into_iter()
                .nth(usize::from(self.index))
                .expect("the fast path's root is a root of the exact solve");
            debug_assert_eq!(root.orientation, self.orientation);
            root.frame
                .into_inner()
                .expect("exact roots carry their frame")
        })
    }

    /// The integer frame: `(exp, disc, den, [x, y, rho] numerators)`.
    pub(crate) fn frame(&self) -> (i64, &Integer, &Integer, &[ZSqrt; 3]) {
        (self.f().exp, &self.f().disc, &self.f().den, &self.f().num)
    }

    /// Numerators of `x, y, rho` and integers for `extra` values, in one frame of exponent
    /// `e' <= exp`: every returned number times `2^e' / den` (root) or `2^e'` (extra) is the value.
    pub(crate) fn rescaled(&self, extra: &[f64]) -> Option<([ZSqrt; 3], Vec<Integer>, i64)> {
        let vals = extra
            .iter()
            .map(|&v| dyadic(v))
            .collect::<Option<Vec<_>>>()?;
        let e = vals.iter().map(|v| v.1).fold(self.f().exp, i64::min);
        let (ints, _) = common_scale(&[vals, vec![(Integer::new(), e)]].concat());
        let up = (self.f().exp - e) as u32;
        let num = [
            self.f().num[0].shl(up),
            self.f().num[1].shl(up),
            self.f().num[2].shl(up),
        ];
        Some((num, ints[..extra.len()].to_vec(), e))
    }

    /// The tangent point on site `i` as a numerator over `den'` in this root's exponent:
    /// `a_i = p + rho (c_i - p) / sigma_i`, i.e. with `U = den c_i - P`, `S = R + den s_i`,
    /// `a_i = 2^exp (P N(S) + R U conj(S)) / (den N(S))`. `None` when undefined.
    ///
    /// The same value as [`ExactApollonius::tangent_point_frac_reference`] (tested), by the
    /// equivalent `a_i = c_i - s_i (c_i - p) / sigma_i` (`c_i - a_i = u (sigma_i - rho) /
    /// sigma_i`) over the smaller denominator `den' = N(S) 2^up`: with `C` the site's centre
    /// coordinate, `U = den C - P = Ua - Pb sqrt(D)` and `S = sa + Rb sqrt(D)`,
    /// `U conj(S) = (Ua sa + Pb Rb D) - (Ua Rb + Pb sa) sqrt(D)`, so the numerator is
    /// `C N(S) - s (Ua sa + Pb Rb D)` plus `s (Ua Rb + Pb sa) sqrt(D)`.
    #[doc(hidden)]
    pub fn tangent_point_frac(&self, i: usize) -> Option<([ZSqrt; 2], Integer)> {
        let site = self.sites.get(i)?;
        let vals = [
            dyadic(site.center[0])?,
            dyadic(site.center[1])?,
            dyadic(site.s)?,
        ];
        let e = vals.iter().map(|v| v.1).fold(self.f().exp, i64::min);
        let ints = vals.map(|(n, ei)| n << ((ei - e) as u32));
        let up = (self.f().exp - e) as u32;
        let shifted;
        let num = if up == 0 {
            &self.f().num
        } else {
            shifted = [0, 1, 2].map(|j| self.f().num[j].shl(up));
            &shifted
        };
        let d = &self.f().disc;
        let [px, py, r] = num;
        if r.sign(d) == Sign::Zero {
            return Some(([px.clone(), py.clone()], self.f().den.clone()));
        }
        let si = &ints[2];
        // S = R + den s_i: sa = R_a + den s_i, sb = R_b.
        let mut sa = Integer::from(&self.f().den * si);
        sa += &r.a;
        let rbd = Integer::from(&r.b * d);
        let mut n = Integer::from(sa.square_ref());
        n -= &rbd * &r.b;
        if n.cmp0() == Ordering::Equal {
            return None;
        }
        let coord = |p: &ZSqrt, c: &Integer| -> ZSqrt {
            let mut ua = Integer::from(&self.f().den * c);
            ua -= &p.a;
            let mut t = Integer::from(&ua * &sa);
            t += &p.b * &rbd;
            t *= si;
            let mut a = Integer::from(c * &n);
            a -= &t;
            let mut b = Integer::from(&ua * &r.b);
            b += &p.b * &sa;
            b *= si;
            ZSqrt::new(a, b)
        };
        let (mut ax, mut ay) = (coord(px, &ints[0]), coord(py, &ints[1]));
        if n.cmp0() == Ordering::Less {
            n = -n;
            for z in [&mut ax, &mut ay] {
                z.a = -std::mem::take(&mut z.a);
                z.b = -std::mem::take(&mut z.b);
            }
        }
        // The frame exponent e may be below exp: scale the denominator to compensate.
        n <<= up;
        Some(([ax, ay], n))
    }

    /// [`ExactApollonius::tangent_point_frac`] by the plain `ZSqrt` formula (the test oracle).
    #[doc(hidden)]
    pub fn tangent_point_frac_reference(&self, i: usize) -> Option<([ZSqrt; 2], Integer)> {
        let site = self.sites.get(i)?;
        let (num, ints, e) = self.rescaled(&[site.center[0], site.center[1], site.s])?;
        let d = &self.f().disc;
        let [px, py, r] = num;
        if r.sign(d) == Sign::Zero {
            return Some(([px, py], self.f().den.clone()));
        }
        let sig = r.add_int(&Integer::from(&self.f().den * &ints[2]));
        let n = sig.norm(d);
        if n.cmp0() == Ordering::Equal {
            return None;
        }
        let f = r.mul(&sig.conj(), d);
        let coord = |p: &ZSqrt, c: &Integer| -> ZSqrt {
            let u = ZSqrt::int(Integer::from(&self.f().den * c)) - p;
            &p.scale(&n) + &u.mul(&f, d)
        };
        let (mut ax, mut ay) = (coord(&px, &ints[0]), coord(&py, &ints[1]));
        let mut den = Integer::from(&self.f().den * &n);
        if den.cmp0() == Ordering::Less {
            den = -den;
            ax = ZSqrt::new(-ax.a, -ax.b);
            ay = ZSqrt::new(-ay.a, -ay.b);
        }
        // The frame exponent e may be below exp: scale the denominator to compensate.
        let fix = (self.f().exp - e) as u32;
        Some(([ax, ay], den << fix))
    }

    /// The orientation recomputed by the plain `ZSqrt` products (the test oracle of the in-place
    /// sum [`orientation_sum`] and of [`orientation_filter`]): `(reference sum == in-place sum,
    /// orientation, the filter's sign of the sum if it decided, the exact sign of the sum)`.
    #[doc(hidden)]
    pub fn orientation_reference(&self) -> Option<(bool, Sign, Option<Sign>, Sign)> {
        let mut vals = Vec::with_capacity(9);
        for s in &self.sites {
            for v in [s.center[0], s.center[1], s.s] {
                vals.push(dyadic(v)?);
            }
        }
        let (ints, exp) = common_scale(&vals);
        if exp != self.f().exp {
            return None;
        }
        let q: [[Integer; 3]; 3] = [0, 1, 2].map(|i| [0, 1, 2].map(|c| ints[3 * i + c].clone()));
        let d = &self.f().disc;
        let sig: Vec<ZSqrt> = q
            .iter()
            .map(|qi| self.f().num[2].add_int(&Integer::from(&self.f().den * &qi[2])))
            .collect();
        let signs: Vec<Sign> = sig.iter().map(|s| s.sign(d)).collect();
        if signs.contains(&Sign::Zero) {
            return Some((true, Sign::Zero, None, Sign::Zero));
        }
        let reference = orientation_sum_reference(&q, &self.f().den, &self.f().num, &sig, d);
        let fast = orientation_sum(&q, &self.f().den, &self.f().num, &sig, d);
        let exact = reference.sign(d);
        let o = exact.times(signs[0].times(signs[1]).times(signs[2]));
        let filter = orientation_filter(&q, &self.f().den, &self.f().num, d);
        Some((reference == fast, o, filter, exact))
    }

    /// The exact tangent point on site `i` (`None` when undefined: the circle is the bounding
    /// circle). For `rho = 0` it is the centre. (By the reference formula: a test oracle.)
    pub fn tangent_point_exact(&self, i: usize) -> Option<[QSqrt; 2]> {
        let ([ax, ay], den) = self.tangent_point_frac_reference(i)?;
        Some([
            ax.to_qsqrt(&den, self.f().exp),
            ay.to_qsqrt(&den, self.f().exp),
        ])
    }

    /// The rounded [`Apollonius`] circle with its tangent points.
    pub fn to_apollonius(&self) -> Result<Apollonius, ApolloniusError> {
        self.to_apollonius_with(None)
    }

    /// [`ExactApollonius::to_apollonius`] with the first bracket of `sqrt(D)` given (the same
    /// values).
    fn to_apollonius_with(&self, sq: Option<&SqrtBracket>) -> Result<Apollonius, ApolloniusError> {
        let tangent_points = self.rounded_tangent_points(sq)?;
        Ok(Apollonius {
            center: self.center_f64(),
            radius: self.radius_f64(),
            tangent_points,
            exact: self.clone(),
        })
    }

    /// [`ExactApollonius::to_apollonius_with`], moving the exact root into the result instead
    /// of cloning it.
    fn into_apollonius_with(self, sq: Option<&SqrtBracket>) -> Result<Apollonius, ApolloniusError> {
        let tangent_points = self.rounded_tangent_points(sq)?;
        Ok(Apollonius {
            center: self.center_f64(),
            radius: self.radius_f64(),
            tangent_points,
            exact: self,
        })
    }

    /// The correctly rounded tangent points (first bracket of `sqrt(D)` given, or `None`).
    fn rounded_tangent_points(
        &self,
        sq: Option<&SqrtBracket>,
    ) -> Result<[[f64; 2]; 3], ApolloniusError> {
        let mut tangent_points = [[0.0; 2]; 3];
        for (i, t) in tangent_points.iter_mut().enumerate() {
            let ([ax, ay], den) = self
                .tangent_point_frac(i)
                .ok_or(ApolloniusError::UndefinedTangentPoint)?;
            *t = [
                ax.to_f64_with(&self.f().disc, &den, self.f().exp, sq),
                ay.to_f64_with(&self.f().disc, &den, self.f().exp, sq),
            ];
        }
        Ok(tangent_points)
    }
}

/// An Apollonius circle rounded to `f64` (each value correctly rounded from the exact one).
#[derive(Debug, Clone, PartialEq)]
pub struct Apollonius {
    pub center: [f64; 2],
    pub radius: f64,
    /// Tangent point on each site, in site order.
    pub tangent_points: [[f64; 2]; 3],
    pub exact: ExactApollonius,
}

/// How to pick one root when the three sites have two valid Apollonius circles.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Choice {
    /// Keep only roots whose tangent points, in site order, have this orientation (`Positive`:
    /// counter-clockwise around the centre, as the vertices of a CCW Delaunay triangle).
    pub orientation: Option<Sign>,
    /// Among the remaining roots prefer the one whose centre is nearest to this point (e.g. the
    /// Delaunay triangle's circumcentre). Compared exactly; ignored if not finite.
    pub hint: Option<[f64; 2]>,
}

impl Choice {
    /// Any valid root; with two, the smaller radius.
    pub fn any() -> Choice {
        Choice::default()
    }
    /// Tangent points counter-clockwise in site order.
    pub fn ccw() -> Choice {
        Choice {
            orientation: Some(Sign::Positive),
            hint: None,
        }
    }
    /// Prefer the root nearest `hint`.
    #[must_use]
    pub fn near(mut self, hint: [f64; 2]) -> Choice {
        self.hint = Some(hint);
        self
    }
}

/// 2x2 determinant of two columns.
fn det(a: [&Integer; 2], b: [&Integer; 2]) -> Integer {
    let mut v = Integer::from(a[0] * b[1]);
    v -= a[1] * b[0];
    v
}

/// Lorentz form `<u, v> = u_x v_x + u_y v_y - u_r v_r`.
fn lorentz(u: &[Integer; 3], v: &[Integer; 3]) -> Integer {
    let mut l = Integer::from(&u[0] * &v[0]);
    l += &u[1] * &v[1];
    l -= &u[2] * &v[2];
    l
}

/// All valid Apollonius circles of three sites (0, 1 or 2), by increasing radius.
///
/// Computed in integers: all nine inputs are scaled by one power of two to integers
/// `X_i, Y_i, S_i`; then `2 (X_j - X_0, Y_j - Y_0, S_j - S_0) . u = K_j - K_0` with minor `m`
/// gives `m u = U0 + t U1` (integer vectors), and `m^2 F_0 = A t^2 + B t + C` with integers
/// `A = <U1, U1>`, `B = 2 <E, U1>`, `C = <E, E>`, `E = U0 - m (X_0, Y_0, -S_0)` in the Lorentz
/// form `<u, v> = u_x v_x + u_y v_y - u_r v_r`. A root `t = (-B ± sqrt(disc)) / 2A` gives
/// `u = (2A U0 - B U1 ± U1 sqrt(disc)) / (2A m)`.
pub fn apollonius_roots(sites: &[Site; 3]) -> Result<Vec<ExactApollonius>, ApolloniusError> {
    let mut roots = unrounded_roots(sites)?;
    for r in &mut roots {
        r.round(None);
    }
    Ok(roots)
}

/// [`apollonius_roots`] without the rounded values (`approx` is left at zero until
/// [`ExactApollonius::round`]): the roots `choose` drops are never rounded.
fn unrounded_roots(sites: &[Site; 3]) -> Result<Vec<ExactApollonius>, ApolloniusError> {
    let mut vals = Vec::with_capacity(9);
    for s in sites {
        for v in [s.center[0], s.center[1], s.s] {
            vals.push(dyadic(v).ok_or(ApolloniusError::NonFinite)?);
        }
    }
    let (ints, exp) = common_scale(&vals);
    let q: [[Integer; 3]; 3] = [0, 1, 2].map(|i| [0, 1, 2].map(|c| ints[3 * i + c].clone()));
    let k = |i: usize| -> Integer {
        let [x, y, s] = &q[i];
        let mut k = Integer::from(x.square_ref());
        k += y * y;
        k -= s * s;
        k
    };
    let k0 = k(0);
    let mut m: [[Integer; 3]; 2] = Default::default();
    let mut h: [Integer; 2] = Default::default();
    for j in 0..2 {
        for c in 0..3 {
            m[j][c] = Integer::from(&q[j + 1][c] - &q[0][c]) << 1u32;
        }
        h[j] = k(j + 1) - &k0;
    }
    let col = |c: usize| -> [&Integer; 2] { [&m[0][c], &m[1][c]] };
    let hcol = [&h[0], &h[1]];
    let pivot = [(0usize, 1usize, 2usize), (0, 2, 1), (1, 2, 0)]
        .into_iter()
        .map(|(p, r, f)| (p, r, f, det(col(p), col(r))))
        .find(|t| t.3.cmp0() != Ordering::Equal);
    let Some((pc, qc, fc, minor)) = pivot else {
        // Rank <= 1: consistent iff every minor of the augmented matrix vanishes.
        let rows_zero = m.iter().flatten().all(|v| v.cmp0() == Ordering::Equal);
        let consistent = if rows_zero {
            h.iter().all(|v| v.cmp0() == Ordering::Equal)
        } else {
            (0..3).all(|c| det(col(c), hcol).cmp0() == Ordering::Equal)
        };
        return if consistent {
            Err(ApolloniusError::Continuum)
        } else {
            Ok(Vec::new())
        };
    };
    let mut u0: [Integer; 3] = Default::default();
    let mut u1: [Integer; 3] = Default::default();
    u0[pc] = det(hcol, col(qc));
    u1[pc] = -det(col(fc), col(qc));
    u0[qc] = det(col(pc), hcol);
    u1[qc] = -det(col(pc), col(fc));
    u1[fc] = minor.clone();
    let e = [
        Integer::from(&u0[0] - &minor * &q[0][0]),
        Integer::from(&u0[1] - &minor * &q[0][1]),
        Integer::from(&u0[2] + &minor * &q[0][2]),
    ];
    let a = lorentz(&u1, &u1);
    let b = lorentz(&e, &u1) << 1u32;
    let c = lorentz(&e, &e);
    // Candidate roots: (numerators, den, disc) with u = num / den.
    let combine = |p: &Integer, r: &Integer, i: usize| -> Integer {
        let mut v = Integer::from(p * &u0[i]);
        v += r * &u1[i];
        v
    };
    let mut cands: Vec<([ZSqrt; 3], Integer, Integer)> = Vec::new();
    if a.cmp0() == Ordering::Equal {
        if b.cmp0() == Ordering::Equal {
            if c.cmp0() == Ordering::Equal {
                return Err(ApolloniusError::Continuum);
            }
        } else {
            // t = -C/B: u = (B U0 - C U1) / (B m).
            let nc = Integer::from(-&c);
            let num = [0, 1, 2].map(|i| ZSqrt::int(combine(&b, &nc, i)));
            cands.push((num, Integer::from(&b * &minor), Integer::new()));
        }
    } else {
        let disc = Integer::from(b.square_ref()) - Integer::from(&a * &c) * 4u32;
        let two_a = Integer::from(&a << 1u32);
        let den = Integer::from(&two_a * &minor);
        let nb = Integer::from(-&b);
        match disc.cmp0() {
            Ordering::Less => {}
            Ordering::Equal => {
                let num = [0, 1, 2].map(|i| ZSqrt::int(combine(&two_a, &nb, i)));
                cands.push((num, den, Integer::new()));
            }
            Ordering::Greater => {
                // GMP's residue tests reject almost every non-square without a square root.
                if disc.is_perfect_square() {
                    let root = Integer::from(disc.sqrt_ref());
                    for r in [Integer::from(&nb - &root), Integer::from(&nb + &root)] {
                        let num = [0, 1, 2].map(|i| ZSqrt::int(combine(&two_a, &r, i)));
                        cands.push((num, den.clone(), Integer::new()));
                    }
                } else {
                    for sgn in [-1i32, 1] {
                        let num = [0, 1, 2].map(|i| {
                            ZSqrt::new(combine(&two_a, &nb, i), Integer::from(&u1[i] * sgn))
                        });
                        cands.push((num, den.clone(), disc.clone()));
                    }
                }
            }
        }
    }
    let mut roots: Vec<ExactApollonius> = cands
        .into_iter()
        .filter_map(|(num, den, disc)| build_root(sites, &q, exp, disc, den, num))
        .collect();
    // Roots of one solve share den and disc (both positive after normalisation).
    roots.sort_by(|r1, r2| Ordering::from((&r1.f().num[2] - &r2.f().num[2]).sign(&r1.f().disc)));
    for (i, r) in roots.iter_mut().enumerate() {
        r.index = i as u8;
    }
    Ok(roots)
}

/// Validate a candidate root and compute its orientation (not its rounded values).
fn build_root(
    sites: &[Site; 3],
    q: &[[Integer; 3]; 3],
    exp: i64,
    disc: Integer,
    mut den: Integer,
    mut num: [ZSqrt; 3],
) -> Option<ExactApollonius> {
    if den.cmp0() == Ordering::Less {
        den = -den;
        num = num.map(|z| ZSqrt::new(-z.a, -z.b));
    }
    let d = &disc;
    if num[2].sign(d) == Sign::Negative {
        return None;
    }
    // den sigma_i / 2^exp = R + den S_i.
    let sig: Vec<ZSqrt> = q
        .iter()
        .map(|qi| num[2].add_int(&Integer::from(&den * &qi[2])))
        .collect();
    let sig_signs: Vec<Sign> = sig.iter().map(|s| s.sign(d)).collect();
    for (site, s) in sites.iter().zip(&sig_signs) {
        let ok = match s {
            Sign::Zero => true,
            Sign::Positive => !site.is_bounding(),
            Sign::Negative => site.is_bounding(),
        };
        if !ok {
            return None;
        }
    }
    let orientation = if sig_signs.contains(&Sign::Zero) {
        Sign::Zero
    } else {
        let den_sign = sig_signs[0].times(sig_signs[1]).times(sig_signs[2]);
        orientation_filter(q, &den, &num, d)
            .unwrap_or_else(|| orientation_sum(q, &den, &num, &sig, d).sign(d))
            .times(den_sign)
    };
    Some(ExactApollonius {
        sites: *sites,
        approx: [0.0; 3],
        orientation,
        index: 0,
        frame: OnceLock::from(Frame {
            exp,
            disc,
            den,
            num,
        }),
    })
}

/// `sigma_2 u_0 x u_1 + sigma_0 u_1 x u_2 + sigma_1 u_2 x u_0` (times `den^3 / 8^exp`), with
/// `U_i = den c_i - P = (A_i - Bx sqrt(D), C_i - By sqrt(D))` (`P = num[0..2]`, the `sqrt(D)`
/// parts shared by every `i`), so that `U_i x U_j = (A_i C_j - C_i A_j) + den (By (x_j - x_i) -
/// Bx (y_j - y_i)) sqrt(D)` (the `D` terms cancel), and every `sigma_k = sa_k + R_b sqrt(D)`
/// shares `R_b`. The same number as [`orientation_sum_reference`] (tested through
/// [`ExactApollonius::orientation_reference`]), accumulated in place.
fn orientation_sum(
    q: &[[Integer; 3]; 3],
    den: &Integer,
    num: &[ZSqrt; 3],
    sig: &[ZSqrt],
    d: &Integer,
) -> ZSqrt {
    let coord = |i: usize, c: usize| -> Integer {
        let mut v = Integer::from(den * &q[i][c]);
        v -= &num[c].a;
        v
    };
    let a = [coord(0, 0), coord(1, 0), coord(2, 0)];
    let c = [coord(0, 1), coord(1, 1), coord(2, 1)];
    let (bx, by, rb) = (&num[0].b, &num[1].b, &num[2].b);
    let (mut acc_a, mut acc_b) = (Integer::new(), Integer::new());
    let (mut sum_ca, mut sum_cb) = (Integer::new(), Integer::new());
    for (k, i, j) in [(2, 0, 1), (0, 1, 2), (1, 2, 0)] {
        let mut ca = Integer::from(&a[i] * &c[j]);
        ca -= &c[i] * &a[j];
        let dx = Integer::from(&q[j][0] - &q[i][0]);
        let dy = Integer::from(&q[j][1] - &q[i][1]);
        let mut cb = Integer::from(by * &dx);
        cb -= bx * &dy;
        cb *= den;
        acc_a += &sig[k].a * &ca;
        acc_b += &sig[k].a * &cb;
        sum_ca += &ca;
        sum_cb += &cb;
    }
    let mut t = Integer::from(rb * &sum_cb);
    t *= d;
    acc_a += &t;
    acc_b += rb * &sum_ca;
    ZSqrt::new(acc_a, acc_b)
}

/// The sign of [`orientation_sum`] when interval arithmetic decides it (`None` otherwise): the
/// same sum over `den^3`, `sum_k sigma_k (c_i - p) x (c_j - p)` in units of `2^exp`, from
/// intervals around the integers (`p = (a + b sqrt(D)) / den`, `sigma_k = rho + s_k`). Every
/// interval contains the exact value, so a decided sign is exact (tested against the exact
/// sign through [`ExactApollonius::orientation_reference`]).
fn orientation_filter(
    q: &[[Integer; 3]; 3],
    den: &Integer,
    num: &[ZSqrt; 3],
    d: &Integer,
) -> Option<Sign> {
    let iv = Interval::of_integer;
    let sq = iv(d)?.sqrt();
    let den = iv(den)?;
    let val = |z: &ZSqrt| -> Option<Interval> {
        Some(iv(&z.a)?.add(iv(&z.b)?.mul(sq)).div_positive(den))
    };
    let (px, py, rho) = (val(&num[0])?, val(&num[1])?, val(&num[2])?);
    let mut u = [[Interval::point(0.0); 2]; 3];
    let mut sig = [Interval::point(0.0); 3];
    for i in 0..3 {
        u[i] = [iv(&q[i][0])?.sub(px), iv(&q[i][1])?.sub(py)];
        sig[i] = rho.add(iv(&q[i][2])?);
    }
    let cross = |a: &[Interval; 2], b: &[Interval; 2]| a[0].mul(b[1]).sub(a[1].mul(b[0]));
    let total = sig[2]
        .mul(cross(&u[0], &u[1]))
        .add(sig[0].mul(cross(&u[1], &u[2])))
        .add(sig[1].mul(cross(&u[2], &u[0])));
    total.sign()
}

/// [`orientation_sum`] by the plain `ZSqrt` products (the test oracle).
fn orientation_sum_reference(
    q: &[[Integer; 3]; 3],
    den: &Integer,
    num: &[ZSqrt; 3],
    sig: &[ZSqrt],
    d: &Integer,
) -> ZSqrt {
    // den (c_i - p) / 2^exp.
    let u: Vec<[ZSqrt; 2]> = q
        .iter()
        .map(|qi| {
            [
                ZSqrt::int(Integer::from(den * &qi[0])) - &num[0],
                ZSqrt::int(Integer::from(den * &qi[1])) - &num[1],
            ]
        })
        .collect();
    let cross =
        |a: &[ZSqrt; 2], b: &[ZSqrt; 2]| -> ZSqrt { &a[0].mul(&b[1], d) - &a[1].mul(&b[0], d) };
    let t0 = sig[2].mul(&cross(&u[0], &u[1]), d);
    let t1 = sig[0].mul(&cross(&u[1], &u[2]), d);
    let t2 = sig[1].mul(&cross(&u[2], &u[0]), d);
    &(&t0 + &t1) + &t2
}

/// Pick one root per `choice`: filter by orientation, then nearest to the hint (exact
/// comparison of squared distances), then the smaller radius. `None` when no root remains.
pub fn choose(roots: Vec<ExactApollonius>, choice: Choice) -> Option<ExactApollonius> {
    let mut kept: Vec<ExactApollonius> = roots
        .into_iter()
        .filter(|r| choice.orientation.is_none_or(|o| r.orientation == o))
        .collect();
    if kept.len() >= 2 {
        if let Some(h) = choice.hint {
            // den^2 |p - h|^2 / 4^e in each root's rescaled frame; roots of one solve share
            // exp, den and disc, so the frames agree.
            let dist2 = |r: &ExactApollonius| -> Option<ZSqrt> {
                let (num, hs, _) = r.rescaled(&h)?;
                let dx = num[0].add_int(&(-Integer::from(&r.f().den * &hs[0])));
                let dy = num[1].add_int(&(-Integer::from(&r.f().den * &hs[1])));
                Some(&dx.square(&r.f().disc) + &dy.square(&r.f().disc))
            };
            let keyed: Option<Vec<ZSqrt>> = kept.iter().map(dist2).collect();
            if let Some(keys) = keyed {
                let mut idx: Vec<usize> = (0..kept.len()).collect();
                let disc = kept[0].f().disc.clone();
                // Stable: ties keep the smaller radius first.
                idx.sort_by(|&i, &j| Ordering::from((&keys[i] - &keys[j]).sign(&disc)));
                let first = idx[0];
                return Some(kept.swap_remove(first));
            }
        }
    }
    kept.into_iter().next()
}

/// The Apollonius circle of three sites selected by `choice`, rounded, with tangent points.
///
/// First by the certified double-double path ([`apollonius_fast`], about a tenth of the exact
/// solve's work; issue 8), which answers nearly every call; otherwise by the exact solve
/// ([`apollonius_exact`]). The same values either way: those of
/// `choose(apollonius_roots(&sites)?, choice)?.to_apollonius()` (tested in
/// `tests/apollonius_solve.rs` and `tests/perf_apollonius_fast.rs`).
pub fn apollonius(sites: [Site; 3], choice: Choice) -> Result<Apollonius, ApolloniusError> {
    match apollonius_fast(sites, choice) {
        Some(ap) => Ok(ap),
        None => apollonius_exact(sites, choice),
    }
}

/// The certified fast path of [`apollonius`] alone (`fast.rs`): `Some` only when every
/// decision and rounding is certain, and then equal to [`apollonius_exact`] (its exact root
/// is built from the exact solve on first use).
#[doc(hidden)]
pub fn apollonius_fast(sites: [Site; 3], choice: Choice) -> Option<Apollonius> {
    let f = fast::solve(&sites, choice)?;
    Some(Apollonius {
        center: [f.approx[0], f.approx[1]],
        radius: f.approx[2],
        tangent_points: f.tangent_points,
        exact: ExactApollonius {
            sites,
            approx: f.approx,
            orientation: f.orientation,
            index: f.index,
            frame: OnceLock::new(),
        },
    })
}

/// [`apollonius`] by the exact solve alone (the fallback of the certified fast path, and its
/// test oracle).
///
/// Only the chosen root is rounded, and all its roundings share one square root of `D`.
#[doc(hidden)]
pub fn apollonius_exact(sites: [Site; 3], choice: Choice) -> Result<Apollonius, ApolloniusError> {
    let roots = unrounded_roots(&sites)?;
    let mut root = choose(roots, choice).ok_or(ApolloniusError::NoCircle)?;
    let sq = SqrtBracket::new(&root.f().disc);
    root.round(sq.as_ref());
    root.into_apollonius_with(sq.as_ref())
}
