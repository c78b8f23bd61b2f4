//! Per-side figures of the report: the growth ratio across block interfaces and the wall
//! orthogonality. The reference passes (`growth_ratios`, `wall_orthogonality`, kept for the
//! tests) read each block side again after the cell pass (the partner block's grid is then far
//! from the cache); the cell pass of [`super::block_stats`] instead takes each block's
//! side-cell heights and wall deviations while its nodes are in L1 ([`Sides`]), and pairs the
//! heights of an interface afterwards: within a chunk of blocks at the chunk's end, across
//! chunks from a buffer ([`Plan`]). Growth ratio counts and extremes and the `max_nan` fold do
//! not depend on the order, so both give the same figures.

use super::{angle_deg, corners, len, well_formed, MetricSummary, CHUNK};
#[cfg(test)]
use crate::connectivity::BlockConnectivity;
use crate::connectivity::Connectivity;
use crate::geometry::Point;
use crate::lanes::Lanes;
use crate::layout::{BlockLayout, Curve, EdgeKind};
use crate::mesh::BlockGrid;
use rayon::prelude::*;
/// Side `s` of `grid`: for position `p` along the side (in the side's direction, see
/// [`crate::layout`]), the node on the side and its neighbour one step into the block (the
/// tests' reference of [`side_lines`]).
#[cfg(test)]
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
pub(super) fn side_cell_height(grid: &BlockGrid, s: usize, p: usize) -> f64 {
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

/// The nodes of side `s` of `grid` in the side's direction and their neighbours one step into
/// the block: `side_node_and_inward(grid, s, p)` for every `p` in `0..=n` (`n` the side's cell
/// count), as two lines `(a, b)`. Side 0's lines are the grid's first two node rows (no copy);
/// the others are copied into `scratch`. Requires a well-formed grid with `ni, nj >= 1`.
fn side_lines<'g>(
    grid: &'g BlockGrid,
    s: usize,
    scratch: &'g mut (Vec<Point>, Vec<Point>),
) -> (&'g [Point], &'g [Point]) {
    let w = grid.ni + 1;
    if s == 0 {
        return (&grid.nodes[..w], &grid.nodes[w..2 * w]);
    }
    let (ni, nj, nodes) = (grid.ni, grid.nj, &grid.nodes[..]);
    let (a, b) = scratch;
    a.clear();
    b.clear();
    // The nodes `side_node_and_inward` reads, by index: a column (sides 1 and 3, stride `w`)
    // or the top rows reversed (side 2).
    match s {
        1 => {
            a.extend((0..=nj).map(|p| nodes[ni + p * w]));
            b.extend((0..=nj).map(|p| nodes[ni - 1 + p * w]));
        }
        2 => {
            a.extend(nodes[nj * w..(nj + 1) * w].iter().rev());
            b.extend(nodes[(nj - 1) * w..nj * w].iter().rev());
        }
        _ => {
            a.extend((0..=nj).map(|p| nodes[(nj - p) * w]));
            b.extend((0..=nj).map(|p| nodes[1 + (nj - p) * w]));
        }
    }
    (&a[..], &b[..])
}

/// The corners `[q0, q1, q2, q3]` (counter-clockwise, as [`corners`]) of the cell at position
/// `p` along side `S`, from its side nodes `a0 = a[p]`, `a1 = a[p + 1]` and their inward
/// neighbours `b0 = b[p]`, `b1 = b[p + 1]` (see [`side_lines`]): the side runs from corner `S`
/// to corner `S + 1`, so `q[S] = a0`, `q[S + 1] = a1`, `q[S + 2] = b1`, `q[S + 3] = b0`.
#[inline(always)]
fn side_corners<const S: usize>(a0: Point, a1: Point, b1: Point, b0: Point) -> [Point; 4] {
    let mut q = [[0.0; 2]; 4];
    q[S % 4] = a0;
    q[(S + 1) % 4] = a1;
    q[(S + 2) % 4] = b1;
    q[(S + 3) % 4] = b0;
    q
}

