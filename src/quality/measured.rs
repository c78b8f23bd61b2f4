//! The report's figures of a mesh whose nodes are not kept ([`crate::Options::keep_nodes`]
//! false, issue 8): each block is measured right after its grid is made, while its nodes
//! are in cache, and the nodes are then dropped, so that the grids never take memory all at
//! once (a 1e3-particle mesh with 16 x 16 cells per block holds 27 MB of nodes: 7 400 fresh
//! pages, a tenth of the run's CPU time on the machines measured; 2.7 GB at 1e5).
//!
//! The figures are those of [`super::measure_all_with`], bit for bit: the maker measures its
//! blocks in chunks of [`CHUNK`] blocks in block order with the cell pass of
//! [`super::block_stats`] ([`super::rows::Chunk`]), so every chunk's metrics and every
//! block's figures are the same values reduced in the same order ([`super::reduce`]); each
//! block's side-cell heights and wall deviations are taken as the fused pass takes them
//! ([`super::sides`]) and the heights paired once the connectivity is known
//! ([`super::sides::pair_measured`]; counts and extremes, the same in any order), but for
//! the medial sides of exact mode's pieces, whose two blocks face each other across them:
//! those are paired as the piece is measured ([`ChunkMeasure::piece_block`]). Tested
//! against the pass over kept nodes in `tests/perf_measured.rs`.
//!
//! The makers: bounded exact mode (`exact_mode::assemble_cached`: the medial blocks piece by
//! piece, their wall the piece's circle, an inserted hole's neighbours kept until its
//! template is made, then the templates' blocks by [`measure_blocks`]) and periodic boxes
//! (`exact_mode::periodic`'s grid pass: one block after another, the walls from the layout).

use super::kernel::{BlockFigures, Tables};
use super::rows::{Chunk, Rows};
use super::sides::{self, max_nan};
use super::{reduce, Quality, QualityMetrics, CHUNK};
use crate::connectivity::Connectivity;
use crate::geometry::Point;
use crate::lanes::Lanes;
use crate::layout::BlockLayout;
use crate::mesh::BlockGrid;

/// What every chunk measurement shares: the cell pass's tables and the build the side loops
/// run in.
pub(crate) struct Measurer {
    tables: Tables,
    lanes: Lanes,
}

impl Measurer {
    pub(crate) fn new() -> Measurer {
        Measurer {
            tables: Tables::new(),
            lanes: Lanes::best(),
        }
    }

    /// Start measuring the chunk of blocks `c * CHUNK ..` (its blocks are then given in
    /// block order, each once).
    pub(crate) fn chunk(&self) -> ChunkMeasure<'_> {
        ChunkMeasure {
            m: self,
            acc: Chunk::new(),
            rows: Rows::default(),
            lines: (Vec::new(), Vec::new()),
            wall_scratch: Vec::new(),
            walls: Vec::new(),
            figs: Vec::with_capacity(CHUNK),
            sides: ChunkSides {
                heights: Vec::new(),
                start: Vec::with_capacity(CHUNK + 1),
                mask: Vec::with_capacity(CHUNK),
                below: Vec::with_capacity(CHUNK),
            },
            wall: None,
            medial: [Vec::new(), Vec::new()],
        }
    }
}

/// The measurement of one chunk of blocks in progress ([`Measurer::chunk`]).
pub(crate) struct ChunkMeasure<'m> {
    m: &'m Measurer,
    acc: Chunk,
    rows: Rows,
    lines: (Vec<Point>, Vec<Point>),
    wall_scratch: Vec<f64>,
    /// A block's wall sides ([`ChunkMeasure::block_in`]).
    walls: Vec<(usize, Point, bool)>,
    figs: Vec<BlockFigures>,
    sides: ChunkSides,
    wall: Option<f64>,
    /// The medial-arc side heights of the two blocks of the piece being measured
    /// ([`ChunkMeasure::piece_block`]; empty when not measured: a measured side has cells).
    medial: [Vec<f64>; 2],
}

/// Bit of [`ChunkSides::mask`]: the block's side 2 was paired with that of the other block of
/// its medial piece when measured ([`ChunkMeasure::piece_block`]); its heights are not kept.
const PAIRED_IN_PIECE: u8 = 1 << 4;

