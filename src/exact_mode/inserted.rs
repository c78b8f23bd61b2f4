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
//! tie arcs in pairs (the ladder or grid of the core pairs opposite core edges, each core edge
//! has its arc's count): `tie_counts` gives every class of opposite sides one count, the
//! largest its arcs asked for, which also makes the hole's perimeter even.

use super::{internal, Clustering, ExactVertex, Piece};
use crate::blocking::MAX_TEMPLATE_SWEEP;
use crate::domain::CircleId;
use crate::geometry::Point;
use crate::grid::tfi;
use crate::layout::{BlockLayout, Curve};
use crate::mesh::BlockGrid;
use crate::mesher::MeshError;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::Relaxed};

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
        if index.lists.is_empty() {
            return index;
        }
        // The pieces on an inserted hole are few: found on the pool (a serial pass read every
        // piece, 18 ms on one CPU at 1e5 particles, issue 8), recorded in piece order.
        let on_fluid: Vec<(usize, [CircleId; 2])> = pieces
            .par_iter()
            .enumerate()
            .with_min_len(crate::tasks::ARCS)
            .filter(|(_, p)| p.circles.iter().any(|&c| marked(is_fluid, c)))
            .map(|(e, p)| (e, p.circles))
            .collect();
        for (e, circles) in on_fluid {
            index.push(e, circles);
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

/// Whether circle `x` is marked in `is_fluid` (by circle slot `x + 1`): an inserted hole.
fn marked(is_fluid: &[bool], x: CircleId) -> bool {
    usize::try_from(x + 1)
        .ok()
        .and_then(|i| is_fluid.get(i).copied())
        .unwrap_or(false)
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
    let fluid = |x: CircleId| marked(is_fluid, x);
    let mut splits = 0;
    for _ in 0..MAX_SPLITS_PER_HOLE {
        let on = sweeps_on(pieces, c, index);
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
        if !split_piece(pieces, vertices, e, index) {
            break;
        }
        splits += 1;
    }
    splits
}

/// Split piece `e` at its middle (an exact medial point with its two exact spokes): the first
/// half keeps index `e`, the second is appended (and recorded in `index`), the middle vertex
/// is appended to `vertices`. False (nothing changed) when the middle is not defined.
fn split_piece(
    pieces: &mut Vec<Piece>,
    vertices: &mut Vec<ExactVertex>,
    e: usize,
    index: &mut PiecesByCircle,
) -> bool {
    let Some((m, a, rho, first, second)) = pieces.get(e).and_then(|p| p.geom.split()) else {
        return false;
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
    true
}

/// The pieces on inserted hole `c` with their sweep on `c` (absolute, radians).
fn sweeps_on(pieces: &[Piece], c: CircleId, index: &PiecesByCircle) -> Vec<(usize, f64)> {
    index
        .on(c)
        .iter()
        .filter_map(|&e| {
            let p = pieces.get(e)?;
            let side = p.circles.iter().position(|&x| x == c)?;
            Some((e, p.geom.sweep[side].abs()))
        })
        .collect()
}

/// Whether inserted hole `c` fits its template: an even number `k >= 4` of arcs, none wider
/// than [`MAX_TEMPLATE_SWEEP`].
pub(crate) fn fits(pieces: &[Piece], c: CircleId, index: &PiecesByCircle) -> bool {
    let on = sweeps_on(pieces, c, index);
    let widest = on.iter().map(|x| x.1).fold(0.0, f64::max);
    on.len().is_multiple_of(2) && on.len() >= 4 && widest <= MAX_TEMPLATE_SWEEP
}

/// Make every inserted hole of `holes` fit its template together, where [`prepare`] hole by
/// hole did not (it splits greedily per hole, and a split between two inserted holes flips the
/// parity of both: two small holes in a large disk get a dozen inserted holes around them,
/// mostly beside each other, and the per-hole rounds ended with a hole of 11 arcs). The two
/// phases of the paper pipeline's joint preparation (`blocking::prepare_inserted_holes_jointly`):
/// 1. widths: on each hole, split its widest arc until it has at least 4, none wider than
///    [`MAX_TEMPLATE_SWEEP`] (a split only adds arcs and halves sweeps, so later splits keep
///    this);
/// 2. parity: from each hole left with an odd count, a breadth-first search over splittable
///    pieces (widest first) to an input circle or the bounding circle (which need no parity)
///    or another inserted hole with an odd count; splitting one piece on each step of the path
///    flips the parity of its two ends only (inner holes gain two arcs each).
///
/// Returns the number of splits.
pub(crate) fn prepare_jointly(
    pieces: &mut Vec<Piece>,
    vertices: &mut Vec<ExactVertex>,
    holes: &[CircleId],
    is_fluid: &[bool],
    index: &mut PiecesByCircle,
) -> usize {
    let fluid = |x: CircleId| marked(is_fluid, x);
    let widest_first = |a: &(usize, f64), b: &(usize, f64)| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0));
    let mut splits = 0;
    for &c in holes {
        for _ in 0..MAX_SPLITS_PER_HOLE {
            let on = sweeps_on(pieces, c, index);
            let widest = on.iter().map(|x| x.1).fold(0.0, f64::max);
            if on.len() >= 4 && widest <= MAX_TEMPLATE_SWEEP {
                break;
            }
            // The widest arc (ties: the smallest index) that can be split.
            let mut order: Vec<(usize, f64)> = on.into_iter().filter(|x| x.1 > 0.0).collect();
            order.sort_by(widest_first);
            if !order
                .iter()
                .any(|&(e, _)| split_piece(pieces, vertices, e, index))
            {
                break;
            }
            splits += 1;
        }
    }
    let odd = |index: &PiecesByCircle, c: CircleId| !index.on(c).len().is_multiple_of(2);
    for &hole in holes {
        if !odd(index, hole) {
            continue;
        }
        // Breadth-first search from `hole`; `parent[c]` = (previous circle, piece).
        let mut parent: HashMap<CircleId, (CircleId, usize)> = HashMap::new();
        let mut queue = std::collections::VecDeque::from([hole]);
        let mut found = None;
        'search: while let Some(c) = queue.pop_front() {
            let mut next = sweeps_on(pieces, c, index);
            next.sort_by(widest_first);
            for (e, w) in next {
                let Some(&other) = pieces[e].circles.iter().find(|&&x| x != c) else {
                    continue;
                };
                if w <= 0.0 || other == hole || parent.contains_key(&other) {
                    continue;
                }
                if pieces[e].geom.split().is_none() {
                    continue;
                }
                parent.insert(other, (c, e));
                if !fluid(other) || odd(index, other) {
                    found = Some(other);
                    break 'search;
                }
                queue.push_back(other);
            }
        }
        let Some(mut c) = found else { continue };
        let mut path = Vec::new();
        while c != hole {
            let Some(&(prev, e)) = parent.get(&c) else {
                break;
            };
            path.push(e);
            c = prev;
        }
        // From `hole` outwards (a split keeps the other pieces' indices).
        for e in path.into_iter().rev() {
            if split_piece(pieces, vertices, e, index) {
                splits += 1;
            }
        }
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

/// Per conformity class, the count [`template_grids`] gives a straight template edge whose
/// class has no gridded member: the longest member's length over `h`, rounded, at least 1 and
/// at most [`crate::grid::MAX_CELLS_PER_SIDE`].
fn free_counts(
    layout: &BlockLayout,
    classes: &(Vec<usize>, usize),
    first: usize,
    h: f64,
) -> Vec<usize> {
    free_counts_at(layout, classes, first, h, classes.1, Some)
}

/// [`free_counts`] of the classes `k` with an entry `at(k)` below `n` only, in that entry.
fn free_counts_at(
    layout: &BlockLayout,
    classes: &(Vec<usize>, usize),
    first: usize,
    h: f64,
    n: usize,
    at: impl Fn(usize) -> Option<usize>,
) -> Vec<usize> {
    let class = &classes.0;
    let vertex = |i: u32| layout.vertices.get(i as usize).copied().unwrap_or([0.0; 2]);
    let length = |e: usize| {
        let [a, b] = layout.edges[e].ends.map(vertex);
        (a[0] - b[0]).hypot(a[1] - b[1])
    };
    let mut free = vec![1usize; n];
    for block in layout.blocks.iter().skip(first) {
        for side in block.sides {
            let e = side.edge as usize;
            let want = (length(e) / h).round();
            if want.is_finite() && want >= 1.0 {
                let want = (want as usize).min(crate::grid::MAX_CELLS_PER_SIDE);
                if let Some(f) = class.get(e).and_then(|&k| free.get_mut(at(k)?)) {
                    *f = (*f).max(want);
                }
            }
        }
    }
    free
}

/// The conformity class of edge `e` (`classes` as [`crate::grid::edge_classes`] gives them),
/// if it has one in range.
fn class_of(classes: &(Vec<usize>, usize), e: u32) -> Option<usize> {
    classes
        .0
        .get(e as usize)
        .copied()
        .filter(|&x| x < classes.1)
}

/// Medial blocks per leaf of [`TemplateSides::new`]'s parallel scan.
const SCAN_BLOCKS: usize = 8192;

/// What [`template_nodes`] reads of a layout besides the counts, found once per layout (the
/// counts change with the target size; this does not): the conformity classes of the
/// templates' sides 0 and 1 (the only ones whose counts it reads), and the last medial block
/// side in each, in block then side order (whose count fixes the class's, as
/// [`template_grids`] reads them).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct TemplateSides {
    /// The classes, sorted.
    needed: Vec<usize>,
    /// Per class of `needed`: the last medial (block, side) in it.
    last: Vec<Option<(usize, usize)>>,
}

