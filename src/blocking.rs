//! Blocking2D (paper section 3, Algorithm 2): two blocks per medial arc.
//!
//! For a medial arc from vertex `m0` to `m1` with sample chains `C1` (on circle `A`, on the
//! right of the walk) and `C2` (on circle `B`, on the left), the pair of blocks is, with the
//! conventions of [`crate::layout`] (corners counter-clockwise, side `k` from corner `k` to
//! `k + 1`):
//!
//! ```text
//! block on A: corners [C1.first, C1.last, m1, m0]
//!             sides   [wall A (C1 forward), spoke(m1 -> C1.last) reversed,
//!                      medial (m0 -> m1) reversed, spoke(m0 -> C1.first)]
//! block on B: corners [C2.last, C2.first, m0, m1]
//!             sides   [wall B (C2 backward), spoke(m0 -> C2.first) reversed,
//!                      medial (m0 -> m1), spoke(m1 -> C2.last)]
//! ```
//!
//! Side 0 is the wall (the paper's xi1 curve): an arc of the *true* circle between the two
//! samples, with the fluid on the block's left, so it runs clockwise about a hole's centre
//! (negative sweep) and counter-clockwise about the bounding circle's (positive sweep). Side 2
//! is the medial arc (xi0), a polyline of circumcentres stored once from `m0` to `m1` and
//! shared by the pair. Sides 1 and 3 are spokes (eta curves), straight segments stored once
//! from the medial vertex to the sample and shared by the two blocks on that sample's circle
//! meeting at that medial vertex. Layout vertices: the medial vertices first (vertex `i` is
//! medial vertex `i`), then one per sample used as a corner, in order of first use.

use crate::domain::{Circle, CircleId, Domain};
use crate::geometry::{Point, Triangulation};
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use crate::medial::{MedialGraph, TriangleKind};
use crate::mesher::{MeshError, Options};
use crate::sampling::{sample_and_triangulate, Samples, SamplingOptions};
use std::collections::HashMap;
use std::f64::consts::TAU;

mod pairs;
use pairs::blocks_reusing;
#[doc(hidden)]
pub use pairs::{blocks_in_waves, blocks_one_by_one};

/// Everything the front end of the pipeline produced.
#[derive(Debug, Clone)]
pub struct Blocking {
    /// The blocks (two per medial arc: block `2e` on the arc's `C1` circle, `2e + 1` on its
    /// `C2` circle).
    pub layout: BlockLayout,
    /// The medial graph (its counts are the medial counts of the mesh).
    pub medial: MedialGraph,
    /// The boundary samples.
    pub samples: Samples,
    /// The Delaunay triangulation of the samples.
    pub triangulation: Triangulation,
    /// The class of each triangle.
    pub kinds: Vec<TriangleKind>,
    /// For each layout vertex, the sample it stands for (`None` for medial vertices).
    pub vertex_samples: Vec<Option<u32>>,
    /// Resampling rounds the sampling needed.
    pub rounds: usize,
    /// Arcs left with a single-sample (zero-length) wall: see
    /// [`crate::sampling::thin_walls`].
    pub thin_walls: Vec<crate::sampling::Violation>,
}

/// Run the front end for a domain with at least two holes: sampling with invariant checks
/// and resampling, exact Delaunay triangulation, classification, medial graph (Algorithm 1)
/// and Blocking2D (Algorithm 2), with the default [`SamplingOptions`].
///
/// Errors: [`MeshError::Options`] when the domain has fewer than two holes (the disk and
/// the annulus have no medial vertex and are meshed by templates), [`MeshError::Sampling`]
/// and [`MeshError::Triangulation`] from sampling, [`MeshError::Internal`] for a broken
/// invariant. Never panics.
pub fn build_layout(domain: &Domain, options: &Options) -> Result<Blocking, MeshError> {
    build_layout_with(domain, options, &SamplingOptions::default())
}

/// [`build_layout`] with explicit sampling options.
pub fn build_layout_with(
    domain: &Domain,
    options: &Options,
    sampling: &SamplingOptions,
) -> Result<Blocking, MeshError> {
    let _ = options;
    let h = domain.hole_count();
    if h < 2 {
        return Err(MeshError::Options(format!(
            "medial blocking needs at least 2 holes, the domain has {h} (use the disk/annulus \
             templates)"
        )));
    }
    let sampled = sample_and_triangulate(domain, sampling)?;
    let (layout, vertex_samples) = blocks(domain, &sampled.samples, &sampled.medial)?;
    Ok(Blocking {
        layout,
        medial: sampled.medial,
        rounds: sampled.rounds,
        thin_walls: sampled.thin_walls,
        samples: sampled.samples,
        triangulation: sampled.triangulation,
        kinds: sampled.kinds,
        vertex_samples,
    })
}

/// The wall arc of a chain of consecutive samples on one circle, in side direction.
/// Checks that every step goes the same way round and that the way is `expected` (`-1`
/// clockwise, `+1` counter-clockwise) when the chain has at least one step.
fn wall_curve(
    domain: &Domain,
    samples: &Samples,
    circle: CircleId,
    chain: &[u32],
    expected: i64,
) -> Result<Curve, MeshError> {
    let c = domain.circle(circle);
    let first = *chain
        .first()
        .ok_or_else(|| MeshError::Internal("empty wall chain".into()))?;
    let n = samples.count_of(first) as i64;
    let grid = samples.grid_count(circle);
    let mut dir = 0i64;
    let mut grid_steps = 0u64;
    for w in chain.windows(2) {
        let (i, j) = (
            samples.index_of[w[0] as usize] as i64,
            samples.index_of[w[1] as usize] as i64,
        );
        let step = step_between(i, j, n);
        if step == 0 || (dir != 0 && step != dir) || samples.circle_of[w[1] as usize] != circle {
            return Err(MeshError::Internal(format!(
                "wall chain on circle {circle} is not a run of consecutive samples"
            )));
        }
        dir = step;
        let (g0, g1) = (samples.grid_index(w[0]), samples.grid_index(w[1]));
        let (from, to) = if step > 0 { (g0, g1) } else { (g1, g0) };
        grid_steps += grid_distance(from, to, grid);
    }
    if dir != 0 && dir != expected {
        return Err(MeshError::Internal(format!(
            "wall on circle {circle} runs the wrong way round"
        )));
    }
    Ok(Curve::Arc {
        center: c.center,
        radius: c.radius,
        start: samples.angle(first),
        sweep: dir as f64 * grid_steps as f64 * TAU / grid as f64,
    })
}

