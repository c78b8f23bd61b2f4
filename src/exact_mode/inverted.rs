//! Whether one block grid has an inverted cell, right after exact mode made it (issue 8).
//!
//! The mesher needs [`crate::quality::inverted_blocks`] of the exact grids; the grid loop of
//! `super::assemble_cached` finds it grid by grid while each grid is in cache. Going through
//! `quality::inverted_cells` for that cost a parallel iterator over one grid and a CPU-feature
//! check per row (about as much as the cells themselves). Here the same test runs as one loop
//! over the grid's rows, compiled for each vector build (`crate::lanes::Lanes`):
//! a cell is inverted when one of its four corner cross products is not `> 0` (zero, negative
//! or NaN), each product formed exactly as `quality::kernel::cell_products` forms it from the
//! edge differences of `quality::kernel::row_edges` (so the same bits, and the same answer as
//! `quality::inverted_cells(&[grid]) > 0`; tested against it in `tests/perf_grid_nodes.rs`).

use crate::geometry::Point;
use crate::lanes::Lanes;
use crate::mesh::BlockGrid;

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
        if row(&nodes[j * w..(j + 1) * w], &nodes[(j + 1) * w..(j + 2) * w]) > 0 {
            return true;
        }
    }
    false
}

/// The cells between node lines `lo` and `hi` (same length) with a corner cross product that
/// is not `> 0`: the products of `quality::kernel::cell_products` of the edges of
/// `quality::kernel::row_edges`, written out (a count, which vectorises, where a flag does
/// not).
#[inline(always)]
fn row(lo: &[Point], hi: &[Point]) -> usize {
    let n = lo.len().min(hi.len()).saturating_sub(1);
    let (lo, hi) = (&lo[..=n], &hi[..=n]);
    let mut bad = 0;
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
        bad += usize::from(!good);
    }
    bad
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
