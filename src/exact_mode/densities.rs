//! The sub-step densities of one arc piece (`k + 1` points of the conic), the inner loop of
//! exact mode (issue 8).
//!
//! The sub-steps adapt to the arc (`ArcGeometry::densities_into`): first
//! [`COARSE_SUBSTEPS`] (64); when both densities change by at most [`SMOOTH_CHANGE`] (5%)
//! from one sub-step to the next (`smooth`) they are kept, else the arc takes all
//! [`ARC_SUBSTEPS`] (256), as does every blended arc. On bubble layouts about nine arcs in ten
//! are smooth; a narrow gap's peak of the length density is not, and keeps every sub-step.
//! Kept coarse sub-steps stand for the fine ones: count targets within 1e-3 relative (the
//! coarse chords of a curved spoke mid-curve are that much shorter), node parameters within a
//! small part of a cell, the same lower bounds (`tests/perf_densities.rs`, against the plain
//! formula at all sub-steps on real layouts). The choice depends on the values only, which are
//! the same bits in every build, so every build chooses alike.
//!
//! `ArcGeometry::densities_into` computes the same quantities as the plain formula
//! (`ArcGeometry::densities_plain`: every point from `ArcGeometry::at`, both wall turns by
//! `atan2`) with cheaper arithmetic, so the values agree to rounding, not bit for bit:
//! - the points are equally spaced in the parametrised wall's angle, so `(cos, sin)` of the
//!   interior points comes from a rotation by the step, restarted exactly (`sin_cos` of the
//!   same angle as in `at`) every [`RESTART`] sub-steps so the drift stays a few ulps;
//! - lengths use `sqrt(x^2 + y^2)` instead of `hypot` (coordinates are far from overflow);
//! - the parametrised wall turns by exactly `|sweep| / ARC_SUBSTEPS` per sub-step, so only the
//!   other wall's turn may need an `atan2`, and not when it is clearly the smaller one.
//!
//! The ends are the exact end points, as in `at`. Tested against the plain formula on random
//! arcs and on every piece of real layouts (`tests/perf_densities.rs`).
//!
//! Arcs with an end off the bisector (blended, `exact_mode::blend`) are the exception: every
//! build gives the plain formula's values bit for bit (`ArcGeometry::densities_blended`, the
//! same operations in passes over arrays).

use super::{blend, dist, larger_turn, medial_point_u, mid, turn_parts, ArcGeometry, Wall};
use super::{ARC_SUBSTEPS, MAX_WALL_ANGLE};
use crate::geometry::Point;
use crate::lanes::Lanes;

/// Sub-steps between exact restarts of the rotation recurrence.
pub const RESTART: usize = 16;

/// The sub-steps an arc is first sampled with (`ArcGeometry::densities_into`); kept where
/// the densities are smooth, else [`ARC_SUBSTEPS`].
pub const COARSE_SUBSTEPS: usize = ARC_SUBSTEPS / 4;

/// Largest change of either density (`sq`, `ang`) between neighbouring coarse sub-steps,
/// relative to the larger of the two, for the coarse sub-steps to be kept (`smooth`).
pub const SMOOTH_CHANGE: f64 = 0.05;

/// Whether the densities `x` (`sq` or `ang`) of the coarse sub-steps are smooth enough to
/// stand for the fine ones: every value positive and finite, and neighbours within
/// [`SMOOTH_CHANGE`] of the larger. Within a coarse sub-step the fine densities then vary by
/// about as much, so the equidistributed parameters move by a small fraction of one coarse
/// sub-step and the sums (the count targets) by its square; the wall-angle density, the larger
/// of two walls' turns, can gain at most about [`SMOOTH_CHANGE`] of one coarse sub-step's turn
/// where the two walls' turns cross.
pub(crate) fn smooth(x: &[f64]) -> bool {
    x.iter().all(|v| v.is_finite() && *v > 0.0)
        && x.windows(2)
            .all(|w| (w[0] - w[1]).abs() <= SMOOTH_CHANGE * w[0].max(w[1]))
}

/// `|a - b|` as `sqrt`, without `hypot`'s overflow guard.
fn len(a: Point, b: Point) -> f64 {
    squared_distance(a, b).sqrt()
}

/// `|a - b|²`, the square [`len`] takes the root of.
#[inline(always)]
fn squared_distance(a: Point, b: Point) -> f64 {
    let (x, y) = (a[0] - b[0], a[1] - b[1]);
    x * x + y * y
}

/// The touching point on `w` of the empty circle centred at `m` (as [`Wall::project`], with
/// `sqrt` instead of `hypot`).
fn project(w: &Wall, m: Point) -> Point {
    let d = [m[0] - w.c[0], m[1] - w.c[1]];
    let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
    [w.c[0] + w.r * d[0] / l, w.c[1] + w.r * d[1] / l]
}

