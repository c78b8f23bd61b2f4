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
//!
//! The per-block pass that applies these rules row by row is [`super::rows`].

use super::{cell_corners, cell_metrics, fold, MetricSummary, QualityMetrics};
use crate::geometry::Point;

/// Pseudo-angle tolerance: the pseudo-angle and `atan2` in degrees are both within ~1e-14 of
/// the true angle of the computed `(cross, dot)`, and the pseudo-angle's slope against the
/// angle in radians is between 1/2 and 1.
pub(super) const KEY_TOL: f64 = 1e-10;
/// Relative tolerance between the `sqrt` and the `hypot` figures (they differ by ~1e-15).
pub(super) const REL_TOL: f64 = 1e-10;
/// Squared edge lengths outside this range take the reference path (no underflow or overflow
/// in `x² + y²` or in the products).
pub(super) const SQ_MIN: f64 = 1e-280;
pub(super) const SQ_MAX: f64 = 1e280;

/// A value in `[0, 4)` increasing with the counter-clockwise angle `atan2(cross, dot)` taken
/// in `[0, 360)` degrees (one unit per quadrant). Requires `(cross, dot) != (0, 0)`.
/// Branch-free: `r = dot / (|cross| + |dot|)` runs from 1 to -1 over the upper half-turn and
/// back over the lower one; its slope against the angle in radians is between 1/2 and 1 in
/// magnitude.
#[inline]
pub(super) fn pseudo_angle(cross: f64, dot: f64) -> f64 {
    let r = dot / (cross.abs() + dot.abs());
    if cross >= 0.0 {
        1.0 - r
    } else {
        3.0 + r
    }
}

