//! End grading of the nodes along an arc piece, so that the cells on either side of a spoke
//! have about the same width (size-driven counts only, in bounded domains and, over arc
//! orbits, periodic boxes; `--block-cells` grids keep their equidistributed nodes).
//!
//! Why: the blocks on one circle share its spokes, but each arc equidistributes its own
//! weights over its own count (`equidistribution::arc_params_into`), and arcs leave a medial
//! vertex at different angles to its spokes. So the cells on the two sides of a spoke could
//! differ in width (normal to the spoke, as the report's growth ratio measures it) by up to
//! 3.4 at the default size: at 1e3 bubbles 15 358 of 102 131 spoke faces were over 1.5.
//!
//! What, per medial vertex ([`end_ratios`]): each piece ending there gets a log ratio `x` for
//! its end cell, the least squares of the log width differences across the vertex's spokes
//! (each spoke has one cell of each of two pieces beside it, [`end_widths`]: the distance
//! between the end spoke's and the next grid line's mid-points, normal to the spoke) plus a
//! penalty `(x / reach)^2` for how far the piece can be graded ([`reach`]: a piece of one
//! cell not at all, so its neighbours adapt to it); no end cell is widened more than
//! [`WIDEN_MAX`], and an end whose corner cell at the vertex would get sharper, below
//! [`GUARD_ANGLE`], keeps its natural cell ([`grade_piece`]). At 1e3 bubbles 999 of 217 576
//! interface faces are then over 1.5 (15 851 before; spoke faces 15 358 -> 482 of 102 131),
//! the equiangle skewness over 0.5 falls from 115 112 to 83 657 cells, the mean smallest
//! angle rises from 75.8 to 77.0 degrees, and the smallest angle and scaled Jacobian are
//! unchanged (1e4: 159 042 -> 6 801 faces over 1.5, smallest angle 14.651 -> 14.656). Over
//! 420 sweep layouts no smallest angle fell by more than 0.1 degree. (With `--block-cells`
//! an earlier form of this grading took the outside count from 67 618 to 43 643 faces but
//! the skewed cells from 30 245 to 38 593, so fixed grids per block are left as they are.)
//!
//! How, per piece ([`grade_piece`]): the natural parameters `t_i` (cell `i` carries `1 / n`
//! of the arc's weight) are re-sampled at `u_i = delta_0 + ... + delta_{i-1}` on their
//! piecewise-linear interpolation `u -> t` ([`graded_params`]). The increments ([`increments`])
//! are `delta_i = exp(L(s_i))`, `s_i = i / (n - 1)`, `L` quadratic: linear from the log of the
//! wanted first increment to that of the wanted last one, plus the bump `B 4 s (1 - s)` that
//! makes them sum to 1. Consecutive increments differ by at most [`MAX_STEP`]: wanted ratios
//! the count cannot reach that smoothly are pulled towards 1, so short pieces are graded
//! little or not at all. Both blocks of a piece share its parameters, so conformity holds by
//! construction; the natural parameters (what the memo compares) are unchanged.

use super::{dist, mid, turn_parts, ArcGeometry};
use crate::geometry::Point;

/// The largest ratio of consecutive increments along an arc that the grading introduces (the
/// natural spacing then multiplies it).
pub const MAX_STEP: f64 = 1.2;

