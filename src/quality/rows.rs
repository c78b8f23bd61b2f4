//! The per-block pass of [`super::measure_all`]: every cell of a block, row by row, with the
//! figures of [`super::kernel`] (bit for bit those of the reference formulas
//! [`super::cell_corners`], [`super::cell_metrics`]).
//!
//! A row of cells is measured in two loops:
//! 1. straight-line arithmetic over arrays: the edge vectors (each computed once and shared by
//!    the two cells on either side), the corner cross and dot products, pseudo-angles,
//!    `sqrt` edge lengths and the approximate length figures, and whether the cell may take
//!    the fast path;
//! 2. per cell: `atan2` for the extreme corners only, histogram slots and counts (or the
//!    reference path).
//!
//! Why shared edges give the reference's numbers: the reference forms a corner's two edge
//! vectors as differences `a - o`; where this pass uses the negated difference `-(o - a)` of
//! the neighbouring corner, the two are equal except possibly for the sign of a zero
//! component. Products and sums then agree except possibly for the sign of a zero result:
//! a zero cross product sends the cell to the reference path, and a zero dot product (with a
//! non-zero cross product) gives the same angle (`atan2(y, ±0)`), pseudo-angle and slot.
//! Edge lengths only use squares. Every other figure is computed with the kernel's
//! expressions, and every running extreme is folded in the reference's visiting order (which
//! decides between `-0.0` and `0.0`).

use super::kernel::{
    angle_deg, bin, count, exact_lengths, exact_slot, extreme_angles, length_figures, pseudo_angle,
    skewness, BlockFigures, Tables, AMBIGUOUS, KEY_TOL, OUTSIDE, REL_TOL, SQ_MAX, SQ_MIN,
};
use super::{cell_corners, cell_metrics, MetricSummary, QualityMetrics};
use crate::geometry::Point;
use crate::mesh::BlockGrid;

/// Scratch arrays of one row of cells (reused from block to block).
#[derive(Default)]
pub(super) struct Rows {
    /// Edges from node `(i, j)` to `(i + 1, j)` of the row's bottom (`b`) and top (`t`) node
    /// lines: x, y and the `sqrt` length (NaN when the squared length is outside
    /// `[SQ_MIN, SQ_MAX]` or not a number: the cell takes the reference path).
    bx: Vec<f64>,
    by: Vec<f64>,
    bl: Vec<f64>,
    tx: Vec<f64>,
    ty: Vec<f64>,
    tl: Vec<f64>,
    /// Edges from node `(i, j)` to `(i, j + 1)`, `i` in `0..=ni`.
    vx: Vec<f64>,
    vy: Vec<f64>,
    vl: Vec<f64>,
    /// Per cell: corner cross and dot products, pseudo-angles.
    cross: [Vec<f64>; 4],
    dot: [Vec<f64>; 4],
    key: [Vec<f64>; 4],
    /// Per cell: cross and dot product at the corner of smallest and of largest pseudo-angle
    /// (`[lo_cross, lo_dot, hi_cross, hi_dot]`), and whether each is the only corner within
    /// [`KEY_TOL`] of its extreme (1.0) or not (0.0).
    extreme: [Vec<f64>; 4],
    single: Vec<f64>,
    /// Per cell: approximate scaled Jacobian, edge ratio, aspect ratio.
    fig: [Vec<f64>; 3],
    /// Per cell: the fast path applies (1.0) or not (0.0).
    ok: Vec<f64>,
    /// Cells that may hold a block extreme of a length figure: (cell, figures).
    candidates: Vec<(usize, [f64; 3])>,
}

/// `sqrt(x² + y²)`, or NaN outside the fast path's range.
#[inline]
fn checked_len(x: f64, y: f64) -> f64 {
    let sq = x * x + y * y;
    if (SQ_MIN..=SQ_MAX).contains(&sq) {
        sq.sqrt()
    } else {
        f64::NAN
    }
}

/// The edges along a node line: `n[i + 1] - n[i]`.
fn along_line(line: &[Point], x: &mut Vec<f64>, y: &mut Vec<f64>, l: &mut Vec<f64>) {
    let n = line.len() - 1;
    for v in [&mut *x, &mut *y, &mut *l] {
        v.resize(n, 0.0);
    }
    let (x, y, l) = (&mut x[..n], &mut y[..n], &mut l[..n]);
    for i in 0..n {
        let (dx, dy) = (line[i + 1][0] - line[i][0], line[i + 1][1] - line[i][1]);
        x[i] = dx;
        y[i] = dy;
        l[i] = checked_len(dx, dy);
    }
}

