//! Node counts, edge discretisation and transfinite interpolation: [`BlockLayout`] in,
//! one [`BlockGrid`] per block out.
//!
//! Invariants of the result of [`build_grids`] (checked independently by `tests/back_*.rs`):
//! - grid `b` belongs to block `b`; its `ni` is the cell count of sides 0 and 2 and `nj` that
//!   of sides 1 and 3, and `nodes.len() == (ni + 1) * (nj + 1)`;
//! - every edge is discretised once; each block side's nodes are copied bit for bit from its
//!   edge's discretisation (reversed when the side runs against the edge), so two blocks that
//!   share an edge have identical nodes along it;
//! - the first and last node of every edge are exactly its end vertices;
//! - interior nodes come from the Coons patch (transfinite interpolation) of the four sides
//!   with uniform parameters `u = i / ni`, `v = j / nj`, which reproduces a bilinear map
//!   exactly (to rounding) when the four sides are uniformly divided straight segments.

use crate::geometry::Point;
use crate::layout::{BlockLayout, Curve, EdgeKind};
use crate::mesh::BlockGrid;
use rayon::prelude::*;

/// The largest cell count accepted along one edge.
pub const MAX_CELLS_PER_SIDE: usize = 100_000;

/// The largest total number of grid nodes (all blocks, shared nodes counted once per block)
/// accepted, checked before any allocation: 400 million nodes is 6.4 GB of coordinates, room
/// for 100,000 particles at 16 x 16 cells per block (about 1.7e8 nodes) on a 24 GB machine.
pub const MAX_TOTAL_NODES: usize = 400_000_000;

/// Why no grid was built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error("the number of cells along a block side must be at least 1")]
    ZeroCells,
    #[error("{cells} cells along a block side is more than the limit of {limit}")]
    TooManyCellsPerSide { cells: usize, limit: usize },
    #[error("the grid would have {nodes} nodes, more than the limit of {limit}")]
    TooManyNodes { nodes: usize, limit: usize },
    #[error("invalid block layout: {0}")]
    InvalidLayout(String),
}

/// Cell counts per edge: the result of the conformity constraints and [`choose_counts`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdgeCounts {
    /// `class[e]`: the conformity class of edge `e` (`0..classes`). Edges in one class must
    /// have the same cell count: the opposite sides of a block are in one class.
    pub class: Vec<usize>,
    /// Number of classes.
    pub classes: usize,
    /// `cells[e]`: the cell count of edge `e`.
    pub cells: Vec<usize>,
}

/// Union-find with path halving; deterministic.
/// Union-find over edge ids (`u32`, as in [`crate::layout::SideRef`]: half the memory of
/// `usize` parents); every root is the smallest id of its set.
struct Dsu(Vec<u32>);

impl Dsu {
    fn find(&mut self, x: usize) -> usize {
        let mut x = x as u32;
        while self.0[x as usize] != x {
            self.0[x as usize] = self.0[self.0[x as usize] as usize];
            x = self.0[x as usize];
        }
        x as usize
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a) as u32, self.find(b) as u32);
        // Keep the smaller root: deterministic and independent of call order.
        if ra < rb {
            self.0[rb as usize] = ra;
        } else if rb < ra {
            self.0[ra as usize] = rb;
        }
    }
}

