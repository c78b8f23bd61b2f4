//! Cell quality: interior angles and corner Jacobians of every quadrilateral cell.
//!
//! A cell `(i, j)` of a [`BlockGrid`] has corners `p0 = (i, j)`, `p1 = (i + 1, j)`,
//! `p2 = (i + 1, j + 1)`, `p3 = (i, j + 1)`, counter-clockwise for a valid cell. The Jacobian
//! at corner `k` is the cross product `(p[k+1] - p[k]) x (p[k-1] - p[k])`: positive for a
//! valid (counter-clockwise, convex at that corner) corner. The interior angle at corner `k`
//! is the angle swept counter-clockwise from `p[k+1] - p[k]` to `p[k-1] - p[k]`, in
//! `[0, 360)` degrees: below 180 where the Jacobian is positive, above 180 at a reflex corner
//! (so the four angles of a simple counter-clockwise cell sum to 360). A cell is *inverted*
//! when any corner Jacobian is `<= 0` or not a number.
//!
//! The reference formulas are [`cell_corners`] and [`cell_metrics`]: corner angles as the
//! differences of the directions of the corners' edges, each direction [`angle_deg`] of the
//! edge vector (an `atan2` in degrees written here, within a few ulps of libm's, see
//! [`atan`]; one per edge, shared by the two cells on either side), within `4e-13` degrees of
//! the exact angle, and `angle_deg(cross, dot)` of the corner where that difference is within
//! `1e-9` degrees of flat; edge lengths `sqrt(x² + y²)` (`hypot` only where the squares could
//! underflow or overflow). The per-block pass of [`measure_all`] gives their bits exactly.

use crate::connectivity::Connectivity;
use crate::geometry::Point;
use crate::layout::BlockLayout;
use crate::mesh::BlockGrid;
use rayon::prelude::*;
use serde::Serialize;

pub mod atan;
mod kernel;
pub(crate) use kernel::row_inverted_portable;
mod fields;
mod measured;
mod rows;

mod sides;

pub use atan::angle_deg;
pub(crate) use measured::{measure_templates_and_drop, ChunkFigures, Measurer};
pub use measured::{measured_all, Measured};

/// Angles (degrees) and Jacobians of the four corners of one quadrilateral `[p0, p1, p2, p3]`
/// (see the module doc for the conventions).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellCorners {
    pub angle_deg: [f64; 4],
    pub jacobian: [f64; 4],
}

/// Measure one quadrilateral's corners.
///
/// A corner's angle is the difference of the directions of its two edges (each direction
/// [`angle_deg`] of the edge vector `to - from`, for the edges `p0 -> p1`, `p1 -> p2`,
/// `p3 -> p2`, `p0 -> p3`: the quality pass finds each edge's direction once for the two
/// cells on either side), within `4e-13` degrees of the exact angle. Where that difference is
/// within `1e-9` degrees of 0, 180 or 360, or on the wrong side of 180 for the sign of the
/// corner's cross product (and where the product is zero or not finite), the angle is
/// `angle_deg(cross, dot)` of the corner instead, accurate to a few units in the last place
/// for nearly flat corners too.
pub fn cell_corners(p: [Point; 4]) -> CellCorners {
    let (jacobian, dots) = kernel::corner_products(&p);
    let dir = |from: Point, to: Point| angle_deg(to[1] - from[1], to[0] - from[0]);
    let candidates = kernel::corner_candidates(
        dir(p[0], p[1]),
        dir(p[1], p[2]),
        dir(p[3], p[2]),
        dir(p[0], p[3]),
    );
    CellCorners {
        angle_deg: [0, 1, 2, 3].map(|k| {
            if kernel::settled(candidates[k], jacobian[k]) {
                candidates[k]
            } else {
                angle_deg(jacobian[k], dots[k])
            }
        }),
        jacobian,
    }
}

/// Per-cell figures of one block, cells in the order `i + j * ni` (VTK's cell order).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CellFields {
    pub min_angle_deg: Vec<f64>,
    pub max_angle_deg: Vec<f64>,
    /// The smallest of the four corner Jacobians (cross products, in squared length units).
    pub min_jacobian: Vec<f64>,
    /// The figures of [`CellMetrics`], per cell.
    pub equiangle_skewness: Vec<f64>,
    pub edge_ratio: Vec<f64>,
    pub scaled_jacobian: Vec<f64>,
    pub aspect_ratio: Vec<f64>,
}

