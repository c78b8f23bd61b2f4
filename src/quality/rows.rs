//! The per-block pass of [`super::measure_all`]: every cell of a block, a band of rows at a
//! time, with the reference formulas ([`super::cell_corners`], [`super::cell_metrics`]) bit for
//! bit.
//!
//! A band of rows of cells (a whole block when it is small, [`BAND_NODES`]) is measured in two
//! loops:
//! 1. straight-line arithmetic over arrays (the compiler vectorises it), over every cell of
//!    the band at once (flat node indices, see [`band`]: the reductions and the loop set-up are
//!    paid once per band, not per row of 16 cells): the edge vectors, lengths and directions
//!    (each computed once and shared by the two cells on either side: one `atan2` per edge,
//!    about two per cell, where the corners' own took four), the corner cross
//!    products, the four corner angles (differences of edge directions,
//!    [`super::kernel::corner_candidates`]), the extreme angles and every length figure,
//!    whether the cell takes this path, the histogram bins (by arithmetic and comparisons with
//!    the edges, [`super::kernel::angle_bin_unsigned`], [`super::kernel::StepBins`] for the
//!    skewness and the scaled Jacobian (one product each); the
//!    ratio bins from a table in the 8-lane and portable builds, by comparisons in the 4-lane
//!    one, where the table load is a gather: [`super::kernel::RatioBins`]; summed
//!    into one packed word, [`super::kernel::PACK`]), and as
//!    reductions over the band the acceptance, inverted and cell counts and the band's extremes
//!    (integer keys); per cell it stores only what loop 2 reads (the two extreme angles and the
//!    eight bins packed in one word: contiguous stores, where a wider record took scatters);
//! 2. per cell, in cell order: the angle sums and the histogram counts (one increment per
//!    pair of values, into a table per pair, see [`Chunk`]), or the reference path.
//!
//! Two figures skip divisions with the same results: the skewness is compared and reduced
//! through its dividend ([`SkewThresholds`](super::kernel::SkewThresholds)), the scaled Jacobian divides at one corner
//! ([`least_scaled_jacobian`]; a cell whose corner pick is uncertain takes the reference path).
//!
//! Why this gives the reference's numbers: every figure is computed with the reference's own
//! functions ([`angle_deg`] of the edge vectors (as [`angle_deg_bounded`], its bits for
//! edges in range),
//! [`corner_candidates`] (a corner whose candidate is not
//! [`settled`] takes the reference path),
//! [`length_figures`](super::kernel::length_figures), [`skewness`](super::kernel::skewness),
//! the `sqrt` length of [`crate::geometry::length`]) on the same operands (the edge
//! directions of the same differences of two nodes as the reference's), except that the
//! reference forms a corner's two edge vectors for its cross product as differences `a - o`
//! where this pass may use
//! the negated difference `-(o - a)` of the neighbouring corner: the two are equal except
//! possibly for the sign of a zero component, so products and sums agree except possibly for
//! the sign of a zero result. A zero cross product sends the cell to the reference path;
//! [`angle_deg`] does not look at the sign of a zero; lengths only use
//! squares. Cells with an edge whose squared length is outside `[SQ_MIN, SQ_MAX]` (or not a
//! number) take the reference path too. On this path no figure is NaN or a zero of either sign
//! (settled angles are at least `1e-9`), so folding extremes with `min` /
//! `max` in any grouping gives the reference's bits; sums are taken in cell order.

#[cfg(any(test, doc))]
use super::angle_deg;
use super::atan::angle_deg_bounded;
use super::kernel::{
    angle_bin_unsigned, cell_products, corner_candidates, corner_products, least_scaled_jacobian,
    packed_bins, settled, BlockFigures, StepBins, Tables, PACK, SQ_MAX, SQ_MIN,
};
use super::{cell_metrics, fold, MetricSummary, QualityMetrics};
use super::{
    ANGLE_ACCEPTABLE, ASPECT_ACCEPTABLE, EDGE_RATIO_ACCEPTABLE, SCALED_JACOBIAN_ACCEPTABLE,
};
use crate::geometry::Point;
use crate::mesh::BlockGrid;

/// The edge arrays of one band of rows of cells (reused from band to band and block to block),
/// indexed by the flat node index `p = r w + i` of the band's nodes (`w = ni + 1` per line).
#[derive(Default)]
pub(super) struct EdgeArrays {
    /// Edges from node `p` to `p + 1` (x, y and the `sqrt` length, NaN when the squared length
    /// is outside `[SQ_MIN, SQ_MAX]` or not a number: the cell takes the reference path): the
    /// bottom edge of cell `p` and the top edge of cell `p - w`. At the end of a node line
    /// (`i = ni`) this joins two lines: its length is set to NaN.
    hx: Vec<f64>,
    hy: Vec<f64>,
    hl: Vec<f64>,
    /// Their directions, [`angle_deg`] of `(hy, hx)` (the reference's edge directions).
    ht: Vec<f64>,
    /// Edges from node `p` to `p + w`: the left edge of cell `p`, the right one of `p - 1`.
    vx: Vec<f64>,
    vy: Vec<f64>,
    vl: Vec<f64>,
    vt: Vec<f64>,
}

