//! Exact mode on one period of a periodic domain (tracker issue 6): the blocks of
//! [`crate::periodic`] with the exact geometry of [`super`] (Apollonius vertices, conic arcs,
//! spoke-aligned grids, wall clustering, counts from [`super::counts`]).
//!
//! A vertex orbit of degree `n > 3` is a co-circular group whose zero-length arcs were
//! collapsed (one hole in a box, the corners of a lattice), or a nearly co-circular one
//! whose arcs were below [`crate::periodic::EXACT_COLLAPSE_FRACTION`] of the local radius:
//! its centre is the Apollonius circle of three of its circles spread around it (every three
//! give the same empty circle, up to that fraction), and every spoke ends at the radial
//! projection of that centre, exactly normal to its wall.
//!
//! # Exactly translated copies
//! The input names every medial vertex and arc *up to a period shift* (an orbit of the
//! infinite periodic medial axis, given by a representative in the tiling), circles as
//! [`Tag`]s `(hole, a, b)` = hole `k` moved by `(a Lx, b Ly)`. Each orbit's geometry is
//! computed once, in its representative's frame: the Apollonius circle of a vertex orbit, the
//! arc's parametrisation, its node parameters and its medial and wall nodes. Every instance
//! in the period is that geometry plus its shift, `p + (a Lx, b Ly)` evaluated by one formula
//! ([`shifted`]), never recomputed: the two copies of a zig-zag side are the same nodes moved
//! by two shifts, so they match to rounding (about `1e-16` of the period) and have equal node
//! counts by construction (one count per arc orbit, one wall-normal count per hole).
//!
//! Every kept block has its wall on a canonical hole (tile `(0, 0)`): arc orbit `o` with
//! circles `[C0, C1]`, `Cs = (k_s, a_s, b_s)`, gives the block on `C0` moved by
//! `-(a_0, b_0)` and the block on `C1` moved by `-(a_1, b_1)`. When the two shifts differ the
//! arc is a zig-zag side: two [`EdgeKind::Periodic`] edges naming each other. Spokes at a
//! vertex instance are shared by the two blocks on the same circle there, both in the period,
//! so every interior side is bitwise shared.

use super::counts::{ArcTarget, CountProblem, Counts};
use super::imposed::{vertex_cycle, BlockKey, CircleTag};
use super::{
    clustering, clustering_of, equidistribute, exact_sweep, expected_sign, internal, median,
    spoke_nodes, validate_options, ArcGeometry, Wall, ZERO_SWEEP,
};
use crate::apollonius::{apollonius, Choice};
use crate::domain::{Circle, CircleId};
use crate::geometry::Point;
use crate::grid::{GridError, MAX_TOTAL_NODES};
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef, Translation};
use crate::mesh::BlockGrid;
use crate::mesher::{MeshError, Options};
use std::collections::HashMap;

/// A circle of the tiling: hole `k` moved by `(a Lx, b Ly)`.
pub type Tag = (u32, i32, i32);

/// A period shift `(a, b)`: `(a Lx, b Ly)`.
pub type Shift = (i32, i32);

/// A medial vertex orbit, in its representative's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicVertex {
    /// Its circles in counter-clockwise order: three (the Delaunay triangle's samples), or
    /// `n > 3` for a (nearly) co-circular group whose arcs were collapsed (a vertex of
    /// degree `n`, `2n` blocks around it).
    pub circles: Vec<Tag>,
    /// The triangle's circumcentre, or the collapsed vertex's position (chooses between two
    /// Apollonius roots).
    pub near: Point,
}

/// A medial arc orbit, in its representative's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicArc {
    /// Its two circles (the blocks on `circles[0]`, `circles[1]` as in
    /// [`crate::blocking::blocks`]).
    pub circles: [Tag; 2],
    /// Its end vertices `A`, `B`: vertex orbit and the shift of the instance.
    pub ends: [(usize, Shift); 2],
    /// The sampled wall sweeps of the block on `circles[0]` (in its side-0 direction, `A` to
    /// `B`) and of the block on `circles[1]` (side-0 direction, `B` to `A`): they fix the
    /// number of turns of the exact sweeps.
    pub hint: [f64; 2],
}

