//! Inserted holes in exact mode (macro Delaunay refinement, paper Algorithm 3; issue #4).
//!
//! An inserted hole is fluid, not a wall. Around it the blocks are built like those of a real
//! circle (spokes from the exact medial nodes to their touching points on the hole's circle,
//! exactly radial), but with equal spacing along the spokes ([`FLUID_CLUSTERING`]): there is no
//! boundary layer to resolve. The hole is then filled by the O-grid / `k`-gon template of
//! [`crate::templates::fill_inserted_hole`], whose ring blocks take the hole's arcs as their
//! outer sides, so the template's perimeter nodes *are* the surrounding blocks' wall nodes.
//!
//! The template needs an even number `k >= 4` of arcs, none wider than
//! [`crate::blocking::MAX_TEMPLATE_SWEEP`]; `prepare` splits the widest arc on the hole at its
//! middle (an exact medial point with its two exact spokes) until that holds. Its node counts
//! tie arcs in pairs (the ladder of the core pairs opposite core edges, each core edge has its
//! arc's count): `tie_counts` gives every class of opposite sides one count, the largest its
//! arcs asked for, which also makes the hole's perimeter even.

use super::{internal, Clustering, ExactVertex, Piece};
use crate::blocking::MAX_TEMPLATE_SWEEP;
use crate::domain::CircleId;
use crate::geometry::Point;
use crate::grid::tfi;
use crate::layout::{BlockLayout, Curve};
use crate::mesh::BlockGrid;
use crate::mesher::MeshError;
use std::collections::HashMap;

/// Spokes on an inserted hole: equal spacing.
pub const FLUID_CLUSTERING: Clustering = Clustering {
    first: None,
    growth: 1.0,
};

/// The most arcs split around one inserted hole.
pub const MAX_SPLITS_PER_HOLE: usize = 16;

/// The pieces on each inserted hole, in increasing piece index: what a scan
/// `pieces.iter().enumerate().filter(|p| p.circles.contains(&c))` lists for an inserted hole
/// `c`, without the scan (issue 8: [`prepare`] ran it per inserted hole and per split,
/// O(holes x arcs)). Only the inserted holes get a list (one allocation per hole, not per
/// circle). Kept up to date by [`prepare`] as it appends split halves.
pub(crate) struct PiecesByCircle {
    /// Per circle slot (`c + 1`): its list in `lists`, or `usize::MAX` (not an inserted hole).
    list_of: Vec<usize>,
    lists: Vec<Vec<usize>>,
}

impl PiecesByCircle {
    /// The lists of the circles `is_fluid` marks (by circle slot).
    pub(crate) fn new(pieces: &[Piece], is_fluid: &[bool]) -> Self {
        let mut list_of = vec![usize::MAX; is_fluid.len()];
        let mut lists = Vec::new();
        for (slot, _) in is_fluid.iter().enumerate().filter(|x| *x.1) {
            list_of[slot] = lists.len();
            lists.push(Vec::new());
        }
        let mut index = PiecesByCircle { list_of, lists };
        for (e, p) in pieces.iter().enumerate() {
            index.push(e, p.circles);
        }
        index
    }
    /// Record piece `e` (larger than every recorded index) on its circles (once per circle).
    fn push(&mut self, e: usize, circles: [CircleId; 2]) {
        for (k, &c) in circles.iter().enumerate() {
            if k == 1 && circles[0] == c {
                continue;
            }
            if let Some(&i) = usize::try_from(c + 1)
                .ok()
                .and_then(|s| self.list_of.get(s))
            {
                if let Some(list) = self.lists.get_mut(i) {
                    list.push(e);
                }
            }
        }
    }
    /// The pieces on inserted hole `c` (empty for any other circle).
    fn on(&self, c: CircleId) -> &[usize] {
        usize::try_from(c + 1)
            .ok()
            .and_then(|s| self.list_of.get(s))
            .and_then(|&i| self.lists.get(i))
            .map_or(&[], |v| v.as_slice())
    }
}