impl CellFields {
    /// The arrays in the order of the writers' cell arrays (`output::vtk::CELL_ARRAYS`).
    pub(crate) fn arrays_mut(&mut self) -> [&mut Vec<f64>; 7] {
        [
            &mut self.min_angle_deg,
            &mut self.max_angle_deg,
            &mut self.min_jacobian,
            &mut self.equiangle_skewness,
            &mut self.edge_ratio,
            &mut self.scaled_jacobian,
            &mut self.aspect_ratio,
        ]
    }
}

/// True when `grid.nodes` has exactly `(ni + 1) * (nj + 1)` nodes.
pub fn well_formed(grid: &BlockGrid) -> bool {
    grid.ni
        .checked_add(1)
        .and_then(|a| grid.nj.checked_add(1).and_then(|b| a.checked_mul(b)))
        == Some(grid.nodes.len())
}

/// The four corners of cell `(i, j)`; requires a well-formed grid and `i < ni`, `j < nj`.
fn corners(grid: &BlockGrid, i: usize, j: usize) -> [Point; 4] {
    [
        grid.node(i, j),
        grid.node(i + 1, j),
        grid.node(i + 1, j + 1),
        grid.node(i, j + 1),
    ]
}

/// Per-cell figures of one block (empty for a malformed grid, see [`well_formed`]); equal to
/// those of [`cell_corners`] and [`cell_metrics`] bit for bit, computed a band of rows at a
/// time with one direction per edge (vectorised where the CPU allows), the reference formulas
/// only for the cells that need them.
pub fn cell_fields(grid: &BlockGrid) -> CellFields {
    let mut f = CellFields::default();
    if !well_formed(grid) || grid.ni == 0 || grid.nj == 0 {
        return f;
    }
    let n = grid.ni * grid.nj;
    for v in f.arrays_mut() {
        v.reserve_exact(n);
    }
    fields::cell_fields_into(grid, &mut f);
    f
}

/// [`cell_fields`] cell by cell with the reference formulas: the tests' oracle.
#[cfg(test)]
pub(crate) fn cell_fields_reference(grid: &BlockGrid) -> CellFields {
    let mut f = CellFields::default();
    if !well_formed(grid) {
        return f;
    }
    for j in 0..grid.nj {
        for i in 0..grid.ni {
            let [lo, hi, mj, sk, er, sj, ar] = kernel::cell_field_values(&corners(grid, i, j));
            f.min_angle_deg.push(lo);
            f.max_angle_deg.push(hi);
            f.min_jacobian.push(mj);
            f.equiangle_skewness.push(sk);
            f.edge_ratio.push(er);
            f.scaled_jacobian.push(sj);
            f.aspect_ratio.push(ar);
        }
    }
    f
}

/// Number of inverted cells (a corner Jacobian `<= 0` or not a number) over well-formed grids:
/// the cheap check of [`Quality::inverted_cells`] (signs of cross products only).
pub fn inverted_cells(grids: &[BlockGrid]) -> usize {
    grids.par_iter().map(grid_inverted_cells).sum()
}

/// [`inverted_cells`] of one grid.
fn grid_inverted_cells(g: &BlockGrid) -> usize {
    if !well_formed(g) {
        return 0;
    }
    let w = g.ni + 1;
    (0..g.nj)
        .map(|j| kernel::row_inverted(&g.nodes[j * w..(j + 1) * w], &g.nodes[(j + 1) * w..][..w]))
        .sum()
}

/// True when some cell of a well-formed `grid` has a corner angle below `deg` degrees
/// (`0 < deg < 90`), or is inverted or not finite: one cross and one dot product per corner
/// (the angle is below `deg` when `0 < cross < tan(deg) dot`), no trigonometry per cell.
pub fn has_corner_below(grid: &BlockGrid, deg: f64) -> bool {
    if !well_formed(grid) {
        return false;
    }
    let t = deg.to_radians().tan();
    let w = grid.ni + 1;
    (0..grid.nj).any(|j| {
        kernel::row_corner_below(
            &grid.nodes[j * w..(j + 1) * w],
            &grid.nodes[(j + 1) * w..][..w],
            t,
        )
    })
}