/// `1` when `j` follows `i` counter-clockwise on a circle of `n` samples (`(i + 1) % n == j`),
/// `-1` when it precedes it (`(j + 1) % n == i`), else `0`. Indices in `0..n` take the branch
/// without a division (a wall walk does one per sample, issue 8).
fn step_between(i: i64, j: i64, n: i64) -> i64 {
    if (0..n).contains(&i) && (0..n).contains(&j) {
        let last = n - 1;
        if j == if i == last { 0 } else { i + 1 } {
            1
        } else if i == if j == last { 0 } else { j + 1 } {
            -1
        } else {
            0
        }
    } else if (i + 1) % n == j {
        1
    } else if (j + 1) % n == i {
        -1
    } else {
        0
    }
}

/// The grid steps counter-clockwise from `from` to `to` on a grid of `grid` points:
/// `(to % grid + grid - from % grid) % grid`, without a division for indices below `grid`.
fn grid_distance(from: u64, to: u64, grid: u64) -> u64 {
    if from < grid && to < grid {
        if to >= from {
            to - from
        } else {
            to + grid - from
        }
    } else {
        (to % grid + grid - from % grid) % grid
    }
}

/// Blocking2D (Algorithm 2) on a medial graph: the layout and, per layout vertex, the sample
/// it stands for.
pub fn blocks(
    domain: &Domain,
    samples: &Samples,
    medial: &MedialGraph,
) -> Result<(BlockLayout, Vec<Option<u32>>), MeshError> {
    blocks_reusing(domain, samples, medial, None)
}