/// The combinatorics of one period.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicBlocking {
    pub size: [f64; 2],
    /// The canonical holes (centres in the box).
    pub holes: Vec<Circle>,
    pub vertices: Vec<PeriodicVertex>,
    pub arcs: Vec<PeriodicArc>,
}

/// What [`build`] made.
#[derive(Debug, Clone)]
pub struct PeriodicExact {
    pub layout: BlockLayout,
    pub grids: Vec<BlockGrid>,
    /// `circle[k + 1]` wall-normal cells of hole `k` (`circle[0]` unused), `arc[o]` cells
    /// along arc orbit `o`.
    pub counts: Counts,
    pub cell_size: f64,
    /// The default target size before [`super::node_budget`] coarsened it to `cell_size`.
    pub coarsened_from: Option<f64>,
    /// Arc orbits whose exact walls run against their blocks (see
    /// [`super::ExactMesh::inconsistent_arcs`]).
    pub inconsistent_arcs: Vec<usize>,
    /// The key of each block ([`super::imposed`]), in block order.
    pub keys: Vec<BlockKey>,
}

/// `p + (a Lx, b Ly)`: the one formula every translated copy uses.
pub fn shifted(p: Point, s: Shift, size: [f64; 2]) -> Point {
    [p[0] + s.0 as f64 * size[0], p[1] + s.1 as f64 * size[1]]
}

fn add(a: Shift, b: Shift) -> Shift {
    (a.0 + b.0, a.1 + b.1)
}

impl PeriodicBlocking {
    fn wall(&self, t: Tag) -> Option<Wall> {
        let c = self.holes.get(t.0 as usize)?;
        Some(Wall {
            c: shifted(c.center, (t.1, t.2), self.size),
            r: c.radius,
            s: c.radius,
        })
    }
}

/// The exact geometry of a vertex orbit (representative frame).
struct Vertex {
    center: Point,
    radius: f64,
    tangent: Vec<Point>,
    circles: Vec<Tag>,
}

impl Vertex {
    /// The slot of circle `t` seen from the instance moved by `s`.
    fn slot(&self, t: Tag, s: Shift) -> Option<usize> {
        self.circles
            .iter()
            .position(|c| (c.0, c.1 + s.0, c.2 + s.1) == t)
    }
}

/// Build the exact-mode blocks and grids of one period (see the module documentation).
///
/// Errors: [`MeshError::Options`] for bad options, [`MeshError::Grid`] for too many nodes,
/// [`MeshError::Internal`] when the exact geometry disagrees with the combinatorics (the
/// caller then resamples or falls back to paper mode). Never panics.
pub fn build(pb: &PeriodicBlocking, options: &Options) -> Result<PeriodicExact, MeshError> {
    build_checking(pb, options, None)
}

/// How far the fast densities of every arc orbit of `pb` are from the plain formula
/// ([`super::densities::Deviation`]; test hook, issue 8), from the arcs [`build`] makes.
#[doc(hidden)]
pub fn density_deviation(
    pb: &PeriodicBlocking,
    options: &Options,
) -> Result<super::densities::Deviation, MeshError> {
    let mut d = super::densities::Deviation::default();
    build_checking(pb, options, Some(&mut d))?;
    Ok(d)
}