/// Check the layout's indices and that every block side runs between the vertices of its
/// edge (in the side's direction), so that side nodes glue up at the corners exactly.
pub fn validate_layout(layout: &BlockLayout) -> Result<(), GridError> {
    let nv = layout.vertices.len();
    let ne = layout.edges.len();
    for (v, p) in layout.vertices.iter().enumerate() {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(GridError::InvalidLayout(format!(
                "vertex {v} is not finite: {p:?}"
            )));
        }
    }
    for (e, edge) in layout.edges.iter().enumerate() {
        for &v in &edge.ends {
            if v as usize >= nv {
                return Err(GridError::InvalidLayout(format!(
                    "edge {e} refers to vertex {v}, but there are {nv} vertices"
                )));
            }
        }
        match &edge.curve {
            Curve::Segment => {}
            Curve::Arc {
                center,
                radius,
                start,
                sweep,
            } => {
                if !(center[0].is_finite()
                    && center[1].is_finite()
                    && radius.is_finite()
                    && *radius > 0.0
                    && start.is_finite()
                    && sweep.is_finite())
                {
                    return Err(GridError::InvalidLayout(format!(
                        "edge {e} is an arc with invalid parameters"
                    )));
                }
                // The arc's own end points must match its end vertices (to a relative 1e-8).
                let scale = radius + center[0].abs().max(center[1].abs());
                let ends = [*start, start + sweep];
                for (k, &a) in ends.iter().enumerate() {
                    let p = [center[0] + radius * a.cos(), center[1] + radius * a.sin()];
                    let q = layout.vertices[edge.ends[k] as usize];
                    let dist = (p[0] - q[0]).hypot(p[1] - q[1]);
                    if dist.is_nan() || dist > 1e-8 * scale {
                        return Err(GridError::InvalidLayout(format!(
                            "edge {e}: arc end {k} is {dist:e} away from its vertex"
                        )));
                    }
                }
            }
            Curve::Polyline(pts) => {
                if pts.len() < 2 {
                    return Err(GridError::InvalidLayout(format!(
                        "edge {e} is a polyline of fewer than 2 points"
                    )));
                }
                if pts.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
                    return Err(GridError::InvalidLayout(format!(
                        "edge {e} is a polyline with a non-finite point"
                    )));
                }
            }
        }
    }
    for (b, block) in layout.blocks.iter().enumerate() {
        for (k, s) in block.sides.iter().enumerate() {
            let e = s.edge as usize;
            if e >= ne {
                return Err(GridError::InvalidLayout(format!(
                    "block {b} side {k} refers to edge {e}, but there are {ne} edges"
                )));
            }
            let ends = layout.edges[e].ends;
            let along = if s.reversed { [ends[1], ends[0]] } else { ends };
            let want = [block.corners[k], block.corners[(k + 1) % 4]];
            if along != want {
                return Err(GridError::InvalidLayout(format!(
                    "block {b} side {k} runs {want:?} but its edge {e} (reversed: {}) runs {along:?}",
                    s.reversed
                )));
            }
        }
    }
    Ok(())
}

/// The conformity classes of the edges: opposite sides of each block are in one class, and
/// so are the two copies of a periodic side ([`EdgeKind::Periodic`]).
/// Classes are numbered in order of their smallest edge id. Assumes valid edge indices.
pub fn edge_classes(layout: &BlockLayout) -> (Vec<usize>, usize) {
    let ne = layout.edges.len();
    // Edge ids are `u32` wherever a layout names an edge (sides, periodic partners).
    let n32 = u32::try_from(ne).expect("a layout has fewer than 2^32 edges");
    let mut dsu = Dsu((0..n32).collect());
    for block in &layout.blocks {
        let e = block.sides.map(|s| s.edge as usize);
        if e.iter().all(|&x| x < ne) {
            dsu.union(e[0], e[2]);
            dsu.union(e[1], e[3]);
        }
    }
    // The two copies of a periodic side have the same count.
    for (e, edge) in layout.edges.iter().enumerate() {
        if let EdgeKind::Periodic { partner, .. } = edge.kind {
            if (partner as usize) < ne {
                dsu.union(e, partner as usize);
            }
        }
    }
    // A root is its class's smallest edge, so it is met first in edge order: it opens the
    // next class, every later edge takes its root's (no per-root table).
    let mut class: Vec<usize> = Vec::with_capacity(ne);
    let mut classes = 0;
    for e in 0..ne {
        let root = dsu.find(e);
        if root == e {
            class.push(classes);
            classes += 1;
        } else {
            class.push(class[root]);
        }
    }
    (class, classes)
}

