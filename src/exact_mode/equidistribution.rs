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

/// `n + 1` parameters in `[0, 1]` equidistributing the sub-step weights `w` (`t_0 = 0`,
/// `t_n = 1` exactly; equal steps when the weights vanish).
pub(crate) fn equidistribute(w: &[f64], n: usize) -> Vec<f64> {
    let mut t = Vec::with_capacity(n + 1);
    equidistribute_into(w, n, &mut t, &mut Vec::with_capacity(w.len() + 1));
    t
}

/// [`equidistribute`] written into `t` (cleared first), with `prefix` the running sums'
/// buffer: the same values, in buffers reused from piece to piece.
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
