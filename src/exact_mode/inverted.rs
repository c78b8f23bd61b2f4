//! Whether one block grid has an inverted cell, right after exact mode made it (issue 8).
//!
//! The mesher needs [`crate::quality::inverted_blocks`] of the exact grids; the grid loop of
//! `super::assemble_cached` finds it grid by grid while each grid is in cache. Going through
//! `quality::inverted_cells` for that cost a parallel iterator over one grid and a CPU-feature
//! check per row (about as much as the cells themselves). Here the same test runs as one loop
//! over the grid's rows, compiled for each vector build (`crate::lanes::Lanes`):
//! a cell is inverted when one of its four corner cross products is not `> 0` (zero, negative
//! or NaN), counted per row by quality's own row pass (`quality::row_inverted_portable`,
//! inlined into each build here), so the same answer as `quality::inverted_cells(&[grid]) > 0`
//! (tested against it in `tests/perf_grid_nodes.rs`).

use crate::geometry::Point;
use crate::lanes::Lanes;
use crate::mesh::BlockGrid;
use crate::quality::row_inverted_portable;

/// True when `g` has an inverted cell: `quality::inverted_cells(&[g]) > 0` (a malformed grid
/// has no cells).
pub(crate) fn has_inverted_cell(g: &BlockGrid) -> bool {
    has_inverted_cell_with(Lanes::best(), g)
}

/// [`has_inverted_cell`] in the build `lanes` (the baseline when the CPU lacks it).
fn has_inverted_cell_with(lanes: Lanes, g: &BlockGrid) -> bool {
    if !crate::quality::well_formed(g) {
        return false;
    }
    let (w, nj) = (g.ni + 1, g.nj);
    #[cfg(target_arch = "x86_64")]
    match lanes {
        // SAFETY: `Lanes::available` checked the CPU's features.
        Lanes::Avx512 if lanes.available() => return unsafe { rows_avx512(&g.nodes, w, nj) },
        // SAFETY: as above.
        Lanes::Avx2 if lanes.available() => return unsafe { rows_avx2(&g.nodes, w, nj) },
        _ => {}
    }
    rows(&g.nodes, w, nj)
}

/// [`rows`] compiled for AVX-512 (8-lane vectors).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
fn rows_avx512(nodes: &[Point], w: usize, nj: usize) -> bool {
    rows(nodes, w, nj)
}

/// [`rows`] compiled for AVX2 (4-lane vectors).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn rows_avx2(nodes: &[Point], w: usize, nj: usize) -> bool {
    rows(nodes, w, nj)
}

/// Some cell of the `nj` rows of cells of a well-formed grid with `w` nodes per node line is
/// inverted. A plain loop: an iterator adaptor's fold would be a function of its own, compiled
/// for the baseline, not for the build that calls it.
#[inline(always)]
fn rows(nodes: &[Point], w: usize, nj: usize) -> bool {
    for j in 0..nj {
        if row_inverted_portable(&nodes[j * w..(j + 1) * w], &nodes[(j + 1) * w..(j + 2) * w]) > 0 {
            return true;
        }
    }
    false
}

/// [`has_inverted_cell`] of `g` in every vector build the CPU has (test hook): `None` if two
/// builds disagree.
#[doc(hidden)]
pub fn has_inverted_cell_every_build(g: &BlockGrid) -> Option<bool> {
    let mut out = None;
    for lanes in Lanes::ALL.into_iter().filter(|l| l.available()) {
        let x = has_inverted_cell_with(lanes, g);
        if out.is_some_and(|y| y != x) {
            return None;
        }
        out = Some(x);
    }
    out
}