/// [`build`], adding each arc orbit's densities to `check` when given.
fn build_checking(
    pb: &PeriodicBlocking,
    options: &Options,
    mut check: Option<&mut super::densities::Deviation>,
) -> Result<PeriodicExact, MeshError> {
    validate_options(options)?;
    let size = pb.size;
    let h = pb.holes.len();
    let ncirc = h + 1;
    let unknown = || internal("a periodic vertex or arc names an unknown hole".into());
    // 1. Vertex orbits.
    let mut verts = Vec::with_capacity(pb.vertices.len());
    for (k, v) in pb.vertices.iter().enumerate() {
        let n = v.circles.len();
        if n < 3 {
            return Err(internal(format!("vertex orbit {k} has {n} circles")));
        }
        // Three circles in counter-clockwise order, spread around a vertex of degree n > 3
        // (a co-circular group: every three of its circles have the same empty circle).
        let pick = [0, n / 3, 2 * n / 3];
        let walls = [
            pb.wall(v.circles[pick[0]]).ok_or_else(unknown)?,
            pb.wall(v.circles[pick[1]]).ok_or_else(unknown)?,
            pb.wall(v.circles[pick[2]]).ok_or_else(unknown)?,
        ];
        let sites = walls.map(|w| w.site());
        let ap = apollonius(sites, Choice::ccw().near(v.near))
            .or_else(|_| apollonius(sites, Choice::any().near(v.near)))
            .map_err(|e| internal(format!("no Apollonius circle for vertex orbit {k}: {e}")))?;
        let tangent = if n == 3 {
            ap.tangent_points.to_vec()
        } else {
            // Every spoke of a collapsed vertex is the radial projection of its centre, so
            // it is exactly normal to its wall (as in `super::collapsed`).
            v.circles
                .iter()
                .map(|&c| pb.wall(c).map(|w| w.project(ap.center)).ok_or_else(unknown))
                .collect::<Result<Vec<Point>, MeshError>>()?
        };
        verts.push(Vertex {
            center: ap.center,
            radius: ap.radius,
            tangent,
            circles: v.circles.clone(),
        });
    }
    // 2. Arc orbits.
    let mut geoms = Vec::with_capacity(pb.arcs.len());
    let mut targets = Vec::with_capacity(pb.arcs.len());
    let mut slots = Vec::with_capacity(pb.arcs.len());
    let mut inconsistent_arcs = Vec::new();
    for (o, arc) in pb.arcs.iter().enumerate() {
        let walls = [
            pb.wall(arc.circles[0]).ok_or_else(unknown)?,
            pb.wall(arc.circles[1]).ok_or_else(unknown)?,
        ];
        let mut ends_a = [[[0.0; 2]; 2]; 2];
        let mut ends_m = [[0.0; 2]; 2];
        let mut slot = [[0usize; 2]; 2];
        for (j, &(w, s)) in arc.ends.iter().enumerate() {
            let v = verts
                .get(w)
                .ok_or_else(|| internal(format!("arc orbit {o} has an unknown end vertex")))?;
            ends_m[j] = shifted(v.center, s, size);
            for (side, &c) in arc.circles.iter().enumerate() {
                let k = v.slot(c, s).ok_or_else(|| {
                    internal(format!("arc orbit {o}: an end vertex does not touch {c:?}"))
                })?;
                slot[j][side] = k;
                ends_a[j][side] = shifted(v.tangent[k], s, size);
            }
        }
        let (s0, w0) = exact_sweep(&walls[0], ends_a[0][0], ends_a[1][0], arc.hint[0]);
        let (s1, w1) = exact_sweep(&walls[1], ends_a[0][1], ends_a[1][1], -arc.hint[1]);
        let wrong = |w: f64| w.abs() > ZERO_SWEEP && w * expected_sign(0) < 0.0;
        if wrong(w0) || wrong(-w1) {
            inconsistent_arcs.push(o);
        }
        let g = ArcGeometry {
            walls,
            param: if w1.abs() > w0.abs() { 1 } else { 0 },
            start: [s0, s1],
            sweep: [w0, w1],
            ends_m,
            ends_a,
        };
        if let Some(d) = check.as_deref_mut() {
            d.add(&g);
        }
        let (sq, ang) = g.densities().ok_or_else(|| {
            internal(format!(
                "arc orbit {o}: the exact medial arc is not defined"
            ))
        })?;
        targets.push(ArcTarget {
            circles: arc.circles.map(|c| c.0 as usize + 1),
            sq,
            ang,
            known: None,
        });
        geoms.push(g);
        slots.push(slot);
    }
    // 3. Counts: one per hole, one per arc orbit.
    let cell = match options.cell_size {
        Some(x) => x,
        None => {
            median(verts.iter().map(|v| v.radius).collect()).unwrap_or(1.0)
                / options.cells.max(1) as f64
        }
    };
    let mut circle_fixed = vec![None; ncirc];
    for (c, n) in &options.wall_cells {
        if *c >= 0 && (*c as usize) < h {
            circle_fixed[*c as usize + 1] = Some(*n);
        }
    }
    // The median Apollonius radius of the vertices touching each hole (independent of the
    // target size).
    let near_len: Vec<f64> = (0..pb.holes.len())
        .map(|k| {
            let near: Vec<f64> = verts
                .iter()
                .filter(|v| v.circles.iter().any(|c| c.0 as usize == k))
                .map(|v| v.radius)
                .collect();
            median(near).unwrap_or(f64::NAN)
        })
        .collect();
    let solve = |cell: f64, arcs: &mut Vec<ArcTarget>| -> Result<Counts, MeshError> {
        let mut circle_target = vec![1.0; ncirc];
        for (k, hole) in pb.holes.iter().enumerate() {
            let len = if near_len[k].is_finite() {
                near_len[k]
            } else {
                cell
            };
            let cl = clustering_of(options, k as CircleId);
            let first = cl.first_height(hole.radius);
            circle_target[k + 1] = clustering::cells_for(len, cell, first, cl.growth) as f64;
        }
        let problem = CountProblem {
            circle_target,
            circle_fixed: circle_fixed.clone(),
            template: vec![false; ncirc],
            arcs: std::mem::take(arcs),
        };
        // `--block-cells n`: n x n per block (arcs raised where a wall turns over 15 degrees
        // per cell), as in bounded domains.
        let solved = match options.block_cells {
            Some(n) => problem.solve_uniform(n),
            None => problem.solve(),
        }
        .map_err(internal);
        *arcs = problem.arcs;
        solved
    };
    let mut counts = solve(cell, &mut targets)?;
    let keys = block_keys(pb, &verts);
    let mut imposed_used = false;
    if let Some(imp) = &options.imposed_counts {
        let arcs: Vec<[usize; 2]> = pb
            .arcs
            .iter()
            .map(|a| a.circles.map(|c| c.0 as usize + 1))
            .collect();
        if let Some((circle, arc)) = imp.counts_for(&keys, &arcs, ncirc) {
            counts = Counts { circle, arc };
            imposed_used = true;
        }
    }
    let total_of = |counts: &Counts| {
        let mut total: usize = 0;
        for (o, arc) in pb.arcs.iter().enumerate() {
            for c in arc.circles {
                let nj = counts.circle[c.0 as usize + 1];
                total = total.saturating_add((counts.arc[o] + 1).saturating_mul(nj + 1));
            }
        }
        total
    };
    // The default target size is coarsened towards the node budget as in bounded domains
    // (see `super::node_budget`): a periodic close pack with tiny gaps has tiny medial
    // vertices everywhere.
    let budget = super::node_budget(2 * pb.arcs.len(), options.cells);
    let user_sized = options.cell_size.is_some() || options.block_cells.is_some() || imposed_used;
    let default_cell = cell;
    let mut cell = cell;
    let mut coarsened = 0;
    let total = loop {
        let total = total_of(&counts);
        if total <= budget || user_sized || coarsened >= super::MAX_COARSENING {
            break total;
        }
        cell *= super::coarsening_step(total, budget);
        coarsened += 1;
        counts = solve(cell, &mut targets)?;
    };
    if total > MAX_TOTAL_NODES {
        return Err(MeshError::Grid(GridError::TooManyNodes {
            nodes: total,
            limit: MAX_TOTAL_NODES,
        }));
    }
    // 4. Layout and grids, instance by instance.
    let mut b = Builder {
        pb,
        verts: &verts,
        layout: BlockLayout::default(),
        centre: HashMap::new(),
        tangent: HashMap::new(),
        spokes: HashMap::new(),
    };
    let mut grids = Vec::with_capacity(2 * pb.arcs.len());
    for (o, arc) in pb.arcs.iter().enumerate() {
        let g = &geoms[o];
        let n = counts.arc[o];
        let nbar = 0.5
            * (counts.circle[arc.circles[0].0 as usize + 1]
                + counts.circle[arc.circles[1].0 as usize + 1]) as f64;
        let weights: Vec<f64> = targets[o]
            .sq
            .iter()
            .zip(&targets[o].ang)
            .map(|(s, a)| (nbar * s).max(*a))
            .collect();
        let params = equidistribute(&weights, n);
        let mut m_nodes = Vec::with_capacity(n + 1);
        let mut a_nodes: [Vec<Point>; 2] = [Vec::with_capacity(n + 1), Vec::with_capacity(n + 1)];
        for &t in &params {
            let (m, a, _) = g
                .at(t)
                .ok_or_else(|| internal(format!("arc orbit {o}: a medial node is not defined")))?;
            m_nodes.push(m);
            a_nodes[0].push(a[0]);
            a_nodes[1].push(a[1]);
        }
        let shifts = arc.circles.map(|c| (-c.1, -c.2));
        let mut medial_edges = [0u32; 2];
        for side in 0..2 {
            let d = shifts[side];
            if side == 1 && shifts[1] == shifts[0] {
                medial_edges[1] = medial_edges[0];
                continue;
            }
            let v = arc.ends.map(|(w, s)| b.centre_vertex(w, add(s, d)));
            let mut pts: Vec<Point> = m_nodes.iter().map(|&p| shifted(p, d, size)).collect();
            pts[0] = b.layout.vertices[v[0] as usize];
            pts[n] = b.layout.vertices[v[1] as usize];
            b.layout.edges.push(Edge {
                ends: v,
                curve: Curve::Polyline(pts),
                kind: EdgeKind::Medial,
            });
            medial_edges[side] = (b.layout.edges.len() - 1) as u32;
        }
        if shifts[0] != shifts[1] {
            let t = |from: Shift, to: Shift| {
                Translation([
                    (to.0 - from.0) as f64 * size[0],
                    (to.1 - from.1) as f64 * size[1],
                ])
            };
            let [e0, e1] = medial_edges;
            b.layout.edges[e0 as usize].kind = EdgeKind::Periodic {
                partner: e1,
                translation: t(shifts[0], shifts[1]),
            };
            b.layout.edges[e1 as usize].kind = EdgeKind::Periodic {
                partner: e0,
                translation: t(shifts[1], shifts[0]),
            };
        }
        for side in 0..2 {
            let d = shifts[side];
            let hole = arc.circles[side].0;
            let nj = counts.circle[hole as usize + 1];
            let cl = clustering_of(options, hole as CircleId);
            let first = cl.first_height(pb.holes[hole as usize].radius);
            let [(w0, e0), (w1, e1)] = arc.ends;
            let (i0, i1) = ((w0, add(e0, d)), (w1, add(e1, d)));
            let (k0, k1) = (slots[o][0][side], slots[o][1][side]);
            let sp0 = b.spoke(i0, k0, nj, first, cl.growth);
            let sp1 = b.spoke(i1, k1, nj, first, cl.growth);
            let (c0, c1) = (b.centre_vertex(i0.0, i0.1), b.centre_vertex(i1.0, i1.1));
            let (t0, t1) = (b.tangent_vertex(i0, k0), b.tangent_vertex(i1, k1));
            let (t_first, t_last) = if side == 0 { (t0, t1) } else { (t1, t0) };
            let sweep = if side == 0 { g.sweep[0] } else { -g.sweep[1] };
            let centre = pb.holes[hole as usize].center;
            let p = b.layout.vertices[t_first as usize];
            b.layout.edges.push(Edge {
                ends: [t_first, t_last],
                curve: Curve::Arc {
                    center: centre,
                    radius: pb.holes[hole as usize].radius,
                    start: (p[1] - centre[1]).atan2(p[0] - centre[0]),
                    sweep,
                },
                kind: EdgeKind::Wall(hole as CircleId),
            });
            let wall_edge = (b.layout.edges.len() - 1) as u32;
            let mut nodes = vec![[0.0; 2]; (n + 1) * (nj + 1)];
            for i in 0..=n {
                let k = if side == 0 { i } else { n - i };
                let col: Vec<Point> = if k == 0 {
                    b.spokes[&(i0, k0)].1.clone()
                } else if k == n {
                    b.spokes[&(i1, k1)].1.clone()
                } else {
                    spoke_nodes(
                        shifted(a_nodes[side][k], d, size),
                        shifted(m_nodes[k], d, size),
                        nj,
                        first,
                        cl.growth,
                    )
                };
                for (j, q) in col.into_iter().enumerate() {
                    nodes[i + j * (n + 1)] = q;
                }
            }
            grids.push(BlockGrid { ni: n, nj, nodes });
            let (fwd, rev) = (SideRef::along, SideRef::against);
            let me = medial_edges[side];
            b.layout.blocks.push(if side == 0 {
                Block {
                    corners: [t_first, t_last, c1, c0],
                    sides: [fwd(wall_edge), rev(sp1), rev(me), fwd(sp0)],
                    wall: Some(hole as CircleId),
                }
            } else {
                Block {
                    corners: [t_first, t_last, c0, c1],
                    sides: [fwd(wall_edge), rev(sp0), fwd(me), fwd(sp1)],
                    wall: Some(hole as CircleId),
                }
            });
        }
    }
    if options.smooth > 0 {
        for g in grids.iter_mut() {
            let rows = super::smoothing::boundary_layer_rows(g);
            super::smoothing::winslow(g, options.smooth, rows);
        }
    }
    Ok(PeriodicExact {
        layout: b.layout,
        grids,
        counts,
        cell_size: cell,
        coarsened_from: (coarsened > 0).then_some(default_cell),
        inconsistent_arcs,
        keys,
    })
}

