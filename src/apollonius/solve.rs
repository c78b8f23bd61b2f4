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

use super::exact::{QSqrt, Sign};
use super::Site;
use rug::Rational;
use std::cmp::Ordering;

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
/// Built only by [`apollonius_roots`], so it is always a *valid* root (see the module docs); the
/// `f64` approximations are the correctly rounded values of the exact ones.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactApollonius {
    sites: [Site; 3],
    d: Rational,
    x: QSqrt,
    y: QSqrt,
    rho: QSqrt,
    approx: [f64; 3],
    orientation: Sign,
}

impl ExactApollonius {
    /// The three sites, in the order they were given.
    pub fn sites(&self) -> &[Site; 3] {
        &self.sites
    }
    /// The shared radicand `D >= 0` (`0` when the root is rational).
    pub fn d(&self) -> &Rational {
        &self.d
    }
    /// Centre x-coordinate, `a + b sqrt(D)`.
    pub fn x(&self) -> &QSqrt {
        &self.x
    }
    /// Centre y-coordinate.
    pub fn y(&self) -> &QSqrt {
        &self.y
    }
    /// Radius `rho >= 0`.
    pub fn rho(&self) -> &QSqrt {
        &self.rho
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

    /// `sigma_i = rho + s_i` for site `i`, exactly.
    fn sigma(&self, s: &Rational) -> QSqrt {
        self.rho.add_rational(s)
    }

    /// The exact tangent point on site `i` (`None` when undefined: the circle is the bounding
    /// circle). For `rho = 0` it is the centre.
    pub fn tangent_point_exact(&self, i: usize) -> Option<[QSqrt; 2]> {
        let site = self.sites.get(i)?;
        let [cx, cy, s] = site.rationals().ok()?;
        if self.rho.sign(&self.d) == Sign::Zero {
            return Some([self.x.clone(), self.y.clone()]);
        }
        let inv = self.sigma(&s).inv(&self.d)?;
        let f = self.rho.mul(&inv, &self.d);
        let ux = QSqrt::rational(cx) - &self.x;
        let uy = QSqrt::rational(cy) - &self.y;
        let ax = &self.x + &ux.mul(&f, &self.d);
        let ay = &self.y + &uy.mul(&f, &self.d);
        Some([ax, ay])
    }

    /// The rounded [`Apollonius`] circle with its tangent points.
    pub fn to_apollonius(&self) -> Result<Apollonius, ApolloniusError> {
        let mut tangent_points = [[0.0; 2]; 3];
        for (i, t) in tangent_points.iter_mut().enumerate() {
            let [ax, ay] = self
                .tangent_point_exact(i)
                .ok_or(ApolloniusError::UndefinedTangentPoint)?;
            *t = [ax.to_f64(&self.d), ay.to_f64(&self.d)];
        }
        Ok(Apollonius {
            center: self.center_f64(),
            radius: self.radius_f64(),
            tangent_points,
            exact: self.clone(),
        })
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

/// All valid Apollonius circles of three sites (0, 1 or 2), by increasing radius.
pub fn apollonius_roots(sites: &[Site; 3]) -> Result<Vec<ExactApollonius>, ApolloniusError> {
    let q: [[Rational; 3]; 3] = [
        sites[0].rationals()?,
        sites[1].rationals()?,
        sites[2].rationals()?,
    ];
    let k = |i: usize| -> Rational {
        let [x, y, s] = &q[i];
        Rational::from(x.square_ref()) + Rational::from(y.square_ref())
            - Rational::from(s.square_ref())
    };
    let k0 = k(0);
    // Rows of M and right-hand side h.
    let mut m: [[Rational; 3]; 2] = Default::default();
    let mut h: [Rational; 2] = Default::default();
    for j in 0..2 {
        for c in 0..3 {
            m[j][c] = Rational::from(&q[j + 1][c] - &q[0][c]);
        }
        h[j] = (k(j + 1) - &k0) / 2u32;
    }
    // 2x2 determinant of columns a, b (as [row0, row1]).
    let det = |a: [&Rational; 2], b: [&Rational; 2]| -> Rational {
        Rational::from(a[0] * b[1]) - Rational::from(a[1] * b[0])
    };
    let col = |c: usize| -> [&Rational; 2] { [&m[0][c], &m[1][c]] };
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
    // u_p = (det(h, M_q) - t det(M_f, M_q)) / minor, u_q = (det(M_p, h) - t det(M_p, M_f)) / minor.
    let mut u0: [Rational; 3] = Default::default();
    let mut u1: [Rational; 3] = Default::default();
    u0[pc] = det(hcol, col(qc)) / &minor;
    u1[pc] = -(det(col(fc), col(qc)) / &minor);
    u0[qc] = det(col(pc), hcol) / &minor;
    u1[qc] = -(det(col(pc), col(fc)) / &minor);
    u1[fc] = Rational::from(1);
    // F_0(u0 + t u1) = A t^2 + B t + C with e = u0 - (x_0, y_0, -s_0).
    let e = [
        Rational::from(&u0[0] - &q[0][0]),
        Rational::from(&u0[1] - &q[0][1]),
        Rational::from(&u0[2] + &q[0][2]),
    ];
    let dot = |a: &[Rational; 3], b: &[Rational; 3]| -> Rational {
        Rational::from(&a[0] * &b[0]) + Rational::from(&a[1] * &b[1])
            - Rational::from(&a[2] * &b[2])
    };
    let a = dot(&u1, &u1);
    let b = dot(&e, &u1) * 2u32;
    let c = dot(&e, &e);
    let zero = Rational::new();
    // Roots t = ta + tb sqrt(D).
    let mut ts: Vec<(QSqrt, Rational)> = Vec::new();
    if a.cmp0() == Ordering::Equal {
        if b.cmp0() == Ordering::Equal {
            if c.cmp0() == Ordering::Equal {
                return Err(ApolloniusError::Continuum);
            }
        } else {
            ts.push((QSqrt::rational(-(c / &b)), zero.clone()));
        }
    } else {
        let disc = Rational::from(b.square_ref()) - Rational::from(&a * &c) * 4u32;
        let two_a = Rational::from(&a * 2u32);
        let mid = -Rational::from(&b / &two_a);
        match disc.cmp0() {
            Ordering::Less => {}
            Ordering::Equal => ts.push((QSqrt::rational(mid), zero.clone())),
            Ordering::Greater => {
                if disc.numer().is_perfect_square() && disc.denom().is_perfect_square() {
                    let r =
                        Rational::from((disc.numer().clone().sqrt(), disc.denom().clone().sqrt()));
                    let off = r / &two_a;
                    ts.push((QSqrt::rational(Rational::from(&mid - &off)), zero.clone()));
                    ts.push((QSqrt::rational(mid + off), zero.clone()));
                } else {
                    let off = two_a.recip();
                    ts.push((QSqrt::new(mid.clone(), Rational::from(-&off)), disc.clone()));
                    ts.push((QSqrt::new(mid, off), disc));
                }
            }
        }
    }
    let mut roots: Vec<ExactApollonius> = ts
        .into_iter()
        .filter_map(|(t, d)| {
            let coord = |i: usize| t.scale(&u1[i]).add_rational(&u0[i]);
            build_root(sites, &q, d, coord(0), coord(1), coord(2))
        })
        .collect();
    roots.sort_by(|r1, r2| {
        let d = &r1.rho - &r2.rho;
        Ordering::from(d.sign(&r1.d))
    });
    Ok(roots)
}

/// Validate a candidate root and compute its orientation and rounded values.
fn build_root(
    sites: &[Site; 3],
    q: &[[Rational; 3]; 3],
    d: Rational,
    x: QSqrt,
    y: QSqrt,
    rho: QSqrt,
) -> Option<ExactApollonius> {
    if rho.sign(&d) == Sign::Negative {
        return None;
    }
    let mut sig: Vec<QSqrt> = Vec::with_capacity(3);
    for (site, qi) in sites.iter().zip(q) {
        let sigma = rho.add_rational(&qi[2]);
        let ok = match sigma.sign(&d) {
            Sign::Zero => true,
            Sign::Positive => !site.is_bounding(),
            Sign::Negative => site.is_bounding(),
        };
        if !ok {
            return None;
        }
        sig.push(sigma);
    }
    let sig_signs: Vec<Sign> = sig.iter().map(|s| s.sign(&d)).collect();
    let orientation = if sig_signs.contains(&Sign::Zero) {
        Sign::Zero
    } else {
        let u: Vec<[QSqrt; 2]> = q
            .iter()
            .map(|qi| {
                [
                    QSqrt::rational(qi[0].clone()) - &x,
                    QSqrt::rational(qi[1].clone()) - &y,
                ]
            })
            .collect();
        let cross = |a: &[QSqrt; 2], b: &[QSqrt; 2]| -> QSqrt {
            &a[0].mul(&b[1], &d) - &a[1].mul(&b[0], &d)
        };
        let t0 = sig[2].mul(&cross(&u[0], &u[1]), &d);
        let t1 = sig[0].mul(&cross(&u[1], &u[2]), &d);
        let t2 = sig[1].mul(&cross(&u[2], &u[0]), &d);
        let total = &(&t0 + &t1) + &t2;
        let den = sig_signs[0].times(sig_signs[1]).times(sig_signs[2]);
        total.sign(&d).times(den)
    };
    let approx = [x.to_f64(&d), y.to_f64(&d), rho.to_f64(&d)];
    Some(ExactApollonius {
        sites: *sites,
        d,
        x,
        y,
        rho,
        approx,
        orientation,
    })
}

/// Pick one root per `choice`: filter by orientation, then nearest to the hint (exact
/// comparison of squared distances), then the smaller radius. `None` when no root remains.
pub fn choose(roots: Vec<ExactApollonius>, choice: Choice) -> Option<ExactApollonius> {
    let mut kept: Vec<ExactApollonius> = roots
        .into_iter()
        .filter(|r| choice.orientation.map_or(true, |o| r.orientation == o))
        .collect();
    let hint = choice
        .hint
        .and_then(|h| Some([Rational::from_f64(h[0])?, Rational::from_f64(h[1])?]));
    if let (Some(h), true) = (hint, kept.len() >= 2) {
        let dist2 = |r: &ExactApollonius| -> QSqrt {
            let dx = r.x.add_rational(&Rational::from(-&h[0]));
            let dy = r.y.add_rational(&Rational::from(-&h[1]));
            &dx.square(&r.d) + &dy.square(&r.d)
        };
        // Roots of one solve share D; stable sort keeps the smaller radius first on ties.
        kept.sort_by(|r1, r2| {
            let diff = &dist2(r1) - &dist2(r2);
            Ordering::from(diff.sign(&r1.d))
        });
    }
    kept.into_iter().next()
}

/// The Apollonius circle of three sites selected by `choice`, rounded, with tangent points.
pub fn apollonius(sites: [Site; 3], choice: Choice) -> Result<Apollonius, ApolloniusError> {
    let roots = apollonius_roots(&sites)?;
    choose(roots, choice)
        .ok_or(ApolloniusError::NoCircle)?
        .to_apollonius()
}