/// The larger of one sub-step's wall turns: `turn_p` of the parametrised wall, or the other
/// wall's, whose turn has cross and dot products `(c, d)` ([`turn_parts`]). `tan_p` is
/// `tan(turn_p)` shrunk by a margin: `atan(|c| / d) < turn_p` when `|c| < tan(turn_p) d`
/// (with a margin for the two roundings of the comparison), and then the `atan2` is skipped.
fn larger_of_turns(c: f64, d: f64, turn_p: f64, tan_p: f64) -> f64 {
    if d > 0.0 && c.abs() < tan_p * d {
        turn_p
    } else {
        turn_p.max(c.atan2(d).abs())
    }
}

/// `u` turned by the angle whose cosine and sine are `cd`, `sd` (one step of the recurrence).
#[inline(always)]
fn rotate(u: Point, cd: f64, sd: f64) -> Point {
    [u[0] * cd - u[1] * sd, u[1] * cd + u[0] * sd]
}

/// Chains of the rotation recurrence between restarts at most (at [`ARC_SUBSTEPS`]): sub-steps
/// `1..RESTART`, then one chain per further `RESTART` sub-steps.
const CHAINS: usize = ARC_SUBSTEPS / RESTART;

/// The arrays of the batched densities' passes (`ArcGeometry::densities_into`): 32 KB, kept
/// per thread instead of zeroed on the stack at each call (issue 8).
struct Passes {
    ux: [f64; ARC_SUBSTEPS + 1],
    uy: [f64; ARC_SUBSTEPS + 1],
    mx: [f64; ARC_SUBSTEPS + 1],
    my: [f64; ARC_SUBSTEPS + 1],
    r: [f64; ARC_SUBSTEPS + 1],
    tx: [[f64; ARC_SUBSTEPS + 1]; 2],
    ty: [[f64; ARC_SUBSTEPS + 1]; 2],
    /// The spoke mid-points `0.5 (m + t[wall])` of every point, once each (every sub-step
    /// reads those of both its ends).
    hx: [[f64; ARC_SUBSTEPS + 1]; 2],
    hy: [[f64; ARC_SUBSTEPS + 1]; 2],
    sqa: [f64; ARC_SUBSTEPS],
    ca: [f64; ARC_SUBSTEPS],
    da: [f64; ARC_SUBSTEPS],
    /// The turn parts of the second wall, for blended arcs (both walls' turns are measured,
    /// [`ArcGeometry::densities_blended`]).
    cb: [f64; ARC_SUBSTEPS],
    db: [f64; ARC_SUBSTEPS],
}

impl Default for Passes {
    fn default() -> Self {
        Passes {
            ux: [0.0; ARC_SUBSTEPS + 1],
            uy: [0.0; ARC_SUBSTEPS + 1],
            mx: [0.0; ARC_SUBSTEPS + 1],
            my: [0.0; ARC_SUBSTEPS + 1],
            r: [0.0; ARC_SUBSTEPS + 1],
            tx: [[0.0; ARC_SUBSTEPS + 1]; 2],
            ty: [[0.0; ARC_SUBSTEPS + 1]; 2],
            hx: [[0.0; ARC_SUBSTEPS + 1]; 2],
            hy: [[0.0; ARC_SUBSTEPS + 1]; 2],
            sqa: [0.0; ARC_SUBSTEPS],
            ca: [0.0; ARC_SUBSTEPS],
            da: [0.0; ARC_SUBSTEPS],
            cb: [0.0; ARC_SUBSTEPS],
            db: [0.0; ARC_SUBSTEPS],
        }
    }
}

/// The touching point `a` on the parametrised wall `wp` at the unit vector `(u0, u1)`, the
/// empty circle's radius `rho` and its centre `m`: the expressions of `medial_point_u`
/// written out (`neg`: `wp.s < 0`), shared by the batched passes of both kinds of arc.
#[inline(always)]
fn bisector_point(wp: &Wall, wq: &Wall, neg: bool, u0: f64, u1: f64) -> (Point, f64, Point) {
    let a0 = wp.c[0] + wp.r * u0;
    let a1 = wp.c[1] + wp.r * u1;
    let (n0, n1) = if neg { (-u0, -u1) } else { (u0, u1) };
    let d0 = a0 - wq.c[0];
    let d1 = a1 - wq.c[1];
    let den = 2.0 * (d0 * n0 + d1 * n1 - wq.s);
    let rho = (wq.s * wq.s - (d0 * d0 + d1 * d1)) / den;
    ([a0, a1], rho, [a0 + rho * n0, a1 + rho * n1])
}

/// The first `n` points' two spoke mid-points (`mid(m, t[wall])`): `h[k][wall][s]` from the
/// centres `m[k][s]` and the touching points `t[k][wall][s]` (`k` the coordinate).
#[inline(always)]
fn spoke_midpoints(
    m: [&[f64; ARC_SUBSTEPS + 1]; 2],
    t: [&[[f64; ARC_SUBSTEPS + 1]; 2]; 2],
    h: [&mut [[f64; ARC_SUBSTEPS + 1]; 2]; 2],
    n: usize,
) {
    for (k, hk) in h.into_iter().enumerate() {
        for (hw, tw) in hk.iter_mut().zip(t[k]) {
            for ((x, &mc), &tc) in hw[..n].iter_mut().zip(&m[k][..n]).zip(&tw[..n]) {
                *x = 0.5 * (mc + tc);
            }
        }
    }
}