/// [`side_cell_height`] of every cell of side `S` into `out` (`n` cells, `a` and `b` the lines
/// of [`side_lines`], `n + 1` nodes each), with the same expressions in a loop the compiler
/// vectorises: the area, then the side edge's length as `sqrt(x² + y²)`. False when some
/// squared length is outside the range where [`crate::geometry::length`] takes that formula
/// (or not a number): the caller then takes the reference for the side.
#[inline(always)]
fn heights_into<const S: usize>(a: &[Point], b: &[Point], out: &mut [f64]) -> bool {
    let n = out.len();
    let (a, b) = (&a[..=n], &b[..=n]);
    let mut fine = true;
    for p in 0..n {
        let (a0, a1) = (a[p], a[p + 1]);
        let q = side_corners::<S>(a0, a1, b[p + 1], b[p]);
        let area = 0.5
            * ((q[2][0] - q[0][0]) * (q[3][1] - q[1][1])
                - (q[2][1] - q[0][1]) * (q[3][0] - q[1][0]));
        let (dx, dy) = (a1[0] - a0[0], a1[1] - a0[1]);
        let sq = dx * dx + dy * dy;
        fine &= (super::kernel::SQ_MIN..=super::kernel::SQ_MAX).contains(&sq);
        let l = sq.sqrt();
        out[p] = if l > 0.0 { area.abs() / l } else { f64::NAN };
    }
    fine
}

/// [`heights_into`] for side `s` (0..4).
#[inline(always)]
fn heights_any(s: usize, a: &[Point], b: &[Point], out: &mut [f64]) -> bool {
    match s {
        0 => heights_into::<0>(a, b, out),
        1 => heights_into::<1>(a, b, out),
        2 => heights_into::<2>(a, b, out),
        _ => heights_into::<3>(a, b, out),
    }
}

/// [`heights_any`] compiled for AVX-512 (the same IEEE operations, no fused multiply-add).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
fn heights_avx512(s: usize, a: &[Point], b: &[Point], out: &mut [f64]) -> bool {
    heights_any(s, a, b, out)
}

/// [`heights_any`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn heights_avx2(s: usize, a: &[Point], b: &[Point], out: &mut [f64]) -> bool {
    heights_any(s, a, b, out)
}

/// [`side_cell_height`] of the `out.len()` cells of side `s` of `grid` (well formed, `ni, nj
/// >= 1`, `out.len()` the side's cell count), bit for bit, in the build `lanes`.
pub(super) fn side_heights(
    grid: &BlockGrid,
    s: usize,
    out: &mut [f64],
    scratch: &mut (Vec<Point>, Vec<Point>),
    lanes: Lanes,
) {
    let (a, b) = side_lines(grid, s, scratch);
    let fine = match lanes {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `lanes` is only `Avx512` when the CPU has these features (`Lanes::available`).
        Lanes::Avx512 => unsafe { heights_avx512(s, a, b, out) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, for AVX2.
        Lanes::Avx2 => unsafe { heights_avx2(s, a, b, out) },
        _ => heights_any(s, a, b, out),
    };
    if !fine {
        for (p, h) in out.iter_mut().enumerate() {
            *h = side_cell_height(grid, s, p);
        }
    }
}

/// The angle (degrees, in `[0, 180]`) between the grid line from wall node `w` to its inward
/// neighbour `inner` and the wall circle's normal into the fluid at `w`: away from the centre
/// of a hole, towards the centre of the bounding circle (`bounding`).
#[inline(always)]
fn wall_deviation(w: Point, inner: Point, center: Point, bounding: bool) -> f64 {
    let normal = if bounding {
        [center[0] - w[0], center[1] - w[1]]
    } else {
        [w[0] - center[0], w[1] - center[1]]
    };
    let d = [inner[0] - w[0], inner[1] - w[1]];
    let cross = normal[0] * d[1] - normal[1] * d[0];
    let dot = normal[0] * d[0] + normal[1] * d[1];
    angle_deg(cross.abs(), dot)
}

/// [`wall_deviation`] of the nodes `a` of a wall side and their inward neighbours `b` (same
/// length as `out`), in a loop the compiler vectorises.
#[inline(always)]
fn wall_into(a: &[Point], b: &[Point], center: Point, bounding: bool, out: &mut [f64]) {
    let n = out.len();
    let (a, b) = (&a[..n], &b[..n]);
    for p in 0..n {
        out[p] = wall_deviation(a[p], b[p], center, bounding);
    }
}

/// [`wall_into`] compiled for AVX-512.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
fn wall_avx512(a: &[Point], b: &[Point], center: Point, bounding: bool, out: &mut [f64]) {
    wall_into(a, b, center, bounding, out)
}

/// [`wall_into`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn wall_avx2(a: &[Point], b: &[Point], center: Point, bounding: bool, out: &mut [f64]) {
    wall_into(a, b, center, bounding, out)
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
            m.add(super::ratio(ha.max(hb), ha.min(hb)));
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
/// [`Sides::wall`] after the block's cells: a miss per side otherwise, the edges
/// being far apart in memory). A hint only: no effect on any result.
#[inline(always)]
pub(super) fn prefetch_edges(layout: &BlockLayout, block: &crate::layout::Block) {
    for side in &block.sides {
        crate::prefetch::read(layout.edges.as_ptr().wrapping_add(side.edge as usize));
    }
}

/// The sides of `block` on a wall arc: `(side, the circle's centre, whether the circle is
/// the bounding circle)` (whose normal into the fluid points to its centre).
pub(super) fn wall_arcs<'l>(
    layout: &'l BlockLayout,
    block: &'l crate::layout::Block,
) -> impl Iterator<Item = (usize, Point, bool)> + 'l {
    block.sides.iter().enumerate().filter_map(|(s, side)| {
        let edge = layout.edges.get(side.edge as usize)?;
        match (edge.kind, &edge.curve) {
            (EdgeKind::Wall(id), Curve::Arc { center, .. }) => Some((s, *center, id < 0)),
            _ => None,
        }
    })
}

