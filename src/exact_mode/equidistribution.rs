//! Node parameters along a medial arc: `n + 1` parameters in `[0, 1]` equidistributing the
//! sub-step weights (issue 8).
//!
//! The weights are summed once, into their running sums `p[s] = w[0] + ... + w[s - 1]` (from
//! `0.0`, in order: each `p[s + 1]` is the very addition `cum + w[s]` the search for a node's
//! sub-step made, and the total is `p[k]`), so the search for each node compares instead of
//! adding: the same values, bit for bit, as the sum-then-scan it replaced
//! ([`equidistribute_reference`]), without its two dependent chains of additions. The total
//! differs from `w.iter().sum()` at most in the sign of a zero (both sums add the same weights
//! in the same order from a zero), which takes the same equal-steps branch.

use crate::lanes::Lanes;

/// `n + 1` parameters in `[0, 1]` equidistributing the sub-step weights `w` (`t_0 = 0`,
/// `t_n = 1` exactly; equal steps when the weights vanish).
#[cfg(test)]
pub(crate) fn equidistribute(w: &[f64], n: usize) -> Vec<f64> {
    let mut t = Vec::with_capacity(n + 1);
    equidistribute_into(w, n, &mut t, &mut Vec::with_capacity(w.len() + 1));
    t
}

/// `equidistribute` (the allocating form, kept for the tests) written into `t` (cleared
/// first), with `prefix` the running sums' buffer: the same values, in buffers reused from
/// piece to piece. Inlined, so that [`arc_params_into`]'s builds compile it in.
#[inline(always)]
pub(crate) fn equidistribute_into(w: &[f64], n: usize, t: &mut Vec<f64>, prefix: &mut Vec<f64>) {
    t.clear();
    prefix.clear();
    prefix.reserve(w.len() + 1);
    let mut cum = 0.0;
    prefix.push(cum);
    prefix.extend(w.iter().map(|&x| {
        cum += x;
        cum
    }));
    fill(w, prefix, n, t);
}

/// The parameters of the weights `w` from their running sums `p` (see the module docs).
#[inline(always)]
fn fill(w: &[f64], p: &[f64], n: usize, t: &mut Vec<f64>) {
    let k = w.len();
    let total = p[k];
    if !(total.is_finite() && total > 0.0) || k == 0 {
        t.extend((0..=n).map(|i| i as f64 / n as f64));
        t[n] = 1.0;
        return;
    }
    t.push(0.0);
    let mut s = 0;
    let mut last = 0.0;
    for i in 1..n {
        let target = total * (i as f64 / n as f64);
        while s < k && p[s + 1] < target {
            s += 1;
        }
        let cum = p[s];
        let frac = if s < k && w[s] > 0.0 {
            ((target - cum) / w[s]).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let ti = ((s.min(k) as f64 + frac) / k as f64).clamp(0.0, 1.0);
        last = ti.max(last);
        t.push(last);
    }
    t.push(1.0);
}

/// How far a cell may go over one unit of the wall-angle density before
/// [`arc_params_into`] rescales the weights (relative; rounding, not a second limit).
const ANG_SLACK: f64 = 1e-6;

/// The node parameters of an arc piece of `n` cells into `t`: [`equidistribute_into`] of its
/// weights `w` (per sub-step `max(nbar sq_k, ang_k)`, see [`super::counts`]), unless a cell
/// would then sweep more than one unit of `ang` (more than [`super::MAX_WALL_ANGLE`] of either
/// wall). That happens when `n` is below the arc's target `sum w`: with a fixed grid per block
/// (`--block-cells`) along an arc that runs through a narrow gap, the short spokes there draw
/// every cell and leave one cell to sweep most of a wall (which folds it). The weights then
/// become `max(alpha w_k, ang_k)`, with the largest `alpha` in `[0, 1]` (to 2^-60) whose total
/// is at most `n`: every cell carries at most one unit of weight, so at most one unit of `ang`,
/// and the spacing still follows the spokes wherever the wall angle allows. When `n` is below
/// `sum ang` itself (a count under the arc's lower bound) `alpha` is 0: the cells share the
/// wall angle equally.
///
/// The limit is on the densities, which take each sub-step's turn as even over it: a cell
/// that starts inside a sub-step turning fast (by an arc's end) can sweep a little more than
/// [`super::MAX_WALL_ANGLE`] of the real wall (17.7 degrees at most over 1 500 random layouts
/// in `tests/exactmode_block_cells.rs`).
///
/// Arcs whose cells all stay within the limit keep the plain parameters, bit for bit. `w` is
/// left holding the weights used; `prefix` is scratch.
///
/// Compiled for each vector build ([`Lanes`], chosen once per call, as the densities are):
/// the baseline (SSE2) has no 64-bit unsigned maximum, no blend for `max` and `clamp`, and
/// 2-lane vectors, and the piece loop of exact mode spent twice as long here as the AVX-512
/// build does (issue 8). The same IEEE operations in the same order (no fused multiply-add,
/// sums in order), so every build gives the same bits (tested).
pub(crate) fn arc_params_into(
    w: &mut [f64],
    ang: &[f64],
    n: usize,
    t: &mut Vec<f64>,
    prefix: &mut Vec<f64>,
) {
    arc_params_with(Lanes::best(), w, ang, n, t, prefix)
}

/// [`arc_params_into`] in the build `lanes` (the baseline when the CPU lacks it): the test
/// hook that compares the builds.
pub(crate) fn arc_params_with(
    lanes: Lanes,
    w: &mut [f64],
    ang: &[f64],
    n: usize,
    t: &mut Vec<f64>,
    prefix: &mut Vec<f64>,
) {
    #[cfg(target_arch = "x86_64")]
    match lanes {
        // SAFETY: `Lanes::available` checked the CPU's features.
        Lanes::Avx512 if lanes.available() => {
            return unsafe { arc_params_avx512(w, ang, n, t, prefix) }
        }
        // SAFETY: as above.
        Lanes::Avx2 if lanes.available() => {
            return unsafe { arc_params_avx2(w, ang, n, t, prefix) }
        }
        _ => {}
    }
    arc_params_body(w, ang, n, t, prefix)
}

/// [`arc_params_body`] compiled for AVX-512 (8-lane vectors).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
fn arc_params_avx512(
    w: &mut [f64],
    ang: &[f64],
    n: usize,
    t: &mut Vec<f64>,
    prefix: &mut Vec<f64>,
) {
    arc_params_body(w, ang, n, t, prefix)
}

/// [`arc_params_body`] compiled for AVX2 (4-lane vectors).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn arc_params_avx2(w: &mut [f64], ang: &[f64], n: usize, t: &mut Vec<f64>, prefix: &mut Vec<f64>) {
    arc_params_body(w, ang, n, t, prefix)
}