/// The points of edge `e` along a block side, into `pts` (cleared first; one buffer reused over
/// every block): end vertices exactly, arcs at 8 equal angle
/// steps, polylines through their points; in the side's direction.
fn side_points_into(layout: &BlockLayout, side: SideRef, pts: &mut Vec<Point>) {
    pts.clear();
    let Some(edge) = layout.edges.get(side.edge as usize) else {
        return;
    };
    let v = |i: u32| layout.vertices.get(i as usize).copied().unwrap_or([0.0; 2]);
    match &edge.curve {
        Curve::Segment => pts.extend([v(edge.ends[0]), v(edge.ends[1])]),
        Curve::Arc {
            center,
            radius,
            start,
            sweep,
        } => pts.extend((0..=8).map(|k| {
            let a = start + sweep * k as f64 / 8.0;
            [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
        })),
        Curve::Polyline(p) => pts.extend_from_slice(p),
    }
    if let Some(first) = pts.first_mut() {
        *first = v(edge.ends[0]);
    }
    if let Some(last) = pts.last_mut() {
        *last = v(edge.ends[1]);
    }
    if side.reversed {
        pts.reverse();
    }
}

/// The signed area of block `b`'s outline (its four sides, arcs sampled at 8 steps): positive
/// for a valid counter-clockwise block, zero for a collapsed one. `0` for a bad index.
pub fn block_area(layout: &BlockLayout, b: usize) -> f64 {
    block_area_with(layout, b, &mut Vec::new(), &mut Vec::new())
}

/// [`block_area`] with caller-owned buffers (a loop over every block allocates nothing).
pub(crate) fn block_area_with(
    layout: &BlockLayout,
    b: usize,
    pts: &mut Vec<Point>,
    outline: &mut Vec<Point>,
) -> f64 {
    let Some(block) = layout.blocks.get(b) else {
        return 0.0;
    };
    outline.clear();
    for s in block.sides {
        side_points_into(layout, s, pts);
        outline.extend_from_slice(&pts[..pts.len().saturating_sub(1)]);
    }
    let n = outline.len();
    if n < 3 {
        return 0.0;
    }
    let o = outline[0];
    let mut twice = 0.0;
    for k in 1..n - 1 {
        let (a, c) = (outline[k], outline[k + 1]);
        twice += (a[0] - o[0]) * (c[1] - o[1]) - (a[1] - o[1]) * (c[0] - o[0]);
    }
    0.5 * twice
}

/// Split edge `e` at the new vertex `v`: `e` keeps `ends[0] -> v`, a new edge `v -> ends[1]`
/// is appended; returns its id. `first` / `second` are the two curves.
fn split_edge(layout: &mut BlockLayout, e: usize, v: u32, first: Curve, second: Curve) -> u32 {
    let end = layout.edges[e].ends[1];
    let kind = layout.edges[e].kind;
    layout.edges[e].ends[1] = v;
    layout.edges[e].curve = first;
    layout.edges.push(Edge {
        ends: [v, end],
        curve: second,
        kind,
    });
    (layout.edges.len() - 1) as u32
}

/// The side reference running `from -> to` along edge `a` or `b`.
fn piece(layout: &BlockLayout, a: u32, b: u32, from: u32, to: u32) -> Option<SideRef> {
    for e in [a, b] {
        let ends = layout.edges[e as usize].ends;
        if ends == [from, to] {
            return Some(SideRef {
                edge: e,
                reversed: false,
            });
        }
        if ends == [to, from] {
            return Some(SideRef {
                edge: e,
                reversed: true,
            });
        }
    }
    None
}

/// The point at half the length of a polyline, and the two halves (each with both ends).
fn halve_polyline(pts: &[Point]) -> Option<(Point, Vec<Point>, Vec<Point>)> {
    let total: f64 = pts
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let mut acc = 0.0;
    for (i, w) in pts.windows(2).enumerate() {
        let l = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        if acc + l >= 0.5 * total && l > 0.0 {
            let t = ((0.5 * total - acc) / l).clamp(0.0, 1.0);
            let m = [
                w[0][0] + t * (w[1][0] - w[0][0]),
                w[0][1] + t * (w[1][1] - w[0][1]),
            ];
            let mut a = pts[..=i].to_vec();
            a.push(m);
            let mut b = vec![m];
            b.extend_from_slice(&pts[i + 1..]);
            return Some((m, a, b));
        }
        acc += l;
    }
    None
}

/// The blocks whose side 2 is edge `e`.
fn blocks_on_medial(layout: &BlockLayout, e: u32) -> Vec<usize> {
    (0..layout.blocks.len())
        .filter(|&b| layout.blocks[b].sides[2].edge == e)
        .collect()
}

/// Sweep of a block's side-0 arc (`None` when it is not an arc).
fn wall_sweep(layout: &BlockLayout, b: usize) -> Option<f64> {
    let e = layout.blocks[b].sides[0].edge as usize;
    match layout.edges.get(e)?.curve {
        Curve::Arc { sweep, .. } => Some(sweep),
        _ => None,
    }
}

/// Split the two medial blocks on medial edge `e` (side 2 of both) into four: a new vertex at
/// half the medial arc's length, one at half of each wall arc's sweep, and a straight spoke
/// from the first to each of the others. Every other block is unchanged; node counts stay
/// conforming (the new spokes join the spoke classes of the two circles). `None` (layout
/// unchanged) when `e` does not have exactly two medial blocks with arc walls, or the medial
/// arc has zero length.
pub fn split_block_pair(layout: &mut BlockLayout, e: u32) -> Option<()> {
    let pair = blocks_on_medial(layout, e);
    if pair.len() != 2 || pair.iter().any(|&b| wall_sweep(layout, b).is_none()) {
        return None;
    }
    let pts = match &layout.edges.get(e as usize)?.curve {
        Curve::Polyline(p) => p.clone(),
        Curve::Segment => {
            let ends = layout.edges[e as usize].ends;
            vec![
                layout.vertices[ends[0] as usize],
                layout.vertices[ends[1] as usize],
            ]
        }
        Curve::Arc { .. } => return None,
    };
    let (m, first, second) = halve_polyline(&pts)?;
    layout.vertices.push(m);
    let mv = (layout.vertices.len() - 1) as u32;
    let e2 = split_edge(
        layout,
        e as usize,
        mv,
        Curve::Polyline(first),
        Curve::Polyline(second),
    );
    for b in pair {
        let block = layout.blocks[b].clone();
        let [c0, c1, c2, c3] = block.corners;
        let we = block.sides[0].edge as usize;
        let Curve::Arc {
            center,
            radius,
            start,
            sweep,
        } = layout.edges[we].curve
        else {
            return None;
        };
        let mid = start + 0.5 * sweep;
        let w = [
            center[0] + radius * mid.cos(),
            center[1] + radius * mid.sin(),
        ];
        layout.vertices.push(w);
        let wv = (layout.vertices.len() - 1) as u32;
        let arc = |start: f64, sweep: f64| Curve::Arc {
            center,
            radius,
            start,
            sweep,
        };
        let w2 = split_edge(
            layout,
            we,
            wv,
            arc(start, 0.5 * sweep),
            arc(mid, sweep - 0.5 * sweep),
        );
        layout.edges.push(Edge {
            ends: [mv, wv],
            curve: Curve::Segment,
            kind: EdgeKind::Spoke,
        });
        let spoke = (layout.edges.len() - 1) as u32;
        let we = we as u32;
        let s0a = piece(layout, we, w2, c0, wv)?;
        let s0b = piece(layout, we, w2, wv, c1)?;
        let s2a = piece(layout, e, e2, mv, c3)?;
        let s2b = piece(layout, e, e2, c2, mv)?;
        layout.blocks[b] = Block {
            corners: [c0, wv, mv, c3],
            sides: [
                s0a,
                SideRef {
                    edge: spoke,
                    reversed: true,
                },
                s2a,
                block.sides[3],
            ],
            wall: block.wall,
        };
        layout.blocks.push(Block {
            corners: [wv, c1, c2, mv],
            sides: [
                s0b,
                block.sides[1],
                s2b,
                SideRef {
                    edge: spoke,
                    reversed: false,
                },
            ],
            wall: block.wall,
        });
    }
    Some(())
}

/// The largest sweep (radians) an inserted hole's side may have before its block pair is split
/// (the template's ring block is then far from convex).
pub const MAX_TEMPLATE_SWEEP: f64 = 2.0 * std::f64::consts::FRAC_PI_3;

/// Make the sides of inserted hole `hole` fit the template: split block pairs (widest side
/// first) until the hole has an even number of sides, at least 4, none wider than
/// [`MAX_TEMPLATE_SWEEP`] (bounded effort). Returns the number of splits.
fn prepare_inserted_hole(layout: &mut BlockLayout, hole: CircleId) -> usize {
    let mut splits = 0;
    for _ in 0..16 {
        let on_hole: Vec<usize> = (0..layout.blocks.len())
            .filter(|&b| {
                let e = layout.blocks[b].sides[0].edge as usize;
                layout.edges.get(e).map(|x| x.kind) == Some(EdgeKind::Wall(hole))
            })
            .collect();
        let k = on_hole.len();
        let widest = on_hole
            .iter()
            .filter_map(|&b| wall_sweep(layout, b).map(|s| s.abs()))
            .fold(0.0, f64::max);
        if k.is_multiple_of(2) && k >= 4 && widest <= MAX_TEMPLATE_SWEEP {
            break;
        }
        // Candidates: blocks on the hole whose partner across the medial arc has a non-empty
        // wall (not yet inside a filled template) and whose medial arc has a length.
        let mut best: Option<(f64, u32)> = None;
        for &b in &on_hole {
            let e = layout.blocks[b].sides[2].edge;
            let pair = blocks_on_medial(layout, e);
            if pair.len() != 2 {
                continue;
            }
            let partner = if pair[0] == b { pair[1] } else { pair[0] };
            // The partner's wall must still be a wall: an `Interface` arc belongs to an
            // inserted hole whose template is already filled, and splitting it would leave
            // that template's ring block on a stale edge.
            let pe = layout.blocks[partner].sides[0].edge as usize;
            let is_wall = matches!(layout.edges[pe].kind, EdgeKind::Wall(_));
            let ok = is_wall && wall_sweep(layout, partner).is_some_and(|s| s != 0.0);
            let sweep = wall_sweep(layout, b).map_or(0.0, f64::abs);
            if ok && best.is_none_or(|(s, _)| sweep > s) {
                best = Some((sweep, e));
            }
        }
        let Some((_, e)) = best else { break };
        if split_block_pair(layout, e).is_none() {
            break;
        }
        splits += 1;
    }
    splits
}

/// The blocks whose side 0 is an edge of kind `Wall(hole)`.
fn blocks_on_hole(layout: &BlockLayout, hole: CircleId) -> Vec<usize> {
    (0..layout.blocks.len())
        .filter(|&b| {
            let e = layout.blocks[b].sides[0].edge as usize;
            layout.edges.get(e).map(|x| x.kind) == Some(EdgeKind::Wall(hole))
        })
        .collect()
}

/// A block pair [`split_block_pair`] can split, seen from one of its blocks: `(sweep of that
/// block's wall, medial edge, circle on the other side)`. The medial edge must have exactly
/// two blocks, both with a wall arc of non-zero sweep on a circle, and a positive length.
fn splittable_from(layout: &BlockLayout, b: usize) -> Option<(f64, u32, CircleId)> {
    let e = layout.blocks[b].sides[2].edge;
    if layout.edges.get(e as usize)?.kind != EdgeKind::Medial {
        return None;
    }
    let pair = blocks_on_medial(layout, e);
    if pair.len() != 2 || !pair.contains(&b) {
        return None;
    }
    let partner = if pair[0] == b { pair[1] } else { pair[0] };
    let EdgeKind::Wall(other) = layout.edges[layout.blocks[partner].sides[0].edge as usize].kind
    else {
        return None;
    };
    let sweep = wall_sweep(layout, b)?.abs();
    let partner_sweep = wall_sweep(layout, partner)?.abs();
    if !(sweep > 0.0 && partner_sweep > 0.0 && sweep.is_finite() && partner_sweep.is_finite()) {
        return None;
    }
    let length_ok = match &layout.edges[e as usize].curve {
        Curve::Polyline(p) => halve_polyline(p).is_some(),
        Curve::Segment => {
            let [a, c] = layout.edges[e as usize].ends;
            let (a, c) = (layout.vertices[a as usize], layout.vertices[c as usize]);
            (a[0] - c[0]).hypot(a[1] - c[1]) > 0.0
        }
        Curve::Arc { .. } => false,
    };
    length_ok.then_some((sweep, e, other))
}

/// The splittable block pairs on inserted hole `hole` ([`splittable_from`]), widest side
/// first (ties: lower medial edge id).
fn splittable_on(layout: &BlockLayout, hole: CircleId) -> Vec<(f64, u32, CircleId)> {
    let mut out: Vec<(f64, u32, CircleId)> = blocks_on_hole(layout, hole)
        .into_iter()
        .filter_map(|b| splittable_from(layout, b))
        .collect();
    out.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    out
}

/// The most block pairs split per inserted hole and phase by
/// [`prepare_inserted_holes_jointly`] to bring its sides under [`MAX_TEMPLATE_SWEEP`].
const MAX_WIDTH_SPLITS_PER_HOLE: usize = 64;

/// Make the sides of every inserted hole in `holes` fit the template at once, before any of
/// them is filled (so no block pair is out of reach because it already lies in a filled
/// template). Returns the number of splits.
///
/// A split of the block pair on a medial arc adds one side to *both* circles of the arc. Two
/// phases:
/// 1. widths: on each hole in turn, split its widest side until it has at least 4 sides, none
///    wider than [`MAX_TEMPLATE_SWEEP`] (a split only adds sides and halves sweeps, so a later
///    split never undoes this);
/// 2. parity: for each hole `A` left with an odd count, a breadth-first search over the
///    splittable pairs (widest first) finds a path `A = c_0, c_1, ..., c_n` of circles, every
///    `c_1..c_{n-1}` an inserted hole, ending at an input circle (or the bounding circle) or at
///    another inserted hole with an odd count; splitting one pair on each step flips the
///    parity of `A` and `c_n` only (the inner circles get two sides each). The medial graph is
///    connected and every inserted hole touches at least one other circle, so such a path
///    exists whenever the pairs on it can be split (a positive-length medial arc and walls of
///    non-zero sweep); when not, the template reports the hole as a typed error.
fn prepare_inserted_holes_jointly(layout: &mut BlockLayout, holes: &[CircleId]) -> usize {
    let mut splits = 0;
    for &hole in holes {
        for _ in 0..MAX_WIDTH_SPLITS_PER_HOLE {
            let on_hole = blocks_on_hole(layout, hole);
            let k = on_hole.len();
            let widest = on_hole
                .iter()
                .filter_map(|&b| wall_sweep(layout, b).map(|s| s.abs()))
                .fold(0.0, f64::max);
            if k >= 4 && widest <= MAX_TEMPLATE_SWEEP {
                break;
            }
            let Some(&(_, e, _)) = splittable_on(layout, hole).first() else {
                break;
            };
            if split_block_pair(layout, e).is_none() {
                break;
            }
            splits += 1;
        }
    }
    let odd = |layout: &BlockLayout, c: CircleId| blocks_on_hole(layout, c).len() % 2 == 1;
    for &hole in holes {
        if !odd(layout, hole) {
            continue;
        }
        // Breadth-first search from `hole`; `parent[c]` = (previous circle, medial edge).
        let mut parent: HashMap<CircleId, (CircleId, u32)> = HashMap::new();
        let mut queue = std::collections::VecDeque::from([hole]);
        let mut found = None;
        'search: while let Some(c) = queue.pop_front() {
            for (_, e, other) in splittable_on(layout, c) {
                if other == hole || parent.contains_key(&other) {
                    continue;
                }
                parent.insert(other, (c, e));
                let fluid = holes.contains(&other);
                if !fluid || odd(layout, other) {
                    found = Some(other);
                    break 'search;
                }
                queue.push_back(other);
            }
        }
        let Some(mut c) = found else { continue };
        let mut path = Vec::new();
        while c != hole {
            let (prev, e) = parent[&c];
            path.push(e);
            c = prev;
        }
        // Split from `hole` outwards (each split leaves the other medial edges' ids alone).
        for e in path.into_iter().rev() {
            if split_block_pair(layout, e).is_some() {
                splits += 1;
            }
        }
    }
    splits
}

