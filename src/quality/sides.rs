//! Per-side figures of the report: the growth ratio across block interfaces and the wall
//! orthogonality. The reference passes (`growth_ratios`, `wall_orthogonality`, kept for the
//! tests) read each block side again after the cell pass (the partner block's grid is then far
//! from the cache); the cell pass of [`super::block_stats`] instead takes each block's
//! side-cell heights and wall deviations while its nodes are in L1 ([`Sides`]), and pairs the
//! heights of an interface afterwards: within a chunk of blocks at the chunk's end, across
//! chunks from a buffer ([`Plan`]). Growth ratio counts and extremes and the `max_nan` fold do
//! not depend on the order, so both give the same figures.

use super::{angle_deg, corners, len, ratio, well_formed, MetricSummary, CHUNK};
#[cfg(test)]
use crate::connectivity::BlockConnectivity;
use crate::connectivity::Connectivity;
use crate::geometry::Point;
use crate::layout::{BlockLayout, Curve, EdgeKind};
use crate::mesh::BlockGrid;
use rayon::prelude::*;
/// Side `s` of `grid`: for position `p` along the side (in the side's direction, see
/// [`crate::layout`]), the node on the side and its neighbour one step into the block.
fn side_node_and_inward(grid: &BlockGrid, s: usize, p: usize) -> (Point, Point) {
    let (ni, nj) = (grid.ni, grid.nj);
    match s {
        0 => (grid.node(p, 0), grid.node(p, 1)),
        1 => (grid.node(ni, p), grid.node(ni - 1, p)),
        2 => (grid.node(ni - p, nj), grid.node(ni - p, nj - 1)),
        _ => (grid.node(0, nj - p), grid.node(1, nj - p)),
    }
}

/// The cell next to side `s` at cell position `p` along the side (in the side's direction):
/// its height normal to the side (area over its edge length on the side). Inlined into the
/// loops over a side, so that the choice of side is made once per side.
#[inline(always)]
fn side_cell_height(grid: &BlockGrid, s: usize, p: usize) -> f64 {
    let (ni, nj) = (grid.ni, grid.nj);
    let (i, j) = match s {
        0 => (p, 0),
        1 => (ni - 1, p),
        2 => (ni - 1 - p, nj - 1),
        _ => (0, nj - 1 - p),
    };
    let q = corners(grid, i, j);
    let area = 0.5
        * ((q[2][0] - q[0][0]) * (q[3][1] - q[1][1]) - (q[2][1] - q[0][1]) * (q[3][0] - q[1][0]));
    // The cell's edge on side `s` runs from corner `s` to corner `s + 1` (in the side's
    // direction): the nodes `side_node_and_inward(grid, s, p)` and `(.., p + 1)`.
    let k = s.min(3);
    let l = len(q[k], q[(k + 1) % 4]);
    if l > 0.0 {
        area.abs() / l
    } else {
        f64::NAN
    }
}

/// The growth ratios across every interface of `conn` (each interface once), counted into
/// `m`. Blocks are visited in parallel in fixed chunks of [`CHUNK`]; counts and extremes do
/// not depend on the order (a ratio is at least 1 or infinite: never NaN nor a zero whose
/// sign a fold could pick), so the result is that of a sequential visit. The reference of the
/// fused pass ([`Plan`], [`Sides`]), kept for the tests.
#[cfg(test)]
pub(super) fn growth_ratios(
    conn: &[BlockConnectivity],
    grids: &[BlockGrid],
    m: &mut MetricSummary,
) {
    let empty = MetricSummary::new(&m.histogram.edges, m.acceptable);
    let parts: Vec<MetricSummary> = conn
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut part = empty.clone();
            for bc in chunk {
                block_growth_ratios(bc, grids, &mut part);
            }
            part
        })
        .collect();
    for part in &parts {
        m.merge(part);
    }
}

/// The growth ratios across the interfaces of one block that it owns (each interface is
/// owned by the side with the smaller (block, side)).
#[cfg(test)]
fn block_growth_ratios(
    bc: &crate::connectivity::BlockConnectivity,
    grids: &[BlockGrid],
    m: &mut MetricSummary,
) {
    for sc in &bc.sides {
        let Some(partner) = sc.partner else { continue };
        if (partner.block, partner.side) < (bc.block, sc.side) {
            continue;
        }
        let (Some(ga), Some(gb)) = (grids.get(bc.block), grids.get(partner.block)) else {
            continue;
        };
        if !well_formed(ga) || !well_formed(gb) {
            continue;
        }
        let n = if sc.side % 2 == 0 { ga.ni } else { ga.nj };
        let nb = if partner.side % 2 == 0 { gb.ni } else { gb.nj };
        if n != nb || n == 0 || ga.ni == 0 || ga.nj == 0 || gb.ni == 0 || gb.nj == 0 {
            continue;
        }
        for p in 0..n {
            let q = if partner.same_direction { p } else { n - 1 - p };
            let ha = side_cell_height(ga, sc.side, p);
            let hb = side_cell_height(gb, partner.side, q);
            m.add(ratio(ha.max(hb), ha.min(hb)));
        }
    }
}

