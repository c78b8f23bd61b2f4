//! Wall clustering: the distribution of nodes along one spoke, from the wall (`d = 0`) to the
//! medial point (`d = L`).
//!
//! A [`Clustering`] asks for a first cell height `delta` (absolute, or relative to the radius of
//! the circle) and a growth ratio `g >= 1`. With `n` cells on a spoke of length `L`:
//! - no first height, `n = 1`, or `n delta >= L` (the first cell cannot be that small... or that
//!   large): equal spacing `L / n`;
//! - otherwise let `q > 1` solve `delta (q^n - 1) / (q - 1) = L` (the pure geometric series
//!   that fills the spoke exactly). If `q <= g`, cells grow by `g` from `delta` for `m` layers
//!   and the remaining `n - m` cells are equal, with `m` the largest count for which the equal
//!   remainder is at least the next geometric cell `delta g^m` (so every ratio between
//!   neighbouring cells is in `[1, g]` except the one transition, which is in `[g, g^2)`);
//!   if `q > g` (the spoke is longer than `n` cells growing by `g` can fill), the series of
//!   ratio `q` is used, so the first height stays exact and the growth exceeds `g` only there.
//!
//! In every clustered case the first cell height is `delta` to rounding. The distances are
//! strictly increasing whenever `L > 0`, with `d_0 = 0` and `d_n = L` exactly.

/// The first cell height of a [`Clustering`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FirstCell {
    /// An absolute length.
    Absolute(f64),
    /// A fraction of the circle's radius (the bounding circle's radius for the outer wall).
    Relative(f64),
}

/// Wall clustering of the wall-normal (spoke) node distribution; see the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clustering {
    /// The first cell height; `None`: equal spacing along each spoke.
    pub first: Option<FirstCell>,
    /// The largest ratio between neighbouring cells (`>= 1`).
    pub growth: f64,
}

impl Default for Clustering {
    /// No clustering (equal spacing); growth 1.2 if a first height is set later.
    fn default() -> Self {
        Clustering {
            first: None,
            growth: 1.2,
        }
    }
}

impl Clustering {
    /// The absolute first height on a circle of radius `radius`, if any.
    pub fn first_height(&self, radius: f64) -> Option<f64> {
        self.first.map(|f| match f {
            FirstCell::Absolute(h) => h,
            FirstCell::Relative(x) => x * radius,
        })
    }

    /// A readable error when the parameters are not usable (non-finite, non-positive first
    /// height, growth below 1).
    pub fn validate(&self) -> Result<(), String> {
        if !(self.growth.is_finite() && self.growth >= 1.0) {
            return Err(format!(
                "the growth ratio must be a number >= 1, not {}",
                self.growth
            ));
        }
        match self.first {
            Some(FirstCell::Absolute(h)) | Some(FirstCell::Relative(h))
                if !(h.is_finite() && h > 0.0) =>
            {
                Err(format!("the first cell height must be positive, not {h}"))
            }
            _ => Ok(()),
        }
    }
}

/// `delta (q^k - 1) / (q - 1)` summed stably as `delta * sum_{i<k} q^i`.
fn geometric_sum(delta: f64, q: f64, k: usize) -> f64 {
    let mut s = 0.0;
    let mut t = delta;
    for _ in 0..k {
        s += t;
        t *= q;
    }
    s
}

/// The distances from the wall of the `n + 1` nodes of a spoke of length `len` (see the module
/// docs): `d[0] = 0`, `d[n] = len`, strictly increasing when `len > 0`. `first` is the absolute
/// first cell height (or `None`), `growth` the ratio `g`. Never panics; `n = 0` gives `[0]`.
pub fn spoke_distances(len: f64, n: usize, first: Option<f64>, growth: f64) -> Vec<f64> {
    let mut d = Vec::with_capacity(n + 1);
    spoke_distances_into(len, n, first, growth, &mut d);
    d
}

/// The first cell height a spoke of length `len` with `n` cells is clustered with, `None` when
/// [`spoke_distances_into`] spaces it equally instead (no usable `first`, one cell, or `n`
/// first heights would not fit).
pub fn clustered_first(len: f64, n: usize, first: Option<f64>) -> Option<f64> {
    first.filter(|&delta| n > 1 && delta.is_finite() && delta > 0.0 && (n as f64) * delta < len)
}