/// The increments `delta_0..delta_{n-1}` (sum 1) whose first and last are as near as
/// [`MAX_STEP`] allows to `rho[0] / n` and `rho[1] / n` (see the module docs), into `out`.
/// `rho` are the wanted ratios of the end cells to the natural ones; non-finite or
/// non-positive ratios count as 1. Fractions `lambda` of the wanted log ratios are tried in
/// [`FRACTIONS`] order; the first whose increments step by at most [`MAX_STEP`] is taken
/// (`lambda = 0`, uniform increments, always is).
pub fn increments(n: usize, rho: [f64; 2], out: &mut Vec<f64>) {
    out.clear();
    if n == 0 {
        return;
    }
    let rho = rho.map(|r| if r.is_finite() && r > 0.0 { r } else { 1.0 });
    if n == 1 {
        out.push(1.0);
        return;
    }
    let step = MAX_STEP.ln();
    if n == 2 {
        // One ratio only: that of the wanted ends, within the step.
        let r = (rho[0] / rho[1]).ln().clamp(-step, step).exp();
        let d0 = r / (1.0 + r);
        out.extend([d0, 1.0 - d0]);
        return;
    }
    let wanted = rho.map(f64::ln);
    if wanted.iter().all(|w| w.abs() <= 1e-3) {
        out.extend((0..n).map(|_| 1.0 / n as f64));
        return;
    }
    let base = -(n as f64).ln();
    let m = (n - 1) as f64;
    // `L(s) = (1 - s) l0 + s l1 + B 4 s (1 - s)` at `s_i = i / m`: its differences are
    // `D + C_i B` with `D = (l1 - l0) / m`, `C_i = 4 (m - 2 i + 1) / m^2` (`|C_i| <= C_1`), so
    // every step is within `|D| + C_1 |B|`.
    let c1 = 4.0 * (m - 1.0) / (m * m);
    let mut b = 0.0;
    for lambda in FRACTIONS {
        let (l0, l1) = (base + lambda * wanted[0], base + lambda * wanted[1]);
        let d = (l1 - l0) / m;
        if d.abs() > step || l0.exp() + l1.exp() >= 1.0 {
            continue;
        }
        // Newton on `B` for `sum exp(L_i) = 1` (convex and increasing in `B`), from the last
        // fraction's `B`; the increments by a product recurrence (three `exp` per pass).
        let mut ok = false;
        for _ in 0..60 {
            let (sum, slope) = sums(n, l0, d, b, m);
            let f = sum - 1.0;
            if f.abs() <= 1e-13 {
                ok = true;
                break;
            }
            if slope.is_nan() || slope <= 0.0 {
                break;
            }
            let next = b - f / slope;
            b = if next.is_finite() { next } else { break };
        }
        if ok && d.abs() + c1 * b.abs() <= step * (1.0 + 1e-12) {
            out.clear();
            fill(n, l0, d, b, m, out);
            let sum: f64 = out.iter().sum();
            for x in out.iter_mut() {
                *x /= sum;
            }
            return;
        }
    }
    out.clear();
    out.extend((0..n).map(|_| 1.0 / n as f64));
}

/// Fractions of the wanted log end ratios [`increments`] tries, in order.
pub const FRACTIONS: [f64; 6] = [1.0, 0.75, 0.5, 0.35, 0.2, 0.1];

/// `sum_i exp(L_i)` and its derivative in `B` (`sum_i 4 s_i (1 - s_i) exp(L_i)`), with
/// `L_i = l0 + d i + B 4 s_i (1 - s_i)`, `s_i = i / m`.
fn sums(n: usize, l0: f64, d: f64, b: f64, m: f64) -> (f64, f64) {
    let (mut sum, mut slope) = (0.0, 0.0);
    each(n, l0, d, b, m, |i, e| {
        let s = i as f64 / m;
        sum += e;
        slope += 4.0 * s * (1.0 - s) * e;
    });
    (sum, slope)
}

/// `exp(L_i)` for `i` in `0..n` into `out` (see [`sums`]).
fn fill(n: usize, l0: f64, d: f64, b: f64, m: f64, out: &mut Vec<f64>) {
    each(n, l0, d, b, m, |_, e| out.push(e));
}

/// Calls `f(i, exp(L_i))` for `i` in `0..n`: `exp(L_{i+1}) = exp(L_i) exp(L_{i+1} - L_i)`,
/// the differences `D + 4 B (m - 2 i - 1) / m^2` themselves a geometric recurrence of ratio
/// `exp(-8 B / m^2)`, restarted exactly every 8 steps so the products drift by ulps only.
fn each(n: usize, l0: f64, d: f64, b: f64, m: f64, mut f: impl FnMut(usize, f64)) {
    let l = |i: usize| {
        let s = i as f64 / m;
        l0 + d * i as f64 + b * 4.0 * s * (1.0 - s)
    };
    let diff = |i: usize| d + 4.0 * b * (m - 2.0 * i as f64 - 1.0) / (m * m);
    let q = (-8.0 * b / (m * m)).exp();
    let (mut e, mut r) = (0.0, 0.0);
    for i in 0..n {
        if i % 8 == 0 {
            e = l(i).exp();
            r = diff(i).exp();
        } else {
            e *= r;
            r *= q;
        }
        f(i, e);
    }
}