/// The indices of the grids with at least one inverted cell (as [`inverted_cells`] counts
/// them), in increasing order: one pass over the cells.
pub fn inverted_blocks(grids: &[BlockGrid]) -> Vec<usize> {
    grids
        .par_iter()
        .enumerate()
        .filter(|(_, g)| grid_inverted_cells(g) > 0)
        .map(|(b, _)| b)
        .collect()
}

fn fold(v: [f64; 4], op: fn(f64, f64) -> f64) -> f64 {
    op(op(v[0], v[1]), op(v[2], v[3]))
}

/// Quality figures of a whole mesh.
///
/// With no cells, every angle figure is 0. Malformed grids (see [`well_formed`]) contribute
/// no cells and are counted in `malformed_grids`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quality {
    /// Number of cells measured.
    pub cells: usize,
    /// Smallest and largest interior angle over all cells, degrees.
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    /// Mean over cells of each cell's smallest / largest interior angle, degrees (the
    /// paper's "average smallest / largest angle").
    pub mean_min_angle_deg: f64,
    pub mean_max_angle_deg: f64,
    /// Cells with a corner Jacobian `<= 0` (or not a number).
    pub inverted_cells: usize,
    /// Smallest corner Jacobian divided by the lengths of its two edges (the sine of the
    /// corner angle; 1 for a rectangle, `<= 0` for an inverted cell).
    pub min_scaled_jacobian: f64,
    /// Grids whose node count does not match `ni`, `nj`.
    pub malformed_grids: usize,
}

/// Measure every cell of every grid.
///
/// Blocks are measured in parallel (on the current rayon pool) and reduced in block order:
/// the means are sums of per-block sums, the same for every thread count.
pub fn measure(grids: &[BlockGrid]) -> Quality {
    reduce(&block_stats(grids, None, None).chunks).0
}

/// Blocks per chunk of [`block_stats`]: a fixed number, so that nothing depends on the
/// thread count.
pub(crate) const CHUNK: usize = 64;

/// The per-chunk results of [`block_stats`], and what it measured besides the cells.
struct Stats {
    chunks: Vec<(Vec<kernel::BlockFigures>, QualityMetrics)>,
    /// The growth ratios of the interfaces between chunks (with `conn`).
    spilled: Option<MetricSummary>,
    /// The wall orthogonality (with `layout`).
    wall: Option<f64>,
}

/// [`measure`] and the cell part of [`quality_metrics`] in one pass over the cells: the
/// figures of every block, and the metrics of every chunk of [`CHUNK`] blocks. With `conn`
/// (one entry per grid, in grid order), also the growth ratios (the heights of each block's
/// interface cells right after its cells, while its nodes are in cache, see [`sides`]), and
/// with `layout` (one block per grid) the wall orthogonality of each block.
fn block_stats(
    grids: &[BlockGrid],
    conn: Option<&Connectivity>,
    layout: Option<&BlockLayout>,
) -> Stats {
    let tables = kernel::Tables::new();
    let lanes = crate::lanes::Lanes::best();
    let plan = conn.map(|conn| sides::Plan::new(conn, grids));
    let mut spill = Vec::new();
    let chunks = grids.len().div_ceil(CHUNK);
    let slices = match &plan {
        Some(plan) => plan.spill_slices(&mut spill),
        None => (0..chunks).map(|_| &mut [][..]).collect(),
    };
    let parts: Vec<_> = grids
        .par_chunks(CHUNK)
        .zip(slices)
        .enumerate()
        .with_max_len(crate::tasks::BLOCKS / CHUNK)
        .map_init(
            || (rows::Rows::default(), sides::Sides::new(lanes)),
            |(scratch, sd), (c, (chunk, spill))| {
                let mut acc = rows::Chunk::new();
                let mut wall = None;
                sd.start();
                let figs = chunk
                    .iter()
                    .enumerate()
                    .map(|(k, g)| {
                        if let Some(l) = layout {
                            sides::prefetch_edges(l, &l.blocks[c * CHUNK + k]);
                        }
                        let f = acc.block(g, &tables, scratch);
                        if let Some(plan) = &plan {
                            sd.block(plan, c, k, g, spill);
                        }
                        if let Some(l) = layout {
                            let b = &l.blocks[c * CHUNK + k];
                            wall = sides::max_nan(wall, sd.wall(l, b, g));
                        }
                        f
                    })
                    .collect();
                if let Some(plan) = &plan {
                    sd.pair_local(plan, c, acc.growth());
                }
                ((figs, acc.finish()), wall)
            },
        )
        .collect();
    let spilled = plan.map(|plan| {
        let mut m = MetricSummary::new(&GROWTH_EDGES, GROWTH_ACCEPTABLE);
        plan.pair_spilled(&spill, &mut m);
        m
    });
    let wall = parts.iter().fold(None, |w, p| sides::max_nan(w, p.1));
    Stats {
        chunks: parts.into_iter().map(|p| p.0).collect(),
        spilled,
        wall,
    }
}