/// [`spoke_distances`] into `d` (cleared first): the grid build reuses one buffer for all its
/// spokes instead of allocating one per spoke.
pub fn spoke_distances_into(len: f64, n: usize, first: Option<f64>, growth: f64, d: &mut Vec<f64>) {
    d.clear();
    if n == 0 {
        d.push(0.0);
        return;
    }
    let Some(delta) = clustered_first(len, n, first) else {
        d.extend((0..=n).map(|j| len * (j as f64 / n as f64)));
        d[n] = len;
        return;
    };
    let g = if growth.is_finite() && growth >= 1.0 {
        growth
    } else {
        1.0
    };
    if geometric_sum(delta, g, n) < len {
        // q > g: the series of ratio q filling the spoke. Bisection on q in (1, hi].
        let mut lo = 1.0_f64;
        let mut hi = g.max(1.0) * 2.0;
        let mut guard = 0;
        while geometric_sum(delta, hi, n) < len && guard < 200 {
            lo = hi;
            hi *= 2.0;
            guard += 1;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if geometric_sum(delta, mid, n) < len {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let q = 0.5 * (lo + hi);
        let mut s = 0.0;
        let mut t = delta;
        d.push(0.0);
        for _ in 1..n {
            s += t;
            t *= q;
            d.push(s);
        }
    } else {
        // q <= g: grow by g for m layers, then equal cells.
        let mut m = 0;
        let mut gm = 0.0; // G_m
        let mut next = delta; // delta g^m
        while m + 1 < n {
            let g_next = gm + next;
            let u_next = (len - g_next) / (n - m - 1) as f64;
            if u_next >= next * g {
                gm = g_next;
                next *= g;
                m += 1;
            } else {
                break;
            }
        }
        if m == 0 {
            // Even the first layer does not fit the pattern: keep the first height exact and
            // spread the rest equally.
            m = 1;
            gm = delta;
        }
        let u = (len - gm) / (n - m) as f64;
        let mut s = 0.0;
        let mut t = delta;
        d.push(0.0);
        for j in 1..n {
            if j <= m {
                s += t;
                t *= g;
                d.push(s);
            } else {
                d.push(gm + (j - m) as f64 * u);
            }
        }
    }
    d.push(len);
    // Guard against rounding making the last interior node reach `len`.
    for j in (1..n).rev() {
        if d[j].partial_cmp(&d[j + 1]) != Some(std::cmp::Ordering::Less) {
            d[j] = 0.5 * (d[j - 1] + d[j + 1]);
        }
    }
}

/// The number of cells a spoke of typical length `len` needs for a target cell size `h` with
/// the given first height and growth: the geometric layers until a cell reaches `h`, then
/// cells of size about `h`. At least 1; `None` first height gives `round(len / h)`.
pub fn cells_for(len: f64, h: f64, first: Option<f64>, growth: f64) -> usize {
    if !(len.is_finite() && len > 0.0 && h.is_finite() && h > 0.0) {
        return 1;
    }
    let Some(delta) = first.filter(|d| d.is_finite() && *d > 0.0 && *d < h) else {
        return ((len / h).round() as usize).max(1);
    };
    let g = if growth.is_finite() && growth > 1.0 {
        growth
    } else {
        return ((len / h).round() as usize).max(1);
    };
    let (mut m, mut gm, mut t) = (0usize, 0.0, delta);
    while t < h && gm + t < len && m < 10_000 {
        gm += t;
        t *= g;
        m += 1;
    }
    let rest = ((len - gm) / h).round().max(0.0) as usize;
    (m + rest).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_without_first_height() {
        let d = spoke_distances(2.0, 4, None, 1.2);
        assert_eq!(d, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
    }

    #[test]
    fn first_height_is_exact_in_both_regimes() {
        for (len, n, g) in [
            (1.0, 20, 1.2),
            (1.0, 5, 1.05),
            (3.0, 30, 1.1),
            (1.0, 3, 1.0),
        ] {
            let d = spoke_distances(len, n, Some(1e-3), g);
            assert_eq!(d.len(), n + 1);
            assert!((d[1] - 1e-3).abs() <= 1e-12, "{d:?}");
            assert_eq!(d[n], len);
            assert!(d.windows(2).all(|w| w[0] < w[1]));
        }
    }

    #[test]
    fn too_large_first_height_falls_back_to_uniform() {
        let d = spoke_distances(1.0, 4, Some(0.5), 1.2);
        assert_eq!(d, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
    }

    #[test]
    fn cells_for_counts_layers() {
        assert_eq!(cells_for(1.0, 0.1, None, 1.2), 10);
        let n = cells_for(1.0, 0.1, Some(0.001), 1.2);
        assert!(n > 10 && n < 40, "{n}");
    }
}