/// Sub-step `s`'s length density (`dist` of consecutive spoke mid-points `h`, over the mean
/// radius `r`), and the two squared distances its `sqrt`s took (`[wall]`).
#[inline(always)]
fn length_density(
    h: [&[[f64; ARC_SUBSTEPS + 1]; 2]; 2],
    r: &[f64; ARC_SUBSTEPS + 1],
    s: usize,
) -> (f64, [f64; 2]) {
    let [hx, hy] = h;
    let mut squares = [0.0; 2];
    let mut ds = 0.0;
    for w in 0..2 {
        let x = hx[w][s - 1] - hx[w][s];
        let y = hy[w][s - 1] - hy[w][s];
        squares[w] = x * x + y * y;
        let l = squares[w].sqrt();
        ds = if w == 0 { l } else { ds + l };
    }
    let ds = 0.5 * ds;
    let rho = 0.5 * (r[s - 1] + r[s]);
    (if rho > 0.0 { ds / rho } else { 0.0 }, squares)
}

thread_local! {
    /// This thread's [`Passes`].
    static PASSES: std::cell::RefCell<Box<Passes>> = std::cell::RefCell::new(Box::default());
}

impl ArcGeometry {
    /// The unit vector of interior sub-step `s` of `k` on the parametrised wall, from `u`
    /// (that of `s - 1`) by the rotation `(cd, sd)` of one step, or computed afresh at `s = 1`
    /// and every [`RESTART`] sub-steps from the same angle as `at(s / k)`.
    fn next_unit(&self, s: usize, k: usize, u: Point, cd: f64, sd: f64) -> Point {
        if s == 1 || s.is_multiple_of(RESTART) {
            self.restart_unit(s, k)
        } else {
            rotate(u, cd, sd)
        }
    }

    /// The unit vector of sub-step `s` of `k` computed afresh, from the same angle as
    /// `at(s / k)`.
    #[inline(always)]
    fn restart_unit(&self, s: usize, k: usize) -> Point {
        let p = self.param;
        let theta = self.start[p] + (s as f64 / k as f64) * self.sweep[p];
        [theta.cos(), theta.sin()]
    }

    /// The exact end points (`at(0)`, `at(1)`) into slots 0 and `k` (the sub-steps) of the
    /// centres and radii `mr` and the touching points `t` of the batched passes.
    #[inline(always)]
    fn put_ends(
        &self,
        k: usize,
        mr: [&mut [f64; ARC_SUBSTEPS + 1]; 3],
        t: [&mut [[f64; ARC_SUBSTEPS + 1]; 2]; 2],
    ) -> Option<()> {
        let ([mx, my, r], [tx, ty]) = (mr, t);
        for (s, at) in [(0, 0.0), (k, 1.0)] {
            let (m, a, rho) = self.at(at)?;
            (mx[s], my[s], r[s]) = (m[0], m[1], rho);
            for w in 0..2 {
                (tx[w][s], ty[w][s]) = (a[w][0], a[w][1]);
            }
        }
        Some(())
    }

    /// Sub-step densities for the count problem: `(sq, ang)` per sub-step.
    pub(crate) fn densities(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        let mut sq = Vec::with_capacity(ARC_SUBSTEPS);
        let mut ang = Vec::with_capacity(ARC_SUBSTEPS);
        self.densities_into(&mut sq, &mut ang)?;
        Some((sq, ang))
    }

    /// [`ArcGeometry::densities`] into `sq` and `ang` (cleared first): the values of
    /// [`ArcGeometry::densities_into_scalar`] bit for bit, computed in passes over arrays (the
    /// unit vectors by their recurrence; then every point; then every sub-step) so that the
    /// divisions and square roots of independent points can run side by side (vector lanes
    /// round every operation as the scalar code does, and nothing is reassociated or fused).
    /// `None` when a point is not defined.
    ///
    /// Compiled three times ([`Lanes`]): for AVX-512 or AVX2 when the CPU has them, else for
    /// the baseline (SSE2): the same IEEE operations on the same operands in every build (no
    /// fused multiply-add, nothing reassociated; `sin`, `cos`, `tan`, `atan2` are the same
    /// library calls), so the same bits, in wider vectors.
    pub(crate) fn densities_into(&self, sq: &mut Vec<f64>, ang: &mut Vec<f64>) -> Option<()> {
        self.densities_with(Lanes::best(), sq, ang)
    }

    /// [`ArcGeometry::densities_into`] in the build `lanes` (the baseline when the CPU lacks
    /// it): the test hook that compares the builds. The sub-steps are chosen by
    /// [`ArcGeometry::adaptive`].
    pub(crate) fn densities_with(
        &self,
        lanes: Lanes,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
    ) -> Option<()> {
        PASSES.with(|cell| {
            let (mut held, mut fresh);
            let b: &mut Passes = match cell.try_borrow_mut() {
                Ok(g) => {
                    held = g;
                    &mut held
                }
                // Never reentered; a fresh set of buffers if it were.
                Err(_) => {
                    fresh = Box::<Passes>::default();
                    &mut fresh
                }
            };
            self.adaptive(sq, ang, |k, sq, ang| {
                self.densities_on(lanes, b, k, sq, ang)
            })
        })
    }