/// The reference corner angle in degrees, `[0, 360)`.
#[inline]
pub(super) fn angle_deg(cross: f64, dot: f64) -> f64 {
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

/// The smallest and largest corner angle: the reference folds all four angles; corners far
/// from the extreme cannot win, so they enter the same fold as +-infinity.
pub(super) fn extreme_angles(keys: [f64; 4], cross: [f64; 4], dot: [f64; 4]) -> (f64, f64) {
    let kmin = fold(keys, f64::min);
    let kmax = fold(keys, f64::max);
    let mut lo4 = [f64::INFINITY; 4];
    let mut hi4 = [f64::NEG_INFINITY; 4];
    for k in 0..4 {
        let near_lo = keys[k] <= kmin + KEY_TOL;
        let near_hi = keys[k] >= kmax - KEY_TOL;
        if near_lo || near_hi {
            let a = angle_deg(cross[k], dot[k]);
            if near_lo {
                lo4[k] = a;
            }
            if near_hi {
                hi4[k] = a;
            }
        }
    }
    (fold(lo4, f64::min), fold(hi4, f64::max))
}

/// The figures of one cell that the fast path computes exactly.
#[derive(Debug, Clone, Copy)]
pub(super) struct FastCell {
    pub cross: [f64; 4],
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
}

impl FastCell {
    /// The fast path, or `None` when the cell must take the reference path (a zero or
    /// non-finite product, or an edge whose squared length is outside `[SQ_MIN, SQ_MAX]`).
    #[inline]
    pub fn of(p: &[Point; 4]) -> Option<FastCell> {
        let (cross, dot) = corner_products(p);
        for k in 0..4 {
            let a = p[k];
            let b = p[(k + 1) % 4];
            let (x, y) = (b[0] - a[0], b[1] - a[1]);
            // Also false for NaN.
            if !(SQ_MIN..=SQ_MAX).contains(&(x * x + y * y)) {
                return None;
            }
        }
        let mut keys = [0.0; 4];
        for k in 0..4 {
            if cross[k] == 0.0 || !cross[k].is_finite() || !dot[k].is_finite() {
                return None;
            }
            keys[k] = pseudo_angle(cross[k], dot[k]);
        }
        let (min_angle_deg, max_angle_deg) = extreme_angles(keys, cross, dot);
        Some(FastCell {
            cross,
            min_angle_deg,
            max_angle_deg,
        })
    }

    /// The smallest corner Jacobian (all four are finite and non-zero here).
    #[inline]
    pub fn min_jacobian(&self) -> f64 {
        fold(self.cross, f64::min)
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

/// Equiangle skewness from the extreme angles (finite), equal to the expression of
/// [`cell_metrics`].
#[inline]
///
/// One division: for finite angles, dividing by 90 is monotone and neither difference is
/// `-0.0`, so the larger quotient is the quotient of the larger difference.
pub(super) fn skewness(min_angle_deg: f64, max_angle_deg: f64) -> f64 {
    (max_angle_deg - 90.0).max(90.0 - min_angle_deg) / 90.0
}

/// Histogram bin of `x` (finite), the rule of [`super::Histogram::add`].
#[inline]
pub(super) fn bin(edges: &[f64], x: f64) -> usize {
    let last = edges.len().saturating_sub(2);
    edges[1..].partition_point(|&e| e <= x).min(last)
}

/// A slot of [`BinTable`] whose bin or acceptance is not certain.
pub(super) const AMBIGUOUS: u8 = u8::MAX;
/// Flag of a [`BinTable`] slot: outside the acceptable range.
pub(super) const OUTSIDE: u8 = 0x80;

/// Slots of a [`BinTable`] (a power of two).
const SLOTS: usize = 4096;

/// Constant-time histogram bins of approximate values: slot `s` covers
/// `[lo + s / scale, lo + (s + 1) / scale)`, padded by a relative 1e-9 (far more than the
/// approximation and slot-index errors), and holds the bin (and [`OUTSIDE`]) shared by every
/// value of the padded slot, or [`AMBIGUOUS`].
pub(super) struct BinTable {
    lo: f64,
    scale: f64,
    slots: Box<[u8; SLOTS]>,
}

impl BinTable {
    fn new(edges: &[f64], acceptable: [f64; 2], lo: f64, hi: f64) -> BinTable {
        let scale = SLOTS as f64 / (hi - lo);
        let accepts = |x: f64| x >= acceptable[0] && x <= acceptable[1];
        let mut slots = Box::new([AMBIGUOUS; SLOTS]);
        for (s, slot) in slots.iter_mut().enumerate() {
            *slot = {
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
            };
        }
        BinTable { lo, scale, slots }
    }

    /// The slot of `x`, or [`AMBIGUOUS`] (also outside the table and for NaN).
    #[inline]
    pub(super) fn get(&self, x: f64) -> u8 {
        let t = (x - self.lo) * self.scale;
        if t >= 0.0 && t < SLOTS as f64 {
            // `t` is in [0, SLOTS): the cast truncates and the mask changes nothing (it only
            // spares the bounds check).
            self.slots[t as u32 as usize & (SLOTS - 1)]
        } else {
            AMBIGUOUS
        }
    }
}

/// The bin tables of one measurement (angles by pseudo-angle; the other metrics by value).
pub(super) struct Tables {
    pub angle_key: BinTable,
    pub skewness: BinTable,
    pub scaled_jacobian: BinTable,
    pub edge_ratio: BinTable,
    pub aspect_ratio: BinTable,
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
            angle_key: BinTable::new(&keys, all, 0.0, 4.0),
            skewness: BinTable::new(&SKEWNESS_EDGES, SKEWNESS_ACCEPTABLE, -1.0, 3.0),
            scaled_jacobian: BinTable::new(&JACOBIAN_EDGES, SCALED_JACOBIAN_ACCEPTABLE, -1.5, 1.5),
            edge_ratio: BinTable::new(&RATIO_EDGES, EDGE_RATIO_ACCEPTABLE, 1.0, 129.0),
            aspect_ratio: BinTable::new(&RATIO_EDGES, ASPECT_ACCEPTABLE, 1.0, 129.0),
        }
    }
}

/// The slot (bin and [`OUTSIDE`]) of an exact value `x`.
#[inline]
pub(super) fn exact_slot(m: &MetricSummary, table: &BinTable, x: f64) -> u8 {
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

/// The slots of the approximate scaled Jacobian, edge ratio and aspect ratio when all three
/// are certain.
#[inline]
pub(super) fn approx_slots(m: &QualityMetrics, t: &Tables, x: [f64; 3]) -> Option<[u8; 3]> {
    Some([
        approx_slot(&m.scaled_jacobian, &t.scaled_jacobian, x[0])?,
        approx_slot(&m.edge_ratio, &t.edge_ratio, x[1])?,
        approx_slot(&m.aspect_ratio, &t.aspect_ratio, x[2])?,
    ])
}

/// Count one value of slot `s` (extremes left to the caller).
#[inline]
pub(super) fn count(m: &mut MetricSummary, s: u8) {
    m.samples += 1;
    m.histogram.counts[(s & !OUTSIDE) as usize] += 1;
    m.outside += u64::from(s & OUTSIDE != 0);
}

/// Per-block partial results of [`super::measure`] (small; the metrics of
/// [`super::quality_metrics`] are accumulated per chunk of blocks, see [`super::rows::Chunk`]).
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

/// The cells between node lines `lo` and `hi` (same length) with some corner Jacobian
/// `<= 0` or not a number: the cross products of [`corner_products`], each edge taken as a
/// difference of its two nodes in one direction and negated for the other corner. Negation
/// changes at most the sign of a zero product, and `!(cross > 0)` holds for both zeros (and
/// NaN), so the count is that of the reference test.
pub(super) fn row_inverted(lo: &[Point], hi: &[Point]) -> usize {
    let n = lo.len().min(hi.len()).saturating_sub(1);
    let (lo, hi) = (&lo[..=n], &hi[..=n]);
    let mut count = 0;
    for i in 0..n {
        // p0 -> p1, p3 -> p2, p0 -> p3, p1 -> p2.
        let (hx, hy) = (lo[i + 1][0] - lo[i][0], lo[i + 1][1] - lo[i][1]);
        let (ux, uy) = (hi[i + 1][0] - hi[i][0], hi[i + 1][1] - hi[i][1]);
        let (vx, vy) = (hi[i][0] - lo[i][0], hi[i][1] - lo[i][1]);
        let (wx, wy) = (hi[i + 1][0] - lo[i + 1][0], hi[i + 1][1] - lo[i + 1][1]);
        let c = [
            hx * vy - hy * vx,
            wx * (-hy) - wy * (-hx),
            (-ux) * (-wy) - (-uy) * (-wx),
            (-vx) * uy - (-vy) * ux,
        ];
        let good = (c[0] > 0.0) & (c[1] > 0.0) & (c[2] > 0.0) & (c[3] > 0.0);
        count += usize::from(!good);
    }
    count
}