/// NaN-propagating maximum: NaN once either is NaN, else the larger. Associative and
/// commutative, so a parallel reduction equals the sequential fold.
pub(super) fn max_nan(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (None, x) | (x, None) => x,
        (Some(x), Some(y)) if x.is_nan() || y.is_nan() => Some(f64::NAN),
        (Some(x), Some(y)) => Some(x.max(y)),
    }
}

/// Largest deviation (degrees) from the wall normal of the grid lines leaving wall nodes
/// (blocks in parallel, reduced with [`max_nan`]: the same for every thread count).
#[cfg(test)]
pub(super) fn wall_orthogonality(layout: &BlockLayout, grids: &[BlockGrid]) -> Option<f64> {
    layout
        .blocks
        .par_iter()
        .zip(grids.par_iter())
        .map(|(block, grid)| block_wall_orthogonality(layout, block, grid))
        .reduce(|| None, max_nan)
}

/// Ask for the layout edges of `block`'s sides to be brought into the cache (read by
/// [`block_wall_orthogonality`] after the block's cells: a miss per side otherwise, the edges
/// being far apart in memory). A hint only: no effect on any result.
#[inline(always)]
pub(super) fn prefetch_edges(layout: &BlockLayout, block: &crate::layout::Block) {
    for side in &block.sides {
        crate::prefetch::read(layout.edges.as_ptr().wrapping_add(side.edge as usize));
    }
}

/// `wall_orthogonality` (the tests' reference) of one block.
pub(super) fn block_wall_orthogonality(
    layout: &BlockLayout,
    block: &crate::layout::Block,
    grid: &BlockGrid,
) -> Option<f64> {
    if !well_formed(grid) || grid.ni == 0 || grid.nj == 0 {
        return None;
    }
    let mut worst: Option<f64> = None;
    for (s, side) in block.sides.iter().enumerate() {
        let Some(edge) = layout.edges.get(side.edge as usize) else {
            continue;
        };
        let (EdgeKind::Wall(id), Curve::Arc { center, .. }) = (edge.kind, &edge.curve) else {
            continue;
        };
        let n = if s % 2 == 0 { grid.ni } else { grid.nj };
        for p in 0..=n {
            let (w, inner) = side_node_and_inward(grid, s, p);
            // Into the fluid: away from a hole's center, towards the bounding circle's.
            let normal = if id < 0 {
                [center[0] - w[0], center[1] - w[1]]
            } else {
                [w[0] - center[0], w[1] - center[1]]
            };
            let d = [inner[0] - w[0], inner[1] - w[1]];
            let cross = normal[0] * d[1] - normal[1] * d[0];
            let dot = normal[0] * d[0] + normal[1] * d[1];
            worst = max_nan(worst, Some(angle_deg(cross.abs(), dot)));
        }
    }
    worst
}

/// The number of cells along the interface from side `sa` of block `a` to side `sb` of block
/// `b` when the tests' reference `block_growth_ratios` measures it (both grids present and
/// well formed, the same non-zero count on both sides, no empty grid), else `None`.
fn interface_cells(grids: &[BlockGrid], a: usize, sa: usize, b: usize, sb: usize) -> Option<usize> {
    let (ga, gb) = (grids.get(a)?, grids.get(b)?);
    if sa >= 4 || sb >= 4 || !well_formed(ga) || !well_formed(gb) {
        return None;
    }
    let n = if sa.is_multiple_of(2) { ga.ni } else { ga.nj };
    let nb = if sb.is_multiple_of(2) { gb.ni } else { gb.nj };
    let empty = ga.ni == 0 || ga.nj == 0 || gb.ni == 0 || gb.nj == 0;
    (n == nb && n != 0 && !empty).then_some(n)
}

/// Bit of [`Plan::need`]: the side's heights are paired within its chunk.
const LOCAL: u8 = 1;
/// Bit of [`Plan::need`]: the side's heights are paired with a side of another chunk.
const SPILL: u8 = 2;