/// The corner of smallest (`less`) or largest pseudo-angle: its cross and dot product, and
/// 1.0 when no other corner is within [`KEY_TOL`] of it.
#[inline]
fn extreme_corner(k: [f64; 4], c: [f64; 4], d: [f64; 4], less: bool) -> (f64, f64, f64) {
    let better = |a: f64, b: f64| if less { a < b } else { a > b };
    let (mut km, mut cm, mut dm) = (k[0], c[0], d[0]);
    for j in 1..4 {
        let take = better(k[j], km);
        km = if take { k[j] } else { km };
        cm = if take { c[j] } else { cm };
        dm = if take { d[j] } else { dm };
    }
    let mut near = 0.0;
    for kj in k {
        let close = if less {
            kj <= km + KEY_TOL
        } else {
            kj >= km - KEY_TOL
        };
        near += if close { 1.0 } else { 0.0 };
    }
    (cm, dm, if near == 1.0 { 1.0 } else { 0.0 })
}

impl Rows {
    /// Loop 1 over the row of cells between node lines `lo` and `hi` (`ni + 1` nodes each);
    /// the bottom edges must already be in `bx, by, bl`.
    fn products(&mut self, lo: &[Point], hi: &[Point]) {
        let n = lo.len() - 1;
        along_line(hi, &mut self.tx, &mut self.ty, &mut self.tl);
        for v in [&mut self.vx, &mut self.vy, &mut self.vl] {
            v.resize(n + 1, 0.0);
        }
        {
            let (vx, vy, vl) = (&mut self.vx[..=n], &mut self.vy[..=n], &mut self.vl[..=n]);
            let (lo, hi) = (&lo[..=n], &hi[..=n]);
            for i in 0..=n {
                let (dx, dy) = (hi[i][0] - lo[i][0], hi[i][1] - lo[i][1]);
                vx[i] = dx;
                vy[i] = dy;
                vl[i] = checked_len(dx, dy);
            }
        }
        for v in self
            .cross
            .iter_mut()
            .chain(&mut self.dot)
            .chain(&mut self.key)
            .chain(&mut self.extreme)
            .chain(&mut self.fig)
            .chain([&mut self.single, &mut self.ok])
        {
            v.resize(n, 0.0);
        }
        let (bx, by, bl) = (&self.bx[..n], &self.by[..n], &self.bl[..n]);
        let (tx, ty, tl) = (&self.tx[..n], &self.ty[..n], &self.tl[..n]);
        let (ax, ay, al) = (&self.vx[..n], &self.vy[..n], &self.vl[..n]);
        let (qx, qy, ql) = (&self.vx[1..=n], &self.vy[1..=n], &self.vl[1..=n]);
        let [c0, c1, c2, c3] = &mut self.cross;
        let (c0, c1, c2, c3) = (&mut c0[..n], &mut c1[..n], &mut c2[..n], &mut c3[..n]);
        let [d0, d1, d2, d3] = &mut self.dot;
        let (d0, d1, d2, d3) = (&mut d0[..n], &mut d1[..n], &mut d2[..n], &mut d3[..n]);
        let [k0, k1, k2, k3] = &mut self.key;
        let (k0, k1, k2, k3) = (&mut k0[..n], &mut k1[..n], &mut k2[..n], &mut k3[..n]);
        let [e0, e1, e2, e3] = &mut self.extreme;
        let (e0, e1, e2, e3) = (&mut e0[..n], &mut e1[..n], &mut e2[..n], &mut e3[..n]);
        let [f0, f1, f2] = &mut self.fig;
        let (f0, f1, f2) = (&mut f0[..n], &mut f1[..n], &mut f2[..n]);
        let (single, ok) = (&mut self.single[..n], &mut self.ok[..n]);
        for i in 0..n {
            // p0 -> p1, p3 -> p2, p0 -> p3, p1 -> p2.
            let (hx, hy) = (bx[i], by[i]);
            let (ux, uy) = (tx[i], ty[i]);
            let (vx, vy) = (ax[i], ay[i]);
            let (wx, wy) = (qx[i], qy[i]);
            // Corner k: e1 = p[k+1] - p[k], e2 = p[k-1] - p[k] (see `corner_products`).
            let c = [
                hx * vy - hy * vx,
                wx * (-hy) - wy * (-hx),
                (-ux) * (-wy) - (-uy) * (-wx),
                (-vx) * uy - (-vy) * ux,
            ];
            let d = [
                hx * vx + hy * vy,
                wx * (-hx) + wy * (-hy),
                (-ux) * (-wx) + (-uy) * (-wy),
                (-vx) * ux + (-vy) * uy,
            ];
            let edges = [bl[i], ql[i], tl[i], al[i]];
            // NaN lengths fail `>= 0`; zero cross products take the reference path.
            let fine = (edges[0] >= 0.0)
                & (edges[1] >= 0.0)
                & (edges[2] >= 0.0)
                & (edges[3] >= 0.0)
                & (c[0] != 0.0)
                & (c[1] != 0.0)
                & (c[2] != 0.0)
                & (c[3] != 0.0);
            ok[i] = if fine { 1.0 } else { 0.0 };
            let (sj, er, ar) = length_figures(&c, &edges);
            let k = [
                pseudo_angle(c[0], d[0]),
                pseudo_angle(c[1], d[1]),
                pseudo_angle(c[2], d[2]),
                pseudo_angle(c[3], d[3]),
            ];
            let (lc, ld, ls) = extreme_corner(k, c, d, true);
            let (hc, hd, hs) = extreme_corner(k, c, d, false);
            (c0[i], c1[i], c2[i], c3[i]) = (c[0], c[1], c[2], c[3]);
            (d0[i], d1[i], d2[i], d3[i]) = (d[0], d[1], d[2], d[3]);
            (k0[i], k1[i], k2[i], k3[i]) = (k[0], k[1], k[2], k[3]);
            (e0[i], e1[i], e2[i], e3[i]) = (lc, ld, hc, hd);
            single[i] = ls * hs;
            (f0[i], f1[i], f2[i]) = (sj, er, ar);
        }
    }
}

