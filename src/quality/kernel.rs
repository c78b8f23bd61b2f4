//! The per-cell kernel of [`super`]: every figure of a cell in one pass, bit for bit equal to
//! the reference formulas ([`super::cell_corners`], [`super::cell_metrics`]) but without an
//! `atan2` per corner or a `hypot` per edge.
//!
//! How the figures stay identical:
//! - cross and dot products are computed with the reference expressions, so Jacobians and the
//!   inverted test are the same numbers;
//! - the corners with the smallest and largest angle are found by a monotone pseudo-angle
//!   ([`pseudo_angle`]); `atan2` is evaluated only for corners whose pseudo-angle is within
//!   [`KEY_TOL`] of the extreme (several when nearly tied), and the extremes are folded as in
//!   the reference;
//! - a corner angle's histogram bin comes from the pseudo-angle unless it is within
//!   [`KEY_TOL`] of a bin edge, where the angle itself is evaluated;
//! - edge lengths are first taken as `sqrt(x² + y²)` (a few ulps from `hypot`); a figure built
//!   on them is recomputed with `hypot` whenever it is within a relative [`REL_TOL`] of a bin
//!   edge, of an acceptance bound, or of the block's running extreme, so every count and
//!   every extreme is that of the reference;
//! - cells with a zero product, a very short or very long edge, or a non-finite number take
//!   the reference path.

use super::{cell_corners, cell_metrics, fold, MetricSummary, QualityMetrics};
use crate::geometry::Point;
use crate::mesh::BlockGrid;

/// Pseudo-angle tolerance: the pseudo-angle and `atan2` in degrees are both within ~1e-14 of
/// the true angle of the computed `(cross, dot)`, and the pseudo-angle's slope against the
/// angle in radians is between 1/2 and 1.
const KEY_TOL: f64 = 1e-10;
/// Relative tolerance between the `sqrt` and the `hypot` figures (they differ by ~1e-15).
const REL_TOL: f64 = 1e-10;
/// Squared edge lengths outside this range take the reference path (no underflow or overflow
/// in `x² + y²` or in the products).
const SQ_MIN: f64 = 1e-280;
const SQ_MAX: f64 = 1e280;

/// A value in `[0, 4)` increasing with the counter-clockwise angle `atan2(cross, dot)` taken
/// in `[0, 360)` degrees (one unit per quadrant). Requires `(cross, dot) != (0, 0)`.
#[inline]
pub(super) fn pseudo_angle(cross: f64, dot: f64) -> f64 {
    if cross >= 0.0 {
        if dot > 0.0 {
            cross / (cross + dot)
        } else {
            1.0 + (-dot) / (cross - dot)
        }
    } else if dot < 0.0 {
        2.0 + (-cross) / (-cross - dot)
    } else {
        3.0 + dot / (dot - cross)
    }
}

/// The reference corner angle in degrees, `[0, 360)`.
#[inline]
fn angle_deg(cross: f64, dot: f64) -> f64 {
    let mut ang = cross.atan2(dot).to_degrees();
    if ang < 0.0 {
        ang += 360.0;
    }
    ang
}

/// Cross and dot products at the four corners, with the reference expressions.
#[inline]
pub(super) fn corner_products(p: &[Point; 4]) -> ([f64; 4], [f64; 4]) {
    let mut cross = [0.0; 4];
    let mut dot = [0.0; 4];
    for k in 0..4 {
        let o = p[k];
        let a = p[(k + 1) % 4];
        let b = p[(k + 3) % 4];
        let e1 = [a[0] - o[0], a[1] - o[1]];
        let e2 = [b[0] - o[0], b[1] - o[1]];
        cross[k] = e1[0] * e2[1] - e1[1] * e2[0];
        dot[k] = e1[0] * e2[0] + e1[1] * e2[1];
    }
    (cross, dot)
}

/// The figures of one cell that the fast path computes exactly.
#[derive(Debug, Clone, Copy)]
pub(super) struct FastCell {
    pub cross: [f64; 4],
    pub keys: [f64; 4],
    pub dot: [f64; 4],
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    /// `sqrt(x² + y²)` of the four edges `p0p1, p1p2, p2p3, p3p0`.
    pub approx_len: [f64; 4],
}