/// Reduce per-block results in block order.
fn reduce(stats: &[(Vec<kernel::BlockFigures>, QualityMetrics)]) -> (Quality, QualityMetrics) {
    let mut q = Quality {
        cells: 0,
        min_angle_deg: f64::INFINITY,
        max_angle_deg: f64::NEG_INFINITY,
        mean_min_angle_deg: 0.0,
        mean_max_angle_deg: 0.0,
        inverted_cells: 0,
        min_scaled_jacobian: f64::INFINITY,
        malformed_grids: 0,
    };
    let mut m = QualityMetrics::empty();
    let (mut sum_min, mut sum_max) = (0.0, 0.0);
    for (figs, metrics) in stats {
        m.merge_metrics(metrics);
        for s in figs {
            if s.malformed {
                q.malformed_grids += 1;
                continue;
            }
            q.cells += s.cells;
            sum_min += s.sum_min;
            sum_max += s.sum_max;
            q.min_angle_deg = q.min_angle_deg.min(s.min_angle_deg);
            q.max_angle_deg = q.max_angle_deg.max(s.max_angle_deg);
            q.inverted_cells += s.inverted;
            // NaN-sticky minimum, as if every cell were visited in order.
            if !q.min_scaled_jacobian.is_nan()
                && (s.min_scaled_jacobian.is_nan() || s.min_scaled_jacobian < q.min_scaled_jacobian)
            {
                q.min_scaled_jacobian = s.min_scaled_jacobian;
            }
        }
    }
    if q.cells == 0 {
        q.min_angle_deg = 0.0;
        q.max_angle_deg = 0.0;
        q.min_scaled_jacobian = 0.0;
    } else {
        q.mean_min_angle_deg = sum_min / q.cells as f64;
        q.mean_max_angle_deg = sum_max / q.cells as f64;
    }
    (q, m)
}

// ---------------------------------------------------------------------------------------------
// Standard quality metrics (equiangle skewness, edge ratio, scaled Jacobian, aspect ratio,
// growth ratio across block interfaces, wall orthogonality), with histograms and acceptable
// ranges, as written into `report.json`'s `"quality"` object.
// ---------------------------------------------------------------------------------------------

/// Every per-cell figure of one quadrilateral `[p0, p1, p2, p3]` (counter-clockwise for a valid
/// cell; see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellMetrics {
    /// The four interior angles, degrees, in `[0, 360)` (see [`cell_corners`]).
    pub angle_deg: [f64; 4],
    /// Smallest and largest interior angle, degrees.
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    /// Equiangle skewness `max((θmax - 90) / 90, (90 - θmin) / 90)` (computed as
    /// `max(θmax - 90, 90 - θmin) / 90`, the same for finite angles): 0 for a rectangle, 1 for a
    /// degenerate cell (an angle of 0 or 180 degrees), above 1 with a reflex corner.
    pub equiangle_skewness: f64,
    /// Longest edge over shortest edge (`>= 1`; infinite with a zero-length edge).
    pub edge_ratio: f64,
    /// Smallest over the corners of `cross(e1, e2) / (|e1| |e2|)`, the sine of the corner
    /// angle: 1 for a rectangle, `<= 0` for an inverted cell (0 with a zero-length edge).
    pub scaled_jacobian: f64,
    /// Ratio of the cell's mean extents in its two index directions, the larger over the
    /// smaller: `max(Li, Lj) / min(Li, Lj)` with `Li = (|p0p1| + |p3p2|) / 2` and
    /// `Lj = (|p1p2| + |p0p3|) / 2` (`>= 1`; 1 for a square, and also for a rhombus).
    pub aspect_ratio: f64,
}