    /// The sub-steps of an arc's densities (see the module docs): first [`COARSE_SUBSTEPS`]
    /// with `at(k, sq, ang)` (the densities of `k` sub-steps), kept when both densities are
    /// [`smooth`], else [`ARC_SUBSTEPS`]. A blended arc always takes [`ARC_SUBSTEPS`].
    #[inline(always)]
    fn adaptive(
        &self,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
        mut at: impl FnMut(usize, &mut Vec<f64>, &mut Vec<f64>) -> Option<()>,
    ) -> Option<()> {
        if !self.blended() && at(COARSE_SUBSTEPS, sq, ang).is_some() && smooth(sq) && smooth(ang) {
            return Some(());
        }
        at(ARC_SUBSTEPS, sq, ang)
    }

    /// The sub-steps [`ArcGeometry::adaptive`] chooses for this arc (a test hook: the plain
    /// formula is compared at the same sub-steps); [`ARC_SUBSTEPS`] when undefined.
    pub(crate) fn substeps(&self) -> usize {
        self.densities().map_or(ARC_SUBSTEPS, |(sq, _)| sq.len())
    }

    /// [`ArcGeometry::densities_with`] of `k` sub-steps on the buffers `b` (the dispatch
    /// happens once the buffers are borrowed, so the whole body is compiled in each build).
    fn densities_on(
        &self,
        lanes: Lanes,
        b: &mut Passes,
        k: usize,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
    ) -> Option<()> {
        #[cfg(target_arch = "x86_64")]
        match lanes {
            // SAFETY: `Lanes::available` checked the CPU's features.
            Lanes::Avx512 if lanes.available() => {
                return unsafe { self.densities_avx512(b, k, sq, ang) }
            }
            // SAFETY: as above.
            Lanes::Avx2 if lanes.available() => {
                return unsafe { self.densities_avx2(b, k, sq, ang) }
            }
            _ => {}
        }
        self.densities_batched(b, k, sq, ang)
    }

    /// [`ArcGeometry::densities_batched`] compiled for AVX-512 (8-lane vectors).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
    fn densities_avx512(
        &self,
        b: &mut Passes,
        k: usize,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
    ) -> Option<()> {
        self.densities_batched(b, k, sq, ang)
    }

