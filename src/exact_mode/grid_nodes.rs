//! The nodes of one medial block, row by row (issue 8): the values of
//! `super::spoke_column` for every column of the block, bit for bit, with less work per node.
//!
//! A block's column `i` is the spoke from its wall point `a_i` to its medial point `m_i`, with
//! node `j` at `a_i + t (m_i - a_i)`, `t = d_j / |m_i - a_i|` (`d` the spoke's distances,
//! [`clustering::spoke_distances_into`]). Built spoke by spoke, the nodes were written with a
//! stride into a zeroed vector and each uniform spoke computed `j / n` for every node; here:
//! - the node vector is filled in order, row after row (`nodes[i + j (n + 1)]`), with no
//!   zeroing pass over fresh memory;
//! - a uniformly spaced spoke's distances are `len * (j / nj)` with the fractions `j / nj`
//!   computed once per block (the same expression, so the same bits). For such a spoke the
//!   safety guard of [`clustering::spoke_distances_into`] (which re-spaces distances that are
//!   not strictly increasing) never fires when `len` is finite and at least [`SAFE_LEN`]: the
//!   fractions are at least `1 / nj` apart (`nj <= MAX_CELLS_PER_SIDE = 1e5`) and each product
//!   is off by at most half an ulp of `len` (or `2^-1075` below the normal range), far less
//!   than `len / (2 nj)`; other spokes take the distances from that function itself;
//! - a row's nodes are independent, so its divisions run in vector lanes (the same IEEE
//!   operations in the same order: the same bits).
//!
//! Tested against `spoke_column` in `tests/perf_grid_nodes.rs` (random, degenerate and
//! clustered spokes) through [`block_nodes_reference`] and [`block_nodes`].

use super::{clustering, dist};
use crate::geometry::Point;
use crate::lanes::Lanes;

/// The shortest spoke whose uniform distances are taken from the shared fractions (see the
/// module docs; any length above `1e5 * 2^-1073` would do).
pub const SAFE_LEN: f64 = 1e-290;

/// Per-task buffers of [`GridScratch::nodes`]: the columns of the block being built, and what
/// its rows need. Reused from block to block; nothing in them outlives a block.
#[derive(Default)]
pub(crate) struct GridScratch {
    ax: Vec<f64>,
    ay: Vec<f64>,
    mx: Vec<f64>,
    my: Vec<f64>,
    /// `m - a` per column (the same value the node formula computes each time).
    dx: Vec<f64>,
    dy: Vec<f64>,
    len: Vec<f64>,
    /// `j / nj` for `j` in `0..=nj`.
    frac: Vec<f64>,
    /// Distances of the interior rows, row-major (`d[(j - 1) ni + i]`), when a column is not
    /// a safe uniform one.
    d: Vec<f64>,
    /// One spoke's distances.
    col: Vec<f64>,
}

impl GridScratch {
    /// Forget the previous block's columns.
    pub(crate) fn clear(&mut self) {
        for v in [
            &mut self.ax,
            &mut self.ay,
            &mut self.mx,
            &mut self.my,
            &mut self.dx,
            &mut self.dy,
            &mut self.len,
        ] {
            v.clear();
        }
    }

    /// Add column `i` (the next one): the spoke from `a` (row 0) to `m` (row `nj`).
    pub(crate) fn push(&mut self, a: Point, m: Point) {
        self.ax.push(a[0]);
        self.ay.push(a[1]);
        self.mx.push(m[0]);
        self.my.push(m[1]);
        self.dx.push(m[0] - a[0]);
        self.dy.push(m[1] - a[1]);
        self.len.push(dist(a, m));
    }

    /// The nodes of the block of the columns pushed since [`GridScratch::clear`], with `nj`
    /// cells along each spoke, first height `first` and growth `growth`: node `(i, j)` at
    /// `i + j * ni` (`ni` columns), exactly what `super::spoke_column` writes for each column.
    pub(crate) fn nodes(&mut self, nj: usize, first: Option<f64>, growth: f64) -> Vec<Point> {
        self.nodes_with(Lanes::best(), nj, first, growth)
    }

    /// [`GridScratch::nodes`] with its rows in the build `lanes`.
    fn nodes_with(
        &mut self,
        lanes: Lanes,
        nj: usize,
        first: Option<f64>,
        growth: f64,
    ) -> Vec<Point> {
        let ni = self.ax.len();
        let mut nodes = Vec::with_capacity(ni * (nj + 1));
        if nj > 0 {
            nodes.extend((0..ni).map(|i| [self.ax[i], self.ay[i]]));
        }
        if nj > 1 {
            self.frac.clear();
            self.frac.extend((0..=nj).map(|j| j as f64 / nj as f64));
            // `spoke_distances_into`'s choice of equal spacing, for a spoke of length `len`.
            let uniform = |len: f64| clustering::clustered_first(len, nj, first).is_none();
            let all_safe = self
                .len
                .iter()
                .all(|&l| l.is_finite() && l >= SAFE_LEN && uniform(l));
            if !all_safe {
                let rows = nj - 1;
                self.d.clear();
                self.d.resize(rows * ni, 0.0);
                for i in 0..ni {
                    let len = self.len[i];
                    if len.is_finite() && len >= SAFE_LEN && uniform(len) {
                        for j in 1..nj {
                            self.d[(j - 1) * ni + i] = len * self.frac[j];
                        }
                    } else {
                        clustering::spoke_distances_into(len, nj, first, growth, &mut self.col);
                        for j in 1..nj {
                            self.d[(j - 1) * ni + i] = self.col[j];
                        }
                    }
                }
            }
            self.rows_with(lanes, nj, all_safe, &mut nodes);
        }
        nodes.extend((0..ni).map(|i| [self.mx[i], self.my[i]]));
        nodes
    }
}