/// Split arcs on inserted hole `c` (widest wall first) until it has an even number `k >= 4`
/// of arcs, none wider than [`MAX_TEMPLATE_SWEEP`] (bounded effort: the template reports what
/// is still wrong). A split arc's halves replace it (the first keeps its index, the second is
/// appended, and recorded in `index`) and the middle vertex is appended to `vertices`.
/// `is_fluid[c + 1]` tells the inserted holes. Returns the number of splits.
pub(crate) fn prepare(
    pieces: &mut Vec<Piece>,
    vertices: &mut Vec<ExactVertex>,
    c: CircleId,
    is_fluid: &[bool],
    index: &mut PiecesByCircle,
) -> usize {
    let fluid = |x: CircleId| {
        usize::try_from(x + 1)
            .ok()
            .and_then(|i| is_fluid.get(i).copied())
            .unwrap_or(false)
    };
    let mut splits = 0;
    for _ in 0..MAX_SPLITS_PER_HOLE {
        let on: Vec<(usize, f64)> = index
            .on(c)
            .iter()
            .filter_map(|&e| {
                let p = pieces.get(e)?;
                let side = p.circles.iter().position(|&x| x == c)?;
                Some((e, p.geom.sweep[side].abs()))
            })
            .collect();
        let k = on.len();
        let widest = on.iter().map(|x| x.1).fold(0.0, f64::max);
        if k.is_multiple_of(2) && k >= 4 && widest <= MAX_TEMPLATE_SWEEP {
            break;
        }
        // The widest arc on the hole whose middle is defined (ties: the smallest index). A
        // split adds an arc to both circles of the arc, so to fix an odd count prefer an arc
        // whose other circle is not another inserted hole (whose parity it would break).
        let other_fluid = |e: usize| pieces[e].circles.iter().any(|&x| x != c && fluid(x));
        let mut best: Option<(f64, usize)> = None;
        for pass in 0..2 {
            for &(e, w) in &on {
                let allowed = pass == 1 || k.is_multiple_of(2) || !other_fluid(e);
                if allowed && w > 0.0 && best.is_none_or(|(bw, _)| w > bw) {
                    best = Some((w, e));
                }
            }
            if best.is_some() {
                break;
            }
        }
        let Some((_, e)) = best else { break };
        let Some((m, a, rho, first, second)) = pieces[e].geom.split() else {
            break;
        };
        let v = vertices.len();
        vertices.push(ExactVertex {
            center: m,
            radius: rho,
            circles: pieces[e].circles.to_vec(),
            tangent: a.to_vec(),
        });
        let end = pieces[e].ends[1];
        let circles = pieces[e].circles;
        let slots = pieces[e].slots;
        let mid = circles.map(|x| vertices[v].slot(x).unwrap_or(0));
        pieces[e].ends[1] = v;
        pieces[e].slots = [[slots[0][0], mid[0]], [slots[1][0], mid[1]]];
        pieces[e].geom = first;
        pieces.push(Piece {
            ends: [v, end],
            circles,
            slots: [[mid[0], slots[0][1]], [mid[1], slots[1][1]]],
            geom: second,
        });
        index.push(pieces.len() - 1, circles);
        splits += 1;
    }
    splits
}

/// Give every conformity class of a layout (`classes`: its [`crate::grid::edge_classes`], opposite block
/// sides) one arc count, the largest of its arcs' (`medial_edge[e]` is the medial edge of arc
/// `e`).
pub(crate) fn tie_counts(classes: &(Vec<usize>, usize), medial_edge: &[u32], arc: &mut [usize]) {
    let (class, n) = (&classes.0, classes.1);
    let mut best = vec![0usize; n];
    for (e, &m) in medial_edge.iter().enumerate() {
        if let (Some(&k), Some(&c)) = (class.get(m as usize), arc.get(e)) {
            best[k] = best[k].max(c);
        }
    }
    for (e, &m) in medial_edge.iter().enumerate() {
        if let Some(&k) = class.get(m as usize) {
            arc[e] = best[k];
        }
    }
}