/// The natural parameters `t` (`n + 1`, from 0 to 1, nondecreasing) re-sampled at the
/// running sums of `delta` (`n` increments summing to about 1) on the piecewise-linear map
/// `i / n -> t_i`, into `out`: ends exactly 0 and 1, nondecreasing.
pub fn graded_params(t: &[f64], delta: &[f64], out: &mut Vec<f64>) {
    out.clear();
    let n = t.len().saturating_sub(1);
    if n == 0 || delta.len() != n {
        out.extend_from_slice(t);
        return;
    }
    let total: f64 = delta.iter().sum();
    out.push(t[0]);
    let mut u = 0.0;
    let mut last = t[0];
    for d in &delta[..n - 1] {
        u += d;
        let x = (u / total * n as f64).clamp(0.0, n as f64);
        let j = (x.floor() as usize).min(n - 1);
        let f = x - j as f64;
        let v = (t[j] + f * (t[j + 1] - t[j])).clamp(last, t[n]);
        out.push(v);
        last = v;
    }
    out.push(t[n]);
}

/// Buffers of [`grade_piece`], reused from piece to piece.
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    delta: Vec<f64>,
    out: Vec<f64>,
}

/// The widths of the cell between the end spoke at arc parameter `te` and the grid line at
/// `tc` on both sides (`[side]`): the distance between the two lines' mid-points, normal to
/// the end spoke (the cell's height across the spoke, as the report's growth ratio measures
/// it; `None` where the arc is not defined or a width is not positive).
fn side_widths(g: &ArcGeometry, te: f64, tc: f64) -> Option<[f64; 2]> {
    let (me, ae, _) = g.at(te)?;
    let (mc, ac, _) = g.at(tc)?;
    let w = [0, 1].map(|s| {
        let (p, q) = (mid(me, ae[s]), mid(mc, ac[s]));
        let d = [ae[s][0] - me[0], ae[s][1] - me[1]];
        let c = [q[0] - p[0], q[1] - p[1]];
        (c[0] * d[1] - c[1] * d[0]).abs() / dist(me, ae[s])
    });
    w.iter().all(|x| x.is_finite() && *x > 0.0).then_some(w)
}

/// The widths of a piece's end cells for its parameters `t`: `[end][side]` (`None` for fewer
/// than one cell or where a width is not defined).
pub(crate) fn end_widths(g: &ArcGeometry, t: &[f64]) -> Option<[[f64; 2]; 2]> {
    let n = t.len().checked_sub(1).filter(|&n| n > 0)?;
    Some([side_widths(g, t[0], t[1])?, side_widths(g, t[n], t[n - 1])?])
}

/// The parameters of a piece (geometry `g`) with natural parameters `t`, graded so that its
/// end cells become `rho[end]` times their natural widths (as near as [`increments`]
/// allows). An end whose corner cell at its vertex would then have a smaller angle than
/// with the natural parameters, below [`GUARD_ANGLE`], keeps its natural end cell (the
/// grading is done again with ratio 1 there). Returns `t` itself when nothing changes, else
/// the graded parameters (and keeps `t`'s buffer in `scratch`).
pub(crate) fn grade_piece(
    g: &ArcGeometry,
    t: Vec<f64>,
    mut rho: [f64; 2],
    scratch: &mut Scratch,
) -> Vec<f64> {
    let n = t.len().saturating_sub(1);
    for _round in 0..2 {
        if n < 2 || rho == [1.0, 1.0] {
            return t;
        }
        increments(n, rho, &mut scratch.delta);
        let uniform = scratch
            .delta
            .iter()
            .all(|&d| (d * n as f64 - 1.0).abs() <= 1e-12);
        if uniform {
            return t;
        }
        graded_params(&t, &scratch.delta, &mut scratch.out);
        let o = &scratch.out;
        let ends = [(t[0], t[1], o[0], o[1]), (t[n], t[n - 1], o[n], o[n - 1])];
        let mut kept = false;
        for (k, &(te, tc, ge, gc)) in ends.iter().enumerate() {
            if rho[k] == 1.0 {
                continue;
            }
            let graded = corner_angle(g, ge, gc);
            if graded.is_some_and(|a| a < GUARD_ANGLE) && graded < corner_angle(g, te, tc) {
                rho[k] = 1.0;
                kept = true;
            }
        }
        if !kept {
            return std::mem::replace(&mut scratch.out, t);
        }
    }
    // Both ends kept (the second round returns before this for any other outcome).
    t
}