impl FastCell {
    /// The fast path, or `None` when the cell must take the reference path.
    #[inline]
    pub fn of(p: &[Point; 4]) -> Option<FastCell> {
        let (cross, dot) = corner_products(p);
        let mut approx_len = [0.0; 4];
        for k in 0..4 {
            let a = p[k];
            let b = p[(k + 1) % 4];
            let (x, y) = (b[0] - a[0], b[1] - a[1]);
            let sq = x * x + y * y;
            // Also false for NaN.
            if !(SQ_MIN..=SQ_MAX).contains(&sq) {
                return None;
            }
            approx_len[k] = sq.sqrt();
        }
        let mut keys = [0.0; 4];
        for k in 0..4 {
            if cross[k] == 0.0 || !cross[k].is_finite() || !dot[k].is_finite() {
                return None;
            }
            keys[k] = pseudo_angle(cross[k], dot[k]);
        }
        let kmin = fold(keys, f64::min);
        let kmax = fold(keys, f64::max);
        // The reference folds all four angles; corners far from the extreme cannot win, so
        // they enter the same fold as +-infinity.
        let mut lo = [f64::INFINITY; 4];
        let mut hi = [f64::NEG_INFINITY; 4];
        for k in 0..4 {
            let near_lo = keys[k] <= kmin + KEY_TOL;
            let near_hi = keys[k] >= kmax - KEY_TOL;
            if near_lo || near_hi {
                let a = angle_deg(cross[k], dot[k]);
                if near_lo {
                    lo[k] = a;
                }
                if near_hi {
                    hi[k] = a;
                }
            }
        }
        Some(FastCell {
            cross,
            keys,
            dot,
            min_angle_deg: fold(lo, f64::min),
            max_angle_deg: fold(hi, f64::max),
            approx_len,
        })
    }

    /// The smallest corner Jacobian (all four are finite and non-zero here).
    #[inline]
    pub fn min_jacobian(&self) -> f64 {
        fold(self.cross, f64::min)
    }

    /// Corner `k`'s angle in degrees, with the reference formula.
    #[inline]
    pub fn angle_deg(&self, k: usize) -> f64 {
        angle_deg(self.cross[k], self.dot[k])
    }
}

/// Edge lengths with the reference formula (`hypot`).
#[inline]
pub(super) fn exact_lengths(p: &[Point; 4]) -> [f64; 4] {
    let mut l = [0.0; 4];
    for k in 0..4 {
        let a = p[k];
        let b = p[(k + 1) % 4];
        l[k] = (b[0] - a[0]).hypot(b[1] - a[1]);
    }
    l
}

/// Scaled Jacobian, edge ratio and aspect ratio from the corner cross products and the edge
/// lengths, with the expressions of [`cell_metrics`].
#[inline]
pub(super) fn length_figures(cross: &[f64; 4], edges: &[f64; 4]) -> (f64, f64, f64) {
    let mut scaled_jacobian = f64::INFINITY;
    for k in 0..4 {
        let (la, lb) = (edges[k], edges[(k + 3) % 4]);
        let s = if la > 0.0 && lb > 0.0 {
            cross[k] / (la * lb)
        } else {
            0.0
        };
        if s.is_nan() || s < scaled_jacobian {
            scaled_jacobian = s;
        }
    }
    let (lo, hi) = (fold(*edges, f64::min), fold(*edges, f64::max));
    let li = 0.5 * (edges[0] + edges[2]);
    let lj = 0.5 * (edges[1] + edges[3]);
    (
        scaled_jacobian,
        super::ratio(hi, lo),
        super::ratio(li.max(lj), li.min(lj)),
    )
}

/// Equiangle skewness from the extreme angles (the expression of [`cell_metrics`]).
#[inline]
pub(super) fn skewness(min_angle_deg: f64, max_angle_deg: f64) -> f64 {
    ((max_angle_deg - 90.0) / 90.0).max((90.0 - min_angle_deg) / 90.0)
}

/// Histogram bin of `x` (finite), the rule of [`super::Histogram::add`].
#[inline]
fn bin(edges: &[f64], x: f64) -> usize {
    let last = edges.len().saturating_sub(2);
    edges[1..].partition_point(|&e| e <= x).min(last)
}

/// A slot of [`BinTable`] whose bin or acceptance is not certain.
const AMBIGUOUS: u8 = u8::MAX;
/// Flag of a [`BinTable`] slot: outside the acceptable range.
const OUTSIDE: u8 = 0x80;

/// Constant-time histogram bins of approximate values: slot `s` covers
/// `[lo + s / scale, lo + (s + 1) / scale)`, padded by a relative 1e-9 (far more than the
/// approximation and slot-index errors), and holds the bin (and [`OUTSIDE`]) shared by every
/// value of the padded slot, or [`AMBIGUOUS`].
pub(super) struct BinTable {
    lo: f64,
    scale: f64,
    slots: Vec<u8>,
}