impl ChunkMeasure<'_> {
    /// Measure the chunk's next block, grid `g`, whose wall sides are `walls` (`(side, the
    /// circle's centre, whether it is the bounding circle)` in side order, as the layout will
    /// give them), and note whether it has a corner angle below `below_deg` degrees
    /// ([`super::has_corner_below`]; `0 < below_deg < 90`). The side-cell heights are kept
    /// for its other sides (a wall side is no interface). True when the block has an
    /// inverted cell (one of [`super::inverted_blocks`]: the cell pass counts the same cells).
    pub(crate) fn block(
        &mut self,
        g: &BlockGrid,
        walls: &[(usize, Point, bool)],
        below_deg: f64,
    ) -> bool {
        self.block_with(g, walls, below_deg, None)
    }

    /// [`ChunkMeasure::block`] of block `half` (0 then 1) of a medial piece of exact mode:
    /// blocks `2 p` and `2 p + 1`, whose sides 2 lie on the piece's medial arc and face each
    /// other in opposite directions (an interface of the connectivity, always). Their growth
    /// ratios are counted as the second is measured, from heights still in cache, instead of
    /// keeping the heights for [`measured_all`] (issue 8: a third of the heights, 75 MB at
    /// 1e5 particles): when both blocks have cells and as many along side 2, as
    /// [`measured_all`] would pair them.
    pub(crate) fn piece_block(
        &mut self,
        g: &BlockGrid,
        walls: &[(usize, Point, bool)],
        below_deg: f64,
        half: usize,
    ) -> bool {
        self.block_with(g, walls, below_deg, Some(half & 1))
    }

    fn block_with(
        &mut self,
        g: &BlockGrid,
        walls: &[(usize, Point, bool)],
        below_deg: f64,
        half: Option<usize>,
    ) -> bool {
        let lanes = self.m.lanes;
        let f = self.acc.block(g, &self.m.tables, &mut self.rows);
        let sd = &mut self.sides;
        sd.start.push(sd.heights.len());
        let mut mask = 0u8;
        if let Some(h) = half {
            // A new piece forgets the last one's sides.
            for m in &mut self.medial[h..] {
                m.clear();
            }
        }
        if super::well_formed(g) && g.ni > 0 && g.nj > 0 {
            for s in (0..4).filter(|&s| walls.iter().all(|w| w.0 != s)) {
                if let (2, Some(h)) = (s, half) {
                    let out = &mut self.medial[h];
                    out.resize(sides::side_cells(g, s), 0.0);
                    sides::side_heights(g, s, out, &mut self.lines, lanes);
                    continue;
                }
                mask |= 1 << s;
                let from = sd.heights.len();
                sd.heights.resize(from + sides::side_cells(g, s), 0.0);
                sides::side_heights(g, s, &mut sd.heights[from..], &mut self.lines, lanes);
            }
        }
        sd.mask.push(mask);
        if half == Some(1)
            && !self.medial[0].is_empty()
            && self.medial[0].len() == self.medial[1].len()
        {
            // Facing each other in opposite directions.
            sides::pair(&self.medial[0], &self.medial[1], false, self.acc.growth());
            let n = sd.mask.len();
            sd.mask[n - 2] |= PAIRED_IN_PIECE;
            sd.mask[n - 1] |= PAIRED_IN_PIECE;
        }
        let w = sides::walls_orthogonality(
            g,
            walls.iter().copied(),
            &mut self.lines,
            &mut self.wall_scratch,
            lanes,
        );
        self.wall = max_nan(self.wall, w);
        // The cell pass's least angle is within 4e-13 degrees of the exact one, and
        // `has_corner_below` within rounding of the exact test: a block whose least angle is
        // well above the threshold (and with no inverted cell) has no corner below it.
        let clear = f.min_angle_deg >= below_deg + 1e-6;
        let maybe = f.inverted > 0 || !clear;
        self.sides
            .below
            .push(maybe && super::has_corner_below(g, below_deg));
        self.figs.push(f);
        f.inverted > 0
    }

    /// [`ChunkMeasure::block`] of `block` of `layout`, grid `g`, its wall sides from the
    /// layout.
    pub(crate) fn block_in(
        &mut self,
        layout: &BlockLayout,
        block: &crate::layout::Block,
        g: &BlockGrid,
        below_deg: f64,
    ) -> bool {
        let mut walls = std::mem::take(&mut self.walls);
        walls.clear();
        walls.extend(sides::wall_arcs(layout, block));
        let bad = self.block(g, &walls, below_deg);
        self.walls = walls;
        bad
    }

    /// The chunk's figures.
    pub(crate) fn finish(mut self) -> ChunkFigures {
        self.sides.start.push(self.sides.heights.len());
        ChunkFigures {
            cells: (self.figs, self.acc.finish()),
            sides: self.sides,
            wall: self.wall,
        }
    }
}