/// The reference edge length ([`crate::geometry::length`]: `sqrt(x² + y²)`, `hypot` only near
/// underflow or overflow).
fn len(a: Point, b: Point) -> f64 {
    crate::geometry::length(b[0] - a[0], b[1] - a[1])
}

/// Ratio `a / b` of two non-negative lengths, `a >= b`: infinite when `b == 0 < a`, 1 when
/// both are 0.
fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else if a > 0.0 {
        f64::INFINITY
    } else {
        1.0
    }
}

/// The reference lengths of a quadrilateral's edges, `edges[k]` from `p[k]` to `p[k + 1]`
/// ([`len`]).
fn edge_lengths(p: &[Point; 4]) -> [f64; 4] {
    [
        len(p[0], p[1]),
        len(p[1], p[2]),
        len(p[2], p[3]),
        len(p[3], p[0]),
    ]
}

/// Measure one quadrilateral (see [`CellMetrics`]).
pub fn cell_metrics(p: [Point; 4]) -> CellMetrics {
    let c = cell_corners(p);
    let min_angle_deg = fold(c.angle_deg, f64::min);
    let max_angle_deg = fold(c.angle_deg, f64::max);
    let edges = edge_lengths(&p);
    let (scaled_jacobian, edge_ratio, aspect_ratio) = kernel::length_figures(&c.jacobian, &edges);
    CellMetrics {
        angle_deg: c.angle_deg,
        min_angle_deg,
        max_angle_deg,
        equiangle_skewness: kernel::skewness(min_angle_deg, max_angle_deg),
        edge_ratio,
        scaled_jacobian,
        aspect_ratio,
    }
}

/// A histogram with fixed bin edges: bin `k` counts the values in `[edges[k], edges[k + 1])`;
/// values below `edges[0]` count in the first bin, values at or above the last edge and
/// values that are not a number in the last bin, so the counts add up to the number of values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Histogram {
    pub edges: Vec<f64>,
    pub counts: Vec<u64>,
}

impl Histogram {
    /// An empty histogram with the given edges (at least two, increasing).
    pub fn new(edges: &[f64]) -> Histogram {
        Histogram {
            edges: edges.to_vec(),
            counts: vec![0; edges.len().saturating_sub(1).max(1)],
        }
    }
    /// Count one value.
    pub fn add(&mut self, x: f64) {
        let last = self.counts.len() - 1;
        // First edge above x; NaN compares false everywhere and lands in the last bin.
        let k = if x.is_nan() {
            last
        } else {
            self.edges[1..].partition_point(|&e| e <= x).min(last)
        };
        self.counts[k] += 1;
    }
    /// Add the counts of `other` (same edges).
    fn merge(&mut self, other: &Histogram) {
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
    }
}

/// One metric over a mesh: extremes, histogram, the conventional acceptable range and how
/// many cells (or interface faces, for the growth ratio) fall outside it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MetricSummary {
    /// Smallest and largest value (`null` in JSON when there is no value or it is not finite).
    pub min: Option<f64>,
    pub max: Option<f64>,
    pub histogram: Histogram,
    /// The conventional acceptable range `[lo, hi]` (inclusive).
    pub acceptable: [f64; 2],
    /// Cells (for `interface_growth_ratio`: interface faces) with a value outside
    /// `acceptable` (or not a number). For `angle_deg`: cells with any corner angle outside.
    pub outside: u64,
    /// Number of values in the histogram: one per cell, four per cell for `angle_deg` (every
    /// corner angle), one per pair of cells facing each other across an interface for
    /// `interface_growth_ratio`.
    pub samples: u64,
}

impl MetricSummary {
    fn new(edges: &[f64], acceptable: [f64; 2]) -> MetricSummary {
        MetricSummary {
            min: None,
            max: None,
            histogram: Histogram::new(edges),
            acceptable,
            outside: 0,
            samples: 0,
        }
    }
    /// True when `x` is inside the acceptable range.
    pub fn accepts(&self, x: f64) -> bool {
        x >= self.acceptable[0] && x <= self.acceptable[1]
    }
    /// Count one value, which alone decides whether its cell is outside (the reference passes
    /// of the tests; the cell pass counts in bulk).
    #[cfg(test)]
    fn add(&mut self, x: f64) {
        self.add_value(x);
        if !self.accepts(x) {
            self.outside += 1;
        }
    }
    /// Count one value in the extremes and the histogram only.
    #[cfg(test)]
    fn add_value(&mut self, x: f64) {
        self.samples += 1;
        self.histogram.add(x);
        if x.is_finite() {
            self.min = Some(self.min.map_or(x, |m| m.min(x)));
            self.max = Some(self.max.map_or(x, |m| m.max(x)));
        }
    }
    fn merge(&mut self, o: &MetricSummary) {
        self.histogram.merge(&o.histogram);
        self.outside += o.outside;
        self.samples += o.samples;
        for x in [o.min, o.max].into_iter().flatten() {
            self.min = Some(self.min.map_or(x, |m| m.min(x)));
            self.max = Some(self.max.map_or(x, |m| m.max(x)));
        }
    }
}