impl TemplateSides {
    /// The template sides of `layout` (`classes` its [`crate::grid::edge_classes`]), whose
    /// blocks from `first` on are templates. The medial blocks are scanned in parallel
    /// (issue 8: a table over every class, filled from every medial block on one CPU, took
    /// 22 ms at 1e5 bubbles, at each target size tried).
    pub(crate) fn new(
        layout: &BlockLayout,
        classes: &(Vec<usize>, usize),
        first: usize,
    ) -> TemplateSides {
        let ncls = classes.1;
        let class_of = |e: u32| class_of(classes, e);
        let mut needed: Vec<usize> = layout
            .blocks
            .get(first..)
            .unwrap_or(&[])
            .iter()
            .flat_map(|b| [b.sides[0].edge, b.sides[1].edge])
            .filter_map(class_of)
            .collect();
        needed.sort_unstable();
        needed.dedup();
        let mut wanted = vec![0u64; ncls.div_ceil(64)];
        for &x in &needed {
            wanted[x / 64] |= 1 << (x % 64);
        }
        let medial = &layout.blocks[..first.min(layout.blocks.len())];
        // The medial sides in a needed class, in block then side order: (its entry in
        // `needed`, block, side).
        let hits: Vec<(usize, usize, usize)> = medial
            .par_chunks(SCAN_BLOCKS)
            .enumerate()
            .flat_map_iter(|(c, chunk)| {
                let (wanted, needed) = (&wanted, &needed);
                chunk.iter().enumerate().flat_map(move |(j, block)| {
                    block.sides.iter().enumerate().filter_map(move |(k, side)| {
                        let x = class_of(side.edge)?;
                        if wanted[x / 64] >> (x % 64) & 1 == 0 {
                            return None;
                        }
                        Some((needed.binary_search(&x).ok()?, c * SCAN_BLOCKS + j, k))
                    })
                })
            })
            .collect();
        let mut last = vec![None; needed.len()];
        for (i, b, k) in hits {
            last[i] = Some((b, k));
        }
        TemplateSides { needed, last }
    }
}