/// The per-cell arrays of one row, cut to the row's length (so that indexing below `ni`
/// needs no further checks).
struct View<'a> {
    cross: [&'a [f64]; 4],
    dot: [&'a [f64]; 4],
    key: [&'a [f64]; 4],
    ext: [&'a [f64]; 4],
    single: &'a [f64],
    fig: [&'a [f64]; 3],
    ok: &'a [f64],
}

impl<'a> View<'a> {
    fn of(r: &'a Rows, n: usize) -> View<'a> {
        let four = |v: &'a [Vec<f64>; 4]| [&v[0][..n], &v[1][..n], &v[2][..n], &v[3][..n]];
        View {
            cross: four(&r.cross),
            dot: four(&r.dot),
            key: four(&r.key),
            ext: four(&r.extreme),
            single: &r.single[..n],
            fig: [&r.fig[0][..n], &r.fig[1][..n], &r.fig[2][..n]],
            ok: &r.ok[..n],
        }
    }
}

/// One cell's figures from the row loop (see [`Rows`]).
struct Cell {
    cross: [f64; 4],
    dot: [f64; 4],
    key: [f64; 4],
    extreme: [f64; 4],
    /// Each extreme corner is alone within [`KEY_TOL`].
    single: bool,
    fig: [f64; 3],
}

/// Running figures of a chunk of blocks, in visiting order: the metrics' counts, and their
/// extremes as plain numbers (`+-inf` until a finite value came), turned into
/// [`MetricSummary::min`] / `max` by [`Chunk::finish`]. Folding `x` into `+inf` gives `x`, so
/// this is the sequence of `Option` folds of [`MetricSummary::add_value`].
pub(super) struct Chunk {
    metrics: QualityMetrics,
    /// `[min, max]` of angle, skewness, scaled Jacobian, edge ratio, aspect ratio.
    ext: [[f64; 2]; 5],
}

const ANGLE: usize = 0;
const SKEW: usize = 1;
const SJ: usize = 2;
const ER: usize = 3;
const AR: usize = 4;

impl Chunk {
    pub fn new() -> Chunk {
        Chunk {
            metrics: QualityMetrics::empty(),
            ext: [[f64::INFINITY, f64::NEG_INFINITY]; 5],
        }
    }

    fn summary(&mut self, which: usize) -> &mut MetricSummary {
        let m = &mut self.metrics;
        match which {
            ANGLE => &mut m.angle_deg,
            SKEW => &mut m.equiangle_skewness,
            SJ => &mut m.scaled_jacobian,
            ER => &mut m.edge_ratio,
            _ => &mut m.aspect_ratio,
        }
    }

    /// Fold a finite value into the extremes of metric `which`.
    #[inline]
    fn extremes(&mut self, which: usize, x: f64) {
        let e = &mut self.ext[which];
        e[0] = e[0].min(x);
        e[1] = e[1].max(x);
    }

    /// [`MetricSummary::add_value`].
    fn add_value(&mut self, which: usize, x: f64) {
        let m = self.summary(which);
        m.samples += 1;
        m.histogram.add(x);
        if x.is_finite() {
            self.extremes(which, x);
        }
    }

    /// [`MetricSummary::add`].
    fn add(&mut self, which: usize, x: f64) {
        self.add_value(which, x);
        let m = self.summary(which);
        if !m.accepts(x) {
            m.outside += 1;
        }
    }

    /// The metrics of every block measured.
    pub fn finish(mut self) -> QualityMetrics {
        for which in [ANGLE, SKEW, SJ, ER, AR] {
            let [lo, hi] = self.ext[which];
            let m = self.summary(which);
            // Only finite values were folded: an infinite bound means none came.
            m.min = lo.is_finite().then_some(lo);
            m.max = hi.is_finite().then_some(hi);
        }
        self.metrics
    }

    /// Measure one block (a malformed grid contributes no cell); `rows` is scratch space.
    pub fn block(&mut self, grid: &BlockGrid, t: &Tables, rows: &mut Rows) -> BlockFigures {
        let mut f = BlockFigures {
            malformed: false,
            cells: 0,
            sum_min: 0.0,
            sum_max: 0.0,
            min_angle_deg: f64::INFINITY,
            max_angle_deg: f64::NEG_INFINITY,
            inverted: 0,
            min_scaled_jacobian: f64::INFINITY,
        };
        if !super::well_formed(grid) {
            f.malformed = true;
            return f;
        }
        let (ni, nj) = (grid.ni, grid.nj);
        if ni == 0 || nj == 0 {
            return f;
        }
        let w = ni + 1;
        let n = &grid.nodes;
        // Taken out of `rows` while the row's arrays are borrowed; put back at the end.
        let mut candidates = std::mem::take(&mut rows.candidates);
        candidates.clear();
        // Running approximate extremes of the length figures (see `candidate`).
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        along_line(&n[..w], &mut rows.bx, &mut rows.by, &mut rows.bl);
        for j in 0..nj {
            let (line, next) = (&n[j * w..(j + 1) * w], &n[(j + 1) * w..(j + 2) * w]);
            rows.products(line, next);
            let v = View::of(rows, ni);
            let corners = |i: usize| [line[i], line[i + 1], next[i + 1], next[i]];
            for i in 0..ni {
                if v.ok[i] == 0.0 {
                    self.add_reference(&mut f, &corners(i));
                    continue;
                }
                let cell = Cell {
                    cross: [v.cross[0][i], v.cross[1][i], v.cross[2][i], v.cross[3][i]],
                    dot: [v.dot[0][i], v.dot[1][i], v.dot[2][i], v.dot[3][i]],
                    key: [v.key[0][i], v.key[1][i], v.key[2][i], v.key[3][i]],
                    extreme: [v.ext[0][i], v.ext[1][i], v.ext[2][i], v.ext[3][i]],
                    single: v.single[i] == 1.0,
                    fig: [v.fig[0][i], v.fig[1][i], v.fig[2][i]],
                };
                let figs = self.add_fast(&mut f, &cell, t, || corners(i));
                // A cell within REL_TOL of the block's final extreme is within 3 REL_TOL of
                // the running extreme when visited (see the module doc of `kernel`).
                let mut keep = false;
                for k in 0..3 {
                    let x = figs[k];
                    lo[k] = lo[k].min(x);
                    hi[k] = hi[k].max(x);
                    keep |= x - lo[k] <= 3.0 * REL_TOL * lo[k].abs()
                        || hi[k] - x <= 3.0 * REL_TOL * hi[k].abs();
                }
                if keep {
                    candidates.push((i + j * ni, figs));
                }
            }
            std::mem::swap(&mut rows.bx, &mut rows.tx);
            std::mem::swap(&mut rows.by, &mut rows.ty);
            std::mem::swap(&mut rows.bl, &mut rows.tl);
        }
        // Extremes of the length figures: the candidates within 2 REL_TOL of the smallest or
        // largest figure, recomputed with `hypot`, in cell order.
        let near = |x: f64, e: f64| (x - e).abs() <= 2.0 * REL_TOL * e.abs();
        for &(c, figs) in &candidates {
            if !(0..3).any(|k| near(figs[k], lo[k]) || near(figs[k], hi[k])) {
                continue;
            }
            let b = c % ni + (c / ni) * w;
            let p = [n[b], n[b + 1], n[b + 1 + w], n[b + w]];
            let (cross, _) = super::kernel::corner_products(&p);
            let (sj, er, ar) = length_figures(&cross, &exact_lengths(&p));
            self.extremes(SJ, sj);
            self.extremes(ER, er);
            self.extremes(AR, ar);
            min_sj(&mut f, sj);
        }
        rows.candidates = candidates;
        f
    }

    /// Everything the reference computes from one cell, with the reference formulas.
    fn add_reference(&mut self, f: &mut BlockFigures, p: &[Point; 4]) {
        let c = cell_metrics(*p);
        let jacobian = cell_corners(*p).jacobian;
        self.add_angles_common(f, c.min_angle_deg, c.max_angle_deg);
        if jacobian.iter().any(|&x| x.is_nan() || x <= 0.0) {
            f.inverted += 1;
        }
        min_sj(f, c.scaled_jacobian);
        for a in c.angle_deg {
            self.add_value(ANGLE, a);
        }
        self.add(SKEW, c.equiangle_skewness);
        self.add(ER, c.edge_ratio);
        self.add(SJ, c.scaled_jacobian);
        self.add(AR, c.aspect_ratio);
    }

    fn add_angles_common(&mut self, f: &mut BlockFigures, lo: f64, hi: f64) {
        f.cells += 1;
        f.sum_min += lo;
        f.sum_max += hi;
        f.min_angle_deg = f.min_angle_deg.min(lo);
        f.max_angle_deg = f.max_angle_deg.max(hi);
        let a = &mut self.metrics.angle_deg;
        if !(a.accepts(lo) && a.accepts(hi)) {
            a.outside += 1;
        }
    }

    /// Cell `i` of the row in `rows` through the fast path: angles and skewness exactly, the
    /// length figures counted in the histograms; returns the length figures (exact when the
    /// approximations' bins were not certain) for the extremes.
    #[inline]
    fn add_fast(
        &mut self,
        f: &mut BlockFigures,
        c: &Cell,
        t: &Tables,
        corners: impl Fn() -> [Point; 4],
    ) -> [f64; 3] {
        let (cross, dot, keys) = (c.cross, c.dot, c.key);
        let (lo, hi) = if c.single {
            // One corner near each extreme: the fold of `extreme_angles` reduces to these.
            (
                angle_deg(c.extreme[0], c.extreme[1]),
                angle_deg(c.extreme[2], c.extreme[3]),
            )
        } else {
            extreme_angles(keys, cross, dot)
        };
        self.add_angles_common(f, lo, hi);
        if cross.iter().any(|&x| x <= 0.0) {
            f.inverted += 1;
        }
        // Corner angles: four samples; the extremes are the cell's (never NaN here).
        self.extremes(ANGLE, lo);
        self.extremes(ANGLE, hi);
        let m = &mut self.metrics;
        {
            let a = &mut m.angle_deg;
            a.samples += 4;
            for k in 0..4 {
                let s = t.angle_key.get(keys[k]);
                let b = if s == AMBIGUOUS {
                    bin(&a.histogram.edges, angle_deg(cross[k], dot[k]))
                } else {
                    (s & !OUTSIDE) as usize
                };
                a.histogram.counts[b] += 1;
            }
        }
        let sk = skewness(lo, hi);
        let s = exact_slot(&m.equiangle_skewness, &t.skewness, sk);
        count(&mut m.equiangle_skewness, s);
        self.extremes(SKEW, sk);
        let m = &mut self.metrics;
        let [sj, er, ar] = c.fig;
        let approx = [
            t.scaled_jacobian.get(sj),
            t.edge_ratio.get(er),
            t.aspect_ratio.get(ar),
        ];
        // The approximations' bins when all three are certain, else the exact figures.
        let (figures, slots) = if !approx.contains(&AMBIGUOUS) {
            ([sj, er, ar], approx)
        } else if let Some(s) = super::kernel::approx_slots(m, t, [sj, er, ar]) {
            ([sj, er, ar], s)
        } else {
            let (sj, er, ar) = length_figures(&cross, &exact_lengths(&corners()));
            let s = [
                exact_slot(&m.scaled_jacobian, &t.scaled_jacobian, sj),
                exact_slot(&m.edge_ratio, &t.edge_ratio, er),
                exact_slot(&m.aspect_ratio, &t.aspect_ratio, ar),
            ];
            ([sj, er, ar], s)
        };
        count(&mut m.scaled_jacobian, slots[0]);
        count(&mut m.edge_ratio, slots[1]);
        count(&mut m.aspect_ratio, slots[2]);
        figures
    }
}

/// NaN-sticky minimum of the scaled Jacobians, in visiting order.
#[inline]
fn min_sj(f: &mut BlockFigures, sj: f64) {
    if sj.is_nan() || sj < f.min_scaled_jacobian {
        f.min_scaled_jacobian = sj;
    }
}