/// Split block pairs and fill every inserted hole (`holes`, the circles of ids `first..`)
/// with its template. Returns (splits, template blocks).
///
/// First the historical order, kept so that every layout it handles is meshed exactly as
/// before: per hole, [`prepare_inserted_hole`] then the template. That greedy order cannot
/// split a pair whose other side is an inserted hole already filled, so a hole whose only
/// fixable sides face such a hole kept an odd count (issue #9: a hole of 21 sides, each of
/// 16 splits made on the wrong side). When any hole does not fit, the layout is restored and
/// the holes are prepared together ([`prepare_inserted_holes_jointly`]), then filled.
fn fill_inserted_holes(
    layout: &mut BlockLayout,
    first: usize,
    holes: &[crate::domain::Circle],
) -> Result<(usize, usize), MeshError> {
    use crate::templates;
    let ids: Vec<CircleId> = (0..holes.len()).map(|k| (first + k) as CircleId).collect();
    let snapshot = layout.clone();
    let (mut splits, mut template_blocks) = (0, 0);
    let mut sequential_ok = true;
    for (&id, &circle) in ids.iter().zip(holes) {
        splits += prepare_inserted_hole(layout, id);
        match templates::fill_inserted_hole(layout, id, circle) {
            Ok(n) => template_blocks += n,
            Err(_) => {
                sequential_ok = false;
                break;
            }
        }
    }
    if sequential_ok {
        return Ok((splits, template_blocks));
    }
    *layout = snapshot;
    let splits = prepare_inserted_holes_jointly(layout, &ids);
    let mut template_blocks = 0;
    for (&id, &circle) in ids.iter().zip(holes) {
        template_blocks += templates::fill_inserted_hole(layout, id, circle)
            .map_err(|e| MeshError::Internal(format!("inserted hole {id}: {e}")))?;
    }
    Ok((splits, template_blocks))
}