/// `wall_orthogonality` (the tests' reference) of one block.
#[cfg(test)]
pub(super) fn block_wall_orthogonality(
    layout: &BlockLayout,
    block: &crate::layout::Block,
    grid: &BlockGrid,
) -> Option<f64> {
    if !well_formed(grid) || grid.ni == 0 || grid.nj == 0 {
        return None;
    }
    let mut worst: Option<f64> = None;
    for (s, center, bounding) in wall_arcs(layout, block) {
        let n = if s % 2 == 0 { grid.ni } else { grid.nj };
        for p in 0..=n {
            let (w, inner) = side_node_and_inward(grid, s, p);
            worst = max_nan(worst, Some(wall_deviation(w, inner, center, bounding)));
        }
    }
    worst
}

/// The largest deviation (degrees) from the wall normal of the grid lines leaving the wall
/// nodes of `block` ([`wall_deviation`]): the tests' reference `block_wall_orthogonality`
/// (node by node, scalar) bit for bit, with the deviations of each wall side computed in the
/// build `lanes` ([`wall_into`]) and folded in the same order.
fn block_wall_orthogonality_with(
    layout: &BlockLayout,
    block: &crate::layout::Block,
    grid: &BlockGrid,
    scratch: &mut (Vec<Point>, Vec<Point>),
    out: &mut Vec<f64>,
    lanes: Lanes,
) -> Option<f64> {
    walls_orthogonality(grid, wall_arcs(layout, block), scratch, out, lanes)
}