/// Which block sides the fused pass measures for the growth ratios, for the connectivity of
/// the grids: every interface the tests' reference `block_growth_ratios` measures (owned by
/// its smaller (block, side)), its two sides in the same chunk of [`CHUNK`] blocks or not.
pub(super) struct Plan<'a> {
    conn: &'a Connectivity<'a>,
    grids: &'a [BlockGrid],
    /// Per block side (`4 b + s`): [`LOCAL`] and [`SPILL`] bits.
    need: Vec<u8>,
    /// Per block side with [`SPILL`]: the offset of its heights in the spill buffer, in
    /// (block, side) order.
    spill_at: Vec<usize>,
    /// Per chunk: the spill offset of its first block (and the total at the end).
    chunk_spill: Vec<usize>,
}

/// The interfaces of blocks `blocks` that their side `(b, s)` owns (the smaller (block, side)
/// of the two): `(b, s, partner)`, in block then side order.
fn owned<'c>(
    conn: &'c Connectivity<'_>,
    blocks: std::ops::Range<usize>,
) -> impl Iterator<Item = (usize, usize, crate::connectivity::Partner)> + 'c {
    blocks
        .flat_map(|b| (0..4).map(move |s| (b, s)))
        .filter_map(|(b, s)| {
            let p = conn.partner(b, s)?;
            ((p.block, p.side) >= (b, s)).then_some((b, s, p))
        })
}

impl<'a> Plan<'a> {
    /// `conn` must be the connectivity of `grids` (one block per grid).
    pub fn new(conn: &'a Connectivity<'a>, grids: &'a [BlockGrid]) -> Plan<'a> {
        let mut need = vec![0u8; 4 * conn.len()];
        for (b, s, p) in owned(conn, 0..conn.len()) {
            if interface_cells(grids, b, s, p.block, p.side).is_none() {
                continue;
            }
            let bit = if b / CHUNK == p.block / CHUNK {
                LOCAL
            } else {
                SPILL
            };
            need[4 * b + s] |= bit;
            need[4 * p.block + p.side] |= bit;
        }
        let mut spill_at = vec![usize::MAX; need.len()];
        let mut chunk_spill = Vec::with_capacity(conn.len() / CHUNK + 2);
        let mut total = 0;
        for (k, &bits) in need.iter().enumerate() {
            if k % (4 * CHUNK) == 0 {
                chunk_spill.push(total);
            }
            if bits & SPILL != 0 {
                spill_at[k] = total;
                total += side_cells(&grids[k / 4], k % 4);
            }
        }
        chunk_spill.push(total);
        Plan {
            conn,
            grids,
            need,
            spill_at,
            chunk_spill,
        }
    }

    /// The blocks of chunk `c`.
    fn chunk(&self, c: usize) -> std::ops::Range<usize> {
        let n = self.conn.len();
        (c * CHUNK).min(n)..((c + 1) * CHUNK).min(n)
    }

    /// Sides paired within their chunk, and sides paired across chunks.
    #[cfg(test)]
    pub fn sides(&self) -> (usize, usize) {
        let count = |bit| self.need.iter().filter(|&&b| b & bit != 0).count();
        (count(LOCAL), count(SPILL))
    }

    /// The spill buffer (zeros, one entry per height) cut into one slice per chunk.
    pub fn spill_slices<'b>(&self, spill: &'b mut Vec<f64>) -> Vec<&'b mut [f64]> {
        let total = *self.chunk_spill.last().unwrap_or(&0);
        spill.clear();
        spill.resize(total, 0.0);
        let mut rest = &mut spill[..];
        let mut out = Vec::with_capacity(self.chunk_spill.len());
        for w in self.chunk_spill.windows(2) {
            let (head, tail) = rest.split_at_mut(w[1] - w[0]);
            out.push(head);
            rest = tail;
        }
        out
    }

    /// The growth ratios of the interfaces between chunks, from the heights the cell pass
    /// left in `spill` (chunks of owners in parallel, merged into `m`).
    pub fn pair_spilled(&self, spill: &[f64], m: &mut MetricSummary) {
        let empty = MetricSummary::new(&m.histogram.edges, m.acceptable);
        let parts: Vec<MetricSummary> = (0..self.conn.len().div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut part = empty.clone();
                for (b, s, p) in owned(self.conn, self.chunk(c)) {
                    if b / CHUNK == p.block / CHUNK {
                        continue;
                    }
                    let Some(n) = interface_cells(self.grids, b, s, p.block, p.side) else {
                        continue;
                    };
                    let (ha, hb) = (
                        self.spill_at[4 * b + s],
                        self.spill_at[4 * p.block + p.side],
                    );
                    pair(
                        &spill[ha..ha + n],
                        &spill[hb..hb + n],
                        p.same_direction,
                        &mut part,
                    );
                }
                part
            })
            .collect();
        for part in &parts {
            m.merge(part);
        }
    }
}