/// The front end of [`build_mesh_layout`] before any block pair is split or any inserted hole
/// filled: macro Delaunay refinement, co-circular groups, arc collapse and Blocking2D on the
/// contracted graph (two blocks per kept arc, block `2e` on its `circles[0]`).
#[derive(Debug, Clone)]
pub struct CollapsedBlocking {
    /// Refinement: the final domain, the inserted holes, the sampled medial graph (before
    /// collapse) and its exact vertex circles. Its triangulation and triangle classes are
    /// released (empty) once the collapse selection is built: nothing later reads them.
    pub refined: crate::refine::Refined,
    pub groups: Vec<crate::cocircular::CocircularGroup>,
    /// The per-arc data of the collapse selection (independent of the exclusions, kept for
    /// [`CollapsedBlocking::recollapse`]).
    pub selection: crate::collapse::Selection,
    /// The contracted medial graph and its clusters.
    pub contracted: crate::collapse::Contracted,
    /// Blocking2D on the contracted graph.
    pub layout: BlockLayout,
    /// Arcs collapsed (`chosen.len()`).
    pub collapsed: usize,
    /// The arcs collapsed, in acceptance order ([`crate::collapse::select_forced`], less the
    /// short ones given up).
    pub chosen: Vec<crate::collapse::Candidate>,
    /// Arcs always collapsed (single-sample walls, when asked for), one flag per sampled arc.
    pub forced: Vec<bool>,
    /// Arcs never collapsed as short arcs, one flag per sampled arc: those excluded by the
    /// caller and those given up because their collapse left a block without area.
    pub excluded: Vec<bool>,
}

/// A name for a sampled medial arc that survives resampling: the circles of its two end
/// vertices, sorted and deduplicated (normally four: the arc's two circles and the third
/// circle of each end). Empty for a malformed arc.
pub fn arc_key(medial: &MedialGraph, arc: usize) -> Vec<CircleId> {
    let Some(a) = medial.arcs.get(arc) else {
        return Vec::new();
    };
    let mut key: Vec<CircleId> = a
        .ends
        .iter()
        .filter_map(|&v| medial.vertices.get(v as usize))
        .flat_map(|v| v.circles)
        .collect();
    key.sort_unstable();
    key.dedup();
    key
}

/// [`CollapsedBlocking`] of `domain` (see [`build_mesh_layout`] for the collapse retries).
///
/// `collapse_thin_walls`: also collapse every arc the sampling left with a single-sample wall
/// (the paper pipeline needs it: its walls follow the samples, so such an arc would give a
/// zero-sweep wall; exact mode computes exact walls and does not). It also says how a short
/// arc is measured: by its sampled polyline when true (the paper pipeline's blocks follow
/// it), by the chord between its ends' exact Apollonius centres when false (exact mode's
/// blocks are built on those centres; [`crate::collapse::ArcLength`]).
pub fn collapsed_blocking_with(
    domain: &Domain,
    options: &Options,
    sampling: &SamplingOptions,
    collapse_thin_walls: bool,
) -> Result<CollapsedBlocking, MeshError> {
    collapsed_blocking_excluding(domain, options, sampling, collapse_thin_walls, &[])
}

/// [`collapsed_blocking_with`], never collapsing as a short arc any arc whose [`arc_key`] is
/// in `never` (sorted; zero-length and forced arcs are still collapsed). Exact mode uses it to
/// keep the short collapses it gave up ([`CollapsedBlocking::recollapse`]) given up after a
/// resampling, where arc ids change but circles do not.
pub fn collapsed_blocking_excluding(
    domain: &Domain,
    options: &Options,
    sampling: &SamplingOptions,
    collapse_thin_walls: bool,
    never: &[Vec<CircleId>],
) -> Result<CollapsedBlocking, MeshError> {
    collapsed_blocking_seeded(domain, options, sampling, collapse_thin_walls, never, &[])
}