/// [`block_wall_orthogonality_with`] of the wall sides `walls` (`(side, the circle's centre,
/// whether it is the bounding circle)`, in side order) of `grid`: the measurement of a block
/// whose layout is not built yet ([`super::measured`]).
pub(super) fn walls_orthogonality(
    grid: &BlockGrid,
    walls: impl Iterator<Item = (usize, Point, bool)>,
    scratch: &mut (Vec<Point>, Vec<Point>),
    out: &mut Vec<f64>,
    lanes: Lanes,
) -> Option<f64> {
    if !well_formed(grid) || grid.ni == 0 || grid.nj == 0 {
        return None;
    }
    let mut worst: Option<f64> = None;
    for (s, center, bounding) in walls {
        let (a, b) = side_lines(grid, s, scratch);
        out.clear();
        out.resize(a.len(), 0.0);
        match lanes {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `lanes` is only `Avx512` when the CPU has these features.
            Lanes::Avx512 => unsafe { wall_avx512(a, b, center, bounding, out) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above, for AVX2.
            Lanes::Avx2 => unsafe { wall_avx2(a, b, center, bounding, out) },
            _ => wall_into(a, b, center, bounding, out),
        }
        for &x in out.iter() {
            worst = max_nan(worst, Some(x));
        }
    }
    worst
}

/// The number of cells along the interface from side `sa` of block `a` to side `sb` of block
/// `b` when the tests' reference `block_growth_ratios` measures it (both grids present and
/// well formed, the same non-zero count on both sides, no empty grid), else `None`.
fn interface_cells(grids: &[BlockGrid], a: usize, sa: usize, b: usize, sb: usize) -> Option<usize> {
    let (ga, gb) = (grids.get(a)?, grids.get(b)?);
    if !well_formed(ga) || !well_formed(gb) {
        return None;
    }
    interface_dims(ga, sa, gb, sb)
}

/// [`interface_cells`] of two grids known to be well formed (measured as they were made, their
/// nodes since dropped: [`super::measured`]), from their dimensions alone.
fn interface_dims(ga: &BlockGrid, sa: usize, gb: &BlockGrid, sb: usize) -> Option<usize> {
    if sa >= 4 || sb >= 4 {
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

/// The growth ratios of every interface of `conn` (the connectivity of `grids`, whose nodes
/// were measured as they were made and dropped) from the side-cell heights `heights(block,
/// side)` ([`super::measured`]): the interfaces the fused pass pairs, with the same
/// expression; chunks of owners in parallel, merged (counts and extremes: in any order the
/// same figures).
///
/// A partner's heights are anywhere in memory (at 1e5 particles 230 MB of them: a cache and
/// TLB miss or more per interface, issue 8), so the loop looks ahead in its chunk's list of
/// interfaces: `ahead(block)` (a hint only: no effect on any result) asks for what the
/// lookup of the partner [`AHEAD`] interfaces on reads first, and the partner's heights are
/// asked for half as far ahead.
pub(super) fn pair_measured<'h>(
    conn: &Connectivity,
    grids: &[BlockGrid],
    heights: &(dyn Fn(usize, usize) -> &'h [f64] + Sync),
    ahead: &(dyn Fn(usize) + Sync),
) -> MetricSummary {
    let empty = MetricSummary::new(&super::GROWTH_EDGES, super::GROWTH_ACCEPTABLE);
    let n = conn.len();
    let parts: Vec<MetricSummary> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map_init(Vec::new, |list, c| {
            let mut part = empty.clone();
            list.clear();
            list.extend(owned(conn, c * CHUNK..((c + 1) * CHUNK).min(n)));
            for (i, &(b, s, p)) in list.iter().enumerate() {
                if let Some(q) = list.get(i + AHEAD) {
                    ahead(q.2.block);
                }
                if let Some(q) = list.get(i + AHEAD / 2) {
                    for x in heights(q.2.block, q.2.side).iter().step_by(8) {
                        crate::prefetch::read(x);
                    }
                }
                let (Some(ga), Some(gb)) = (grids.get(b), grids.get(p.block)) else {
                    continue;
                };
                let Some(cells) = interface_dims(ga, s, gb, p.side) else {
                    continue;
                };
                let (ha, hb) = (heights(b, s), heights(p.block, p.side));
                if ha.len() == cells && hb.len() == cells {
                    pair(ha, hb, p.same_direction, &mut part);
                }
            }
            part
        })
        .collect();
    let mut m = empty;
    for part in &parts {
        m.merge(part);
    }
    m
}

/// How many interfaces ahead [`pair_measured`] asks for a partner's place.
const AHEAD: usize = 16;

/// Cells along side `s` of `grid`.
pub(super) fn side_cells(grid: &BlockGrid, s: usize) -> usize {
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
/// [`super::Histogram::add`] for increasing edges, the last bin taking the rest).
///
/// Counted without a scatter: for each inner edge `e_k` below the last bin, how many ratios
/// are at or above it (`ge[k]`); the edges increase, so a ratio's bin is `j` exactly when it
/// is at or above `e_(j-1)` and below `e_j`, and bin `j` counts `ge[j - 1] - ge[j]`. The loop
/// then has no store to memory and no branch: the same counts, outside count and extremes as
/// a ratio-by-ratio count (test `pair_counts_as_the_reference_does`), several times faster
/// (issue 8: the increments of consecutive ratios, which mostly fall in one bin, chained
/// through memory).
#[inline]
pub(super) fn pair(ha: &[f64], hb: &[f64], same_direction: bool, m: &mut MetricSummary) {
    if same_direction {
        pair_in::<true>(ha, hb, m)
    } else {
        pair_in::<false>(ha, hb, m)
    }
}

/// Bins of the growth histogram ([`super::Histogram::new`] of its edges).
const GROWTH_BINS: usize = super::GROWTH_EDGES.len() - 1;

/// [`pair`] for one direction of the partner side.
#[inline(always)]
fn pair_in<const SAME: bool>(ha: &[f64], hb: &[f64], m: &mut MetricSummary) {
    let n = ha.len();
    debug_assert_eq!(hb.len(), n);
    // Always the growth histogram.
    debug_assert_eq!(m.histogram.edges, super::GROWTH_EDGES);
    debug_assert_eq!(m.histogram.counts.len(), GROWTH_BINS);
    let (lo, hi) = (m.acceptable[0], m.acceptable[1]);
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut outside = 0u64;
    let mut ge = [0u64; GROWTH_BINS - 1];
    for p in 0..n {
        let x = ha[p];
        let y = hb[if SAME { p } else { n - 1 - p }];
        let (a, b) = (x.max(y), x.min(y));
        // `super::ratio(a, b)`, as selects.
        let q = a / b;
        let r = if b > 0.0 {
            q
        } else if a > 0.0 {
            f64::INFINITY
        } else {
            1.0
        };
        debug_assert!(!r.is_nan());
        // The inner edges below the last bin (which takes every ratio from its first edge on).
        for (g, &e) in ge.iter_mut().zip(&super::GROWTH_EDGES[1..]) {
            *g += u64::from(e <= r);
        }
        outside += u64::from(!(r >= lo && r <= hi));
        let finite = r.is_finite();
        min = if finite && r < min { r } else { min };
        max = if finite && r > max { r } else { max };
    }
    let counts = &mut m.histogram.counts;
    counts[0] += n as u64 - ge[0];
    for j in 1..GROWTH_BINS - 1 {
        counts[j] += ge[j - 1] - ge[j];
    }
    counts[GROWTH_BINS - 1] += ge[GROWTH_BINS - 2];
    m.outside += outside;
    m.samples += n as u64;
    // Not NaN, and no zero: folding the extremes here rather than value by value is the same.
    if min.is_finite() {
        m.min = Some(m.min.map_or(min, |v| v.min(min)));
        m.max = Some(m.max.map_or(max, |v| v.max(max)));
    }
}

/// Scratch of the fused pass for one chunk: the heights of the sides paired within the chunk.
pub(super) struct Sides {
    heights: Vec<f64>,
    /// Per block side of the chunk (`4 k + s`): the offset of its heights in `heights`.
    at: Vec<usize>,
    /// A side's two node lines ([`side_lines`]) and its wall deviations.
    lines: (Vec<Point>, Vec<Point>),
    wall: Vec<f64>,
    /// The build the side loops run in.
    lanes: Lanes,
}

impl Sides {
    /// Scratch for the side loops, run in the build `lanes` (one the CPU has).
    pub fn new(lanes: Lanes) -> Sides {
        Sides {
            heights: Vec::new(),
            at: Vec::new(),
            lines: (Vec::new(), Vec::new()),
            wall: Vec::new(),
            lanes: if lanes.available() {
                lanes
            } else {
                Lanes::Base
            },
        }
    }

    /// The wall orthogonality of `block` (grid `grid`, see [`block_wall_orthogonality_with`]).
    pub fn wall(
        &mut self,
        layout: &BlockLayout,
        block: &crate::layout::Block,
        grid: &BlockGrid,
    ) -> Option<f64> {
        block_wall_orthogonality_with(
            layout,
            block,
            grid,
            &mut self.lines,
            &mut self.wall,
            self.lanes,
        )
    }
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
                let from = self.heights.len();
                self.at[4 * k + s] = from;
                self.heights.resize(from + n, 0.0);
                side_heights(g, s, &mut self.heights[from..], &mut self.lines, self.lanes);
                if bits & SPILL != 0 {
                    let from = self.at[4 * k + s];
                    let to = plan.spill_at[4 * b + s] - plan.chunk_spill[c];
                    spill[to..to + n].copy_from_slice(&self.heights[from..from + n]);
                }
            } else {
                let to = plan.spill_at[4 * b + s] - plan.chunk_spill[c];
                side_heights(g, s, &mut spill[to..to + n], &mut self.lines, self.lanes);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layouts::SplitMix64;

    /// A random `ni x nj` grid: a sheared, wavy lattice at a random scale, with some nodes
    /// repeated (zero-length edges), some far away (squared lengths outside the fast range),
    /// and some not a number.
    fn grid(r: &mut SplitMix64, ni: usize, nj: usize) -> BlockGrid {
        let scale = [1.0, 1e-150, 1e150, 1e-3, 7.0][(r.next_f64() * 5.0) as usize % 5];
        let mut nodes = Vec::with_capacity((ni + 1) * (nj + 1));
        for j in 0..=nj {
            for i in 0..=ni {
                let (x, y) = (i as f64 + 0.3 * j as f64, j as f64 + 0.2 * (i as f64).sin());
                let jitter = 0.3 * (r.next_f64() - 0.5);
                nodes.push([scale * (x + jitter), scale * (y - jitter)]);
            }
        }
        for _ in 0..(r.next_f64() * 3.0) as usize {
            let k = (r.next_f64() * nodes.len() as f64) as usize % nodes.len();
            let other = (r.next_f64() * nodes.len() as f64) as usize % nodes.len();
            nodes[k] = match (r.next_f64() * 4.0) as u32 {
                0 => nodes[other],
                1 => [1e200, -3e199],
                2 => [f64::NAN, 0.0],
                _ => [nodes[k][0], nodes[(k + 1) % nodes.len()][1]],
            };
        }
        BlockGrid { ni, nj, nodes }
    }

    /// [`pair`] gives the counts, outside count, samples and extremes of counting every
    /// ratio with `MetricSummary::add` (the tests' reference), in both directions, on heights
    /// spread over every bin and beyond: equal ones (ratio 1), ratios on the bins' edges,
    /// zeros (ratio 1 or infinite), and extreme magnitudes; several interfaces into one
    /// summary.
    #[test]
    fn pair_counts_as_the_reference_does() {
        let mut r = SplitMix64(41);
        let edges = &super::super::GROWTH_EDGES;
        let mut seen = vec![0u64; edges.len() - 1];
        for _ in 0..300 {
            let empty = MetricSummary::new(edges, super::super::GROWTH_ACCEPTABLE);
            let (mut got, mut want) = (empty.clone(), empty);
            for _ in 0..1 + r.next_u64() % 4 {
                let n = 1 + (r.next_u64() % 40) as usize;
                let same = r.next_u64().is_multiple_of(2);
                let mut ha = Vec::with_capacity(n);
                let mut hb = Vec::with_capacity(n);
                for _ in 0..n {
                    let x = 10f64.powf(12.0 * r.next_f64() - 6.0);
                    let y = match r.next_u64() % 8 {
                        0 => x,
                        1 => x * edges[(r.next_u64() % edges.len() as u64) as usize],
                        2 => 0.0,
                        3 => x * 10f64.powf(4.0 * r.next_f64()),
                        4 => 10f64.powf(600.0 * r.next_f64() - 300.0),
                        _ => x * (1.0 + 0.6 * r.next_f64()),
                    };
                    let x = if r.next_u64().is_multiple_of(16) {
                        0.0
                    } else {
                        x
                    };
                    let (x, y) = if r.next_u64().is_multiple_of(2) {
                        (x, y)
                    } else {
                        (y, x)
                    };
                    ha.push(x);
                    hb.push(y);
                }
                pair(&ha, &hb, same, &mut got);
                for p in 0..n {
                    let (x, y) = (ha[p], hb[if same { p } else { n - 1 - p }]);
                    want.add(super::super::ratio(x.max(y), x.min(y)));
                }
            }
            assert_eq!(format!("{got:?}"), format!("{want:?}"));
            for (s, c) in seen.iter_mut().zip(&want.histogram.counts) {
                *s += c;
            }
        }
        assert!(seen.iter().all(|&c| c > 20), "{seen:?}");
    }

    /// The side heights of every build the CPU has are [`side_cell_height`]'s bits, on every
    /// side of random, degenerate and extreme grids (the fast range's fallback included).
    #[test]
    fn vectorised_side_heights_equal_the_reference() {
        let mut r = SplitMix64(36);
        let mut scratch = (Vec::new(), Vec::new());
        let mut fallbacks = 0;
        for round in 0..3000 {
            let (ni, nj) = (1 + round % 17, 1 + (round / 17) % 9);
            let g = grid(&mut r, ni, nj);
            for s in 0..4 {
                let want: Vec<u64> = (0..side_cells(&g, s))
                    .map(|p| side_cell_height(&g, s, p).to_bits())
                    .collect();
                for lanes in Lanes::ALL.into_iter().filter(|l| l.available()) {
                    let mut out = vec![0.0; want.len()];
                    side_heights(&g, s, &mut out, &mut scratch, lanes);
                    let got: Vec<u64> = out.iter().map(|h| h.to_bits()).collect();
                    assert_eq!(got, want, "round {round} side {s} {lanes:?}");
                }
                let (a, b) = side_lines(&g, s, &mut scratch);
                let pairs: Vec<_> = (0..=want.len())
                    .map(|p| side_node_and_inward(&g, s, p))
                    .collect();
                let lines: Vec<_> = a.iter().copied().zip(b.iter().copied()).collect();
                assert_eq!(format!("{lines:?}"), format!("{pairs:?}"));
                let mut out = vec![0.0; want.len()];
                fallbacks += usize::from(!heights_any(s, a, b, &mut out));
            }
        }
        // Both paths were taken.
        assert!(fallbacks > 100 && fallbacks < 6000, "{fallbacks}");
    }

    /// The wall orthogonality of every build is the reference's, block by block, on real
    /// meshes (both walls: holes and the bounding circle) whose grids are then moved about.
    #[test]
    fn vectorised_wall_orthogonality_equals_the_reference() {
        let domain = crate::layouts::bubbles(12, 5).expect("layout");
        let m = crate::mesh(&domain, &crate::Options::default()).expect("mesh");
        let mut r = SplitMix64(7);
        let mut grids = m.grids.clone();
        let mut scratch = (Vec::new(), Vec::new());
        let mut out = Vec::new();
        let mut walls = 0;
        for round in 0..4 {
            for (b, g) in m.layout.blocks.iter().zip(&grids) {
                let want = block_wall_orthogonality(&m.layout, b, g);
                walls += usize::from(want.is_some());
                for lanes in Lanes::ALL.into_iter().filter(|l| l.available()) {
                    let got = block_wall_orthogonality_with(
                        &m.layout,
                        b,
                        g,
                        &mut scratch,
                        &mut out,
                        lanes,
                    );
                    assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{lanes:?}");
                }
            }
            // Move the nodes (more each round; a NaN node in the last round).
            for g in &mut grids {
                for p in &mut g.nodes {
                    p[0] += 0.01 * round as f64 * (r.next_f64() - 0.5);
                    p[1] += 0.01 * round as f64 * (r.next_f64() - 0.5);
                }
                if round == 2 {
                    g.nodes[1] = [f64::NAN, 1.0];
                }
            }
        }
        assert!(walls > 20, "{walls}");
    }
}