    /// [`ArcGeometry::densities_batched`] compiled for AVX2 (4-lane vectors).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn densities_avx2(
        &self,
        b: &mut Passes,
        k: usize,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
    ) -> Option<()> {
        self.densities_batched(b, k, sq, ang)
    }

    /// The body of [`ArcGeometry::densities_into`] for `k` sub-steps (a multiple of
    /// [`RESTART`], at most [`ARC_SUBSTEPS`]), inlined into each build, on this thread's
    /// [`Passes`] buffers `b` (every entry read is written first in the same call: nothing of
    /// an earlier call is seen). A blended arc always has [`ARC_SUBSTEPS`].
    #[inline(always)]
    fn densities_batched(
        &self,
        b: &mut Passes,
        k: usize,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
    ) -> Option<()> {
        if self.blended() {
            return self.densities_blended(b, sq, ang);
        }
        debug_assert!(k.is_multiple_of(RESTART) && k <= ARC_SUBSTEPS);
        let k = k.clamp(RESTART, ARC_SUBSTEPS);
        let n = k + 1;
        let Passes {
            ux,
            uy,
            mx,
            my,
            r,
            tx,
            ty,
            hx,
            hy,
            sqa,
            ca,
            da,
            ..
        } = b;
        sq.clear();
        ang.clear();
        let p = self.param;
        let q = 1 - p;
        let (wp, wq) = (&self.walls[p], &self.walls[q]);
        let step = self.sweep[p] / k as f64;
        let (sd, cd) = step.sin_cos();
        let turn_p = step.abs();
        let tan_p = turn_p.tan() / (1.0 + 1e-9);
        let chains = k / RESTART;
        // Pass 1: the unit vectors of the interior points, as `densities_into_scalar` makes
        // them one after the other. The recurrence restarts exactly at sub-step 1 and every
        // `RESTART` sub-steps, so it is `k / RESTART` independent chains (chain `c` from
        // sub-step `max(1, c RESTART)` to `(c + 1) RESTART - 1`), run side by side here: each unit
        // vector is the same rotation of the same predecessor, so the same bits, without
        // waiting on one long chain of dependent multiplications.
        let (mut cx, mut cy) = ([0.0; CHAINS], [0.0; CHAINS]);
        for c in 0..chains {
            let s = (c * RESTART).max(1);
            [cx[c], cy[c]] = self.restart_unit(s, k);
            (ux[s], uy[s]) = (cx[c], cy[c]);
        }
        for r in 1..RESTART {
            for c in 0..chains {
                [cx[c], cy[c]] = rotate([cx[c], cy[c]], cd, sd);
            }
            // Chain 0 starts one sub-step late: its last rotation (sub-step `RESTART`,
            // a restart) is not used.
            if r + 1 < RESTART {
                (ux[r + 1], uy[r + 1]) = (cx[0], cy[0]);
            }
            for c in 1..chains {
                (ux[c * RESTART + r], uy[c * RESTART + r]) = (cx[c], cy[c]);
            }
        }
        // Pass 2: every point: medial point `m`, radius `r`, touching points `t[wall]` (the
        // expressions of `medial_point_u` and `project`, written out).
        self.put_ends(k, [mx, my, r], [tx, ty])?;
        let neg = wp.s < 0.0;
        let mut ok = true;
        {
            let [tpx, tqx] = if p == 0 {
                let [a, b] = tx;
                [a, b]
            } else {
                let [b, a] = tx;
                [a, b]
            };
            let [tpy, tqy] = if p == 0 {
                let [a, b] = ty;
                [a, b]
            } else {
                let [b, a] = ty;
                [a, b]
            };
            for s in 1..k {
                let (u0, u1) = (ux[s], uy[s]);
                let ([a0, a1], rho, [m0, m1]) = bisector_point(wp, wq, neg, u0, u1);
                let e0 = m0 - wq.c[0];
                let e1 = m1 - wq.c[1];
                let l = (e0 * e0 + e1 * e1).sqrt();
                let b0 = wq.c[0] + wq.r * e0 / l;
                let b1 = wq.c[1] + wq.r * e1 / l;
                ok &= rho.is_finite()
                    & (rho >= 0.0)
                    & m0.is_finite()
                    & m1.is_finite()
                    & b0.is_finite()
                    & b1.is_finite();
                (mx[s], my[s], r[s]) = (m0, m1, rho);
                (tpx[s], tpy[s], tqx[s], tqy[s]) = (a0, a1, b0, b1);
            }
        }
        if !ok {
            return None;
        }
        // Pass 3: every point's spoke mid-points, then every sub-step's length density and
        // the other wall's turn parts.
        spoke_midpoints([mx, my], [tx, ty], [hx, hy], n);
        let cq = wq.c;
        for s in 1..n {
            (sqa[s - 1], _) = length_density([hx, hy], r, s);
            (ca[s - 1], da[s - 1]) =
                turn_parts(cq, [tx[q][s - 1], ty[q][s - 1]], [tx[q][s], ty[q][s]]);
        }
        sq.extend_from_slice(&sqa[..k]);
        // `larger_of_turns(c, d, turn_p, tan_p) / MAX_WALL_ANGLE`: first its common case (the
        // parametrised wall's turn, no `atan2`) for every sub-step side by side, then the
        // sub-steps that need the `atan2` one by one (the same operations on each value).
        let clear = |c: f64, d: f64| d > 0.0 && c.abs() < tan_p * d;
        let common = turn_p / MAX_WALL_ANGLE;
        ang.extend(
            ca[..k]
                .iter()
                .zip(&da[..k])
                .map(|(&c, &d)| if clear(c, d) { common } else { 0.0 }),
        );
        for ((a, &c), &d) in ang.iter_mut().zip(&ca[..k]).zip(&da[..k]) {
            if !clear(c, d) {
                *a = larger_of_turns(c, d, turn_p, tan_p) / MAX_WALL_ANGLE;
            }
        }
        Some(())
    }

    /// [`ArcGeometry::densities_plain_into`] of a blended arc (an end off the bisector), bit
    /// for bit, in passes over arrays: the unit vectors (`cos` and `sin` of the very angles of
    /// [`ArcGeometry::at`], one point after the other), then every point (the expressions of
    /// `at`'s blended branch: bisector point, faded offsets, projections on both walls), then
    /// every sub-step's length density and both walls' turn parts, and last the larger turn
    /// ([`larger_turn`], one `atan2` where it is clear) one sub-step after the other. The
    /// divisions and square roots of independent points run side by side in vector lanes
    /// (the same IEEE operations on the same operands, nothing fused or reassociated).
    ///
    /// A squared length outside `[LENGTH_SQ_MIN, LENGTH_SQ_MAX]` (where `length` takes
    /// `hypot`) sends the arc to the plain formula. `None` exactly when the plain formula
    /// gives it: some point not defined.
    #[inline(always)]
    fn densities_blended(
        &self,
        b: &mut Passes,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
    ) -> Option<()> {
        use crate::geometry::{LENGTH_SQ_MAX, LENGTH_SQ_MIN};
        const K: usize = ARC_SUBSTEPS;
        const N: usize = K + 1;
        let Passes {
            ux,
            uy,
            mx,
            my,
            r,
            tx,
            ty,
            hx,
            hy,
            sqa,
            ca,
            da,
            cb,
            db,
        } = b;
        sq.clear();
        ang.clear();
        let p = self.param;
        let q = 1 - p;
        let (wp, wq) = (&self.walls[p], &self.walls[q]);
        let [w0, w1] = &self.walls;
        let [o0, o1] = self.offset;
        let in_range = |x: f64| (LENGTH_SQ_MIN..=LENGTH_SQ_MAX).contains(&x);
        // Pass 1: the unit vectors of `at(s / K)` (`medial_point`'s `cos` and `sin`).
        for s in 1..K {
            let t = s as f64 / K as f64;
            let theta = self.start[p] + t * self.sweep[p];
            (ux[s], uy[s]) = (theta.cos(), theta.sin());
        }
        // Pass 2: every point, as `at`: the ends exactly, the interior points from the
        // bisector point (`medial_point_u`) moved by the faded offsets and projected on both
        // walls (`Wall::project`), the radius the mean of the two spokes (`dist`).
        self.put_ends(K, [mx, my, r], [tx, ty])?;
        let neg = wp.s < 0.0;
        let (mut ok, mut fits) = (true, true);
        {
            let [t0x, t1x] = tx;
            let [t0y, t1y] = ty;
            for s in 1..K {
                let (u0, u1) = (ux[s], uy[s]);
                let (_, rho, [m0, m1]) = bisector_point(wp, wq, neg, u0, u1);
                ok &= rho.is_finite() & (rho >= 0.0) & m0.is_finite() & m1.is_finite();
                // The offsets faded by `blend` (an interior parameter and its complement).
                let t = s as f64 / K as f64;
                let (b0, b1) = (blend(t), blend(1.0 - t));
                let m = [m0 + b0 * o0[0] + b1 * o1[0], m1 + b0 * o0[1] + b1 * o1[1]];
                // `Wall::project` on each wall, then `dist` back to the point, by `sqrt`
                // (`project`, `len`): the same values while every squared length is in range.
                let (pe, pf) = (project(w0, m), project(w1, m));
                let radius = 0.5 * (len(m, pe) + len(m, pf));
                let sq = |x: Point| in_range(squared_distance(m, x));
                fits &= sq(w0.c) & sq(w1.c) & sq(pe) & sq(pf);
                let finite = |x: Point| x[0].is_finite() & x[1].is_finite();
                ok &= finite(pe) & finite(pf) & finite(m) & radius.is_finite();
                (mx[s], my[s], r[s]) = (m[0], m[1], radius);
                (t0x[s], t0y[s], t1x[s], t1y[s]) = (pe[0], pe[1], pf[0], pf[1]);
            }
        }
        if !fits {
            return self.densities_plain_into(K, sq, ang);
        }
        if !ok {
            return None;
        }
        // Pass 3: the spoke mid-points (`mid`), then every sub-step's length density (`dist`
        // of consecutive mid-points) and both walls' turn parts (`turn_parts`).
        spoke_midpoints([mx, my], [tx, ty], [hx, hy], N);
        for s in 1..N {
            let (d, [l0, l1]) = length_density([hx, hy], r, s);
            sqa[s - 1] = d;
            fits &= in_range(l0) & in_range(l1);
            let (a, b) = ([tx[0][s - 1], ty[0][s - 1]], [tx[0][s], ty[0][s]]);
            (ca[s - 1], da[s - 1]) = turn_parts(w0.c, a, b);
            let (a, b) = ([tx[1][s - 1], ty[1][s - 1]], [tx[1][s], ty[1][s]]);
            (cb[s - 1], db[s - 1]) = turn_parts(w1.c, a, b);
        }
        if !fits {
            return self.densities_plain_into(K, sq, ang);
        }
        sq.extend_from_slice(&sqa[..]);
        ang.extend((0..K).map(|s| larger_turn(ca[s], da[s], cb[s], db[s]) / MAX_WALL_ANGLE));
        Some(())
    }

    /// The densities point by point, one sub-step after the other (see the module docs), with
    /// the same choice of sub-steps ([`ArcGeometry::adaptive`]): the reference
    /// [`ArcGeometry::densities_into`] is tested against, bit for bit.
    pub(crate) fn densities_into_scalar(
        &self,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
    ) -> Option<()> {
        self.adaptive(sq, ang, |k, sq, ang| self.densities_scalar_at(k, sq, ang))
    }

    /// [`ArcGeometry::densities_into_scalar`] of `k` sub-steps.
    fn densities_scalar_at(&self, k: usize, sq: &mut Vec<f64>, ang: &mut Vec<f64>) -> Option<()> {
        if self.blended() {
            return self.densities_plain_into(ARC_SUBSTEPS, sq, ang);
        }
        sq.clear();
        ang.clear();
        let p = self.param;
        let q = 1 - p;
        let (wp, wq) = (&self.walls[p], &self.walls[q]);
        let step = self.sweep[p] / k as f64;
        let (sd, cd) = step.sin_cos();
        let turn_p = step.abs();
        let tan_p = turn_p.tan() / (1.0 + 1e-9);
        let (mut m0, mut a0, mut r0) = self.at(0.0)?;
        let mut u = [1.0, 0.0];
        for s in 1..=k {
            let (m1, a1, r1) = if s == k {
                self.at(1.0)?
            } else {
                u = self.next_unit(s, k, u, cd, sd);
                let (a, m, rho) = medial_point_u(wp, wq, u)?;
                let b = project(wq, m);
                if !(b[0].is_finite() && b[1].is_finite()) {
                    return None;
                }
                let mut both = [a, a];
                both[q] = b;
                (m, both, rho)
            };
            let ds =
                0.5 * (len(mid(m0, a0[0]), mid(m1, a1[0])) + len(mid(m0, a0[1]), mid(m1, a1[1])));
            let rho = 0.5 * (r0 + r1);
            sq.push(if rho > 0.0 { ds / rho } else { 0.0 });
            let (c, d) = turn_parts(wq.c, a0[q], a1[q]);
            ang.push(larger_of_turns(c, d, turn_p, tan_p) / MAX_WALL_ANGLE);
            (m0, a0, r0) = (m1, a1, r1);
        }
        Some(())
    }

    /// The plain formula the fast [`ArcGeometry::densities_into`] stands for: every point from
    /// [`ArcGeometry::at`], `ds` between the spoke mid-points (`super::dist`), both wall turns by
    /// `atan2` ([`larger_turn`] takes the larger), at the sub-steps the fast densities chose
    /// ([`ArcGeometry::substeps`]). The reference of the tests.
    pub(crate) fn densities_plain(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        self.densities_plain_of(self.substeps())
    }

    /// [`ArcGeometry::densities_plain`] of `k` sub-steps.
    pub(crate) fn densities_plain_of(&self, k: usize) -> Option<(Vec<f64>, Vec<f64>)> {
        let mut sq = Vec::with_capacity(k);
        let mut ang = Vec::with_capacity(k);
        self.densities_plain_into(k, &mut sq, &mut ang)?;
        Some((sq, ang))
    }

    /// [`ArcGeometry::densities_plain`] into `sq` and `ang` (cleared first): what every build
    /// of the densities gives for an arc with an end off the bisector (every point of such an
    /// arc is off the bisector, [`super::blend`]), there computed in passes over arrays
    /// ([`ArcGeometry::densities_blended`]), here point by point.
    pub(crate) fn densities_plain_into(
        &self,
        k: usize,
        sq: &mut Vec<f64>,
        ang: &mut Vec<f64>,
    ) -> Option<()> {
        sq.clear();
        ang.clear();
        let (mut m0, mut a0, mut r0) = self.at(0.0)?;
        for s in 1..=k {
            let (m1, a1, r1) = self.at(s as f64 / k as f64)?;
            let ds =
                0.5 * (dist(mid(m0, a0[0]), mid(m1, a1[0])) + dist(mid(m0, a0[1]), mid(m1, a1[1])));
            let rho = 0.5 * (r0 + r1);
            sq.push(if rho > 0.0 { ds / rho } else { 0.0 });
            let (c0, d0) = turn_parts(self.walls[0].c, a0[0], a1[0]);
            let (c1, d1) = turn_parts(self.walls[1].c, a0[1], a1[1]);
            ang.push(larger_turn(c0, d0, c1, d1) / MAX_WALL_ANGLE);
            (m0, a0, r0) = (m1, a1, r1);
        }
        Some(())
    }
}