/// Conventional acceptable range of the interior angles, degrees.
pub const ANGLE_ACCEPTABLE: [f64; 2] = [40.0, 135.0];
/// Equiangle skewness up to 0.5 ("good" on the usual 0-1 scale).
pub const SKEWNESS_ACCEPTABLE: [f64; 2] = [0.0, 0.5];
/// Edge ratio up to 5.
pub const EDGE_RATIO_ACCEPTABLE: [f64; 2] = [1.0, 5.0];
/// Scaled Jacobian at least 0.3.
pub const SCALED_JACOBIAN_ACCEPTABLE: [f64; 2] = [0.3, 1.0];
/// Size ratio across an interface up to 1.5.
pub const GROWTH_ACCEPTABLE: [f64; 2] = [1.0, 1.5];
/// Aspect ratio up to 5.
pub const ASPECT_ACCEPTABLE: [f64; 2] = [1.0, 5.0];

const ANGLE_EDGES: [f64; 20] = [
    0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 110.0, 120.0, 130.0, 135.0,
    140.0, 150.0, 160.0, 170.0, 180.0,
];
const SKEWNESS_EDGES: [f64; 12] = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 2.0];
const RATIO_EDGES: [f64; 11] = [1.0, 1.25, 1.5, 2.0, 3.0, 4.0, 5.0, 10.0, 20.0, 50.0, 100.0];
const JACOBIAN_EDGES: [f64; 12] = [-1.0, 0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0];
const GROWTH_EDGES: [f64; 11] = [1.0, 1.1, 1.2, 1.3, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 100.0];

/// The standard metrics of a whole mesh (serialised as `report.json`'s `"quality"` object,
/// keys in this order).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QualityMetrics {
    /// Every corner angle, degrees (4 samples per cell).
    pub angle_deg: MetricSummary,
    pub equiangle_skewness: MetricSummary,
    pub edge_ratio: MetricSummary,
    pub scaled_jacobian: MetricSummary,
    /// For every pair of cells facing each other across a block interface, the ratio of their
    /// heights normal to the interface (cell area over its edge length on the interface), the
    /// larger over the smaller.
    pub interface_growth_ratio: MetricSummary,
    pub aspect_ratio: MetricSummary,
    /// Over every node of every wall side (an edge of kind [`EdgeKind::Wall`](crate::layout::EdgeKind::Wall) that is an arc),
    /// the angle in degrees between the grid line leaving the wall node into the block and
    /// the circle's normal into the fluid there (0 for an orthogonal grid; `None` without
    /// wall arcs).
    #[serde(skip)]
    pub max_wall_orthogonality_deviation_deg: Option<f64>,
}

impl QualityMetrics {
    fn empty() -> QualityMetrics {
        QualityMetrics {
            angle_deg: MetricSummary::new(&ANGLE_EDGES, ANGLE_ACCEPTABLE),
            equiangle_skewness: MetricSummary::new(&SKEWNESS_EDGES, SKEWNESS_ACCEPTABLE),
            edge_ratio: MetricSummary::new(&RATIO_EDGES, EDGE_RATIO_ACCEPTABLE),
            scaled_jacobian: MetricSummary::new(&JACOBIAN_EDGES, SCALED_JACOBIAN_ACCEPTABLE),
            interface_growth_ratio: MetricSummary::new(&GROWTH_EDGES, GROWTH_ACCEPTABLE),
            aspect_ratio: MetricSummary::new(&RATIO_EDGES, ASPECT_ACCEPTABLE),
            max_wall_orthogonality_deviation_deg: None,
        }
    }