/// The key ([`BlockKey`]) of block `2o + s` (side `s` of arc orbit `o`), in the frame where
/// its wall is the canonical copy.
fn block_keys(pb: &PeriodicBlocking, verts: &[Vertex]) -> Vec<BlockKey> {
    let cycle = |w: usize, s: Shift| -> Vec<CircleTag> {
        let Some(v) = verts.get(w) else {
            return Vec::new();
        };
        let touching: Vec<(CircleTag, Point)> = v
            .circles
            .iter()
            .zip(&v.tangent)
            .map(|(c, &p)| ((c.0 as i64, (c.1 + s.0) as i64, (c.2 + s.1) as i64), p))
            .collect();
        vertex_cycle(v.center, &touching)
    };
    let mut keys = Vec::with_capacity(2 * pb.arcs.len());
    for arc in &pb.arcs {
        for side in 0..2 {
            let c = arc.circles[side];
            let d = (-c.1, -c.2);
            let [(w0, e0), (w1, e1)] = arc.ends;
            let (a, b) = (cycle(w0, add(e0, d)), cycle(w1, add(e1, d)));
            let wall = (c.0 as i64, 0, 0);
            keys.push(if side == 0 {
                (wall, a, b)
            } else {
                (wall, b, a)
            });
        }
    }
    keys
}