/// Cells along side `s` of `grid`.
fn side_cells(grid: &BlockGrid, s: usize) -> usize {
    if s.is_multiple_of(2) {
        grid.ni
    } else {
        grid.nj
    }
}

/// The growth ratios of one interface from the heights of its owner side `ha` and of the
/// partner side `hb` (same length), with the expression of the tests' reference
/// `block_growth_ratios`, counted as `MetricSummary::add` does: a ratio is at least 1 or
/// infinite, never NaN, so its bin is the number of inner edges at or below it (the rule of
/// [`super::Histogram::add`] for increasing edges), counted without a search.
#[inline]
fn pair(ha: &[f64], hb: &[f64], same_direction: bool, m: &mut MetricSummary) {
    let n = ha.len();
    // Always the growth histogram: its edges as a constant, so that the count unrolls.
    debug_assert_eq!(m.histogram.edges, super::GROWTH_EDGES);
    let edges = &super::GROWTH_EDGES[1..];
    let last = m.histogram.counts.len() - 1;
    let (lo, hi) = (m.acceptable[0], m.acceptable[1]);
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    for (p, &x) in ha.iter().enumerate() {
        let y = hb[if same_direction { p } else { n - 1 - p }];
        let r = ratio(x.max(y), x.min(y));
        debug_assert!(!r.is_nan());
        let bin = edges.iter().map(|&e| usize::from(e <= r)).sum::<usize>();
        m.histogram.counts[bin.min(last)] += 1;
        m.outside += u64::from(!(r >= lo && r <= hi));
        if r.is_finite() {
            min = min.min(r);
            max = max.max(r);
        }
    }
    m.samples += n as u64;
    // Not NaN, and no zero: folding the extremes here rather than value by value is the same.
    if min.is_finite() {
        m.min = Some(m.min.map_or(min, |v| v.min(min)));
        m.max = Some(m.max.map_or(max, |v| v.max(max)));
    }
}

/// Scratch of the fused pass for one chunk: the heights of the sides paired within the chunk.
#[derive(Default)]
pub(super) struct Sides {
    heights: Vec<f64>,
    /// Per block side of the chunk (`4 k + s`): the offset of its heights in `heights`.
    at: Vec<usize>,
}

impl Sides {
    /// Forget the previous chunk.
    pub fn start(&mut self) {
        self.heights.clear();
        self.at.clear();
        self.at.resize(4 * CHUNK, usize::MAX);
    }

    /// The side-cell heights of block `b` (the `k`-th of chunk `c`, grid `g`) that `plan`
    /// needs: into the chunk's own list, and into the chunk's slice `spill` of the spill
    /// buffer.
    pub fn block(&mut self, plan: &Plan, c: usize, k: usize, g: &BlockGrid, spill: &mut [f64]) {
        let b = c * CHUNK + k;
        for s in 0..4 {
            let bits = plan.need[4 * b + s];
            if bits == 0 {
                continue;
            }
            let n = side_cells(g, s);
            if bits & LOCAL != 0 {
                self.at[4 * k + s] = self.heights.len();
                self.heights
                    .extend((0..n).map(|p| side_cell_height(g, s, p)));
                if bits & SPILL != 0 {
                    let from = self.at[4 * k + s];
                    let to = plan.spill_at[4 * b + s] - plan.chunk_spill[c];
                    spill[to..to + n].copy_from_slice(&self.heights[from..from + n]);
                }
            } else {
                let to = plan.spill_at[4 * b + s] - plan.chunk_spill[c];
                for (p, h) in spill[to..to + n].iter_mut().enumerate() {
                    *h = side_cell_height(g, s, p);
                }
            }
        }
    }

    /// The growth ratios of the interfaces within chunk `c` (after every block of it).
    pub fn pair_local(&self, plan: &Plan, c: usize, m: &mut MetricSummary) {
        let first = c * CHUNK;
        for (b, s, p) in owned(plan.conn, plan.chunk(c)) {
            if b / CHUNK != p.block / CHUNK {
                continue;
            }
            let Some(n) = interface_cells(plan.grids, b, s, p.block, p.side) else {
                continue;
            };
            let ha = self.at[4 * (b - first) + s];
            let hb = self.at[4 * (p.block - first) + p.side];
            pair(
                &self.heights[ha..ha + n],
                &self.heights[hb..hb + n],
                p.same_direction,
                m,
            );
        }
    }
}