/// The grid nodes [`template_grids`] will make for the template blocks `layout.blocks[first..]`
/// (saturating), before any grid exists: `side_count(b, k)` is the cell count of side `k` of
/// medial block `b < first`, which fixes the count of its class (`sides`, found by
/// [`TemplateSides::new`] from the same layout, classes and `first`); the other classes get
/// their free count ([`free_counts`]). For the node limit of exact mode (the templates of a
/// tiny target size can outweigh every other block). The same count as filling a table over
/// every class (`template_nodes_reference`, the tests' reference).
pub(crate) fn template_nodes(
    layout: &BlockLayout,
    classes: &(Vec<usize>, usize),
    sides: &TemplateSides,
    first: usize,
    h: f64,
    side_count: impl Fn(usize, usize) -> usize,
) -> usize {
    let needed = &sides.needed;
    let at = |x: usize| needed.binary_search(&x).ok();
    let free = free_counts_at(layout, classes, first, h, needed.len(), at);
    let cells = |e: u32| match class_of(classes, e).and_then(at) {
        Some(i) => sides.last[i].map_or(free[i], |(b, k)| side_count(b, k)),
        None => 1,
    };
    layout
        .blocks
        .get(first..)
        .unwrap_or(&[])
        .iter()
        .map(|b| (cells(b.sides[0].edge) + 1).saturating_mul(cells(b.sides[1].edge) + 1))
        .fold(0usize, usize::saturating_add)
}