/// Scratch space of the per-block pass: the band's edges and its cells' figures.
#[derive(Default)]
pub(super) struct Rows {
    edges: EdgeArrays,
    /// Per cell `p` (`i < ni`; the slots `i = ni` and the padding hold no cell): its figures.
    cells: Vec<Figures>,
}

/// A band of rows of a block has about this many nodes (its scratch arrays stay in the
/// first-level cache; a 16 x 16 block is one band).
pub(super) const BAND_NODES: usize = 512;

/// Loop 1 runs over a multiple of this many cells (the vector loops then end without a
/// scalar remainder: the padding cells have NaN edges and count nowhere).
const PAD: usize = 16;

/// `sqrt(x² + y²)`, or NaN outside `[SQ_MIN, SQ_MAX]` (where [`crate::geometry::length`] takes
/// `hypot`); a select rather than a branch, so that the edge loops vectorise.
#[inline(always)]
fn checked_len(x: f64, y: f64) -> f64 {
    let sq = x * x + y * y;
    let l = sq.sqrt();
    if (SQ_MIN..=SQ_MAX).contains(&sq) {
        l
    } else {
        f64::NAN
    }
}

/// The edges along a node line into `e` (x, y, [`checked_len`], direction; `line.len() - 1`
/// each).
#[inline(always)]
fn line_edges(line: &[Point], e: [&mut [f64]; 4]) {
    let [x, y, l, t] = e;
    let n = x.len();
    let (y, l, t, line) = (&mut y[..n], &mut l[..n], &mut t[..n], &line[..=n]);
    for i in 0..n {
        let (dx, dy) = (line[i + 1][0] - line[i][0], line[i + 1][1] - line[i][1]);
        x[i] = dx;
        y[i] = dy;
        l[i] = checked_len(dx, dy);
        t[i] = angle_deg_bounded(dy, dx);
    }
}

/// The edges from node `lo[i]` to `hi[i]` into `e` (x, y, [`checked_len`], direction;
/// `lo.len()` each).
#[inline(always)]
fn cross_edges(lo: &[Point], hi: &[Point], e: [&mut [f64]; 4]) {
    let [x, y, l, t] = e;
    let n = x.len();
    let (y, l, t, lo, hi) = (&mut y[..n], &mut l[..n], &mut t[..n], &lo[..n], &hi[..n]);
    for i in 0..n {
        let (dx, dy) = (hi[i][0] - lo[i][0], hi[i][1] - lo[i][1]);
        x[i] = dx;
        y[i] = dy;
        l[i] = checked_len(dx, dy);
        t[i] = angle_deg_bounded(dy, dx);
    }
}

/// The edges and loop 1 of a band of `nb` rows of cells: `nodes` the band's `nb + 1` node
/// lines of `w` nodes, `h` and `v` as [`EdgeArrays::hx`] and [`EdgeArrays::vx`] (at least `m + w` and
/// `m + 1` long), `out` the `m` cells of loop 1 (`m >= nb w - 1`, a multiple of [`PAD`]).
///
/// Cell `p = r w + i` has the bottom edge `h[p]`, the top edge `h[p + w]`, the left edge
/// `v[p]` and the right edge `v[p + 1]`: loop 1 runs over every `p` of the band at once (one
/// reduction of its counts per band, not per row); the slots `i = ni` and the padding get a
/// NaN edge, so they are not on the fast path and count nowhere.
#[inline(always)]
fn band<const TABLE: bool>(
    nodes: &[Point],
    w: usize,
    nb: usize,
    h: [&mut [f64]; 4],
    v: [&mut [f64]; 4],
    th: &Tables,
    out: &mut [Figures],
) -> RowCounts {
    let (b, t, v) = band_edges(nodes, w, nb, h, v, out.len());
    row_figures::<TABLE>(b, t, v, th, out)
}

/// The bottom, top and across edges of a band's cells, see [`band_edges`].
pub(super) type BandEdges<'a> = ([&'a [f64]; 4], [&'a [f64]; 4], [&'a [f64]; 4]);

