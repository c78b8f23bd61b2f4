//! The certified fast path of [`super::apollonius`]: the same solve in double-double ball
//! arithmetic ([`super::ball`]), deciding every sign, the root choice and the correctly
//! rounded outputs when the balls are tight enough, and giving up (`None`) otherwise, so that
//! the exact solve ([`super::solve`]) answers.
//!
//! Written here for a reference site `0` (the code takes the site of smallest `|s|` as the
//! reference `k`, whose tangency is the best conditioned, and relabels): in the frame of its
//! centre (`P = p - c_0`, `d_j = c_j - c_0`, `e_j = s_j - s_0`), `F_j - F_0 = 0` reads
//! `d_j . P + e_j rho = h_j`, `h_j = (|d_j|^2 - e_j (s_j + s_0)) / 2`. With
//! `det = d_1 x d_2 != 0` (twice the signed area of the centres' triangle, for any reference;
//! the exact solve's first pivot, the `(x, y)` minor, is non-zero exactly then) Cramer gives
//! `P = Q_0 + rho Q_1`, and `F_0 = 0` becomes `A rho^2 + B rho + C = 0` with
//! `A = |Q_1|^2 - 1`, `B = 2 (Q_0 . Q_1 - s_0)`, `C = |Q_0|^2 - s_0^2`. The line `P(rho)` is the
//! solution set of the linear equations, which span the same space for every reference, and
//! `F_k - F_0` vanishes on it, so this is the same quadratic in `rho` for every reference: the
//! exact solve's quadratic in `t = rho` times a positive factor (`m^2` over powers of two).
//! The signs of `A` and of `D = B^2 - 4 A C` are therefore the exact ones.
//!
//! Every decision of the exact solve is taken here only when certified, else `None`:
//! - the pivot (`det` certainly non-zero), `A != 0` (else the exact solve's linear case),
//!   `D > 0` (two simple roots; `D <= 0` or undecided goes to the exact solve);
//! - validity of each root (`rho > 0`, each `sigma_i = rho + s_i` certainly non-zero with the
//!   site's sense), its orientation (the sign of the sum of `solve.rs`, which is invariant under
//!   translation), the order of the valid roots by radius, the root kept by the
//!   [`Choice`] (orientation, then the hint's certainly smaller distance);
//! - every output is the `f64` nearest to every value of its ball ([`Ball::round`]), which is
//!   the exact solve's correctly rounded value; zero, subnormal and near-midpoint values give
//!   up.
//!
//! Because each decision equals the exact one, the kept root is the `index`-th valid root of
//! the exact solve in order of radius: its exact form is recomputed from that index when asked
//! for (tested against the exact solve in `tests/perf_apollonius_fast.rs`).

use super::ball::Ball;
use super::exact::Sign;
use super::solve::Choice;
use super::Site;

/// The certified answer of the fast path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FastRoot {
    /// Correctly rounded `x`, `y`, `rho`.
    pub approx: [f64; 3],
    pub tangent_points: [[f64; 2]; 3],
    pub orientation: Sign,
    /// Position of the kept root among the exact solve's valid roots (by increasing radius).
    pub index: u8,
}

/// Inputs the fast path takes: finite, and zero or of magnitude in `[2^-200, 2^200]` (far from
/// overflow and underflow through the degree-eight expressions below).
fn in_range(v: f64) -> bool {
    v == 0.0
        || (v.is_finite() && (6.223015277861142e-61..=1.6069380442589903e60).contains(&v.abs()))
}

/// One candidate root with its certified properties.
struct Cand {
    rho: Ball,
    p: [Ball; 2],
    sigma: [Ball; 3],
    orientation: Sign,
}

/// `a x b` for two ball vectors.
fn cross(a: [Ball; 2], b: [Ball; 2]) -> Ball {
    a[0].mul(b[1]).sub(a[1].mul(b[0]))
}

/// Validate the root `rho` (certified, `None` when undecided): `Some(None)` when it is not a
/// valid root, `Some(Some(c))` when it is.
fn candidate(
    sites: &[Site; 3],
    d: &[[Ball; 2]; 3],
    q0: [Ball; 2],
    q1: [Ball; 2],
    rho: Ball,
) -> Option<Option<Cand>> {
    if rho.sign()? == Sign::Negative {
        return Some(None);
    }
    let p = [q0[0].add(rho.mul(q1[0])), q0[1].add(rho.mul(q1[1]))];
    let mut sigma = [rho; 3];
    let mut signs = [Sign::Zero; 3];
    for i in 0..3 {
        sigma[i] = rho.add(Ball::exact(sites[i].s));
        signs[i] = sigma[i].sign()?;
        let ok = match signs[i] {
            Sign::Positive => !sites[i].is_bounding(),
            _ => sites[i].is_bounding(),
        };
        if !ok {
            return Some(None);
        }
    }
    let u = [0, 1, 2].map(|i| [d[i][0].sub(p[0]), d[i][1].sub(p[1])]);
    let sum = sigma[2]
        .mul(cross(u[0], u[1]))
        .add(sigma[0].mul(cross(u[1], u[2])))
        .add(sigma[1].mul(cross(u[2], u[0])));
    let orientation = sum.sign()?.times(signs[0].times(signs[1]).times(signs[2]));
    Some(Some(Cand {
        rho,
        p,
        sigma,
        orientation,
    }))
}