/// The largest angle one cell may span along a wall arc (15 degrees): a coarse `cells` on a
/// block whose wall is a long arc (a small hole seen by few blocks, the bounding circle with
/// few holes) would otherwise make transfinite interpolation fold cells near the wall.
pub const MAX_ARC_PER_CELL: f64 = std::f64::consts::PI / 12.0;

/// The hook for choosing the cell count of each conformity class. Every class gets the target
/// `cells` (the paper: equal counts and equal spacing), raised where a class holds a wall arc
/// that would otherwise span more than [`MAX_ARC_PER_CELL`] per cell. A smarter choice (by
/// edge length, per-circle wall-normal counts, ...) belongs here. Returns one count per class,
/// each at least 1.
pub fn choose_counts(
    layout: &BlockLayout,
    class: &[usize],
    classes: usize,
    cells: usize,
) -> Vec<usize> {
    let mut counts = vec![cells.max(1); classes];
    for (edge, &c) in layout.edges.iter().zip(class) {
        if let Curve::Arc { sweep, .. } = edge.curve {
            let needed = (sweep.abs() / MAX_ARC_PER_CELL).ceil();
            if needed.is_finite() && needed > counts[c] as f64 {
                counts[c] = (needed as usize).min(MAX_CELLS_PER_SIDE);
            }
        }
    }
    counts
}

/// Conformity classes and cell counts of every edge, with the limits checked.
pub fn edge_counts(layout: &BlockLayout, cells: usize) -> Result<EdgeCounts, GridError> {
    edge_counts_forced(layout, cells, &[])
}

/// [`edge_counts`] with some counts imposed: `forced` lists `(edge, count)`; the edge's whole
/// conformity class gets that count. Two different counts imposed on one class are an
/// [`GridError::InvalidLayout`].
pub fn edge_counts_forced(
    layout: &BlockLayout,
    cells: usize,
    forced: &[(usize, usize)],
) -> Result<EdgeCounts, GridError> {
    if cells == 0 {
        return Err(GridError::ZeroCells);
    }
    if cells > MAX_CELLS_PER_SIDE {
        return Err(GridError::TooManyCellsPerSide {
            cells,
            limit: MAX_CELLS_PER_SIDE,
        });
    }
    validate_layout(layout)?;
    let (class, classes) = edge_classes(layout);
    let mut per_class = choose_counts(layout, &class, classes, cells);
    let mut imposed: Vec<Option<usize>> = vec![None; classes];
    for &(e, n) in forced {
        let c = *class.get(e).ok_or_else(|| {
            GridError::InvalidLayout(format!(
                "a count is imposed on edge {e}, which does not exist"
            ))
        })?;
        match imposed[c] {
            Some(m) if m != n => {
                return Err(GridError::InvalidLayout(format!(
                    "edge {e} must have {n} cells, but its conformity class must have {m}"
                )))
            }
            _ => imposed[c] = Some(n),
        }
        if let Some(slot) = per_class.get_mut(c) {
            *slot = n;
        }
    }
    if per_class.len() != classes {
        return Err(GridError::InvalidLayout(
            "choose_counts returned the wrong number of counts".into(),
        ));
    }
    for &n in &per_class {
        if n == 0 {
            return Err(GridError::ZeroCells);
        }
        if n > MAX_CELLS_PER_SIDE {
            return Err(GridError::TooManyCellsPerSide {
                cells: n,
                limit: MAX_CELLS_PER_SIDE,
            });
        }
    }
    let cells = class.iter().map(|&c| per_class[c]).collect();
    Ok(EdgeCounts {
        class,
        classes,
        cells,
    })
}

/// Total number of nodes of the grids and edge discretisations, or `None` on overflow.
fn total_nodes(layout: &BlockLayout, counts: &EdgeCounts) -> Option<usize> {
    let mut total: usize = 0;
    for n in &counts.cells {
        total = total.checked_add(n.checked_add(1)?)?;
    }
    for block in &layout.blocks {
        let ni = counts.cells[block.sides[0].edge as usize];
        let nj = counts.cells[block.sides[1].edge as usize];
        let n = ni.checked_add(1)?.checked_mul(nj.checked_add(1)?)?;
        total = total.checked_add(n)?;
    }
    Some(total)
}