/// Corner cells at a vertex whose smallest angle is below this (degrees) are not made worse
/// by the grading ([`grade_piece`]).
pub const GUARD_ANGLE: f64 = 20.0;

/// The smallest angle (degrees) of the cells between the end spoke at arc parameter `te`
/// and the grid line at `tc` where they meet the medial arc, on either side: the angles at
/// the two medial nodes between the chord joining them and each spoke, and their
/// supplements (the cell's corners on the spokes one row in). `None` where not defined.
fn corner_angle(g: &ArcGeometry, te: f64, tc: f64) -> Option<f64> {
    let (me, ae, _) = g.at(te)?;
    let (mc, ac, _) = g.at(tc)?;
    let angle = |o: Point, p: Point, q: Point| {
        let (cross, dot) = turn_parts(o, p, q);
        cross.abs().atan2(dot).to_degrees()
    };
    let mut least = f64::INFINITY;
    for s in 0..2 {
        for a in [angle(me, mc, ae[s]), angle(mc, me, ac[s])] {
            least = least.min(a).min(180.0 - a);
        }
    }
    least.is_finite().then_some(least)
}

/// The most an end cell is widened (its natural width times this). Widening an end cell moves
/// the first grid line off the vertex along a medial arc that may curve there, which can
/// narrow the corner cell's angle at the vertex (a layout of mixed sizes lost 1.8 degrees of
/// its smallest angle to a 3.6-fold widening, before [`GUARD_ANGLE`]); at most 2: 227 of
/// 102 131 spoke faces of 1e3 bubbles stayed over 1.5 (120 unbounded, 1 101 at 1.5).
pub const WIDEN_MAX: f64 = 2.0;

/// What [`end_ratios`] reads of one piece.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EndInput {
    /// Its end vertices.
    pub ends: [usize; 2],
    /// `slots[side][end]`: the spoke (slot of the vertex) of side `side` at end `end`.
    pub slots: [[usize; 2]; 2],
    /// Its cell count.
    pub n: usize,
    /// Its natural end widths `[end][side]` ([`end_widths`]); `None`: not graded, and not
    /// a constraint on its neighbours.
    pub widths: Option<[[f64; 2]; 2]>,
}

/// How much the log width of an end cell of a piece of `n` cells may move, about: the
/// increments ramp by at most [`MAX_STEP`] per cell over about half the piece.
fn reach(n: usize) -> f64 {
    MAX_STEP.ln() * (n.saturating_sub(1) as f64 / 2.0)
}

/// The ratios `rho[end]` each piece's end cell is graded by, from one small least-squares
/// problem per vertex: with `x` the log ratio of every piece end at the vertex, minimise
/// `sum over spokes (x_i + u_i - x_j - u_j)^2 + sum_i (x_i / reach_i)^2`, `u` the log natural
/// widths of the two cells beside a spoke (one on each side: the blocks on its circle) and
/// `reach_i` how far piece end `i` can be graded ([`reach`]: a piece of one cell not at all,
/// so its neighbours adapt to it). Vertices are solved in parallel; the result does not
/// depend on the thread count.
pub(crate) fn end_ratios(inputs: &[EndInput], vertex_count: usize) -> Vec<[f64; 2]> {
    use rayon::prelude::*;
    // Piece ends by vertex (counting sort: piece order within a vertex).
    let (start, at) = crate::buckets::group(vertex_count, || {
        inputs.iter().enumerate().flat_map(|(e, p)| {
            p.ends
                .iter()
                .enumerate()
                .filter(|&(_, &v)| v < vertex_count)
                .map(move |(k, &v)| (v, (e as u32, k as u8)))
        })
    });
    let solved: Vec<Vec<f64>> = (0..vertex_count)
        .into_par_iter()
        .map(|v| solve_vertex(inputs, &at[start[v]..start[v + 1]]))
        .collect();
    let mut rho = vec![[1.0; 2]; inputs.len()];
    for v in 0..vertex_count {
        for (&(e, k), &x) in at[start[v]..start[v + 1]].iter().zip(&solved[v]) {
            rho[e as usize][k as usize] = x.exp();
        }
    }
    rho
}