impl BinTable {
    fn new(edges: &[f64], acceptable: [f64; 2], lo: f64, hi: f64, n: usize) -> BinTable {
        let scale = n as f64 / (hi - lo);
        let accepts = |x: f64| x >= acceptable[0] && x <= acceptable[1];
        let slots = (0..n)
            .map(|s| {
                let a = lo + s as f64 / scale;
                let b = lo + (s + 1) as f64 / scale;
                let pad = 1e-9 * a.abs().max(b.abs()).max(1.0);
                let (a, b) = (a - pad, b + pad);
                let (ba, bb) = (bin(edges, a), bin(edges, b));
                if ba != bb || accepts(a) != accepts(b) || ba >= OUTSIDE as usize {
                    AMBIGUOUS
                } else {
                    ba as u8 | if accepts(a) { 0 } else { OUTSIDE }
                }
            })
            .collect();
        BinTable { lo, scale, slots }
    }

    /// The slot of `x`, or [`AMBIGUOUS`] (also outside the table and for NaN).
    #[inline]
    fn get(&self, x: f64) -> u8 {
        let t = (x - self.lo) * self.scale;
        if t >= 0.0 && t < self.slots.len() as f64 {
            self.slots[t as usize]
        } else {
            AMBIGUOUS
        }
    }
}

/// The bin tables of one measurement (angles by pseudo-angle; the other metrics by value).
pub(super) struct Tables {
    angle_key: BinTable,
    skewness: BinTable,
    scaled_jacobian: BinTable,
    edge_ratio: BinTable,
    aspect_ratio: BinTable,
}

impl Tables {
    pub fn new() -> Tables {
        use super::*;
        let keys: Vec<f64> = ANGLE_EDGES
            .iter()
            .map(|&e| {
                let r = e.to_radians();
                pseudo_angle(r.sin(), r.cos())
            })
            .collect();
        let all = [f64::NEG_INFINITY, f64::INFINITY];
        Tables {
            angle_key: BinTable::new(&keys, all, 0.0, 4.0, 4096),
            skewness: BinTable::new(&SKEWNESS_EDGES, SKEWNESS_ACCEPTABLE, -1.0, 3.0, 4096),
            scaled_jacobian: BinTable::new(
                &JACOBIAN_EDGES,
                SCALED_JACOBIAN_ACCEPTABLE,
                -1.5,
                1.5,
                4096,
            ),
            edge_ratio: BinTable::new(&RATIO_EDGES, EDGE_RATIO_ACCEPTABLE, 1.0, 129.0, 4096),
            aspect_ratio: BinTable::new(&RATIO_EDGES, ASPECT_ACCEPTABLE, 1.0, 129.0, 4096),
        }
    }
}

/// The slot (bin and [`OUTSIDE`]) of an exact value `x`.
#[inline]
fn exact_slot(m: &MetricSummary, table: &BinTable, x: f64) -> u8 {
    let s = table.get(x);
    if s != AMBIGUOUS {
        return s;
    }
    // Histogram::add's rule, NaN in the last bin.
    let last = m.histogram.counts.len() - 1;
    let b = if x.is_nan() {
        last
    } else {
        bin(&m.histogram.edges, x)
    };
    b as u8 | if m.accepts(x) { 0 } else { OUTSIDE }
}

/// The slot of the approximation `x` (finite, relative error far below [`REL_TOL`]) when its
/// bin and acceptance are certain.
#[inline]
fn approx_slot(m: &MetricSummary, table: &BinTable, x: f64) -> Option<u8> {
    let s = table.get(x);
    if s != AMBIGUOUS {
        return Some(s);
    }
    let d = x.abs() * REL_TOL;
    let (lo, hi) = (x - d, x + d);
    let edges = &m.histogram.edges;
    let b = bin(edges, lo);
    (m.accepts(lo) == m.accepts(hi) && b == bin(edges, hi))
        .then(|| b as u8 | if m.accepts(x) { 0 } else { OUTSIDE })
}

/// Count one value of slot `s` (extremes left to the caller).
#[inline]
fn count(m: &mut MetricSummary, s: u8) {
    m.samples += 1;
    m.histogram.counts[(s & !OUTSIDE) as usize] += 1;
    m.outside += u64::from(s & OUTSIDE != 0);
}

/// Update `m`'s extremes with a finite value.
#[inline]
fn extremes(m: &mut MetricSummary, x: f64) {
    m.min = Some(m.min.map_or(x, |a| a.min(x)));
    m.max = Some(m.max.map_or(x, |a| a.max(x)));
}