impl GridScratch {
    /// The interior rows `1..nj`, appended to `nodes`, in the build `lanes` (the baseline when
    /// the CPU lacks it): the same IEEE operations in every build (no fused multiply-add), so
    /// the same bits ([`Lanes`]).
    fn rows_with(&mut self, lanes: Lanes, nj: usize, all_safe: bool, nodes: &mut Vec<Point>) {
        #[cfg(target_arch = "x86_64")]
        match lanes {
            // SAFETY: `Lanes::available` checked the CPU's features.
            Lanes::Avx512 if lanes.available() => {
                return unsafe { self.rows_avx512(nj, all_safe, nodes) }
            }
            // SAFETY: as above.
            Lanes::Avx2 if lanes.available() => {
                return unsafe { self.rows_avx2(nj, all_safe, nodes) }
            }
            _ => {}
        }
        self.rows(nj, all_safe, nodes)
    }

    /// [`GridScratch::rows`] compiled for AVX-512 (8-lane vectors).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
    fn rows_avx512(&mut self, nj: usize, all_safe: bool, nodes: &mut Vec<Point>) {
        self.rows(nj, all_safe, nodes)
    }

    /// [`GridScratch::rows`] compiled for AVX2 (4-lane vectors).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn rows_avx2(&mut self, nj: usize, all_safe: bool, nodes: &mut Vec<Point>) {
        self.rows(nj, all_safe, nodes)
    }

    /// The body of [`GridScratch::rows_with`], inlined into each build: each row appended to
    /// `nodes` as it is computed (no row buffer copied in).
    #[inline(always)]
    fn rows(&mut self, nj: usize, all_safe: bool, nodes: &mut Vec<Point>) {
        for j in 1..nj {
            if all_safe {
                row_uniform(self, self.frac[j], nodes);
            } else {
                row_general(self, j, nodes);
            }
        }
    }
}

/// One interior row of a block whose spokes are all safe uniform ones, appended to `nodes`:
/// node `i` at distance `len_i * f` (`f = j / nj`).
#[inline(always)]
fn row_uniform(s: &GridScratch, f: f64, nodes: &mut Vec<Point>) {
    let n = s.len.len();
    let (ax, ay, dx, dy, len) = (&s.ax[..n], &s.ay[..n], &s.dx[..n], &s.dy[..n], &s.len[..n]);
    let out = row_slots(nodes, n);
    for i in 0..n {
        let l = len[i];
        let t = (l * f) / l;
        out[i].write([ax[i] + t * dx[i], ay[i] + t * dy[i]]);
    }
    // SAFETY: `row_slots` reserved the `n` slots, and each was written just above.
    unsafe { nodes.set_len(nodes.len() + n) };
}

/// The `n` slots after the last node, reserved (a block's node vector has room for all its
/// rows: nothing is moved then).
#[inline(always)]
fn row_slots(nodes: &mut Vec<Point>, n: usize) -> &mut [std::mem::MaybeUninit<Point>] {
    nodes.reserve(n);
    &mut nodes.spare_capacity_mut()[..n]
}

/// Interior row `j` from the distances `s.d` (the formula of `super::spoke_column`), appended
/// to `nodes`.
#[inline(always)]
fn row_general(s: &GridScratch, j: usize, nodes: &mut Vec<Point>) {
    let n = s.len.len();
    let d = &s.d[(j - 1) * n..j * n];
    let (ax, ay, dx, dy, len) = (&s.ax[..n], &s.ay[..n], &s.dx[..n], &s.dy[..n], &s.len[..n]);
    let out = row_slots(nodes, n);
    for i in 0..n {
        let l = len[i];
        let t = if l > 0.0 { d[i] / l } else { 0.0 };
        out[i].write([ax[i] + t * dx[i], ay[i] + t * dy[i]]);
    }
    // SAFETY: `row_slots` reserved the `n` slots, and each was written just above.
    unsafe { nodes.set_len(nodes.len() + n) };
}

/// The nodes of the block whose column `i` runs from `ends[i].0` to `ends[i].1`, built by
/// [`GridScratch::nodes`] (test hook), once per vector build the CPU has: `None` if two builds
/// differ in any bit.
#[doc(hidden)]
pub fn block_nodes(
    ends: &[(Point, Point)],
    nj: usize,
    first: Option<f64>,
    growth: f64,
) -> Option<Vec<Point>> {
    let mut s = GridScratch::default();
    let mut out: Option<Vec<Point>> = None;
    for lanes in Lanes::ALL.into_iter().filter(|l| l.available()) {
        s.clear();
        for &(a, m) in ends {
            s.push(a, m);
        }
        let nodes = s.nodes_with(lanes, nj, first, growth);
        let bits = |v: &[Point]| v.iter().map(|p| p.map(f64::to_bits)).collect::<Vec<_>>();
        match &out {
            Some(prev) if bits(prev) != bits(&nodes) => return None,
            Some(_) => {}
            None => out = Some(nodes),
        }
    }
    out
}

/// The same block built spoke by spoke into a zeroed vector (`super::spoke_column`, the
/// reference of the tests).
#[doc(hidden)]
pub fn block_nodes_reference(
    ends: &[(Point, Point)],
    nj: usize,
    first: Option<f64>,
    growth: f64,
) -> Vec<Point> {
    let ni = ends.len();
    let mut nodes = vec![[0.0; 2]; ni * (nj + 1)];
    let mut d = Vec::new();
    for (i, &(a, m)) in ends.iter().enumerate() {
        super::spoke_column(a, m, nj, first, growth, &mut d, &mut nodes, i, ni);
    }
    nodes
}