/// The grids of the template blocks `layout.blocks[first..]`: sides already gridded by the
/// medial blocks (`grids[b]` for `b < first`) are copied bit for bit, the straight template
/// edges get equally spaced nodes with their class's count (the gridded member's, else the
/// longest member's length over `h`, at least 1), and the interior is transfinite
/// interpolation. Errors when a class gets two different counts (a broken tie). `classes` are
/// the layout's [`crate::grid::edge_classes`] (computed once per build: the layout's edges and blocks do
/// not change after the templates are filled).
pub(crate) fn template_grids(
    layout: &BlockLayout,
    classes: &(Vec<usize>, usize),
    grids: &[BlockGrid],
    first: usize,
    h: f64,
) -> Result<Vec<BlockGrid>, MeshError> {
    let (class, ncls) = (&classes.0, classes.1);
    // The edges the template blocks lie on: only their gridded nodes are copied (copying
    // every gridded side of a large layout cost more than the templates themselves).
    let mut on_template = vec![false; layout.edges.len()];
    for block in layout.blocks.iter().skip(first) {
        for side in block.sides {
            if let Some(t) = on_template.get_mut(side.edge as usize) {
                *t = true;
            }
        }
    }
    let mut known: HashMap<usize, Vec<Point>> = HashMap::new();
    let mut count: Vec<Option<usize>> = vec![None; ncls];
    for (b, g) in grids.iter().enumerate().take(first) {
        for (k, side) in layout.blocks[b].sides.iter().enumerate() {
            let e = side.edge as usize;
            // Side k has ni cells (k even) or nj cells (k odd), as `g.side(k)` has nodes - 1.
            let n = if k % 2 == 0 { g.ni } else { g.nj };
            match count[class[e]] {
                Some(m) if m != n => {
                    return Err(internal(format!(
                        "template: edge {e} has {n} cells, its class {m}"
                    )))
                }
                _ => count[class[e]] = Some(n),
            }
            if on_template.get(e).copied().unwrap_or(false) {
                known.entry(e).or_insert_with(|| {
                    let mut nodes = g.side(k);
                    if side.reversed {
                        nodes.reverse();
                    }
                    nodes
                });
            }
        }
    }
    let vertex = |i: u32| layout.vertices.get(i as usize).copied().unwrap_or([0.0; 2]);
    let length = |e: usize| {
        let [a, b] = layout.edges[e].ends.map(vertex);
        (a[0] - b[0]).hypot(a[1] - b[1])
    };
    let mut free = vec![1usize; ncls];
    for block in &layout.blocks[first..] {
        for side in block.sides {
            let e = side.edge as usize;
            let want = (length(e) / h).round();
            if want.is_finite() && want >= 1.0 {
                let want = (want as usize).min(crate::grid::MAX_CELLS_PER_SIDE);
                free[class[e]] = free[class[e]].max(want);
            }
        }
    }
    let mut out = Vec::with_capacity(layout.blocks.len() - first);
    for block in &layout.blocks[first..] {
        let mut sides: Vec<Vec<Point>> = Vec::with_capacity(4);
        for side in block.sides {
            let e = side.edge as usize;
            let mut nodes = match known.get(&e) {
                Some(n) => n.clone(),
                None => {
                    if !matches!(layout.edges[e].curve, Curve::Segment) {
                        return Err(internal(format!("template edge {e} is not straight")));
                    }
                    let n = count[class[e]].unwrap_or(free[class[e]]);
                    let [a, b] = layout.edges[e].ends.map(vertex);
                    let mut pts: Vec<Point> = (0..=n)
                        .map(|i| {
                            let t = i as f64 / n as f64;
                            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
                        })
                        .collect();
                    pts[0] = a;
                    pts[n] = b;
                    known.insert(e, pts.clone());
                    pts
                }
            };
            if side.reversed {
                nodes.reverse();
            }
            sides.push(nodes);
        }
        let g = tfi(&sides[0], &sides[1], &sides[2], &sides[3])
            .ok_or_else(|| internal("template: opposite sides of different counts".into()))?;
        out.push(g);
    }
    Ok(out)
}