/// [`collapsed_blocking_excluding`] with the fluid holes `seed` inserted from the start
/// ([`crate::refine::refine_seeded`]); they count towards the two holes the blocking needs.
pub fn collapsed_blocking_seeded(
    domain: &Domain,
    options: &Options,
    sampling: &SamplingOptions,
    collapse_thin_walls: bool,
    never: &[Vec<CircleId>],
    seed: &[Circle],
) -> Result<CollapsedBlocking, MeshError> {
    use crate::{cocircular, refine};
    let h = domain.hole_count() + seed.len();
    if h < 2 {
        return Err(MeshError::Options(format!(
            "medial blocking needs at least 2 holes, the domain has {h} (use the disk/annulus \
             templates)"
        )));
    }
    if !(options.collapse_fraction.is_finite() && options.collapse_fraction >= 0.0) {
        return Err(MeshError::Options(format!(
            "the collapse fraction must be a number >= 0, not {}",
            options.collapse_fraction
        )));
    }
    let mut refined = refine::refine_seeded(
        domain,
        options.refine_ratio,
        options.max_inserted_holes,
        sampling,
        seed,
    )?;
    let sampled = &refined.sampled;
    let medial = &sampled.medial;
    let groups = cocircular::cocircular_groups(medial, &refined.circles);
    let mut exclude = vec![false; medial.arcs.len()];
    if !never.is_empty() {
        for (e, x) in exclude.iter_mut().enumerate() {
            *x = never.binary_search(&arc_key(medial, e)).is_ok();
        }
    }
    // Arcs the sampling left with a single-sample wall: always collapsed (their block on the
    // thin side would have a zero-sweep wall, and a zero-area ring block in a template).
    let mut forced = vec![false; medial.arcs.len()];
    for v in sampled.thin_walls.iter().filter(|_| collapse_thin_walls) {
        if let crate::sampling::ViolationKind::SingleSampleWall { arc } = v.kind {
            if let Some(f) = forced.get_mut(arc as usize) {
                *f = true;
            }
        }
    }
    let selection = crate::collapse::Selection::new(
        medial,
        &sampled.triangulation,
        &refined.circles,
        &groups,
        &sampled.samples.points,
        options.collapse_fraction,
        if collapse_thin_walls {
            crate::collapse::ArcLength::Polyline
        } else {
            crate::collapse::ArcLength::Chord
        },
    );
    release_triangulation(&mut refined.sampled);
    let (layout, chosen, contracted, excluded) =
        collapse_and_block(&refined, &selection, &forced, exclude, None)?;
    Ok(CollapsedBlocking {
        refined,
        groups,
        selection,
        contracted,
        layout,
        collapsed: chosen.len(),
        chosen,
        forced,
        excluded,
    })
}

/// Free the triangulation and the triangle classes of `sampled` (left empty): after the
/// collapse selection ([`crate::collapse::Selection`]) nothing reads them (the selection keeps
/// its per-arc data; the blocks, the exact geometry and the rebuilds read the samples and the
/// medial graph). At 1e5 particles they are ~70 bytes per sample, a few hundred MB that would
/// otherwise stay alive under the grids (issue 8). They are freed on the pool, off this
/// thread (26 ms at 1e5).
fn release_triangulation(sampled: &mut crate::sampling::SampledDomain) {
    let old = (
        std::mem::take(&mut sampled.triangulation),
        std::mem::take(&mut sampled.kinds),
    );
    rayon::spawn(move || drop(old));
}

impl CollapsedBlocking {
    /// Redo arc collapse and Blocking2D on the same sampling, triangulation and medial graph
    /// (no resampling), giving up the short collapses of the sampled arcs `give_up` on top of
    /// [`CollapsedBlocking::excluded`], and force-collapsing the arcs `force` (as zero-length
    /// arcs are). The selection is the same deterministic greedy pass, so every other collapse
    /// is chosen again unless a given-up arc was joining clusters another arc now joins.
    ///
    /// The per-arc data of the selection are those of the construction
    /// ([`CollapsedBlocking::selection`], with its collapse fraction): `options` is not read.
    pub fn recollapse(
        &mut self,
        options: &Options,
        give_up: &[u32],
        force: &[u32],
    ) -> Result<(), MeshError> {
        let _ = options;
        self.recollapse_with(give_up, force, true)
    }

    /// [`CollapsedBlocking::recollapse`] building every arc and curve afresh instead of taking
    /// over those of the current build that the changes cannot reach: the oracle of the tests
    /// (`tests/perf_blocking.rs`), same result.
    #[doc(hidden)]
    pub fn recollapse_from_scratch(
        &mut self,
        give_up: &[u32],
        force: &[u32],
    ) -> Result<(), MeshError> {
        self.recollapse_with(give_up, force, false)
    }

    /// [`CollapsedBlocking::recollapse`]; `reuse`: hand the current contraction and layout
    /// over to the new build. On an error they are rebuilt (from the flags of
    /// [`CollapsedBlocking::chosen`], as they were built), so `self` is left as it was but for
    /// the forced flags.
    fn recollapse_with(
        &mut self,
        give_up: &[u32],
        force: &[u32],
        reuse: bool,
    ) -> Result<(), MeshError> {
        let before = self.excluded.clone();
        let mut exclude = std::mem::take(&mut self.excluded);
        for &e in give_up {
            if let Some(x) = exclude.get_mut(e as usize) {
                *x = true;
            }
        }
        for &e in force {
            if let Some(f) = self.forced.get_mut(e as usize) {
                *f = true;
            }
        }
        let medial = &self.refined.sampled.medial;
        let previous = reuse.then(|| {
            (
                collapse_flags(&self.chosen, medial.arcs.len()),
                std::mem::take(&mut self.contracted),
                std::mem::take(&mut self.layout),
            )
        });
        match collapse_and_block(
            &self.refined,
            &self.selection,
            &self.forced,
            exclude,
            previous,
        ) {
            Ok((layout, chosen, contracted, excluded)) => {
                self.layout = layout;
                self.collapsed = chosen.len();
                self.chosen = chosen;
                self.contracted = contracted;
                self.excluded = excluded;
                Ok(())
            }
            Err(err) => {
                self.excluded = before;
                if reuse {
                    // `chosen` is unchanged: rebuild what was handed over from its flags.
                    let flags = collapse_flags(&self.chosen, medial.arcs.len());
                    let rebuilt = self.selection.contract(medial, &flags).and_then(|c| {
                        let (layout, _) = blocks(
                            &self.refined.domain,
                            &self.refined.sampled.samples,
                            &c.graph,
                        )?;
                        Ok((c, layout))
                    });
                    if let Ok((contracted, layout)) = rebuilt {
                        self.contracted = contracted;
                        self.layout = layout;
                    }
                }
                Err(err)
            }
        }
    }
}