/// The figures of one chunk of blocks ([`ChunkMeasure::finish`]).
#[derive(Debug)]
pub(crate) struct ChunkFigures {
    cells: (Vec<BlockFigures>, QualityMetrics),
    sides: ChunkSides,
    wall: Option<f64>,
}

/// The report's figures of every block of a mesh whose nodes were not kept, in block order
/// ([`crate::Mesh::measured`]): read by [`crate::output::report::Report`] through
/// [`measured_all`].
#[derive(Debug, Default)]
pub struct Measured {
    cells: Vec<(Vec<BlockFigures>, QualityMetrics)>,
    sides: Vec<ChunkSides>,
    wall: Option<f64>,
    /// The first block of the second run of chunks (the templates' blocks, measured after
    /// the medial blocks: [`Measured::new`]), and its first chunk.
    split: usize,
    split_chunk: usize,
}

/// What a chunk keeps of its blocks' sides and corners.
#[derive(Debug)]
struct ChunkSides {
    /// The side-cell heights of every block, its sides in `mask[k]` in turn (none for a
    /// block without cells), block `k`'s from `start[k]` (one more entry at the end).
    heights: Vec<f64>,
    start: Vec<usize>,
    mask: Vec<u8>,
    /// Per block: a corner angle below the threshold ([`ChunkMeasure::block`]).
    below: Vec<bool>,
}

impl Measured {
    /// The figures of two runs of chunks of [`CHUNK`] blocks, in block order, every chunk of
    /// a run full but its last: the medial blocks' `chunks`, then the blocks from `split` on
    /// (`more`; none when `split` is the block count). The way blocks are grouped into
    /// chunks changes no figure (per-block figures are reduced in block order, chunk metrics
    /// are counts and extremes).
    pub(crate) fn new(
        chunks: Vec<ChunkFigures>,
        split: usize,
        more: Vec<ChunkFigures>,
    ) -> Measured {
        let mut out = Measured {
            cells: Vec::with_capacity(chunks.len() + more.len()),
            sides: Vec::with_capacity(chunks.len() + more.len()),
            wall: None,
            split,
            split_chunk: chunks.len(),
        };
        for c in chunks.into_iter().chain(more) {
            out.wall = max_nan(out.wall, c.wall);
            out.cells.push(c.cells);
            out.sides.push(c.sides);
        }
        out
    }

    /// Blocks measured.
    pub fn blocks(&self) -> usize {
        self.cells.iter().map(|c| c.0.len()).sum()
    }

    /// True when block `b` has a corner angle below the threshold it was measured with
    /// ([`ChunkMeasure::block`]); false for a block not measured.
    pub(crate) fn corner_below(&self, b: usize) -> bool {
        let (c, k) = self.chunk_of(b);
        self.sides
            .get(c)
            .and_then(|c| c.below.get(k))
            .copied()
            .unwrap_or(false)
    }

    /// The chunk holding block `b`, and the block's place in it.
    fn chunk_of(&self, b: usize) -> (usize, usize) {
        if b < self.split {
            (b / CHUNK, b % CHUNK)
        } else {
            let r = b - self.split;
            (self.split_chunk + r / CHUNK, r % CHUNK)
        }
    }

    /// The side-cell heights of side `s` of block `b` (grid dimensions `g`), empty when not
    /// measured (a wall side, a block without cells).
    fn heights(&self, b: usize, s: usize, g: &BlockGrid) -> &[f64] {
        let (c, k) = self.chunk_of(b);
        let Some(c) = self.sides.get(c) else {
            return &[];
        };
        let (Some(&from), Some(&to), Some(&mask)) =
            (c.start.get(k), c.start.get(k + 1), c.mask.get(k))
        else {
            return &[];
        };
        let kept = |q: usize| mask >> q & 1 == 1;
        let cells = |q: usize| if kept(q) { sides::side_cells(g, q) } else { 0 };
        if s >= 4 || !kept(s) || to - from != (0..4).map(cells).sum::<usize>() {
            return &[];
        }
        let before: usize = (0..s).map(cells).sum();
        &c.heights[from + before..from + before + cells(s)]
    }