/// The edges of a band of `nb` rows of cells for a loop over `m` cells (`m >= nb w - 1`, a
/// multiple of [`PAD`]): `nodes` the band's `nb + 1` node lines of `w` nodes, `h` and `v` as
/// [`EdgeArrays::hx`] and [`EdgeArrays::vx`] (at least `m + w` and `m + 1` long). Returns, for cell
/// `p = r w + i`, its bottom edges `b[p]` (`h[p]`), top edges `t[p]` (`h[p + w]`) and the
/// edges across `v` (left `v[p]`, right `v[p + 1]`), each as x, y, length and direction; the
/// slots `i = ni` and the padding get a NaN length, so they are never on a fast path.
#[inline(always)]
pub(super) fn band_edges<'a>(
    nodes: &[Point],
    w: usize,
    nb: usize,
    h: [&'a mut [f64]; 4],
    v: [&'a mut [f64]; 4],
    m: usize,
) -> BandEdges<'a> {
    let [hx, hy, hl, ht] = h;
    let [vx, vy, vl, vt] = v;
    let (nh, nv) = ((nb + 1) * w - 1, nb * w);
    line_edges(
        &nodes[..=nh],
        [&mut hx[..nh], &mut hy[..nh], &mut hl[..nh], &mut ht[..nh]],
    );
    cross_edges(
        &nodes[..nv],
        &nodes[w..w + nv],
        [&mut vx[..nv], &mut vy[..nv], &mut vl[..nv], &mut vt[..nv]],
    );
    hl[nh..m + w].fill(f64::NAN);
    vl[nv..=m].fill(f64::NAN);
    for r in 0..nb {
        hl[r * w + w - 1] = f64::NAN;
    }
    let (hx, hy, hl, ht) = (&*hx, &*hy, &*hl, &*ht);
    let (vx, vy, vl, vt) = (&*vx, &*vy, &*vl, &*vt);
    (
        [&hx[..m], &hy[..m], &hl[..m], &ht[..m]],
        [&hx[w..w + m], &hy[w..w + m], &hl[w..w + m], &ht[w..w + m]],
        [&vx[..=m], &vy[..=m], &vl[..=m], &vt[..=m]],
    )
}

/// [`band`] compiled for AVX-512 (8-lane vectors; the same IEEE operations on the same
/// operands, no fused multiply-add, so the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
fn band_avx512(
    nodes: &[Point],
    w: usize,
    nb: usize,
    h: [&mut [f64]; 4],
    v: [&mut [f64]; 4],
    th: &Tables,
    out: &mut [Figures],
) -> RowCounts {
    band::<true>(nodes, w, nb, h, v, th, out)
}

/// [`band`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn band_avx2(
    nodes: &[Point],
    w: usize,
    nb: usize,
    h: [&mut [f64]; 4],
    v: [&mut [f64]; 4],
    th: &Tables,
    out: &mut [Figures],
) -> RowCounts {
    band::<false>(nodes, w, nb, h, v, th, out)
}

/// The figures of one cell from loop 1 (one record per cell, so that loop 1 writes through a
/// single `&mut` slice: the compiler then needs no aliasing checks to vectorise it).
#[derive(Debug, Clone, Copy, Default)]
struct Figures {
    /// Smallest and largest angle (the only per-cell values loop 2 sums).
    fig: [f64; 2],
    /// The histogram bins of the four angles ([`super::kernel::angle_bin_unsigned`]) and of
    /// the figures from skewness on ([`super::kernel::weighted_bin`]), 5 bits each (bin `k` in
    /// bits `5k..5k + 5`), and [`FAST`] when the cell takes the fast path (0: the reference
    /// path).
    bins: u64,
}

/// The bit of [`Figures::bins`] set for a cell of the fast path.
const FAST: u64 = 1 << 40;

/// The bit of [`Figures::bins`] set for a cell of the fast path whose scaled Jacobian pick
/// was not certain (two corners' products compared equal: an isosceles trapezoid, as every
/// cell of a block around a centred hole is, has four equal quotients in exact arithmetic):
/// loop 1 counted every other figure, and loop 2 takes the scaled Jacobian with the reference
/// expression (`length_figures` of the corner products and the `len` edges), its bin (field
/// 5, [`PACK`]), its acceptance and extremes. Before, such a cell took the whole reference
/// path: a quality pass 7x slower per cell around a centred hole.
const REDO: u64 = 1 << 41;

/// The 5-bit field of the scaled Jacobian's bin in [`Figures::bins`].
const SJ_FIELD: u64 = 31 << 25;

/// The portable (2-lane SSE2) build takes the ratio bins from the table: 7% faster there than
/// the comparisons (Zen 3; the AVX2 build is the other way round, see
/// [`super::kernel::RatioBins::bin_by_compares`]). The bits are the same either way.
const PORTABLE_TABLE: bool = true;

impl EdgeArrays {
    /// The number of cells a loop over a band of `nb` rows of `w - 1` cells runs over: the
    /// band's flat cell indices `r w + i`, padded to a multiple of [`PAD`].
    pub(super) fn cells_of_band(w: usize, nb: usize) -> usize {
        (nb * w - 1).next_multiple_of(PAD)
    }