/// The log ratios of the piece ends `ends` (`(piece, end)`) at one vertex (see
/// [`end_ratios`]); 0 for a piece end without widths.
fn solve_vertex(inputs: &[EndInput], ends: &[(u32, u8)]) -> Vec<f64> {
    let k = ends.len();
    let mut a = vec![0.0; k * k];
    let mut b = vec![0.0; k];
    // Every pair of piece ends sharing a spoke (the same slot), one on each of its sides.
    let spoke = |i: usize, side: usize| {
        let (e, end) = ends[i];
        inputs[e as usize].slots[side][end as usize]
    };
    let log_width = |i: usize, side: usize| {
        let (e, end) = ends[i];
        inputs[e as usize]
            .widths
            .map(|w| w[end as usize][side].ln())
    };
    let mut any = false;
    for i in 0..k {
        for j in i + 1..k {
            for si in 0..2 {
                for sj in 0..2 {
                    if spoke(i, si) != spoke(j, sj) {
                        continue;
                    }
                    let (Some(ui), Some(uj)) = (log_width(i, si), log_width(j, sj)) else {
                        continue;
                    };
                    // Residual x_i - x_j + (ui - uj).
                    let r = ui - uj;
                    a[i * k + i] += 1.0;
                    a[j * k + j] += 1.0;
                    a[i * k + j] -= 1.0;
                    a[j * k + i] -= 1.0;
                    b[i] -= r;
                    b[j] += r;
                    any = true;
                }
            }
        }
    }
    if !any {
        return vec![0.0; k];
    }
    for (i, &(e, _)) in ends.iter().enumerate() {
        let p = &inputs[e as usize];
        let reach = if p.widths.is_some() { reach(p.n) } else { 0.0 };
        a[i * k + i] += if reach > 0.0 {
            1.0 / (reach * reach)
        } else {
            1e12
        };
    }
    let x = solve_dense(a, b, k).unwrap_or_else(|| vec![0.0; k]);
    // Within each piece end's reach (the increments would clamp further anyway), widened by
    // at most [`WIDEN_MAX`].
    x.iter()
        .zip(ends)
        .map(|(&x, &(e, _))| {
            let r = reach(inputs[e as usize].n);
            if x.is_finite() {
                x.clamp(-r, r.min(WIDEN_MAX.ln()))
            } else {
                0.0
            }
        })
        .collect()
}