/// A vertex instance: orbit and shift.
type Instance = (usize, Shift);

/// The layout under construction: every vertex instance, tangent point and spoke once.
struct Builder<'a> {
    pb: &'a PeriodicBlocking,
    verts: &'a [Vertex],
    layout: BlockLayout,
    centre: HashMap<Instance, u32>,
    tangent: HashMap<(Instance, usize), u32>,
    /// Spoke edge and nodes (wall to centre) per tangent point instance.
    spokes: HashMap<(Instance, usize), (u32, Vec<Point>)>,
}

impl Builder<'_> {
    fn push(&mut self, p: Point) -> u32 {
        self.layout.vertices.push(p);
        (self.layout.vertices.len() - 1) as u32
    }
    fn centre_vertex(&mut self, w: usize, s: Shift) -> u32 {
        if let Some(&v) = self.centre.get(&(w, s)) {
            return v;
        }
        let v = self.push(shifted(self.verts[w].center, s, self.pb.size));
        self.centre.insert((w, s), v);
        v
    }
    fn tangent_vertex(&mut self, i: Instance, k: usize) -> u32 {
        if let Some(&v) = self.tangent.get(&(i, k)) {
            return v;
        }
        let v = self.push(shifted(self.verts[i.0].tangent[k], i.1, self.pb.size));
        self.tangent.insert((i, k), v);
        v
    }
    /// The spoke edge of tangent point `k` of instance `i`, its nodes computed once.
    fn spoke(&mut self, i: Instance, k: usize, nj: usize, first: Option<f64>, growth: f64) -> u32 {
        if let Some((e, _)) = self.spokes.get(&(i, k)) {
            return *e;
        }
        let c = self.centre_vertex(i.0, i.1);
        let t = self.tangent_vertex(i, k);
        let (a, m) = (
            self.layout.vertices[t as usize],
            self.layout.vertices[c as usize],
        );
        let nodes = spoke_nodes(a, m, nj, first, growth);
        self.layout.edges.push(Edge {
            ends: [c, t],
            curve: Curve::Segment,
            kind: EdgeKind::Spoke,
        });
        let e = (self.layout.edges.len() - 1) as u32;
        self.spokes.insert((i, k), (e, nodes));
        e
    }
}