    /// The edge arrays, sized for a loop over `m` cells of lines of `w` nodes (see
    /// [`band_edges`]).
    pub(super) fn arrays(&mut self, w: usize, m: usize) -> ([&mut [f64]; 4], [&mut [f64]; 4]) {
        for v in [&mut self.hx, &mut self.hy, &mut self.hl, &mut self.ht] {
            v.resize(m + w, 0.0);
        }
        for v in [&mut self.vx, &mut self.vy, &mut self.vl, &mut self.vt] {
            v.resize(m + 1, 0.0);
        }
        (
            [
                &mut self.hx[..],
                &mut self.hy[..],
                &mut self.hl[..],
                &mut self.ht[..],
            ],
            [
                &mut self.vx[..],
                &mut self.vy[..],
                &mut self.vl[..],
                &mut self.vt[..],
            ],
        )
    }
}

impl Rows {
    /// The `nb` rows of cells between the `nb + 1` node lines `nodes` (`w` nodes each) into
    /// `self.cells` (cell `(i, r)` at `r w + i`), see [`band`].
    ///
    /// With [`Tables::wider`] (AVX-512) loop 1 runs in 8-lane vectors, with [`Tables::wide`]
    /// (the CPU has AVX2) in 4-lane vectors (the same IEEE operations on
    /// the same operands, so the same bits as the 2-lane SSE2 build; no fused multiply-add).
    fn figures(&mut self, nodes: &[Point], w: usize, nb: usize, bins: &Tables) -> RowCounts {
        let m = EdgeArrays::cells_of_band(w, nb);
        self.cells.resize(m, Figures::default());
        let (h, v) = self.edges.arrays(w, m);
        let out = &mut self.cells[..m];
        #[cfg(target_arch = "x86_64")]
        if bins.wider {
            // SAFETY: `wider` is only set when the CPU has these features (see `Tables::wider`).
            return unsafe { band_avx512(nodes, w, nb, h, v, bins, out) };
        }
        #[cfg(target_arch = "x86_64")]
        if bins.wide {
            // SAFETY: `wide` is only set when the CPU has AVX2 (see `Tables::wide`).
            return unsafe { band_avx2(nodes, w, nb, h, v, bins, out) };
        }
        band::<PORTABLE_TABLE>(nodes, w, nb, h, v, bins, out)
    }
}

/// Counts of the cells of a row that take the fast path (integer sums: any order).
#[derive(Debug, Clone, Copy, Default)]
struct RowCounts {
    /// Cells outside the acceptable range, per metric (angle: any corner).
    outside: [u64; 5],
    /// Cells, and inverted cells.
    fast: u64,
    inverted: u64,
    /// Smallest and largest [`key`] per metric (angle: of the cells' smallest and largest
    /// angles), `i64::MAX` and `i64::MIN` without a cell.
    lo: [i64; 5],
    hi: [i64; 5],
}

/// An integer ordered as the float `x` (the order of `f64::total_cmp`; that of `<` for
/// numbers other than NaN and zeros, which the fast path does not produce): integer minima
/// and maxima are reductions the compiler vectorises, float ones (`minnum`) are not.
#[inline(always)]
fn key(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    b ^ (((b >> 63) as u64) >> 1) as i64
}

/// [`key`] of an `x` with the sign bit clear (`>= +0`, or a NaN of that sign): its bits (the
/// exclusive or of [`key`] is then with 0).
#[inline(always)]
fn key_unsigned(x: f64) -> i64 {
    x.to_bits() as i64
}

/// The float of a [`key`].
fn unkey(k: i64) -> f64 {
    f64::from_bits((k ^ (((k >> 63) as u64) >> 1) as i64) as u64)
}

/// [`row_figures`] compiled for AVX2.
#[cfg(all(test, target_arch = "x86_64"))]
#[target_feature(enable = "avx2")]
fn row_figures_avx2(
    b: [&[f64]; 4],
    t: [&[f64]; 4],
    v: [&[f64]; 4],
    th: &Tables,
    out: &mut [Figures],
) -> RowCounts {
    row_figures::<false>(b, t, v, th, out)
}