/// How far the fast densities are from the plain formula (test hook, issue 8).
#[doc(hidden)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Deviation {
    /// Arcs compared (pieces and both halves of each).
    pub arcs: usize,
    /// Largest `|fast - plain|` of one sub-step's `sq`, relative to the arc's mean plain `sq`
    /// (what the node parameters see: the weights are equidistributed against their sum).
    pub sq: f64,
    /// The same for `ang`.
    pub ang: f64,
    /// Arcs whose lower bound `ceil(sum ang)` differs, or defined by only one of the two.
    pub mismatches: usize,
    /// Arcs whose fast densities (the batched passes) differ in any bit, or in being defined,
    /// from the point-by-point ones (`ArcGeometry::densities_into_scalar`): must be 0.
    pub batched_bits: usize,
    /// Arcs whose densities kept the [`COARSE_SUBSTEPS`] (see [`ArcGeometry::adaptive`]).
    pub coarse: usize,
    /// Over those, the largest difference of an arc's count target (the sum of its weights,
    /// for a mean wall-normal count `nbar` of 1, 4 and 16) from the plain formula's at
    /// [`ARC_SUBSTEPS`], relative to the latter.
    pub coarse_target: f64,
    /// Over those, the largest difference of the node parameters of 8 and 32 cells
    /// (`equidistribution::arc_params_into` of those weights) from the plain formula's at
    /// [`ARC_SUBSTEPS`] (parameters run over `[0, 1]`).
    pub coarse_params: f64,
    /// Over those, the arcs whose lower bound `ceil(sum ang)` differs from the plain formula's
    /// at [`ARC_SUBSTEPS`].
    pub coarse_bounds: usize,
}