/// [`template_nodes`] with a table over every class, filled from every medial block in order
/// (the tests' reference).
#[cfg(test)]
fn template_nodes_reference(
    layout: &BlockLayout,
    classes: &(Vec<usize>, usize),
    first: usize,
    h: f64,
    side_count: impl Fn(usize, usize) -> usize,
) -> usize {
    let (class, ncls) = (&classes.0, classes.1);
    let mut count: Vec<Option<usize>> = vec![None; ncls];
    for (b, block) in layout.blocks.iter().enumerate().take(first) {
        for (k, side) in block.sides.iter().enumerate() {
            if let Some(c) = class
                .get(side.edge as usize)
                .and_then(|&x| count.get_mut(x))
            {
                *c = Some(side_count(b, k));
            }
        }
    }
    let free = free_counts(layout, classes, first, h);
    let cells = |e: u32| {
        class.get(e as usize).map_or(1, |&x| {
            count
                .get(x)
                .copied()
                .flatten()
                .unwrap_or_else(|| free.get(x).copied().unwrap_or(1))
        })
    };
    layout
        .blocks
        .iter()
        .skip(first)
        .map(|b| (cells(b.sides[0].edge) + 1).saturating_mul(cells(b.sides[1].edge) + 1))
        .fold(0usize, usize::saturating_add)
}

