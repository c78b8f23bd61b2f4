//! End grading of the nodes along an arc piece, so that the cells on either side of a spoke
//! have about the same width.
//!
//! Why: the blocks on one circle share its spokes, but each arc equidistributes its own
//! weights over its own count (`equidistribution::arc_params_into`), so the cells next to a
//! spoke on its two sides can differ in width by the ratio of the two arcs' `t_e / n_e` and
//! of their mean wall-normal counts (a growth ratio up to 3.4 across spokes at the default
//! size, far more with `--block-cells`, where every arc gets the same count whatever its
//! length).
//!
//! What: every arc that ends at medial vertex `V` aims its end cell at one width,
//! [`vertex_width`]: the vertex's empty-circle radius (the spokes' length) over the mean
//! wall-normal count of the circles touching `V`, in the measure of the weights (the mean of
//! the spoke mid-curve chords of both blocks). The three arcs at `V` compute the same target,
//! so the cells on both sides of each of its spokes approach the same width.
//!
//! How: the natural parameters `t_i` (cell `i` carries `1 / n` of the arc's weight) are
//! re-sampled at `u_i = delta_0 + ... + delta_{i-1}` on their piecewise-linear interpolation
//! `u -> t` ([`graded_params`]). The increments are `delta_i = exp(L(s_i))`, `s_i = i / (n -
//! 1)`, with `L` quadratic: linear from the log of the wanted first increment to that of the
//! wanted last one, plus the bump `B 4 s (1 - s)` that makes them sum to 1. Consecutive
//! increments differ by at most [`MAX_STEP`]: wanted ratios the count cannot reach that
//! smoothly are pulled towards 1 (geometrically, the largest fraction that fits), so short
//! arcs of few cells are graded a little or not at all.

use super::{dist, mid, ArcGeometry};

/// The largest ratio of consecutive increments along an arc that the grading introduces (the
/// natural spacing then multiplies it).
pub const MAX_STEP: f64 = 1.2;

/// The end-cell width every arc at a vertex aims for: the vertex's radius over the mean of
/// `counts` (the wall-normal counts of the circles touching it). `None` when either is not
/// a positive finite number.
pub fn vertex_width(radius: f64, counts: impl IntoIterator<Item = usize>) -> Option<f64> {
    let (mut sum, mut k) = (0usize, 0usize);
    for c in counts {
        sum = sum.saturating_add(c);
        k += 1;
    }
    let mean = sum as f64 / k as f64;
    let w = radius / mean;
    (k > 0 && sum > 0 && w.is_finite() && w > 0.0).then_some(w)
}

/// The natural end widths of an arc piece of `n` cells whose ends have the radii `radius`,
/// each with the weight of that estimate in its vertex's target ([`vertex_widths`]). From
/// the geometry alone (so the same whatever a cache holds): with `L` the mid-curve chord of
/// the whole piece, one cell is `L` wide; more cells equidistribute about `L / rho` over `n`
/// (the spoke-length density), so the end cell at radius `r_k` is about `r_k L / (rho n)`,
/// `rho` the geometric mean of the end radii. The weight `1 / n²`: arcs of few cells can
/// hardly be graded, so the others adapt to them.
pub(crate) fn end_estimates(
    g: &ArcGeometry,
    n: usize,
    radius: [f64; 2],
) -> [Option<(f64, f64)>; 2] {
    let Some(chord) = (n > 0).then(|| mid_width(g, 0.0, 1.0)).flatten() else {
        return [None; 2];
    };
    let weight = 1.0 / (n as f64 * n as f64);
    let rho = (radius[0] * radius[1]).sqrt();
    radius.map(|r| {
        let w = if n == 1 {
            chord
        } else {
            r * chord / (rho * n as f64)
        };
        (w.is_finite() && w > 0.0).then_some((w, weight))
    })
}

/// The target width of each of `count` vertices: the weighted geometric mean of the end
/// estimates `(ends, [estimate at ends[0], at ends[1]])` of the pieces meeting there (summed
/// in the order given), or `fallback(v)` where no piece gave one.
pub(crate) fn vertex_widths<'a>(
    count: usize,
    pieces: impl Iterator<Item = ([usize; 2], &'a [Option<(f64, f64)>; 2])>,
    fallback: impl Fn(usize) -> Option<f64> + Sync,
) -> Vec<Option<f64>> {
    let mut acc = vec![(0.0f64, 0.0f64); count];
    for (ends, est) in pieces {
        for k in 0..2 {
            if let (Some(a), Some((w, weight))) = (acc.get_mut(ends[k]), est[k]) {
                a.0 += weight * w.ln();
                a.1 += weight;
            }
        }
    }
    acc.iter()
        .enumerate()
        .map(|(v, &(s, wsum))| {
            let w = (s / wsum).exp();
            if wsum > 0.0 && w.is_finite() && w > 0.0 {
                Some(w)
            } else {
                fallback(v)
            }
        })
        .collect()
}

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

/// The width of the cell between arc parameters `ta` and `tb` in the measure of the weights:
/// the mean of the two spoke mid-curve chords (`None` where the arc is not defined).
fn mid_width(g: &ArcGeometry, ta: f64, tb: f64) -> Option<f64> {
    let (ma, aa, _) = g.at(ta)?;
    let (mb, ab, _) = g.at(tb)?;
    let w = 0.5 * (dist(mid(ma, aa[0]), mid(mb, ab[0])) + dist(mid(ma, aa[1]), mid(mb, ab[1])));
    (w.is_finite() && w > 0.0).then_some(w)
}

/// The parameters of a piece with natural parameters `t`, graded so that its end cells
/// approach `widths` (those of its start and end vertices, [`vertex_width`]; `None`: that end
/// keeps its natural cell). Returns `t` itself when nothing changes, else the graded
/// parameters (and keeps `t`'s buffer in `scratch`).
pub(crate) fn grade_piece(
    g: &ArcGeometry,
    t: Vec<f64>,
    widths: [Option<f64>; 2],
    scratch: &mut Scratch,
) -> Vec<f64> {
    let n = t.len().saturating_sub(1);
    if n < 2 || widths.iter().all(Option::is_none) {
        return t;
    }
    let natural = [mid_width(g, t[0], t[1]), mid_width(g, t[n - 1], t[n])];
    let rho = [0, 1].map(|k| match (widths[k], natural[k]) {
        (Some(w), Some(nat)) => w / nat,
        _ => 1.0,
    });
    increments(n, rho, &mut scratch.delta);
    let uniform = scratch
        .delta
        .iter()
        .all(|&d| (d * n as f64 - 1.0).abs() <= 1e-12);
    if uniform {
        return t;
    }
    graded_params(&t, &scratch.delta, &mut scratch.out);
    std::mem::replace(&mut scratch.out, t)
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

    #[test]
    fn vertex_width_is_radius_over_mean_count() {
        assert_eq!(vertex_width(3.0, [2, 4, 6]), Some(0.75));
        assert_eq!(vertex_width(3.0, []), None);
        assert_eq!(vertex_width(0.0, [2]), None);
        assert_eq!(vertex_width(f64::NAN, [2]), None);
    }
}