/// Loop 1: the figures of every cell of a row from its edges (`x`, `y`, length, direction):
/// bottom `b`
/// and top `t` edges (`out.len()` each), the edges `v` across the row (`out.len() + 1`).
/// `TABLE`: the ratio bins from [`super::kernel::RatioBins::bin`], else from its comparisons
/// (the same bits).
///
/// The skewness is not divided per cell: its bins, acceptance and extremes come from its
/// dividend `D` ([`SkewThresholds`](super::kernel::SkewThresholds)); the scaled Jacobian takes one division at the corner
/// [`least_scaled_jacobian`] picks (a cell whose pick is not certain takes the reference
/// path).
#[inline(always)]
fn row_figures<const TABLE: bool>(
    b: [&[f64]; 4],
    t: [&[f64]; 4],
    v: [&[f64]; 4],
    th: &Tables,
    out: &mut [Figures],
) -> RowCounts {
    let n = out.len();
    let rb = &th.ratios;
    let mut k = RowCounts {
        lo: [i64::MAX; 5],
        hi: [i64::MIN; 5],
        ..RowCounts::default()
    };
    let (bx, by, bl, bt) = (&b[0][..n], &b[1][..n], &b[2][..n], &b[3][..n]);
    let (tx, ty, tl, tt) = (&t[0][..n], &t[1][..n], &t[2][..n], &t[3][..n]);
    let (ax, ay, al, at) = (&v[0][..n], &v[1][..n], &v[2][..n], &v[3][..n]);
    let (qx, qy, ql, qt) = (&v[0][1..=n], &v[1][1..=n], &v[2][1..=n], &v[3][1..=n]);
    for i in 0..n {
        let CellCore {
            c,
            edges,
            sj,
            a,
            fine: exact,
            geom: fine,
        } = cell_core(
            [bx[i], by[i], bl[i], bt[i]],
            [tx[i], ty[i], tl[i], tt[i]],
            [ax[i], ay[i], al[i], at[i]],
            [qx[i], qy[i], ql[i], qt[i]],
        );
        let inverted = (c[0] < 0.0) | (c[1] < 0.0) | (c[2] < 0.0) | (c[3] < 0.0);
        // No NaN and no `-0.0` on the fast path: the plain compares are `f64::min` / `max`.
        let (amin, amax) = (fold(a, less), fold(a, more));
        let (er, ar) = edge_ratios(&edges);
        // The dividend of `skewness(amin, amax)`.
        let sd = more(amax - 90.0, 90.0 - amin);
        k.fast += u64::from(fine);
        k.inverted += u64::from(fine & inverted);
        // `amin <= amax` (folds of the same four numbers), so only these two ends can be
        // outside.
        let [a_lo, a_hi] = ANGLE_ACCEPTABLE;
        k.outside[ANGLE] += u64::from(fine & ((amin < a_lo) | (amax > a_hi)));
        k.outside[SKEW] += u64::from(fine & !((sd >= th.skew.lo) & (sd < th.skew.above)));
        // A cell whose scaled Jacobian pick is not certain ([`REDO`]) counts it in loop 2;
        // its keys below are the extremes' neutral values (a float select: an integer one
        // kept the compiler from vectorising the loop).
        k.outside[SJ] += u64::from(exact & outside(sj, SCALED_JACOBIAN_ACCEPTABLE));
        // Both ratios are at least 1 (a quotient of a larger by a smaller positive number,
        // rounded), the ranges' low end: only the high end can be passed.
        k.outside[ER] += u64::from(fine & (er > EDGE_RATIO_ACCEPTABLE[1]));
        k.outside[AR] += u64::from(fine & (ar > ASPECT_ACCEPTABLE[1]));
        // Angles, edge and aspect ratios are `>= +0` (see the module doc): their keys are
        // their bits.
        let keys = [
            (key_unsigned(amin), key_unsigned(amax)),
            (key(sd), key(sd)),
            (
                key(if exact { sj } else { f64::INFINITY }),
                key(if exact { sj } else { f64::NEG_INFINITY }),
            ),
            (key_unsigned(er), key_unsigned(er)),
            (key_unsigned(ar), key_unsigned(ar)),
        ];
        for (m, (x, y)) in keys.into_iter().enumerate() {
            k.lo[m] = k.lo[m].min(if fine { x } else { i64::MAX });
            k.hi[m] = k.hi[m].max(if fine { y } else { i64::MIN });
        }
        // The eight bins packed in one float sum (see `PACK`), in four independent parts.
        let angles = (angle_bin_unsigned(a[0]) + angle_bin_unsigned(a[1]) * PACK[1])
            + (angle_bin_unsigned(a[2]) * PACK[2] + angle_bin_unsigned(a[3]) * PACK[3]);
        // The bins of the skewness (from its dividend) and the scaled Jacobian by one
        // product each (`StepBins`), weighted for their fields.
        let skew = StepBins::SKEW.count(sd) * PACK[4];
        let sj_bin = StepBins::JACOBIAN.count(sj) * PACK[5];
        let ratios = if TABLE {
            rb[0].bin(er) + rb[1].bin(ar)
        } else {
            rb[0].bin_by_compares(er) + rb[1].bin_by_compares(ar)
        };
        let bins = packed_bins((angles + skew) + (sj_bin + ratios))
            | if fine { FAST } else { 0 }
            | if fine & !exact { REDO } else { 0 };
        out[i] = Figures {
            fig: [amin, amax],
            bins,
        };
    }
    // The skewness extremes: the quotients of the extremes of its dividend.
    if k.fast > 0 {
        k.lo[SKEW] = key(unkey(k.lo[SKEW]) / 90.0);
        k.hi[SKEW] = key(unkey(k.hi[SKEW]) / 90.0);
    }
    k
}