    /// True when block `b`'s side 2 was paired within its medial piece as measured
    /// ([`ChunkMeasure::piece_block`]).
    fn paired_in_piece(&self, b: usize) -> bool {
        let (c, k) = self.chunk_of(b);
        self.sides
            .get(c)
            .and_then(|c| c.mask.get(k))
            .is_some_and(|&m| m & PAIRED_IN_PIECE != 0)
    }

    /// Ask for what [`Measured::heights`] of block `b` reads before the heights (its
    /// chunk's offsets and side mask); a hint only.
    fn prefetch_place(&self, b: usize) {
        let (c, k) = self.chunk_of(b);
        if let Some(c) = self.sides.get(c) {
            crate::prefetch::read(c.start.as_ptr().wrapping_add(k));
            crate::prefetch::read(c.mask.as_ptr().wrapping_add(k));
        }
    }
}

/// [`measure_blocks`] of the inserted holes' template grids `templates` (blocks `first..` of
/// `layout`), then every node of them and of the medial blocks' `grids` dropped: the medial
/// blocks on inserted holes kept theirs until the templates were made from them, and nothing
/// reads a node once measured. The one ending of bounded and periodic exact mode's grids when
/// they are measured as made (issue 8). Returns the templates' figures and which of them have
/// an inverted cell.
pub(crate) fn measure_templates_and_drop(
    m: &Measurer,
    layout: &BlockLayout,
    templates: &mut [BlockGrid],
    grids: &mut [BlockGrid],
    first: usize,
    below_deg: f64,
) -> (Vec<ChunkFigures>, Vec<bool>) {
    use rayon::prelude::*;
    let measured = measure_blocks(m, layout, templates, first, below_deg);
    templates
        .par_iter_mut()
        .chain(grids.par_iter_mut())
        .for_each(|g| g.nodes = Vec::new());
    measured
}

/// Measure `grids`, blocks `first..` of `layout` (their wall sides from it), in chunks of
/// [`CHUNK`] blocks in parallel, each block's corner-angle flag against `below_deg`: the
/// second run of [`Measured::new`] (the templates' blocks, made after the medial ones).
/// Also returns which blocks have an inverted cell.
pub(crate) fn measure_blocks(
    m: &Measurer,
    layout: &BlockLayout,
    grids: &[BlockGrid],
    first: usize,
    below_deg: f64,
) -> (Vec<ChunkFigures>, Vec<bool>) {
    use rayon::prelude::*;
    let parts: Vec<(ChunkFigures, Vec<bool>)> = grids
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut cm = m.chunk();
            let mut bad = Vec::with_capacity(chunk.len());
            for (k, g) in chunk.iter().enumerate() {
                bad.push(match layout.blocks.get(first + c * CHUNK + k) {
                    Some(b) => cm.block_in(layout, b, g, below_deg),
                    None => cm.block(g, &[], below_deg),
                });
            }
            (cm.finish(), bad)
        })
        .collect();
    let mut bad = Vec::with_capacity(grids.len());
    let figures = parts
        .into_iter()
        .map(|(f, b)| {
            bad.extend(b);
            f
        })
        .collect();
    (figures, bad)
}