/// `A x = b` for a symmetric positive definite `k x k` matrix `a` (row major), by Gaussian
/// elimination with partial pivoting; `None` when singular or not finite.
fn solve_dense(mut a: Vec<f64>, mut b: Vec<f64>, k: usize) -> Option<Vec<f64>> {
    for c in 0..k {
        let p = (c..k).max_by(|&i, &j| a[i * k + c].abs().total_cmp(&a[j * k + c].abs()))?;
        let pivot = a[p * k + c].abs();
        if pivot.is_nan() || pivot == 0.0 {
            return None;
        }
        if p != c {
            for j in 0..k {
                a.swap(p * k + j, c * k + j);
            }
            b.swap(p, c);
        }
        for i in c + 1..k {
            let f = a[i * k + c] / a[c * k + c];
            for j in c..k {
                a[i * k + j] -= f * a[c * k + j];
            }
            b[i] -= f * b[c];
        }
    }
    let mut x = vec![0.0; k];
    for c in (0..k).rev() {
        let s: f64 = (c + 1..k).map(|j| a[c * k + j] * x[j]).sum();
        x[c] = (b[c] - s) / a[c * k + c];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layouts::SplitMix64;

    #[test]
    fn increments_sum_to_one_and_step_gently() {
        let mut r = SplitMix64(7);
        let mut out = Vec::new();
        for _ in 0..3000 {
            let n = 1 + (r.next_f64() * 40.0) as usize;
            let rho = [
                (r.next_f64() * 6.0 - 3.0).exp(),
                (r.next_f64() * 6.0 - 3.0).exp(),
            ];
            increments(n, rho, &mut out);
            assert_eq!(out.len(), n);
            let sum: f64 = out.iter().sum();
            assert!((sum - 1.0).abs() < 1e-9, "n {n} rho {rho:?}: sum {sum}");
            assert!(out.iter().all(|&d| d > 0.0));
            for w in out.windows(2) {
                let q = w[1] / w[0];
                assert!(
                    (1.0 / MAX_STEP / (1.0 + 1e-9)..=MAX_STEP * (1.0 + 1e-9)).contains(&q),
                    "n {n} rho {rho:?}: step {q}"
                );
            }
        }
    }

    #[test]
    fn reachable_ends_are_met_and_ratio_one_is_uniform() {
        let mut out = Vec::new();
        // 20 cells: end cells at 0.5 and 1.5 of the natural ones are within reach.
        increments(20, [0.5, 1.5], &mut out);
        assert!((out[0] * 20.0 - 0.5).abs() < 1e-9, "{}", out[0] * 20.0);
        assert!((out[19] * 20.0 - 1.5).abs() < 1e-9, "{}", out[19] * 20.0);
        increments(9, [1.0, 1.0], &mut out);
        assert!(out.iter().all(|&d| (d - 1.0 / 9.0).abs() < 1e-12));
        // The grading never goes the wrong way: a smaller wanted end gives a smaller end.
        for n in 2..30 {
            increments(n, [0.3, 1.0], &mut out);
            assert!(out[0] <= 1.0 / n as f64 + 1e-12, "n {n}: {}", out[0]);
            increments(n, [1.0, 3.0], &mut out);
            assert!(
                out[n - 1] >= 1.0 / n as f64 - 1e-12,
                "n {n}: {}",
                out[n - 1]
            );
        }
    }

    #[test]
    fn graded_params_keep_the_ends_and_the_order() {
        let mut r = SplitMix64(3);
        let (mut d, mut out) = (Vec::new(), Vec::new());
        for _ in 0..500 {
            let n = 1 + (r.next_f64() * 30.0) as usize;
            let mut t: Vec<f64> = (0..=n).map(|_| r.next_f64()).collect();
            t.sort_by(f64::total_cmp);
            t[0] = 0.0;
            t[n] = 1.0;
            increments(n, [r.next_f64() * 3.0, r.next_f64() * 3.0], &mut d);
            graded_params(&t, &d, &mut out);
            assert_eq!(out.len(), n + 1);
            assert_eq!((out[0], out[n]), (0.0, 1.0));
            assert!(out.windows(2).all(|w| w[0] <= w[1]));
        }
        // Uniform increments give the natural parameters back.
        let t = [0.0, 0.1, 0.5, 0.7, 1.0];
        increments(4, [1.0, 1.0], &mut d);
        graded_params(&t, &d, &mut out);
        for (a, b) in out.iter().zip(&t) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    /// Three piece ends at one vertex, sharing its three spokes pairwise (slots 0, 1, 2).
    fn vertex(n: [usize; 3], logw: [[f64; 2]; 3]) -> Vec<EndInput> {
        // Piece k has side 0 on spoke k and side 1 on spoke (k + 1) % 3, at its end 0.
        (0..3)
            .map(|k| EndInput {
                ends: [0, 1 + k],
                slots: [[k, 0], [(k + 1) % 3, 0]],
                n: n[k],
                widths: Some([[logw[k][0].exp(), logw[k][1].exp()], [1.0, 1.0]]),
            })
            .collect()
    }

    /// The width ratio across each spoke of [`vertex`] after grading by `rho`.
    fn spoke_ratios(inputs: &[EndInput], rho: &[[f64; 2]]) -> [f64; 3] {
        let w = |k: usize, side: usize| inputs[k].widths.unwrap()[0][side] * rho[k][0];
        // Spoke s: piece s side 0 and piece (s + 2) % 3 side 1.
        [0, 1, 2].map(|s| {
            let (a, b) = (w(s, 0), w((s + 2) % 3, 1));
            a.max(b) / a.min(b)
        })
    }

    #[test]
    fn a_rigid_arc_is_not_graded_and_its_neighbours_adapt_to_it() {
        let mut r = SplitMix64(5);
        for _ in 0..300 {
            let mut logw = [[0.0; 2]; 3];
            for w in logw.iter_mut() {
                *w = [r.next_f64() * 1.6 - 0.8, 0.0];
                w[1] = w[0] + (r.next_f64() - 0.5) * 0.2;
            }
            let n = [
                1,
                30 + (r.next_f64() * 40.0) as usize,
                30 + (r.next_f64() * 40.0) as usize,
            ];
            let inputs = vertex(n, logw);
            let rho = end_ratios(&inputs, 4);
            assert_eq!(rho[0], [1.0, 1.0], "a one-cell arc keeps its cell");
            assert!(rho.iter().flatten().all(|&r| r > 0.0 && r <= WIDEN_MAX));
            // The other ends are at vertices of their own, with no partner: not graded.
            assert!(rho.iter().all(|r| r[1] == 1.0));
            let before = spoke_ratios(&inputs, &[[1.0; 2]; 3]);
            let after = spoke_ratios(&inputs, &rho);
            // The spokes of the rigid arc: matched up to the flexible arcs' small pull
            // towards their natural cells (and the side ratios no single scale can fix),
            // unless that would widen a cell more than `WIDEN_MAX`.
            for s in [0, 1] {
                let bound = (0.25 * before[s].ln() + 0.12).max(before[s].ln() - WIDEN_MAX.ln());
                assert!(
                    after[s].ln() <= bound + 1e-9,
                    "spoke {s}: {} -> {}",
                    before[s],
                    after[s]
                );
            }
        }
    }

    #[test]
    fn matched_widths_stay_and_missing_widths_do_not_constrain() {
        let inputs = vertex([10, 20, 30], [[0.3, 0.3]; 3]);
        let rho = end_ratios(&inputs, 4);
        for r in &rho {
            assert!((r[0] - 1.0).abs() < 1e-12, "{r:?}");
        }
        let mut inputs = vertex([10, 20, 30], [[0.0, 0.0], [0.5, 0.5], [-0.5, -0.5]]);
        inputs[1].widths = None;
        let rho = end_ratios(&inputs, 4);
        assert_eq!(rho[1], [1.0, 1.0], "no widths: not graded");
        // Pieces 0 and 2 share spoke 0 (piece 0 side 0 at log width 0, piece 2 side 1 at
        // -0.5): they close most of the gap, less the pull of each towards its own cell, and
        // the piece of more cells moves more.
        let (a, c) = (rho[0][0].ln(), rho[2][0].ln());
        assert!(a < 0.0 && c > 0.0, "{a} {c}");
        assert!(c - a < 0.5 && c - a > 0.4 && c > -a, "{a} {c}");
    }

    #[test]
    fn dense_solve_solves() {
        let mut r = SplitMix64(9);
        for k in 1..8 {
            // A symmetric positive definite matrix: M^T M + I.
            let m: Vec<f64> = (0..k * k).map(|_| r.next_f64() - 0.5).collect();
            let mut a = vec![0.0; k * k];
            for i in 0..k {
                for j in 0..k {
                    a[i * k + j] = (0..k).map(|l| m[l * k + i] * m[l * k + j]).sum::<f64>()
                        + if i == j { 1.0 } else { 0.0 };
                }
            }
            let b: Vec<f64> = (0..k).map(|_| r.next_f64() - 0.5).collect();
            let x = solve_dense(a.clone(), b.clone(), k).unwrap();
            for i in 0..k {
                let ax: f64 = (0..k).map(|j| a[i * k + j] * x[j]).sum();
                assert!((ax - b[i]).abs() < 1e-12, "k {k}");
            }
        }
        assert!(solve_dense(vec![0.0; 4], vec![1.0, 1.0], 2).is_none());
    }
}