/// What the row loops take from one cell's four edges (each x, y, length, direction:
/// bottom `p0 -> p1`, top `p3 -> p2`, left `p0 -> p3`, right `p1 -> p2`).
pub(super) struct CellCore {
    /// Corner cross products ([`cell_products`]).
    pub c: [f64; 4],
    /// Edge lengths from `p[k]` to `p[k + 1]`.
    pub edges: [f64; 4],
    /// The scaled Jacobian ([`least_scaled_jacobian`]; the reference's when `fine`).
    pub sj: f64,
    /// The corner angle candidates ([`corner_candidates`]; the reference's when `fine`).
    pub a: [f64; 4],
    /// The cell takes the fast path: every length in range, every corner [`settled`], the
    /// scaled Jacobian's pick certain.
    pub fine: bool,
    /// Every length in range and every corner settled (`fine` but for the pick): the cell
    /// pass takes every figure but the scaled Jacobian from loop 1 ([`REDO`]).
    pub geom: bool,
}

/// [`CellCore`] of a cell from its edges `b`, `t`, `l`, `r` (bottom, top, left, right).
///
/// The loops cut their edge arrays to the loop's length themselves, in the loop's own
/// function, and index them there: behind a struct of slices or a method taking the index
/// the compiler no longer vectorised the loop (the quality pass took 60 ms instead of 18 at
/// 1e3 bubbles).
#[inline(always)]
pub(super) fn cell_core(b: [f64; 4], t: [f64; 4], l: [f64; 4], r: [f64; 4]) -> CellCore {
    let (c, _) = cell_products([[b[0], b[1]], [t[0], t[1]], [l[0], l[1]], [r[0], r[1]]]);
    let edges = [b[2], r[2], t[2], l[2]];
    let (sj, certain) = least_scaled_jacobian(&c, &edges);
    // The reference's corner angles where they are settled (which needs a non-zero cross
    // product: a zero one, of either sign, takes the reference path).
    let a = corner_candidates(b[3], r[3], t[3], l[3]);
    // NaN lengths fail `>= 0`; with every length in range the products are finite.
    let fine = (edges[0] >= 0.0)
        & (edges[1] >= 0.0)
        & (edges[2] >= 0.0)
        & (edges[3] >= 0.0)
        & settled(a[0], c[0])
        & settled(a[1], c[1])
        & settled(a[2], c[2])
        & settled(a[3], c[3]);
    CellCore {
        c,
        edges,
        sj,
        a,
        fine: fine & certain,
        geom: fine,
    }
}

/// Edge ratio and aspect ratio from the edge lengths, the expressions of
/// [`length_figures`](super::kernel::length_figures) for the fast path's positive finite
/// lengths (elsewhere the results are not used): no NaN, no zero, so the plain compares are
/// `f64::min` / `max` and [`super::ratio`] is the division.
#[inline(always)]
pub(super) fn edge_ratios(edges: &[f64; 4]) -> (f64, f64) {
    let (lo, hi) = (fold(*edges, less), fold(*edges, more));
    let li = 0.5 * (edges[0] + edges[2]);
    let lj = 0.5 * (edges[1] + edges[3]);
    (hi / lo, more(li, lj) / less(li, lj))
}

/// Running figures of a chunk of blocks, in visiting order: the fast path's histogram counts,
/// outside counts and samples in plain arrays, and the extremes as plain numbers (`+-inf`
/// until a finite value came), turned into [`MetricSummary`] fields by [`Chunk::finish`].
/// Folding `x` into `+inf` gives `x`, so this is the sequence of `Option` folds of
/// `MetricSummary::add_value` (the tests' reference).
pub(super) struct Chunk {
    /// The reference path's counts.
    metrics: QualityMetrics,
    /// The fast path's histogram counts (bins below 32), per value of a cell (the four
    /// angles, then skewness, scaled Jacobian, edge ratio, aspect ratio), folded in from
    /// [`Chunk::pairs`] by [`Chunk::flush`].
    counts: [[u64; 32]; 8],
    /// The fast path's histogram counts per pair of values of a cell (angles 0 and 1, angles
    /// 2 and 3, skewness and scaled Jacobian, edge ratio and aspect ratio): entry `a + 32 b`
    /// of table `t` counts the cells whose values `2t` and `2t + 1` fall in bins `a` and `b`,
    /// which is the 10-bit field `t` of [`Figures::bins`]. One increment per pair rather than
    /// per value halves the scattered increments of the cell loop (each one a load, add and
    /// store, chained through memory when consecutive cells hit the same entry); each value's
    /// counts are the table's row or column sums. `u32` entries: flushed before
    /// [`Chunk::pending`] could exceed `u32::MAX`.
    pairs: Box<[[u32; 1024]; 4]>,
    /// Cells counted in [`Chunk::pairs`] since the last flush.
    pending: u64,
    /// The fast path's cells outside the acceptable range, per metric.
    outside: [u64; 5],
    /// Cells through the fast path.
    fast: u64,
    /// `[min, max]` of angle, skewness, scaled Jacobian, edge ratio, aspect ratio.
    ext: [[f64; 2]; 5],
}