impl Deviation {
    /// Compare the densities of `g`.
    pub(crate) fn add(&mut self, g: &ArcGeometry) {
        use super::counts::ArcTarget;
        self.arcs += 1;
        let (fast, plain) = (g.densities(), g.densities_plain());
        let (mut ssq, mut sang) = (Vec::new(), Vec::new());
        let scalar = g
            .densities_into_scalar(&mut ssq, &mut sang)
            .map(|()| (ssq, sang));
        let bits = |v: &(Vec<f64>, Vec<f64>)| {
            let b = |x: &[f64]| x.iter().map(|y| y.to_bits()).collect::<Vec<u64>>();
            (b(&v.0), b(&v.1))
        };
        self.batched_bits += usize::from(fast.as_ref().map(bits) != scalar.as_ref().map(bits));
        for lanes in Lanes::ALL {
            let (mut bsq, mut bang) = (Vec::new(), Vec::new());
            let built = g
                .densities_with(lanes, &mut bsq, &mut bang)
                .map(|()| (bsq, bang));
            self.batched_bits += usize::from(built.as_ref().map(bits) != scalar.as_ref().map(bits));
        }
        let (Some((fs, fa)), Some((ps, pa))) = (fast.clone(), plain.clone()) else {
            self.mismatches += usize::from(fast.is_some() != plain.is_some());
            return;
        };
        let rel = |f: &[f64], p: &[f64]| {
            let mean = p.iter().sum::<f64>() / p.len() as f64;
            let worst = f
                .iter()
                .zip(p)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if mean > 0.0 {
                worst / mean
            } else {
                worst
            }
        };
        self.sq = self.sq.max(rel(&fs, &ps));
        self.ang = self.ang.max(rel(&fa, &pa));
        let target = |sq: &[f64], ang: &[f64]| ArcTarget {
            circles: [0, 0],
            sq: sq.to_vec(),
            ang: ang.to_vec(),
            known: None,
        };
        self.mismatches +=
            usize::from(target(&fs, &fa).min_cells() != target(&ps, &pa).min_cells());
        if fs.len() != COARSE_SUBSTEPS {
            return;
        }
        // The coarse sub-steps against the plain formula at all of them.
        self.coarse += 1;
        let Some((ws, wa)) = g.densities_plain_of(ARC_SUBSTEPS) else {
            self.mismatches += 1;
            return;
        };
        let (coarse, fine) = (target(&fs, &fa), target(&ws, &wa));
        self.coarse_bounds += usize::from(coarse.min_cells() != fine.min_cells());
        for nbar in [1.0, 4.0, 16.0] {
            let (c, f) = (coarse.target(nbar), fine.target(nbar));
            self.coarse_target = self.coarse_target.max((c - f).abs() / f);
            let weights = |sq: &[f64], ang: &[f64]| -> Vec<f64> {
                sq.iter()
                    .zip(ang)
                    .map(|(&s, &a)| super::counts::weight(nbar, s, a))
                    .collect()
            };
            for n in [8, 32] {
                let params = |sq: &[f64], ang: &[f64]| {
                    let (mut t, mut prefix) = (Vec::new(), Vec::new());
                    let mut w = weights(sq, ang);
                    super::equidistribution::arc_params_into(&mut w, ang, n, &mut t, &mut prefix);
                    t
                };
                let (tc, tf) = (params(&fs, &fa), params(&ws, &wa));
                let worst = tc.iter().zip(&tf).map(|(a, b)| (a - b).abs());
                self.coarse_params = worst.fold(self.coarse_params, f64::max);
            }
        }
    }
}