/// Per-block partial results of [`super::measure`] (small; the metrics of
/// [`super::quality_metrics`] are accumulated per chunk of blocks, see [`BlockStats`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct BlockFigures {
    /// The grid's node count does not match `ni`, `nj` (no cell measured).
    pub malformed: bool,
    pub cells: usize,
    pub sum_min: f64,
    pub sum_max: f64,
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    pub inverted: usize,
    /// NaN-sticky minimum of the cells' scaled Jacobians.
    pub min_scaled_jacobian: f64,
}

/// One block's figures, and the metrics it was counted into (shared by a chunk of blocks:
/// counts and extremes do not depend on how blocks are grouped).
#[derive(Debug, Clone)]
pub(super) struct BlockStats {
    pub fig: BlockFigures,
    pub metrics: QualityMetrics,
}

/// A fast-path cell's length figures (scaled Jacobian, edge ratio, aspect ratio), `exact`
/// when computed with `hypot`; its index in the block.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pending {
    cell: usize,
    figures: [f64; 3],
    exact: bool,
}

impl BlockStats {
    fn new(metrics: QualityMetrics) -> BlockStats {
        BlockStats {
            fig: BlockFigures {
                malformed: false,
                cells: 0,
                sum_min: 0.0,
                sum_max: 0.0,
                min_angle_deg: f64::INFINITY,
                max_angle_deg: f64::NEG_INFINITY,
                inverted: 0,
                min_scaled_jacobian: f64::INFINITY,
            },
            metrics,
        }
    }

    fn add_angles_common(&mut self, lo: f64, hi: f64) {
        self.fig.cells += 1;
        self.fig.sum_min += lo;
        self.fig.sum_max += hi;
        self.fig.min_angle_deg = self.fig.min_angle_deg.min(lo);
        self.fig.max_angle_deg = self.fig.max_angle_deg.max(hi);
        let a = &mut self.metrics.angle_deg;
        if !(a.accepts(lo) && a.accepts(hi)) {
            a.outside += 1;
        }
    }

    fn min_sj(&mut self, sj: f64) {
        if sj.is_nan() || sj < self.fig.min_scaled_jacobian {
            self.fig.min_scaled_jacobian = sj;
        }
    }

    /// Everything the reference computes from one cell, with the reference formulas.
    fn add_reference(&mut self, p: &[Point; 4]) {
        let c = cell_metrics(*p);
        let jacobian = cell_corners(*p).jacobian;
        self.add_angles_common(c.min_angle_deg, c.max_angle_deg);
        if jacobian.iter().any(|&x| x.is_nan() || x <= 0.0) {
            self.fig.inverted += 1;
        }
        self.min_sj(c.scaled_jacobian);
        let m = &mut self.metrics;
        for a in c.angle_deg {
            m.angle_deg.add_value(a);
        }
        m.equiangle_skewness.add(c.equiangle_skewness);
        m.edge_ratio.add(c.edge_ratio);
        m.scaled_jacobian.add(c.scaled_jacobian);
        m.aspect_ratio.add(c.aspect_ratio);
    }

    /// One cell through the fast path (the reference path where it must); the length figures
    /// are counted in the histograms and queued in `pending` for the extremes.
    #[inline]
    fn add_cell(&mut self, p: &[Point; 4], t: &Tables, cell: usize, pending: &mut Vec<Pending>) {
        let Some(f) = FastCell::of(p) else {
            self.add_reference(p);
            return;
        };
        let (lo, hi) = (f.min_angle_deg, f.max_angle_deg);
        self.add_angles_common(lo, hi);
        if f.cross.iter().any(|&x| x <= 0.0) {
            self.fig.inverted += 1;
        }
        let m = &mut self.metrics;
        {
            // Corner angles: four samples; the extremes are the cell's (never 0 or NaN here).
            let a = &mut m.angle_deg;
            a.samples += 4;
            extremes(a, lo);
            extremes(a, hi);
            for k in 0..4 {
                let s = t.angle_key.get(f.keys[k]);
                let b = if s == AMBIGUOUS {
                    bin(&a.histogram.edges, f.angle_deg(k))
                } else {
                    (s & !OUTSIDE) as usize
                };
                a.histogram.counts[b] += 1;
            }
        }
        let sk = skewness(lo, hi);
        let s = exact_slot(&m.equiangle_skewness, &t.skewness, sk);
        count(&mut m.equiangle_skewness, s);
        extremes(&mut m.equiangle_skewness, sk);
        let (sj, er, ar) = length_figures(&f.cross, &f.approx_len);
        // The approximations' bins when all three are certain, else the exact figures.
        let slots = approx_slot(&m.scaled_jacobian, &t.scaled_jacobian, sj).and_then(|a| {
            let b = approx_slot(&m.edge_ratio, &t.edge_ratio, er)?;
            let c = approx_slot(&m.aspect_ratio, &t.aspect_ratio, ar)?;
            Some([a, b, c])
        });
        let (figures, slots, exact) = match slots {
            Some(s) => ([sj, er, ar], s, false),
            None => {
                let (sj, er, ar) = length_figures(&f.cross, &exact_lengths(p));
                let s = [
                    exact_slot(&m.scaled_jacobian, &t.scaled_jacobian, sj),
                    exact_slot(&m.edge_ratio, &t.edge_ratio, er),
                    exact_slot(&m.aspect_ratio, &t.aspect_ratio, ar),
                ];
                ([sj, er, ar], s, true)
            }
        };
        count(&mut m.scaled_jacobian, slots[0]);
        count(&mut m.edge_ratio, slots[1]);
        count(&mut m.aspect_ratio, slots[2]);
        pending.push(Pending {
            cell,
            figures,
            exact,
        });
    }
}