/// Per edge of `layout`: true when a template block (block `first` on) lies on it.
pub(crate) fn template_edges(layout: &BlockLayout, first: usize) -> Vec<bool> {
    let mut on_template = vec![false; layout.edges.len()];
    for block in layout.blocks.iter().skip(first) {
        for side in block.sides {
            if let Some(t) = on_template.get_mut(side.edge as usize) {
                *t = true;
            }
        }
    }
    on_template
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
    let on_template = template_edges(layout, first);
    // Every class's count from the medial blocks' grids, and their sides on template edges,
    // in parallel (2.4 M sides at 1e5 particles: 10 ms on one thread, issue 8). The counts
    // of a class agree (else an internal error, the one the block-order loop meets first), so
    // whichever side records a class's count records the same.
    const UNSET: usize = usize::MAX;
    let medial = first.min(grids.len());
    let seen: Vec<AtomicUsize> = (0..ncls).map(|_| AtomicUsize::new(UNSET)).collect();
    let clash = AtomicBool::new(false);
    let (seen_ref, clash_ref, on_template_ref) = (&seen, &clash, &on_template);
    let on_templates: Vec<(usize, usize)> = (0..medial)
        .into_par_iter()
        .with_max_len(crate::tasks::BLOCKS)
        .flat_map_iter(|b| {
            let g = &grids[b];
            let sides = &layout.blocks[b].sides;
            (0..4).filter_map(move |k| {
                let e = sides[k].edge as usize;
                let n = side_cells(g, k);
                match seen_ref[class[e]].compare_exchange(UNSET, n, Relaxed, Relaxed) {
                    Err(m) if m != n => clash_ref.store(true, Relaxed),
                    _ => {}
                }
                on_template_ref
                    .get(e)
                    .copied()
                    .unwrap_or(false)
                    .then_some((b, k))
            })
        })
        .collect();
    if clash.into_inner() {
        return Err(first_clash(layout, class, ncls, &grids[..medial]));
    }
    let count: Vec<Option<usize>> = seen
        .into_iter()
        .map(|n| Some(n.into_inner()).filter(|&n| n != UNSET))
        .collect();
    let mut known: HashMap<usize, Vec<Point>> = HashMap::new();
    for (b, k) in on_templates {
        let side = layout.blocks[b].sides[k];
        known.entry(side.edge as usize).or_insert_with(|| {
            let mut nodes = grids[b].side(k);
            if side.reversed {
                nodes.reverse();
            }
            nodes
        });
    }
    let vertex = |i: u32| layout.vertices.get(i as usize).copied().unwrap_or([0.0; 2]);
    let free = free_counts(layout, classes, first, h);
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

/// Side `k` of grid `g` has `ni` cells (`k` even) or `nj` (`k` odd), as `g.side(k)` has
/// nodes - 1.
fn side_cells(g: &BlockGrid, k: usize) -> usize {
    if k.is_multiple_of(2) {
        g.ni
    } else {
        g.nj
    }
}

/// The error of [`template_grids`] when two sides of a class have different counts: the
/// first side, in block order, whose count differs from its class's first.
fn first_clash(
    layout: &BlockLayout,
    class: &[usize],
    ncls: usize,
    grids: &[BlockGrid],
) -> MeshError {
    let mut count: Vec<Option<usize>> = vec![None; ncls];
    for (b, g) in grids.iter().enumerate() {
        for (k, side) in layout.blocks[b].sides.iter().enumerate() {
            let e = side.edge as usize;
            let n = side_cells(g, k);
            match count[class[e]] {
                Some(m) if m != n => {
                    return internal(format!("template: edge {e} has {n} cells, its class {m}"))
                }
                _ => count[class[e]] = Some(n),
            }
        }
    }
    internal("template: sides of a class with different counts".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two tiny holes far inside the bounding circle: refinement inserts holes around them,
    /// so the mesh has template blocks.
    fn tiny_holes_mesh() -> crate::mesh::Mesh {
        let d = crate::Domain::from_json_str(
            r#"{"bounding":{"center":[0,0],"radius":10},"holes":[{"center":[0,0],"radius":0.003},{"center":[0.009,0],"radius":0.0018}]}"#,
        )
        .unwrap();
        let opts = crate::Options {
            block_cells: Some(3),
            ..crate::Options::default()
        };
        crate::mesh(&d, &opts).unwrap()
    }

    /// Medial grids whose counts disagree within a class (here: one medial block given one
    /// cell more along its wall, whose class its partner blocks share) are refused with the
    /// first disagreeing side in block order, whichever thread met a side first.
    #[test]
    fn template_grids_refuse_classes_that_disagree() {
        let m = tiny_holes_mesh();
        let first = m.grids.len() - m.template_blocks;
        let classes = crate::grid::edge_classes(&m.layout);
        assert!(template_grids(&m.layout, &classes, &m.grids, first, 1.0).is_ok());
        for b in [0, first / 2, first - 1] {
            let mut grids = m.grids.clone();
            grids[b].ni += 1;
            // The block-order loop's answer: the first side whose class saw another count.
            let mut count: Vec<Option<usize>> = vec![None; classes.1];
            let mut want = None;
            'scan: for (c, g) in grids.iter().enumerate().take(first) {
                for (k, side) in m.layout.blocks[c].sides.iter().enumerate() {
                    let e = side.edge as usize;
                    let n = if k % 2 == 0 { g.ni } else { g.nj };
                    match count[classes.0[e]] {
                        Some(x) if x != n => {
                            want = Some(format!("template: edge {e} has {n} cells, its class {x}"));
                            break 'scan;
                        }
                        _ => count[classes.0[e]] = Some(n),
                    }
                }
            }
            let want = want.expect("a class with two counts");
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| template_grids(&m.layout, &classes, &grids, first, 1.0));
                match got {
                    Err(MeshError::Internal(msg)) => assert!(msg.contains(&want), "{msg}"),
                    other => panic!("block {b}: {:?}", other.map(|g| g.len())),
                }
            }
        }
    }

    /// [`template_nodes`] counts, before any grid exists, exactly the nodes [`template_grids`]
    /// then makes, for target sizes from far coarser to far finer than the mesh's own (the
    /// node limit of exact mode relies on it).
    #[test]
    fn template_nodes_predicts_the_template_grids() {
        let m = tiny_holes_mesh();
        assert!(m.template_blocks > 0);
        let first = m.grids.len() - m.template_blocks;
        let classes = crate::grid::edge_classes(&m.layout);
        let side_count = |b: usize, k: usize| {
            let g = &m.grids[b];
            if k.is_multiple_of(2) {
                g.ni
            } else {
                g.nj
            }
        };
        // Found once per layout, whatever the target size.
        let sides = TemplateSides::new(&m.layout, &classes, first);
        for h in [1e3, 1.0, 0.05, 1e-3, 1e-5] {
            let made = template_grids(&m.layout, &classes, &m.grids, first, h).unwrap();
            let nodes: usize = made.iter().map(|g| g.nodes.len()).sum();
            assert_eq!(
                template_nodes(&m.layout, &classes, &sides, first, h, side_count),
                nodes,
                "h = {h}"
            );
            assert_eq!(
                template_nodes_reference(&m.layout, &classes, first, h, side_count),
                nodes,
                "h = {h}"
            );
        }
    }
}