/// One flag per arc (`arcs` of them): collapsed by one of `chosen`.
fn collapse_flags(chosen: &[crate::collapse::Candidate], arcs: usize) -> Vec<bool> {
    let mut flags = vec![false; arcs];
    for c in chosen {
        if let Some(f) = flags.get_mut(c.arc as usize) {
            *f = true;
        }
    }
    flags
}

/// What [`collapse_and_block`] returns: the layout, the collapses chosen, the contraction and
/// the final exclusions.
type Collapsed = (
    BlockLayout,
    Vec<crate::collapse::Candidate>,
    crate::collapse::Contracted,
    Vec<bool>,
);

/// A contraction and its Blocking2D whose unchanged arcs the next one takes over: the collapse
/// flags, the contraction and the layout.
type PreviousBuild = (Vec<bool>, crate::collapse::Contracted, BlockLayout);

/// Arc collapse and Blocking2D on the contracted graph, giving up short collapses that leave
/// a block with non-positive outline area (at most 8 tries); `exclude` the arcs never
/// collapsed as short ones (grows with the given-up ones). Each try takes over from the
/// previous one (the first from `previous`, an earlier build on the same graph) the arcs and
/// curves whose collapse flags did not change around them
/// ([`crate::collapse::Selection::contract_reusing`]); the result is that of building each
/// try from scratch (`previous` `None`).
fn collapse_and_block(
    refined: &crate::refine::Refined,
    selection: &crate::collapse::Selection,
    forced: &[bool],
    mut exclude: Vec<bool>,
    mut previous: Option<PreviousBuild>,
) -> Result<Collapsed, MeshError> {
    let final_domain = &refined.domain;
    let sampled = &refined.sampled;
    let medial = &sampled.medial;
    exclude.resize(medial.arcs.len(), false);
    let mut attempt = 0;
    loop {
        attempt += 1;
        let chosen = selection.select(&exclude, forced);
        let flags = collapse_flags(&chosen, medial.arcs.len());
        let (contracted, layout) = match previous.take() {
            Some((old_flags, mut old_contracted, mut old_layout)) => {
                let (contracted, taken) =
                    selection.contract_reusing(medial, &flags, &old_flags, &mut old_contracted)?;
                // The rest of the previous build is freed on the pool, off this thread (many
                // small vectors: the numbering of the blocks below runs on this thread alone).
                rayon::spawn(move || drop(old_contracted));
                let (layout, _) = blocks_reusing(
                    final_domain,
                    &sampled.samples,
                    &contracted.graph,
                    Some((&mut old_layout, &taken)),
                )?;
                rayon::spawn(move || drop(old_layout));
                (contracted, layout)
            }
            None => {
                let contracted = selection.contract(medial, &flags)?;
                let (layout, _) = blocks(final_domain, &sampled.samples, &contracted.graph)?;
                (contracted, layout)
            }
        };
        let nv = contracted.graph.vertices.len() as u32;
        // Only a block with a corner at a cluster merging a short collapse can make that
        // collapse given up: the other blocks' areas are not computed (same outcome).
        let mut short_cluster = vec![false; nv as usize];
        for c in chosen.iter().filter(|c| !c.zero) {
            let ends = medial.arcs[c.arc as usize].ends;
            short_cluster[contracted.cluster_of[ends[0] as usize] as usize] = true;
        }
        let bad_clusters = bad_clusters(&layout, nv, Some(&short_cluster));
        let mut changed = false;
        for c in &chosen {
            let ends = medial.arcs[c.arc as usize].ends;
            let cluster = contracted.cluster_of[ends[0] as usize];
            if !c.zero && bad_clusters.binary_search(&cluster).is_ok() {
                exclude[c.arc as usize] = true;
                changed = true;
            }
        }
        if !changed || attempt >= 8 {
            return Ok((layout, chosen, contracted, exclude));
        }
        previous = Some((flags, contracted, layout));
    }
}

/// The medial corners (`< nv`, sorted, deduplicated) of the blocks with non-positive outline
/// area ([`block_area`]), among the blocks with a corner `v` flagged in `only` (every block
/// for `None`).
fn bad_clusters(layout: &BlockLayout, nv: u32, only: Option<&[bool]>) -> Vec<u32> {
    use rayon::prelude::*;
    // On the pool (issue 8: 20 ms on one CPU at 1e5 particles); the corners are sorted
    // below, so the order the blocks are met in does not matter.
    let bad_blocks: Vec<usize> = layout
        .blocks
        .par_iter()
        .enumerate()
        .with_min_len(crate::tasks::BLOCKS)
        .map_init(
            || (Vec::new(), Vec::new()),
            |(pts, outline), (b, block)| {
                let wanted = only.is_none_or(|only| {
                    block
                        .corners
                        .iter()
                        .any(|&v| v < nv && only.get(v as usize).copied().unwrap_or(false))
                });
                (wanted && block_area_with(layout, b, pts, outline) <= 0.0).then_some(b)
            },
        )
        .flatten()
        .collect();
    let mut bad: Vec<u32> = bad_blocks
        .iter()
        .flat_map(|&b| layout.blocks[b].corners)
        .filter(|&v| v < nv)
        .collect();
    // Sorted for the lookups of the caller (bad blocks can be many on large layouts).
    bad.sort_unstable();
    bad.dedup();
    bad
}