    /// The metrics in report order, with their `report.json` names.
    pub fn named(&self) -> [(&'static str, &MetricSummary); 6] {
        [
            ("angle_deg", &self.angle_deg),
            ("equiangle_skewness", &self.equiangle_skewness),
            ("edge_ratio", &self.edge_ratio),
            ("scaled_jacobian", &self.scaled_jacobian),
            ("interface_growth_ratio", &self.interface_growth_ratio),
            ("aspect_ratio", &self.aspect_ratio),
        ]
    }

    fn merge_metrics(&mut self, o: &QualityMetrics) {
        self.angle_deg.merge(&o.angle_deg);
        self.equiangle_skewness.merge(&o.equiangle_skewness);
        self.edge_ratio.merge(&o.edge_ratio);
        self.scaled_jacobian.merge(&o.scaled_jacobian);
        self.aspect_ratio.merge(&o.aspect_ratio);
        self.interface_growth_ratio.merge(&o.interface_growth_ratio);
    }
}

/// The standard metrics of a mesh given by its layout and grids (one grid per block).
///
/// Per-cell metrics are computed block by block in parallel (on the current rayon pool) and
/// merged in block order, so the result does not depend on the number of threads.
pub fn quality_metrics(layout: &BlockLayout, grids: &[BlockGrid]) -> QualityMetrics {
    measure_all(layout, grids).1
}

/// [`measure`] and [`quality_metrics`] together, with one pass over the cells.
pub fn measure_all(layout: &BlockLayout, grids: &[BlockGrid]) -> (Quality, QualityMetrics) {
    let conn = Connectivity::new(layout, grids).ok();
    measure_all_with(layout, grids, conn.as_ref())
}

/// [`measure_all`] with the block connectivity already computed: `conn` must be
/// `Connectivity::new(layout, grids).ok()` (without it, as when the layout has no valid
/// connectivity, there are no interface growth ratios; one of another number of blocks is
/// not used).
pub fn measure_all_with(
    layout: &BlockLayout,
    grids: &[BlockGrid],
    conn: Option<&Connectivity>,
) -> (Quality, QualityMetrics) {
    let same = layout.blocks.len() == grids.len();
    // One block per grid: the growth ratios go with the cell pass.
    let conn = conn.filter(|c| same && c.len() == grids.len());
    let stats = block_stats(grids, conn, same.then_some(layout));
    let (q, mut m) = reduce(&stats.chunks);
    if let Some(spilled) = &stats.spilled {
        m.interface_growth_ratio.merge(spilled);
    }
    if same {
        m.max_wall_orthogonality_deviation_deg = stats.wall;
    }
    (q, m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The sequential fold [`sides::wall_orthogonality`] used before it ran in parallel.
    fn fold_sequential(values: &[f64]) -> Option<f64> {
        let mut worst: Option<f64> = None;
        for &ang in values {
            worst = Some(match worst {
                Some(x) if x.is_nan() || ang <= x => x,
                _ => ang,
            });
        }
        worst
    }

    fn value() -> impl Strategy<Value = f64> {
        prop_oneof![0.0f64..180.0, Just(f64::NAN), Just(0.0), Just(90.0)]
    }

    /// The growth ratios and the wall orthogonality of the cell pass (blocks in grid order:
    /// interfaces paired within a chunk and across chunks) equal those of the separate passes
    /// over the connectivity records and the layout, on real meshes of both modes; without a
    /// connectivity, or with one of another mesh, there are no growth ratios.
    #[test]
    fn side_figures_of_the_cell_pass_equal_the_separate_passes() {
        let domain = crate::layouts::bubbles(40, 3).expect("layout");
        let other = crate::mesh(
            &crate::Domain::hexagon_example(),
            &crate::Options::default(),
        )
        .expect("mesh");
        let other_conn = Connectivity::new(&other.layout, &other.grids).expect("connectivity");
        for opts in [crate::Options::default(), crate::Options::paper()] {
            let m = crate::mesh(&domain, &opts).expect("mesh");
            let conn = Connectivity::new(&m.layout, &m.grids).expect("connectivity");
            let (local, spilled) = sides::Plan::new(&conn, &m.grids).sides();
            assert!(local > 0 && spilled > 0, "{local} {spilled}");
            let mut want = MetricSummary::new(&GROWTH_EDGES, GROWTH_ACCEPTABLE);
            let records = crate::connectivity::connectivity(&m.layout, &m.grids).expect("records");
            sides::growth_ratios(&records, &m.grids, &mut want);
            assert!(want.samples > 0);
            let wall = sides::wall_orthogonality(&m.layout, &m.grids);
            assert!(wall.is_some());
            let (_, got) = measure_all_with(&m.layout, &m.grids, Some(&conn));
            assert_eq!(
                format!("{:?}", got.interface_growth_ratio),
                format!("{want:?}")
            );
            assert_eq!(
                got.max_wall_orthogonality_deviation_deg.map(f64::to_bits),
                wall.map(f64::to_bits)
            );
            let none = MetricSummary::new(&GROWTH_EDGES, GROWTH_ACCEPTABLE);
            for c in [None, Some(&other_conn)] {
                let (_, got) = measure_all_with(&m.layout, &m.grids, c);
                assert_eq!(
                    format!("{:?}", got.interface_growth_ratio),
                    format!("{none:?}")
                );
            }
        }
    }

    /// [`has_corner_below`] cell by cell with the reference products (its former body).
    fn corner_below_by_cells(grid: &BlockGrid, deg: f64) -> bool {
        let t = deg.to_radians().tan();
        (0..grid.nj).any(|j| {
            (0..grid.ni).any(|i| {
                let (crosses, dots) = kernel::corner_products(&corners(grid, i, j));
                crosses.into_iter().zip(dots).any(|(cross, dot)| {
                    cross.is_nan() || cross <= 0.0 || (dot > 0.0 && cross < t * dot)
                })
            })
        })
    }

    fn coord() -> impl Strategy<Value = f64> {
        prop_oneof![
            8 => -3.0..3.0f64,
            2 => (-2i32..3).prop_map(f64::from),
            1 => prop_oneof![Just(0.0), Just(-0.0), Just(f64::NAN), Just(f64::INFINITY)],
        ]
    }

    proptest! {
        /// The row pass of [`has_corner_below`] decides as the cell-by-cell test, on blocks of
        /// random, degenerate (repeated, collinear, signed-zero) and non-finite nodes.
        #[test]
        fn corner_below_rows_equal_cells(
            ni in 1usize..5,
            nj in 1usize..4,
            deg in prop_oneof![Just(5.0), Just(30.0), Just(45.0), 1.0..89.0f64],
            v in proptest::collection::vec(coord(), 60),
        ) {
            let nodes = (0..(ni + 1) * (nj + 1)).map(|k| [v[2 * k], v[2 * k + 1]]).collect();
            let g = BlockGrid { ni, nj, nodes };
            prop_assert_eq!(has_corner_below(&g, deg), corner_below_by_cells(&g, deg));
        }

        /// A block with an inverted cell (as [`inverted_blocks`] finds them) has a corner below
        /// any angle in `(0, 90)` ([`has_corner_below`]): periodic exact mode's strict check
        /// takes the second for both.
        #[test]
        fn inverted_cells_have_a_corner_below_any_angle(
            ni in 1usize..5,
            nj in 1usize..4,
            deg in prop_oneof![Just(1e-9), Just(5.0), 1e-6..89.9f64],
            v in proptest::collection::vec(coord(), 60),
        ) {
            let nodes = (0..(ni + 1) * (nj + 1)).map(|k| [v[2 * k], v[2 * k + 1]]).collect();
            let g = BlockGrid { ni, nj, nodes };
            let inverted = inverted_blocks(std::slice::from_ref(&g)) == [0];
            prop_assert_eq!(inverted, grid_inverted_cells(&g) > 0);
            if inverted {
                prop_assert!(has_corner_below(&g, deg));
            }
        }

        /// Any split of the values into chunks reduced with `max_nan` in any grouping gives
        /// the sequential fold's result, bit for bit (NaN when any value is NaN).
        #[test]
        fn max_nan_reduction_equals_the_sequential_fold(
            values in proptest::collection::vec(value(), 0..40),
            cut in 0usize..40,
        ) {
            let cut = cut.min(values.len());
            let (a, b) = values.split_at(cut);
            let parts = sides::max_nan(fold_sequential(b), fold_sequential(a));
            let want = fold_sequential(&values);
            prop_assert_eq!(parts.map(f64::to_bits), want.map(f64::to_bits));
        }
    }
}