const ANGLE: usize = 0;
const SKEW: usize = 1;
const SJ: usize = 2;
const ER: usize = 3;
const AR: usize = 4;

// The cell loop counts a ratio outside its range by the high end alone (see `row_figures`).
const _: () = assert!(EDGE_RATIO_ACCEPTABLE[0] <= 1.0 && ASPECT_ACCEPTABLE[0] <= 1.0);

/// True when `x` is outside `acc` (or not a number).
#[inline(always)]
fn outside(x: f64, acc: [f64; 2]) -> bool {
    !((x >= acc[0]) & (x <= acc[1]))
}

impl Chunk {
    pub fn new() -> Chunk {
        Chunk {
            metrics: QualityMetrics::empty(),
            counts: [[0; 32]; 8],
            pairs: Box::new([[0; 1024]; 4]),
            pending: 0,
            outside: [0; 5],
            fast: 0,
            ext: [[f64::INFINITY, f64::NEG_INFINITY]; 5],
        }
    }

    fn summary(m: &mut QualityMetrics, which: usize) -> &mut MetricSummary {
        match which {
            ANGLE => &mut m.angle_deg,
            SKEW => &mut m.equiangle_skewness,
            SJ => &mut m.scaled_jacobian,
            ER => &mut m.edge_ratio,
            _ => &mut m.aspect_ratio,
        }
    }

    /// Fold a value into the extremes of metric `which`.
    #[inline(always)]
    fn extremes(&mut self, which: usize, lo: f64, hi: f64) {
        let e = &mut self.ext[which];
        e[0] = e[0].min(lo);
        e[1] = e[1].max(hi);
    }

    /// `MetricSummary::add_value` (the tests' reference).
    fn add_value(&mut self, which: usize, x: f64) {
        let m = Self::summary(&mut self.metrics, which);
        m.samples += 1;
        m.histogram.add(x);
        if x.is_finite() {
            self.extremes(which, x, x);
        }
    }

    /// `MetricSummary::add` (the tests' reference).
    fn add(&mut self, which: usize, x: f64) {
        self.add_value(which, x);
        let m = Self::summary(&mut self.metrics, which);
        if !m.accepts(x) {
            m.outside += 1;
        }
    }

    /// Fold [`Chunk::pairs`] into [`Chunk::counts`] (row and column sums) and clear it.
    fn flush(&mut self) {
        // The entries a field pair can reach: angle bins are at most 18, skewness and scaled
        // Jacobian bins at most 10, ratio bins at most 9.
        const USED: [usize; 4] = [
            18 + 32 * 18 + 1,
            18 + 32 * 18 + 1,
            10 + 32 * 10 + 1,
            9 + 32 * 9 + 1,
        ];
        for (t, table) in self.pairs.iter_mut().enumerate() {
            let [lo, hi] = &mut self.counts[2 * t..2 * t + 2] else {
                unreachable!()
            };
            debug_assert!(table[USED[t]..].iter().all(|&v| v == 0));
            for (k, v) in table[..USED[t]].iter_mut().enumerate() {
                let n = u64::from(std::mem::take(v));
                lo[k & 31] += n;
                hi[k >> 5] += n;
            }
        }
        self.pending = 0;
    }

    /// The growth ratios of the chunk (counted by the caller).
    pub fn growth(&mut self) -> &mut MetricSummary {
        &mut self.metrics.interface_growth_ratio
    }