/// Last-line guard of [`build_mesh_layout`] (issue 4: "no zero-area block ever reaches the
/// output"): every arc side of every block has a finite non-zero sweep, and every block has a
/// positive outline area ([`block_area`]). A violation is a [`MeshError::Internal`], never
/// output.
pub fn check_blocks(layout: &BlockLayout) -> Result<(), MeshError> {
    for (b, block) in layout.blocks.iter().enumerate() {
        for (k, side) in block.sides.iter().enumerate() {
            let Some(edge) = layout.edges.get(side.edge as usize) else {
                return Err(MeshError::Internal(format!(
                    "block {b} side {k} refers to a missing edge"
                )));
            };
            if let Curve::Arc { sweep, .. } = edge.curve {
                if !(sweep.is_finite() && sweep != 0.0) {
                    return Err(MeshError::Internal(format!(
                        "block {b} side {k} is an arc of sweep {sweep} (a zero-length wall)"
                    )));
                }
            }
        }
        let area = block_area(layout, b);
        if area.is_nan() || area <= 0.0 {
            return Err(MeshError::Internal(format!(
                "block {b} has outline area {area} (zero or negative)"
            )));
        }
    }
    Ok(())
}

/// The result of [`build_mesh_layout`]: the full blocking with degeneracy handling.
#[derive(Debug, Clone)]
pub struct MeshLayout {
    pub layout: BlockLayout,
    /// The final domain: the input holes, then the inserted ones.
    pub domain: Domain,
    /// Medial counts of the final domain before collapse.
    pub medial_vertices: usize,
    pub medial_arcs: usize,
    pub cocircular_groups: Vec<crate::cocircular::CocircularGroup>,
    pub collapsed_arcs: usize,
    pub inserted_holes: Vec<crate::domain::Circle>,
    pub split_arcs: usize,
    pub template_blocks: usize,
    /// Minimum gap of the domain per refinement round (non-decreasing, paper Lemma 2).
    pub min_gaps: Vec<f64>,
}

/// The full pipeline front end for `h >= 2` holes (paper sections 3 and 4): macro Delaunay
/// refinement ([`crate::refine`]), exact circles and co-circular groups
/// ([`crate::cocircular`]), arc collapse ([`crate::collapse`]), Blocking2D on the contracted
/// graph, then templates in the inserted holes ([`crate::templates::fill_inserted_hole`]),
/// after splitting block pairs so that each inserted hole has an even number of sides.
///
/// Blocks: `6(h + m - 1) - 2 collapsed + 2 splits + template blocks`. Short (non-zero)
/// collapses that would leave a block with non-positive outline area ([`block_area`]) are
/// given up (at most 8 retries); zero-length arcs, and arcs the sampling left with a
/// single-sample wall ([`crate::sampling::thin_walls`]), are always collapsed. The result
/// passes [`check_blocks`] (every arc side of positive sweep, every block of positive area) or
/// is a [`MeshError::Internal`].
pub fn build_mesh_layout(domain: &Domain, options: &Options) -> Result<MeshLayout, MeshError> {
    build_mesh_layout_with(domain, options, &SamplingOptions::default())
}

/// [`build_mesh_layout`] with explicit sampling options.
pub fn build_mesh_layout_with(
    domain: &Domain,
    options: &Options,
    sampling: &SamplingOptions,
) -> Result<MeshLayout, MeshError> {
    let h = domain.hole_count();
    let CollapsedBlocking {
        refined,
        groups,
        mut layout,
        collapsed,
        ..
    } = collapsed_blocking_with(domain, options, sampling, true)?;
    let medial = &refined.sampled.medial;
    let before = layout.blocks.len();
    let (split_arcs, template_blocks) = fill_inserted_holes(&mut layout, h, &refined.inserted)?;
    debug_assert_eq!(
        layout.blocks.len(),
        before + split_arcs * 2 + template_blocks
    );
    check_blocks(&layout)?;
    Ok(MeshLayout {
        layout,
        domain: refined.domain.clone(),
        medial_vertices: medial.vertex_count(),
        medial_arcs: medial.arc_count(),
        cocircular_groups: groups,
        collapsed_arcs: collapsed,
        inserted_holes: refined.inserted,
        split_arcs,
        template_blocks,
        min_gaps: refined.min_gaps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The division-free wall steps equal the modulo formulas they replace, indices in and
        /// out of range.
        #[test]
        fn wall_steps_equal_the_modulo_formulas(
            n in 1i64..50, i in -3i64..60, j in -3i64..60,
            grid in 1u64..80, from in 0u64..100, to in 0u64..100,
        ) {
            let slow = if (i + 1) % n == j { 1 } else if (j + 1) % n == i { -1 } else { 0 };
            prop_assert_eq!(step_between(i, j, n), slow);
            prop_assert_eq!(grid_distance(from, to, grid), (to % grid + grid - from % grid) % grid);
        }
    }

    /// The area scan restricted to blocks at flagged clusters finds, among the flagged
    /// clusters, exactly those the full scan finds, on layouts with vertices moved at random
    /// (so that many blocks have non-positive area).
    #[test]
    fn restricted_area_scan_finds_the_flagged_bad_clusters() {
        let mut rng = crate::layouts::SplitMix64(3);
        let d = crate::layouts::bubbles(60, 2).unwrap();
        let b = build_layout(&d, &Options::default()).unwrap();
        let nv = b.medial.vertices.len() as u32;
        let mut seen = 0;
        for round in 0..20 {
            let mut layout = b.layout.clone();
            for _ in 0..round {
                let v = (rng.next_f64() * layout.vertices.len() as f64) as usize;
                layout.vertices[v] = [rng.next_f64() * 2.0 - 1.0, rng.next_f64() * 2.0 - 1.0];
            }
            let only: Vec<bool> = (0..nv).map(|_| rng.next_f64() < 0.3).collect();
            let full = bad_clusters(&layout, nv, None);
            let part = bad_clusters(&layout, nv, Some(&only));
            let flagged = |v: &u32| only[*v as usize];
            let a: Vec<u32> = full.iter().copied().filter(flagged).collect();
            let b: Vec<u32> = part.iter().copied().filter(flagged).collect();
            assert_eq!(a, b);
            seen += a.len();
        }
        assert!(seen >= 10, "{seen}");
    }
}