/// The partial results of one block (a malformed grid contributes no cell), counted into
/// `metrics`. `pending` is scratch space.
pub(super) fn block_stats(
    grid: &BlockGrid,
    t: &Tables,
    pending: &mut Vec<Pending>,
    metrics: QualityMetrics,
) -> BlockStats {
    let mut s = BlockStats::new(metrics);
    if !super::well_formed(grid) {
        s.fig.malformed = true;
        return s;
    }
    pending.clear();
    let w = grid.ni + 1;
    let n = &grid.nodes;
    let cell_corners_at = |c: usize| {
        let (i, j) = (c % grid.ni, c / grid.ni);
        let b = i + j * w;
        [n[b], n[b + 1], n[b + 1 + w], n[b + w]]
    };
    for c in 0..grid.ni * grid.nj {
        s.add_cell(&cell_corners_at(c), t, c, pending);
    }
    // Extremes of the length figures: the approximations within REL_TOL of the smallest or
    // largest approximation are the only candidates; they are recomputed exactly.
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for q in pending.iter() {
        for k in 0..3 {
            lo[k] = lo[k].min(q.figures[k]);
            hi[k] = hi[k].max(q.figures[k]);
        }
    }
    let near = |x: f64, e: f64| (x - e).abs() <= 2.0 * REL_TOL * e.abs();
    for q in pending.iter() {
        if !(0..3).any(|k| near(q.figures[k], lo[k]) || near(q.figures[k], hi[k])) {
            continue;
        }
        let [sj, er, ar] = if q.exact {
            q.figures
        } else {
            let p = cell_corners_at(q.cell);
            let (cross, _) = corner_products(&p);
            let (sj, er, ar) = length_figures(&cross, &exact_lengths(&p));
            [sj, er, ar]
        };
        let m = &mut s.metrics;
        extremes(&mut m.scaled_jacobian, sj);
        extremes(&mut m.edge_ratio, er);
        extremes(&mut m.aspect_ratio, ar);
        s.min_sj(sj);
    }
    s
}

/// Per-cell figures of [`super::CellFields`] for one cell: (min angle, max angle, min
/// Jacobian, skewness, edge ratio, scaled Jacobian, aspect ratio), equal to the reference.
#[inline]
pub(super) fn cell_field_values(p: &[Point; 4]) -> [f64; 7] {
    if let Some(f) = FastCell::of(p) {
        let (sj, er, ar) = length_figures(&f.cross, &exact_lengths(p));
        let (lo, hi) = (f.min_angle_deg, f.max_angle_deg);
        return [lo, hi, f.min_jacobian(), skewness(lo, hi), er, sj, ar];
    }
    let c = cell_corners(*p);
    let m = cell_metrics(*p);
    // NaN-propagating minimum: a NaN Jacobian must not look valid.
    let mut mj = c.jacobian[0];
    for &x in &c.jacobian[1..] {
        if x.is_nan() || x < mj {
            mj = x;
        }
    }
    [
        fold(c.angle_deg, f64::min),
        fold(c.angle_deg, f64::max),
        mj,
        m.equiangle_skewness,
        m.edge_ratio,
        m.scaled_jacobian,
        m.aspect_ratio,
    ]
}

/// True when some corner Jacobian of the cell is `<= 0` or not a number.
#[inline]
pub(super) fn is_inverted(p: &[Point; 4]) -> bool {
    corner_products(p).0.iter().any(|&x| x.is_nan() || x <= 0.0)
}