/// [`Deviation`] over every piece of the exact build of `cb` and both halves of each piece (the
/// halves inserted holes split arcs into): exact vertices, collapse and pieces as
/// [`super::collapsed::build_collapsed`] makes them.
#[doc(hidden)]
pub fn deviation(
    cb: &crate::blocking::CollapsedBlocking,
) -> Result<Deviation, crate::mesher::MeshError> {
    let (_, pieces) = super::build_pieces(cb)?;
    let mut out = Deviation::default();
    for p in &pieces {
        out.add(&p.geom);
        if let Some((_, _, _, first, second)) = p.geom.split() {
            out.add(&first);
            out.add(&second);
        }
    }
    Ok(out)
}

/// [`Deviation`] of one random-ish arc given by its two walls and end angles on the first
/// (the ends from [`super::medial_point`], the second wall's sweep from the turn between its
/// touching points): `None` when an end is not defined.
#[doc(hidden)]
pub fn deviation_of_arc(p: [f64; 3], q: [f64; 3], t0: f64, t1: f64) -> Option<Deviation> {
    let wall = |w: [f64; 3]| Wall {
        c: [w[0], w[1]],
        r: w[2].abs(),
        s: w[2],
    };
    let (p, q) = (wall(p), wall(q));
    let (a0, m0, _) = super::medial_point(&p, &q, t0)?;
    let (a1, m1, _) = super::medial_point(&p, &q, t1)?;
    let ends_a = [[a0, q.project(m0)], [a1, q.project(m1)]];
    let (c, d) = turn_parts(q.c, ends_a[0][1], ends_a[1][1]);
    let g = ArcGeometry::new([p, q], [m0, m1], ends_a, [t1 - t0, c.atan2(d)]);
    let mut out = Deviation::default();
    out.add(&g);
    Some(out)
}