/// `n + 1` nodes equally spaced along the edge `e` of the layout (equal parameter steps for a
/// segment, equal angle steps on the true circle for an arc, equal arc length for a
/// polyline); the first and last are exactly the edge's end vertices. Assumes a validated
/// layout and `n >= 1`.
fn discretise(layout: &BlockLayout, e: usize, n: usize) -> Vec<Point> {
    let edge = &layout.edges[e];
    let p0 = layout.vertices[edge.ends[0] as usize];
    let p1 = layout.vertices[edge.ends[1] as usize];
    let nf = n as f64;
    let mut out: Vec<Point> = match &edge.curve {
        Curve::Segment => (0..=n).map(|i| lerp(p0, p1, i as f64 / nf)).collect(),
        Curve::Arc {
            center,
            radius,
            start,
            sweep,
        } => (0..=n)
            .map(|i| {
                let a = start + sweep * (i as f64 / nf);
                [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
            })
            .collect(),
        Curve::Polyline(pts) => polyline_equal(pts, n),
    };
    out[0] = p0;
    out[n] = p1;
    out
}

fn lerp(a: Point, b: Point, t: f64) -> Point {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

/// `n + 1` points at equal arc length along the polyline `pts` (at least 2 points).
fn polyline_equal(pts: &[Point], n: usize) -> Vec<Point> {
    let mut cum = Vec::with_capacity(pts.len());
    cum.push(0.0);
    for w in pts.windows(2) {
        let l = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        cum.push(cum[cum.len() - 1] + l);
    }
    let total = cum[cum.len() - 1];
    let last = pts.len() - 1;
    if !(total > 0.0 && total.is_finite()) {
        return (0..=n)
            .map(|i| lerp(pts[0], pts[last], i as f64 / n as f64))
            .collect();
    }
    let mut out = Vec::with_capacity(n + 1);
    let mut seg = 0;
    for i in 0..=n {
        let s = total * (i as f64 / n as f64);
        while seg + 1 < last && cum[seg + 1] < s {
            seg += 1;
        }
        let l = cum[seg + 1] - cum[seg];
        let t = if l > 0.0 {
            ((s - cum[seg]) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(lerp(pts[seg], pts[seg + 1], t));
    }
    out
}

/// Transfinite interpolation (Coons patch) of a block from its four sides, each given in the
/// side's direction (see [`crate::layout`]): `s0` and `s2` have `ni + 1` nodes, `s1` and `s3`
/// have `nj + 1`; consecutive sides should share their corner node (the corners are taken
/// from `s0` and `s2`; [`build_grids`] guarantees they match bit for bit). Boundary nodes are
/// copied exactly from the sides.
///
/// Returns `None` when the side lengths are inconsistent (fewer than 2 nodes, or opposite
/// sides of different lengths).
pub fn tfi(s0: &[Point], s1: &[Point], s2: &[Point], s3: &[Point]) -> Option<BlockGrid> {
    if s0.len() < 2 || s1.len() < 2 || s0.len() != s2.len() || s1.len() != s3.len() {
        return None;
    }
    let ni = s0.len() - 1;
    let nj = s1.len() - 1;
    // In grid terms: bottom(i) = node(i, 0), right(j) = node(ni, j), top(i) = node(i, nj),
    // left(j) = node(0, j).
    let bottom = |i: usize| s0[i];
    let right = |j: usize| s1[j];
    let top = |i: usize| s2[ni - i];
    let left = |j: usize| s3[nj - j];
    let (c00, c10, c11, c01) = (bottom(0), bottom(ni), top(ni), top(0));
    let mut nodes = Vec::with_capacity((ni + 1) * (nj + 1));
    for j in 0..=nj {
        let v = j as f64 / nj as f64;
        for i in 0..=ni {
            let p = if j == 0 {
                bottom(i)
            } else if j == nj {
                top(i)
            } else if i == 0 {
                left(j)
            } else if i == ni {
                right(j)
            } else {
                let u = i as f64 / ni as f64;
                let (b, t, l, r) = (bottom(i), top(i), left(j), right(j));
                let mut q = [0.0; 2];
                for d in 0..2 {
                    q[d] = (1.0 - v) * b[d] + v * t[d] + (1.0 - u) * l[d] + u * r[d]
                        - ((1.0 - u) * (1.0 - v) * c00[d]
                            + u * (1.0 - v) * c10[d]
                            + u * v * c11[d]
                            + (1.0 - u) * v * c01[d]);
                }
                q
            };
            nodes.push(p);
        }
    }
    Some(BlockGrid { ni, nj, nodes })
}

/// Build one structured grid per block of `layout`, with `cells` cells along every edge
/// (through [`choose_counts`]).
///
/// Errors (never panics): `cells == 0`, `cells` above [`MAX_CELLS_PER_SIDE`], a total node
/// count above [`MAX_TOTAL_NODES`] (checked before allocating), or a layout with dangling
/// indices, non-finite coordinates, arcs whose end points are not at their vertices, or block
/// sides that do not run between the vertices of their edge.
pub fn build_grids(layout: &BlockLayout, cells: usize) -> Result<Vec<BlockGrid>, GridError> {
    build_grids_forced(layout, cells, &[])
}

/// [`build_grids`] with imposed counts (see [`edge_counts_forced`]).
pub fn build_grids_forced(
    layout: &BlockLayout,
    cells: usize,
    forced: &[(usize, usize)],
) -> Result<Vec<BlockGrid>, GridError> {
    let counts = edge_counts_forced(layout, cells, forced)?;
    match total_nodes(layout, &counts) {
        Some(n) if n <= MAX_TOTAL_NODES => {}
        Some(n) => {
            return Err(GridError::TooManyNodes {
                nodes: n,
                limit: MAX_TOTAL_NODES,
            })
        }
        None => {
            return Err(GridError::TooManyNodes {
                nodes: usize::MAX,
                limit: MAX_TOTAL_NODES,
            })
        }
    }
    // Discretise each edge used by a block exactly once.
    let mut used = vec![false; layout.edges.len()];
    for block in &layout.blocks {
        for s in &block.sides {
            used[s.edge as usize] = true;
        }
    }
    // In parallel (each edge on its own; collected in edge order).
    let mut discrete: Vec<Option<Vec<Point>>> = (0..layout.edges.len())
        .into_par_iter()
        .map(|e| used[e].then(|| discretise(layout, e, counts.cells[e])))
        .collect();
    // The second copy of a periodic side: the first copy's interior nodes moved by the
    // translation (its end nodes stay exactly its own end vertices).
    for e in 0..layout.edges.len() {
        if let EdgeKind::Periodic {
            partner,
            translation,
        } = layout.edges[e].kind
        {
            let p = partner as usize;
            if p < e {
                if let (Some(src), Some(dst)) = (discrete[p].clone(), discrete[e].as_mut()) {
                    if src.len() == dst.len() {
                        let n = dst.len() - 1;
                        for i in 1..n {
                            dst[i] = [src[i][0] - translation.0[0], src[i][1] - translation.0[1]];
                        }
                    }
                }
            }
        }
    }

    // Blocks in parallel (on the current rayon pool), collected in block order; the first
    // error in block order is reported, so nothing depends on the thread count.
    let grids: Vec<Result<BlockGrid, GridError>> = layout
        .blocks
        .par_iter()
        .enumerate()
        .map(|(b, block)| {
            let side = |k: usize| {
                let s = &block.sides[k];
                let mut v = discrete[s.edge as usize].clone().unwrap_or_default();
                if s.reversed {
                    v.reverse();
                }
                v
            };
            tfi(&side(0), &side(1), &side(2), &side(3)).ok_or_else(|| {
                GridError::InvalidLayout(format!("block {b}: inconsistent side node counts"))
            })
        })
        .collect();
    grids.into_iter().collect()
}