/// The certified solve (see the module docs): `None` whenever some decision or rounding is
/// not certain, or when the exact solve would not return a circle.
pub(crate) fn solve(sites: &[Site; 3], choice: Choice) -> Option<FastRoot> {
    if !sites
        .iter()
        .all(|s| in_range(s.center[0]) && in_range(s.center[1]) && in_range(s.s))
    {
        return None;
    }
    // Frame: the centre of the smallest site `k` (the tangency the best conditioned), its
    // equation the quadratic one, `F_j - F_k` the linear ones (the same line of solutions and
    // the same quadratic in `rho` as the exact solve's `F_j - F_0`, `F_0`: see the module docs).
    let k = (0..3)
        .min_by(|&a, &b| sites[a].s.abs().total_cmp(&sites[b].s.abs()))
        .unwrap_or(0);
    let [j1, j2] = [[1, 2], [0, 2], [0, 1]][k];
    let c0 = sites[k].center;
    let s0 = sites[k].s;
    let d = [0, 1, 2].map(|i| {
        [
            Ball::diff(sites[i].center[0], c0[0]),
            Ball::diff(sites[i].center[1], c0[1]),
        ]
    });
    let half = Ball::exact(0.5);
    let h = [j1, j2].map(|j| {
        let e = Ball::diff(sites[j].s, s0);
        let sum = Ball::diff(sites[j].s, -s0);
        let h = d[j][0].square().add(d[j][1].square()).sub(e.mul(sum));
        (e, h.mul(half))
    });
    let [(e1, h1), (e2, h2)] = h;
    let [d1, d2] = [d[j1], d[j2]];
    let det = cross(d1, d2);
    det.sign()?;
    let q0 = [
        h1.mul(d2[1]).sub(h2.mul(d1[1])).div(det)?,
        d1[0].mul(h2).sub(d2[0].mul(h1)).div(det)?,
    ];
    let q1 = [
        e2.mul(d1[1]).sub(e1.mul(d2[1])).div(det)?,
        d2[0].mul(e1).sub(d1[0].mul(e2)).div(det)?,
    ];
    let s0b = Ball::exact(s0);
    let a = q1[0].square().add(q1[1].square()).sub(Ball::exact(1.0));
    let b = q0[0]
        .mul(q1[0])
        .add(q0[1].mul(q1[1]))
        .sub(s0b)
        .mul(Ball::exact(2.0));
    let c = q0[0].square().add(q0[1].square()).sub(s0b.square());
    a.sign()?;
    let disc = b.square().sub(Ball::exact(4.0).mul(a).mul(c));
    if disc.sign()? != Sign::Positive {
        return None;
    }
    let sq = disc.sqrt()?;
    // The root without cancellation first, the other by Vieta (C / q), when B's sign is known.
    let roots = match b.sign() {
        Some(sb) => {
            let t = if sb == Sign::Positive {
                b.add(sq)
            } else {
                b.sub(sq)
            };
            let q = t.mul(Ball::exact(-0.5));
            [q.div(a)?, c.div(q)?]
        }
        None => {
            let two_a = a.mul(Ball::exact(2.0));
            [b.neg().sub(sq).div(two_a)?, b.neg().add(sq).div(two_a)?]
        }
    };
    let mut valid: Vec<Cand> = Vec::with_capacity(2);
    for rho in roots {
        if let Some(c) = candidate(sites, &d, q0, q1, rho)? {
            valid.push(c);
        }
    }
    if valid.len() == 2 && !valid[0].rho.certainly_less(valid[1].rho)? {
        valid.swap(0, 1);
    }
    let mut kept: Vec<usize> = (0..valid.len())
        .filter(|&i| choice.orientation.is_none_or(|o| valid[i].orientation == o))
        .collect();
    if kept.len() >= 2 {
        if let Some(hint) = choice.hint.filter(|h| h[0].is_finite() && h[1].is_finite()) {
            // |p - hint|^2 with p - hint = (c_0 - hint) + P.
            let off = [Ball::diff(c0[0], hint[0]), Ball::diff(c0[1], hint[1])];
            let dist2 = |c: &Cand| off[0].add(c.p[0]).square().add(off[1].add(c.p[1]).square());
            let (k0, k1) = (dist2(&valid[kept[0]]), dist2(&valid[kept[1]]));
            if k1.certainly_less(k0)? {
                kept.swap(0, 1);
            }
        }
    }
    let index = *kept.first()?;
    let root = &valid[index];
    let approx = [
        Ball::exact(c0[0]).add(root.p[0]).round()?,
        Ball::exact(c0[1]).add(root.p[1]).round()?,
        root.rho.round()?,
    ];
    let mut tangent_points = [[0.0; 2]; 3];
    for (i, t) in tangent_points.iter_mut().enumerate() {
        // a_i = c_i - s_i u_i / sigma_i with u_i = d_i - P.
        let k = Ball::exact(sites[i].s).div(root.sigma[i])?;
        for (c, slot) in t.iter_mut().enumerate() {
            let u = d[i][c].sub(root.p[c]);
            *slot = Ball::exact(sites[i].center[c]).sub(k.mul(u)).round()?;
        }
    }
    Some(FastRoot {
        approx,
        tangent_points,
        orientation: root.orientation,
        index: index as u8,
    })
}