/// The body of [`arc_params_into`], inlined into each build.
#[inline(always)]
fn arc_params_body(w: &mut [f64], ang: &[f64], n: usize, t: &mut Vec<f64>, prefix: &mut Vec<f64>) {
    equidistribute_into(w, n, t, prefix);
    if ang.len() != w.len()
        || within_ang_limit(ang, t)
        || largest_cell_ang(ang, t) <= 1.0 + ANG_SLACK
    {
        return;
    }
    let limit = n as f64;
    let total = |a: f64| -> f64 { w.iter().zip(ang).map(|(&x, &g)| (a * x).max(g)).sum() };
    let alpha = if total(0.0) <= limit {
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if total(mid) <= limit {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    } else {
        0.0
    };
    for (x, &g) in w.iter_mut().zip(ang) {
        *x = (alpha * *x).max(g);
    }
    equidistribute_into(w, n, t, prefix);
}

/// A sufficient test for `largest_cell_ang(ang, t) <= 1 + ANG_SLACK`, without its running
/// sums: no cell carries more than `G k W`, with `G` the largest density, `k` the sub-steps
/// and `W` the widest cell (in parameter), and the rounding of those sums is at most a few
/// hundred ulps of their total `<= G k` (the `1e-12 G k` term, with a margin of
/// `ANG_SLACK / 2` besides). False when a density is negative (`-0.0` too) or a density or a
/// parameter is not finite (the full computation decides those).
#[inline(always)]
fn within_ang_limit(ang: &[f64], t: &[f64]) -> bool {
    // Non-negative finite floats order as their bits; every other bit pattern (negative,
    // `-0.0` included, infinite, NaN) is at least that of `+inf`: one unsigned maximum (a
    // reduction the compiler vectorises) gives both the largest density and the check.
    let top = ang.iter().fold(0u64, |m, x| m.max(x.to_bits()));
    if top >= f64::INFINITY.to_bits() {
        return false;
    }
    let g = f64::from_bits(top);
    if !t.iter().all(|x| x.is_finite()) {
        return false;
    }
    let mut widest = 0.0f64;
    for c in t.windows(2) {
        let d = c[1] - c[0];
        widest = if d > widest { d } else { widest };
    }
    let gk = g * ang.len() as f64;
    gk * widest + 1e-12 * gk <= 1.0 + 0.5 * ANG_SLACK
}

/// The most wall-angle density (`ang`, per sub-step, taken as spread evenly over its
/// sub-step) that one cell between consecutive parameters `t` (in `[0, 1]`, nondecreasing)
/// sweeps.
#[inline(always)]
fn largest_cell_ang(ang: &[f64], t: &[f64]) -> f64 {
    let k = ang.len();
    let Some((&first, rest)) = t.split_first() else {
        return 0.0;
    };
    if k == 0 {
        return 0.0;
    }
    let kf = k as f64;
    // The density before sub-step `s`, summed once, in order.
    let (mut s, mut before) = (0usize, 0.0);
    let mut cumulative = |x: f64| {
        let x = (x * kf).clamp(0.0, kf);
        while s + 1 < k && (s + 1) as f64 <= x {
            before += ang[s];
            s += 1;
        }
        before + ang[s] * (x - s as f64)
    };
    let mut last = cumulative(first);
    let mut most = 0.0f64;
    for &x in rest {
        let c = cumulative(x);
        most = most.max(c - last);
        last = c;
    }
    most
}

/// The sum-then-scan form (the reference of the tests, bit for bit).
#[doc(hidden)]
pub fn equidistribute_reference(w: &[f64], n: usize) -> Vec<f64> {
    let mut t = Vec::with_capacity(n + 1);
    let k = w.len();
    let total: f64 = w.iter().sum();
    if !(total.is_finite() && total > 0.0) || k == 0 {
        t.extend((0..=n).map(|i| i as f64 / n as f64));
        t[n] = 1.0;
        return t;
    }
    t.push(0.0);
    let mut cum = 0.0;
    let mut s = 0;
    for i in 1..n {
        let target = total * (i as f64 / n as f64);
        while s < k && cum + w[s] < target {
            cum += w[s];
            s += 1;
        }
        let frac = if s < k && w[s] > 0.0 {
            ((target - cum) / w[s]).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let ti = ((s.min(k) as f64 + frac) / k as f64).clamp(0.0, 1.0);
        let last = t[t.len() - 1];
        t.push(ti.max(last));
    }
    t.push(1.0);
    t
}

/// The bits of [`equidistribute_into`]'s parameters, on buffers left over from another call
/// (test hook).
#[doc(hidden)]
pub fn equidistribute_bits(w: &[f64], n: usize) -> Vec<u64> {
    let mut t = vec![f64::NAN; 7];
    let mut prefix = vec![f64::NAN; 3];
    equidistribute_into(w, n, &mut t, &mut prefix);
    t.iter().map(|x| x.to_bits()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layouts::SplitMix64;

    /// The density `ang` (even over each sub-step) inside `[a, b]` (parameters in `[0, 1]`),
    /// summed sub-step by sub-step from the overlaps: not the running sums of
    /// [`largest_cell_ang`].
    fn swept(ang: &[f64], a: f64, b: f64) -> f64 {
        let k = ang.len() as f64;
        let (a, b) = (a * k, b * k);
        ang.iter()
            .enumerate()
            .map(|(s, g)| g * ((b.min(s as f64 + 1.0) - a.max(s as f64)).max(0.0)))
            .sum()
    }

    fn most_swept(ang: &[f64], t: &[f64]) -> f64 {
        t.windows(2)
            .map(|c| swept(ang, c[0], c[1]))
            .fold(0.0, f64::max)
    }

    /// Sub-step weights `w >= ang` with a narrow gap: weights up to 1e6 times the rest on a
    /// few sub-steps, and wall-angle densities up to `ang_max` per sub-step.
    fn gap_arc(rng: &mut SplitMix64, k: usize, ang_max: f64) -> (Vec<f64>, Vec<f64>) {
        let ang: Vec<f64> = (0..k).map(|_| ang_max * rng.next_f64()).collect();
        let at = (rng.next_f64() * k as f64) as usize;
        let w = ang
            .iter()
            .enumerate()
            .map(|(s, &g)| {
                let spoke = if s.abs_diff(at) < 3 { 1e6 } else { 1.0 };
                (spoke * rng.next_f64()).max(g)
            })
            .collect();
        (w, ang)
    }

    fn well_formed(t: &[f64], n: usize) {
        assert_eq!(t.len(), n + 1);
        assert_eq!((t[0], t[n]), (0.0, 1.0));
        assert!(t.windows(2).all(|c| c[0] <= c[1]), "{t:?}");
    }

    #[test]
    fn largest_cell_ang_matches_the_overlap_sums() {
        let mut rng = SplitMix64(7);
        for _ in 0..500 {
            let k = 1 + (rng.next_f64() * 40.0) as usize;
            let ang: Vec<f64> = (0..k).map(|_| rng.next_f64()).collect();
            let n = 1 + (rng.next_f64() * 30.0) as usize;
            let mut t: Vec<f64> = (0..=n).map(|_| rng.next_f64()).collect();
            t.sort_by(f64::total_cmp);
            t[0] = 0.0;
            t[n] = 1.0;
            let (fast, slow) = (largest_cell_ang(&ang, &t), most_swept(&ang, &t));
            assert!((fast - slow).abs() <= 1e-12 * (1.0 + slow), "{fast} {slow}");
        }
        assert_eq!(largest_cell_ang(&[], &[0.0, 1.0]), 0.0);
        assert_eq!(largest_cell_ang(&[1.0], &[]), 0.0);
    }

    /// The cheap test never passes an arc that the running sums would rescale: on random
    /// densities (even, spiky with zeros between, random) and parameters, whenever
    /// [`within_ang_limit`] holds, [`largest_cell_ang`] is within `1 + ANG_SLACK`; and the
    /// test does decide many of them (it is not vacuous) but not all.
    #[test]
    fn the_cheap_limit_test_implies_the_running_sums_test() {
        let mut rng = SplitMix64(29);
        let (mut passed, mut cases) = (0, 0);
        for case in 0..20_000 {
            let k = 1 + (rng.next_f64() * 300.0) as usize;
            let n = 1 + (rng.next_f64() * 40.0) as usize;
            let scale = [0.01, 0.1, 1.0, 4.0][case % 4] / k as f64 * n as f64;
            let ang: Vec<f64> = (0..k)
                .map(|s| match case % 3 {
                    0 => scale * rng.next_f64(),
                    1 if s % 17 == 0 => scale * 20.0 * rng.next_f64(),
                    1 => 0.0,
                    _ => scale,
                })
                .collect();
            let w: Vec<f64> = (0..k).map(|_| 0.01 + rng.next_f64()).collect();
            let t = equidistribute(&w, n);
            cases += 1;
            if within_ang_limit(&ang, &t) {
                passed += 1;
                let most = largest_cell_ang(&ang, &t);
                assert!(most <= 1.0 + ANG_SLACK, "{most} k {k} n {n}");
                assert!(most <= most_swept(&ang, &t) + 1e-9, "{most}");
            }
        }
        assert!(passed * 5 > cases && passed < cases, "{passed} of {cases}");
        // Densities not finite or negative are left to the running sums.
        assert!(!within_ang_limit(&[0.1, f64::NAN], &[0.0, 1.0]));
        assert!(!within_ang_limit(&[0.1, -0.1], &[0.0, 1.0]));
        assert!(!within_ang_limit(&[0.1, f64::INFINITY], &[0.0, 1.0]));
        assert!(!within_ang_limit(&[0.1, -0.0], &[0.0, 1.0]));
        assert!(!within_ang_limit(&[0.1, 0.1], &[0.0, f64::NAN, 1.0]));
        assert!(within_ang_limit(&[0.1, 0.0], &[0.0, 0.5, 1.0]));
    }

    /// Arcs whose cells all stay within one unit keep the plain parameters, bit for bit.
    #[test]
    fn arcs_within_the_limit_keep_their_parameters() {
        let mut rng = SplitMix64(11);
        for _ in 0..300 {
            let k = 1 + (rng.next_f64() * 64.0) as usize;
            let ang: Vec<f64> = (0..k).map(|_| 0.05 * rng.next_f64()).collect();
            let mut w: Vec<f64> = ang.iter().map(|&g| g + rng.next_f64()).collect();
            // At least as many cells as the total weight: every cell carries at most one unit.
            let n = (w.iter().sum::<f64>().ceil() as usize).max(1);
            let plain = equidistribute(&w, n);
            let (mut t, mut prefix) = (Vec::new(), Vec::new());
            let before = w.clone();
            arc_params_into(&mut w, &ang, n, &mut t, &mut prefix);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
            assert_eq!(bits(&t), bits(&plain));
            assert_eq!(bits(&w), bits(&before));
        }
    }

    /// With fewer cells than the total weight and a narrow gap drawing the weight, the plain
    /// parameters leave a cell sweeping several units; the capped ones keep every cell within
    /// one unit, as long as there are at least `sum ang` cells.
    #[test]
    fn a_narrow_gap_no_longer_draws_every_cell() {
        let mut rng = SplitMix64(13);
        let mut over = 0;
        for _ in 0..300 {
            let k = 256;
            let (mut w, ang) = gap_arc(&mut rng, k, 0.1);
            let lower = ang.iter().sum::<f64>().ceil() as usize;
            let n = lower + (rng.next_f64() * 8.0) as usize;
            over += usize::from(most_swept(&ang, &equidistribute(&w, n)) > 1.5);
            let (mut t, mut prefix) = (Vec::new(), Vec::new());
            arc_params_into(&mut w, &ang, n, &mut t, &mut prefix);
            well_formed(&t, n);
            let most = most_swept(&ang, &t);
            assert!(most <= 1.0 + 1e-9, "{most} with {n} cells");
            // The weights used are `max(alpha w, ang)`: never below the wall angle.
            assert!(w.iter().zip(&ang).all(|(x, g)| x >= g));
        }
        // The plain parameters were over the limit on most of these arcs.
        assert!(over > 200, "{over}");
    }

    /// Every vector build of [`arc_params_into`] gives the baseline's bits (parameters and the
    /// weights left in `w`) on arcs within the limit, narrow-gap arcs that are rescaled, counts
    /// below the lower bound, and degenerate densities (zeros of both signs, negative,
    /// infinite and NaN entries, empty arcs), on buffers left over from other calls; and the
    /// builds do run here (the AVX-512 one on this project's machines).
    #[test]
    fn every_build_gives_the_baselines_bits() {
        let mut rng = SplitMix64(41);
        let builds: Vec<Lanes> = Lanes::ALL.into_iter().filter(|l| l.available()).collect();
        let odd = [0.0, -0.0, -1.0, f64::INFINITY, f64::NAN, 1e-300, 1e300];
        let mut rescaled = 0;
        for case in 0..3000 {
            let k = [0, 1, 2, 7, 64, 256][case % 6];
            let (mut w, mut ang) = if case % 3 == 0 && k > 0 {
                gap_arc(&mut rng, k, 0.1)
            } else {
                let ang: Vec<f64> = (0..k).map(|_| 0.05 * rng.next_f64()).collect();
                let w = ang.iter().map(|&g| g + rng.next_f64()).collect();
                (w, ang)
            };
            if case % 5 == 0 && k > 0 {
                for _ in 0..2 {
                    let at = (rng.next_f64() * k as f64) as usize;
                    let x = odd[(rng.next_f64() * odd.len() as f64) as usize];
                    if rng.next_f64() < 0.5 {
                        w[at] = x;
                    } else {
                        ang[at] = x;
                    }
                }
            }
            // (At most 68 cells: an entry of 1e300 would ask for more than memory holds.)
            let lower = ang
                .iter()
                .filter(|g| g.is_finite())
                .sum::<f64>()
                .ceil()
                .min(60.0) as usize;
            let n = 1 + (lower + (rng.next_f64() * 8.0) as usize).saturating_sub(case % 4);
            let run = |lanes: Lanes| {
                let mut w = w.clone();
                let (mut t, mut prefix) = (vec![f64::NAN; case % 9], vec![7.0; case % 5]);
                arc_params_with(lanes, &mut w, &ang, n, &mut t, &mut prefix);
                (run_bits(&t), run_bits(&w))
            };
            let base = run(Lanes::Base);
            rescaled += usize::from(base.1 != run_bits(&w));
            for &lanes in &builds {
                assert_eq!(run(lanes), base, "{lanes:?}, case {case}: k {k}, n {n}");
            }
        }
        // Many arcs took the rescaling branch, whose loops differ most between builds.
        assert!(rescaled > 200, "{rescaled}");
    }

    /// The bits of `v`.
    fn run_bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// Below the lower bound (`n < sum ang`) the cells share the wall angle equally.
    #[test]
    fn below_the_lower_bound_the_cells_share_the_wall_angle() {
        let mut rng = SplitMix64(17);
        for _ in 0..200 {
            let (mut w, ang) = gap_arc(&mut rng, 64, 1.0);
            let total: f64 = ang.iter().sum();
            let n = ((total * rng.next_f64()) as usize).max(1);
            if n as f64 >= total {
                continue;
            }
            let (mut t, mut prefix) = (Vec::new(), Vec::new());
            arc_params_into(&mut w, &ang, n, &mut t, &mut prefix);
            well_formed(&t, n);
            for c in t.windows(2) {
                let share = swept(&ang, c[0], c[1]);
                assert!((share - total / n as f64).abs() <= 1e-9 * total, "{share}");
            }
        }
    }
}