/// [`super::measure_all_with`] of a mesh whose grids were measured as they were made
/// (`measured`, one entry per grid; the grids may have dropped their nodes): the same
/// figures, bit for bit, from what the maker measured.
pub fn measured_all(
    layout: &BlockLayout,
    grids: &[BlockGrid],
    conn: Option<&Connectivity>,
    measured: &Measured,
) -> (Quality, QualityMetrics) {
    let same = layout.blocks.len() == grids.len() && measured.blocks() == grids.len();
    let conn = conn.filter(|c| same && c.len() == grids.len());
    // The blocks' figures reduced in block order (serial: 10-20 ms at 1e5 particles) beside
    // the growth ratios of the interfaces, which it does not touch (issue 8).
    let ((q, mut m), growth) = rayon::join(
        || reduce(&measured.cells),
        || {
            let conn = conn?;
            // A side paired within its piece faces the other block's side 2 (the interface
            // `pair_measured` then skips: neither side kept its heights).
            debug_assert!((0..grids.len())
                .filter(|&b| measured.paired_in_piece(b))
                .all(|b| {
                    conn.partner(b, 2)
                        .is_some_and(|p| p.block == b ^ 1 && p.side == 2 && !p.same_direction)
                }));
            let heights = |b: usize, s: usize| -> &[f64] {
                match grids.get(b) {
                    Some(g) => measured.heights(b, s, g),
                    None => &[],
                }
            };
            let ahead = |b: usize| {
                crate::prefetch::read(grids.as_ptr().wrapping_add(b));
                measured.prefetch_place(b);
            };
            Some(sides::pair_measured(conn, grids, &heights, &ahead))
        },
    );
    if let Some(g) = growth {
        m.interface_growth_ratio.merge(&g);
    }
    if same {
        m.max_wall_orthogonality_deviation_deg = measured.wall;
    }
    (q, m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layouts::SplitMix64;

    /// An `ni x nj` grid of parallelograms whose acute angle is `deg` degrees, at a random
    /// scale and rotation, with one node moved at random (sometimes far enough to invert a
    /// cell, sometimes to a non-finite value).
    fn sheared(r: &mut SplitMix64, ni: usize, nj: usize, deg: f64) -> BlockGrid {
        let (s, c) = deg.to_radians().sin_cos();
        let scale = 10f64.powf(6.0 * r.next_f64() - 3.0);
        let (rs, rc) = (6.3 * r.next_f64()).sin_cos();
        let mut nodes = Vec::with_capacity((ni + 1) * (nj + 1));
        for j in 0..=nj {
            for i in 0..=ni {
                let (x, y) = (i as f64 + j as f64 * c, j as f64 * s);
                nodes.push([scale * (rc * x - rs * y), scale * (rs * x + rc * y)]);
            }
        }
        let k = (r.next_u64() % nodes.len() as u64) as usize;
        match r.next_u64() % 4 {
            0 => nodes[k][1] += scale * (r.next_f64() - 0.5),
            1 => nodes[k][0] = f64::NAN,
            _ => {}
        }
        BlockGrid { ni, nj, nodes }
    }

    /// The flags a measured block gets are `has_corner_below`'s and the inverted-cell
    /// count's, for least angles on either side of the threshold (within 1e-9 degrees too),
    /// inverted and non-finite cells; and a chunk's heights are found where
    /// [`Measured::heights`] looks for them.
    #[test]
    fn corner_below_flags_and_heights_are_those_of_the_grids() {
        let m = Measurer::new();
        let mut r = SplitMix64(17);
        let mut seen = [0usize; 2];
        let mut bad = [0usize; 2];
        for _ in 0..20 {
            let mut chunk = m.chunk();
            let mut grids = Vec::new();
            for _ in 0..CHUNK {
                let deg = match r.next_u64() % 3 {
                    0 => 5.0 + 1e-9 * (r.next_f64() - 0.5),
                    1 => 3.0 + 4.0 * r.next_f64(),
                    _ => 5.0 + 80.0 * r.next_f64(),
                };
                let ni = 1 + (r.next_u64() % 5) as usize;
                let nj = 1 + (r.next_u64() % 5) as usize;
                let g = sheared(&mut r, ni, nj, deg);
                // Side 1 of every other block a wall (its heights not kept).
                let walls: &[(usize, Point, bool)] = match grids.len() % 2 {
                    0 => &[],
                    _ => &[(1, [0.0, 0.0], false)],
                };
                let inverted = chunk.block(&g, walls, 5.0);
                assert_eq!(inverted, super::super::grid_inverted_cells(&g) > 0);
                bad[usize::from(inverted)] += 1;
                grids.push(g);
            }
            let measured = Measured::new(vec![chunk.finish()], CHUNK, Vec::new());
            assert_eq!(measured.blocks(), CHUNK);
            for (b, g) in grids.iter().enumerate() {
                let want = super::super::has_corner_below(g, 5.0);
                assert_eq!(measured.corner_below(b), want, "block {b}");
                seen[usize::from(want)] += 1;
                for s in 0..4 {
                    let h = measured.heights(b, s, g);
                    if s == 1 && b % 2 == 1 {
                        assert!(h.is_empty(), "a wall side has no heights");
                        continue;
                    }
                    assert_eq!(h.len(), sides::side_cells(g, s));
                    for (p, &x) in h.iter().enumerate() {
                        let y = sides::side_cell_height(g, s, p);
                        assert!(x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()));
                    }
                }
            }
        }
        assert!(seen[0] > 100 && seen[1] > 100, "{seen:?}");
        assert!(bad[0] > 100 && bad[1] > 100, "{bad:?}");
    }
}