    /// The metrics of every block measured.
    pub fn finish(mut self) -> QualityMetrics {
        self.flush();
        for which in [ANGLE, SKEW, SJ, ER, AR] {
            let [lo, hi] = self.ext[which];
            let m = Self::summary(&mut self.metrics, which);
            // Only finite values were folded: an infinite bound means none came.
            m.min = lo.is_finite().then_some(lo);
            m.max = hi.is_finite().then_some(hi);
            let slots = match which {
                ANGLE => 0..4,
                SKEW => 4..5,
                SJ => 5..6,
                ER => 6..7,
                _ => 7..8,
            };
            for c in &self.counts[slots] {
                for (a, b) in m.histogram.counts.iter_mut().zip(c) {
                    *a += b;
                }
            }
            m.outside += self.outside[which];
            m.samples += self.fast * if which == ANGLE { 4 } else { 1 };
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
        let per_band = (BAND_NODES / w).max(1);
        for j0 in (0..nj).step_by(per_band) {
            let nb = per_band.min(nj - j0);
            let nodes = &grid.nodes[j0 * w..(j0 + nb + 1) * w];
            let k = rows.figures(nodes, w, nb, t);
            if self.pending + k.fast > u64::from(u32::MAX) {
                self.flush();
            }
            self.pending += k.fast;
            if k.fast > 0 {
                // Extremes of the band's fast cells: no NaN, no zero, so merging them here
                // (before the band's reference cells) rather than cell by cell gives the same
                // bits.
                self.fast += k.fast;
                f.cells += k.fast as usize;
                f.inverted += k.inverted as usize;
                for (a, b) in self.outside.iter_mut().zip(k.outside) {
                    *a += b;
                }
                for (m, e) in self.ext.iter_mut().enumerate() {
                    e[0] = less(unkey(k.lo[m]), e[0]);
                    e[1] = more(unkey(k.hi[m]), e[1]);
                }
                f.min_angle_deg = less(unkey(k.lo[ANGLE]), f.min_angle_deg);
                f.max_angle_deg = more(unkey(k.hi[ANGLE]), f.max_angle_deg);
                min_sj(&mut f, unkey(k.lo[SJ]));
            }
            // Loop 2, in cell order.
            for r in 0..nb {
                let (line, next) = (&nodes[r * w..(r + 1) * w], &nodes[(r + 1) * w..(r + 2) * w]);
                for (i, cell) in rows.cells[r * w..r * w + ni].iter().enumerate() {
                    if cell.bins & FAST == 0 {
                        self.add_reference(&mut f, &[line[i], line[i + 1], next[i + 1], next[i]]);
                        continue;
                    }
                    f.sum_min += cell.fig[0];
                    f.sum_max += cell.fig[1];
                    let mut s = cell.bins;
                    if s & REDO != 0 {
                        let p = [line[i], line[i + 1], next[i + 1], next[i]];
                        s = (s & !SJ_FIELD) | self.redo_scaled_jacobian(&mut f, &p);
                    }
                    let c = &mut *self.pairs;
                    for (t, c) in c.iter_mut().enumerate() {
                        c[(s >> (10 * t)) as usize & 1023] += 1;
                    }
                }
            }
        }
        f
    }

    /// The scaled Jacobian of a [`REDO`] cell with corners `p`, by the reference expression,
    /// counted in its acceptance, extremes and the block's least; returns its bin as field 5
    /// of a packed word. On the fast path it is finite and not zero (every corner settled:
    /// `|sin|` at least that of `1e-9` degrees), so folding it here gives the same bits.
    fn redo_scaled_jacobian(&mut self, f: &mut BlockFigures, p: &[Point; 4]) -> u64 {
        let sj = reference_scaled_jacobian(p);
        self.outside[SJ] += u64::from(outside(sj, SCALED_JACOBIAN_ACCEPTABLE));
        self.extremes(SJ, sj, sj);
        min_sj(f, sj);
        (StepBins::JACOBIAN.count(sj) as u64) << 25
    }

    /// Everything the reference computes from one cell, with the reference formulas.
    fn add_reference(&mut self, f: &mut BlockFigures, p: &[Point; 4]) {
        let c = cell_metrics(*p);
        let (jacobian, _) = corner_products(p);
        f.cells += 1;
        f.sum_min += c.min_angle_deg;
        f.sum_max += c.max_angle_deg;
        f.min_angle_deg = f.min_angle_deg.min(c.min_angle_deg);
        f.max_angle_deg = f.max_angle_deg.max(c.max_angle_deg);
        let a = &mut self.metrics.angle_deg;
        if !(a.accepts(c.min_angle_deg) && a.accepts(c.max_angle_deg)) {
            a.outside += 1;
        }
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
}

/// The scaled Jacobian of the cell with corners `p` by the reference expression
/// ([`super::cell_metrics`]'s: `length_figures` of the corner products and
/// [`super::edge_lengths`]).
pub(super) fn reference_scaled_jacobian(p: &[Point; 4]) -> f64 {
    let (cross, _) = corner_products(p);
    super::kernel::length_figures(&cross, &super::edge_lengths(p)).0
}

/// `min(x, e)` for the fast path's figures (never NaN nor zero, so this equals `f64::min` in
/// either order, and is one instruction).
#[inline(always)]
pub(super) fn less(x: f64, e: f64) -> f64 {
    if x < e {
        x
    } else {
        e
    }
}

/// `max(x, e)`, as [`less`].
#[inline(always)]
pub(super) fn more(x: f64, e: f64) -> f64 {
    if x > e {
        x
    } else {
        e
    }
}

/// NaN-sticky minimum of the scaled Jacobians, in visiting order.
#[inline(always)]
fn min_sj(f: &mut BlockFigures, sj: f64) {
    if sj.is_nan() || sj < f.min_scaled_jacobian {
        f.min_scaled_jacobian = sj;
    }
}

#[cfg(test)]
mod tests;
