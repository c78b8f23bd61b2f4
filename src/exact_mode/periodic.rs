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

use super::counts::{ArcTarget, CountProblem, Counts, Known};
use super::imposed::{vertex_cycle, BlockKey, CircleTag};
use super::{
    arc_params_into, clustering, clustering_of, expected_sign, internal, median, validate_options,
    ArcGeometry, Wall, ZERO_SWEEP,
};
use crate::apollonius::{apollonius, Choice};
use crate::blocking::MAX_TEMPLATE_SWEEP;
use crate::domain::{Circle, CircleId};
use crate::geometry::Point;
use crate::grid::{GridError, MAX_CELLS_PER_SIDE, MAX_TOTAL_NODES};
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef, Translation};
use crate::mesh::BlockGrid;
use crate::mesher::{MeshError, Options, MERGED_MIN_ANGLE_DEG};
use rayon::prelude::*;
/// Hash maps with a fast hasher (issue 8: SipHash of the orbit keys was 4% of a periodic
/// mesh); nothing reads them in iteration order.
type HashMap<K, V> = std::collections::HashMap<K, V, foldhash::fast::RandomState>;

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
    /// The key of each block ([`super::imposed`]), in block order (the medial blocks only:
    /// template blocks, after them, have none); empty when the build was not asked for them
    /// (the periodic mesher asks only for a sequence's frames and for imposed counts).
    pub keys: Vec<BlockKey>,
    /// Arc orbits split in two so that every inserted hole fits its template.
    pub split_arcs: usize,
    /// Template blocks inside the inserted holes (the last blocks).
    pub template_blocks: usize,
    /// The blocks the build was asked to flag ([`Flag`]), increasing; empty when it was not.
    pub(crate) flagged: Vec<usize>,
    /// The report's figures of every block when the nodes were not kept
    /// ([`Options::keep_nodes`], [`crate::Mesh::measured`]); `None` when the grids hold them.
    pub measured: Option<std::sync::Arc<crate::quality::Measured>>,
}

/// Which blocks a build flags as it makes their grids (issue 8: each block's cells are
/// measured right after its grid is made, while in cache, instead of in a pass over every
/// grid after the build: 0.23 s at 1e5 holes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Flag {
    /// The blocks with an inverted cell ([`crate::quality::inverted_blocks`], found as
    /// bounded exact mode finds them, [`super::inverted::has_inverted_cell`]).
    Inverted,
    /// The blocks with a corner below this many degrees, or an inverted cell
    /// ([`crate::quality::has_corner_below`]).
    CornerBelow(f64),
}

impl Flag {
    /// Whether `g` is flagged.
    fn flags(self, g: &BlockGrid) -> bool {
        match self {
            Flag::Inverted => super::inverted::has_inverted_cell(g),
            Flag::CornerBelow(deg) => crate::quality::has_corner_below(g, deg),
        }
    }
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

/// A refinement candidate: `(ratio, empty circle centre, radius)`.
pub(crate) type Candidate = (f64, Point, f64);

/// The vertex orbits of three circles whose exact empty circle is *poor* for macro Delaunay
/// refinement (see [`crate::refine`]): the triangle of its three touching points has
/// circumradius over shortest edge above `limit` (its angles are the block corners there,
/// paper Lemma 1). Per poor orbit: the ratio, the empty circle's centre (representative
/// frame) and radius. Orbits whose circle has no exact solve are skipped. A collapsed vertex
/// of degree `n > 3` is measured on its `n` touching points (shortest distance between two).
pub(crate) fn poor_vertices(pb: &PeriodicBlocking, limit: f64) -> Vec<Candidate> {
    use rayon::prelude::*;
    // In parallel (issue 8: one exact solve per vertex orbit, 0.3 s a round at 1e5 holes when
    // serial); collected in orbit order.
    pb.vertices
        .par_iter()
        .filter(|v| v.circles.len() >= 3)
        .filter_map(|v| {
            // A collapsed (co-circular) vertex of degree n > 3: the circle of three of its
            // circles spread around it, touching points the radial projections of its centre
            // (as `build` places them); the measure is then over all its touching points.
            let n = v.circles.len();
            let walls = [
                pb.wall(v.circles[0])?,
                pb.wall(v.circles[n / 3])?,
                pb.wall(v.circles[2 * n / 3])?,
            ];
            let sites = walls.map(|w| w.site());
            let ap = apollonius(sites, Choice::ccw().near(v.near))
                .or_else(|_| apollonius(sites, Choice::any().near(v.near)))
                .ok()?;
            let t: Vec<Point> = if n == 3 {
                ap.tangent_points.to_vec()
            } else {
                v.circles
                    .iter()
                    .map(|&c| pb.wall(c).map(|w| w.project(ap.center)))
                    .collect::<Option<_>>()?
            };
            poor_at(ap.center, ap.radius, &t, limit)
        })
        .collect()
}

/// The refinement candidate of a vertex orbit whose empty circle (`center`, `radius`)
/// touches its walls at `t`, when it is poor: `(radius / shortest distance between two
/// touching points, center, radius)` with the ratio above `limit`.
fn poor_at(center: Point, radius: f64, t: &[Point], limit: f64) -> Option<Candidate> {
    let dist = |a: Point, b: Point| (a[0] - b[0]).hypot(a[1] - b[1]);
    let mut l = f64::INFINITY;
    for i in 0..t.len() {
        for j in i + 1..t.len() {
            l = l.min(dist(t[i], t[j]));
        }
    }
    let ratio = if l > 0.0 { radius / l } else { f64::INFINITY };
    let ok = radius.is_finite() && center.iter().all(|x| x.is_finite());
    (ok && ratio > limit).then_some((ratio, center, radius))
}

/// [`poor_vertices`] and [`backwards_orbits`] of `pb` with one exact solve per vertex orbit
/// (issue 8: a refinement round's extraction asked both, and solved every vertex orbit
/// twice): the same answers. When some vertex orbit cannot be solved, [`poor_vertices`] skips
/// it and [`backwards_orbits`] fails; so here.
pub(crate) fn poor_and_backwards(
    pb: &PeriodicBlocking,
    limit: f64,
) -> (Vec<Candidate>, Result<Backwards, MeshError>) {
    use rayon::prelude::*;
    match orbits_of(pb, None) {
        Ok((verts, _, _, backwards)) => {
            let poor = verts
                .par_iter()
                .filter_map(|v| poor_at(v.center, v.radius, &v.tangent, limit))
                .collect();
            (poor, Ok((backwards, SolvedOrbits::new(pb, verts))))
        }
        Err(e) => (poor_vertices(pb, limit), Err(e)),
    }
}

/// The arc orbits running backwards (orbit order) and the vertex orbits solved to find them.
pub(crate) type Backwards = (Vec<usize>, SolvedOrbits);

/// A solved vertex orbit's inputs besides the period: its circles and its hint's bits.
type OrbitInput<'a> = (&'a [Tag], [u64; 2]);

/// The vertex orbits of a [`PeriodicBlocking`] with their exact circles, as a build solved
/// them, for a later build of another blocking of the same period ([`build_unless_backwards_with`]):
/// a vertex orbit's solve is a function of its circles (tags), its hint and the period's
/// holes and size, so an orbit with the same circles and the same hint, bit for bit, takes
/// the earlier answer (issue 8: exact mode's local fix builds a layout whose vertex orbits are
/// nearly all those of the layout it fixes, 0.19 s of solves at 1e5 holes).
pub(crate) struct SolvedOrbits {
    size: [f64; 2],
    holes: Vec<Circle>,
    /// Per solved vertex, the hint's bits.
    near: Vec<[u64; 2]>,
    verts: Vec<Vertex>,
}

impl std::fmt::Debug for SolvedOrbits {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SolvedOrbits")
            .field("vertices", &self.verts.len())
            .finish()
    }
}

impl SolvedOrbits {
    fn new(pb: &PeriodicBlocking, verts: Vec<Vertex>) -> SolvedOrbits {
        SolvedOrbits {
            size: pb.size,
            holes: pb.holes.clone(),
            near: pb
                .vertices
                .iter()
                .map(|v| v.near.map(f64::to_bits))
                .collect(),
            verts,
        }
    }

    /// The solved orbits by their inputs, when they are of `pb`'s period (its holes and size).
    fn table(&self, pb: &PeriodicBlocking) -> Option<HashMap<OrbitInput<'_>, &Vertex>> {
        (self.size == pb.size && self.holes == pb.holes).then(|| {
            self.verts
                .iter()
                .zip(&self.near)
                .map(|(v, n)| ((v.circles.as_slice(), *n), v))
                .collect()
        })
    }
}

/// The exact geometry of a vertex orbit (representative frame).
#[derive(Clone)]
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
    build_with_inserted(pb, options, &[])
}

/// [`build`] with inserted holes: `fluid[k]` marks hole `k` as inserted by macro Delaunay
/// refinement (fluid, not a wall; see `crate::periodic::refine_periodic`). As in bounded
/// exact mode ([`super::inserted`]): the spokes on such a hole are equally spaced, arc orbits
/// around it are split at their middle until it has an even number `k >= 4` of arcs, none
/// wider than [`MAX_TEMPLATE_SWEEP`], and it is filled with the O-grid / `k`-gon template
/// ([`crate::templates::fill_inserted_holes`]) whose opposite sides share their counts
/// (`super::inserted::tie_counts`). The canonical copy of each inserted hole is filled: its
/// whole ring of blocks is in the period (every kept block has its wall on a canonical
/// copy), so the template's perimeter nodes are those blocks' wall nodes.
pub fn build_with_inserted(
    pb: &PeriodicBlocking,
    options: &Options,
    fluid: &[bool],
) -> Result<PeriodicExact, MeshError> {
    match build_checking(pb, options, fluid, None, false, true, None, None)? {
        Built::Mesh(x) => Ok(*x),
        Built::Backwards(_) => Err(internal("stopped at backwards arcs".into())),
    }
}

/// What [`build_unless_backwards_with`] made.
#[derive(Debug)]
pub(crate) enum Built {
    /// The whole build, as [`build_with_inserted`] makes it (no arc runs backwards).
    Mesh(Box<PeriodicExact>),
    /// The arc orbits whose exact walls run against their blocks (sorted, not empty): the
    /// build stopped there, before the counts and grids.
    Backwards(Vec<usize>),
}

/// [`build_unless_backwards_with`] with the block keys (the tests' entry point).
#[cfg(test)]
pub(crate) fn build_unless_backwards(
    pb: &PeriodicBlocking,
    options: &Options,
    fluid: &[bool],
) -> Result<Built, MeshError> {
    build_unless_backwards_with(pb, options, fluid, true, None, None)
}

/// [`build_with_inserted`] that stops as soon as an arc orbit runs backwards (issue 8): such
/// a mesh is never kept (the periodic mesher resamples around those arcs), and the counts,
/// nodes and grids of the whole period were most of the build's time (0.39 s of a failed
/// attempt at 10 000 holes). With `keys` false the mesh has no block keys
/// ([`PeriodicExact::keys`] empty; they are still made for imposed counts, which read them).
/// The vertex orbits `known` solved (those of an earlier blocking of the same period,
/// [`SolvedOrbits`]) are taken from it, the same build; it is freed once they are. With
/// `flag`, the mesh lists the blocks it flags ([`PeriodicExact::flagged`]).
pub(crate) fn build_unless_backwards_with(
    pb: &PeriodicBlocking,
    options: &Options,
    fluid: &[bool],
    keys: bool,
    known: Option<SolvedOrbits>,
    flag: Option<Flag>,
) -> Result<Built, MeshError> {
    build_checking(pb, options, fluid, None, true, keys, known, flag)
}

/// How far the fast densities of every arc orbit of `pb` are from the plain formula
/// ([`super::densities::Deviation`]; test hook, issue 8), from the arcs [`build`] makes.
#[doc(hidden)]
pub fn density_deviation(
    pb: &PeriodicBlocking,
    options: &Options,
) -> Result<super::densities::Deviation, MeshError> {
    let mut d = super::densities::Deviation::default();
    build_checking(pb, options, &[], Some(&mut d), false, true, None, None)?;
    Ok(d)
}

/// The vertex orbits' exact circles, the arc orbits' exact geometry and tangent slots, and
/// the arc orbits that run backwards (in orbit order): stages 1 and 2 of [`build`] before
/// the densities, the first error in orbit order.
#[allow(clippy::type_complexity)]
fn orbits_of(
    pb: &PeriodicBlocking,
    known: Option<&SolvedOrbits>,
) -> Result<
    (
        Vec<Vertex>,
        Vec<ArcGeometry>,
        Vec<[[usize; 2]; 2]>,
        Vec<usize>,
    ),
    MeshError,
> {
    let size = pb.size;
    let unknown = || internal("a periodic vertex or arc names an unknown hole".into());
    // 1. Vertex orbits, in parallel (each its own Apollonius solve, or the answer `known`
    //    has for the same inputs); the first error in orbit order is the one returned.
    let table = known.and_then(|k| k.table(pb));
    let solved: Vec<Result<Vertex, MeshError>> = pb
        .vertices
        .par_iter()
        .enumerate()
        .map(|(k, v)| -> Result<Vertex, MeshError> {
            let near = v.near.map(f64::to_bits);
            if let Some(&x) = table
                .as_ref()
                .and_then(|t| t.get(&(v.circles.as_slice(), near)))
            {
                return Ok(x.clone());
            }
            let n = v.circles.len();
            if n < 3 {
                return Err(internal(format!("vertex orbit {k} has {n} circles")));
            }
            // Three circles in counter-clockwise order, spread around a vertex of degree
            // n > 3 (a co-circular group: every three of its circles have the same empty
            // circle).
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
                // Every spoke of a collapsed vertex is the radial projection of its centre,
                // so it is exactly normal to its wall (as in `super::collapsed`).
                v.circles
                    .iter()
                    .map(|&c| pb.wall(c).map(|w| w.project(ap.center)).ok_or_else(unknown))
                    .collect::<Result<Vec<Point>, MeshError>>()?
            };
            Ok(Vertex {
                center: ap.center,
                radius: ap.radius,
                tangent,
                circles: v.circles.clone(),
            })
        })
        .collect();
    let verts = solved
        .into_iter()
        .collect::<Result<Vec<Vertex>, MeshError>>()?;
    // 2. Arc orbits, in parallel: their exact geometry and whether they run backwards; the
    //    first error in orbit order. A build that stops at backwards arcs stops here, before
    //    the densities (issue 8: they were half of a stopped build at 1e5 holes).
    type ArcOrbit = (ArcGeometry, [[usize; 2]; 2], bool);
    let made: Vec<Result<ArcOrbit, MeshError>> = pb
        .arcs
        .par_iter()
        .enumerate()
        .map(|(o, arc)| -> Result<ArcOrbit, MeshError> {
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
            let g = ArcGeometry::new(walls, ends_m, ends_a, [arc.hint[0], -arc.hint[1]]);
            let [w0, w1] = g.sweep;
            let wrong = |w: f64| w.abs() > ZERO_SWEEP && w * expected_sign(0) < 0.0;
            Ok((g, slot, wrong(w0) || wrong(-w1)))
        })
        .collect();
    let mut geoms = Vec::with_capacity(pb.arcs.len());
    let mut slots = Vec::with_capacity(pb.arcs.len());
    let mut inconsistent_arcs = Vec::new();
    for (o, m) in made.into_iter().enumerate() {
        let (g, slot, backwards) = m?;
        if backwards {
            inconsistent_arcs.push(o);
        }
        geoms.push(g);
        slots.push(slot);
    }
    Ok((verts, geoms, slots, inconsistent_arcs))
}

/// The arc orbits of `pb` that run backwards (orbit order): what [`build_unless_backwards_with`]
/// stops at, without the options check (the periodic extraction looks before numbering its
/// layout, issue 8).
pub(crate) fn backwards_orbits(pb: &PeriodicBlocking) -> Result<Backwards, MeshError> {
    orbits_of(pb, None).map(|(verts, _, _, backwards)| (backwards, SolvedOrbits::new(pb, verts)))
}

/// [`build`], adding each arc orbit's densities to `check` when given; with `stop`, returns
/// [`Built::Backwards`] after the arc orbits when one of them runs backwards; with `flag`,
/// lists the blocks it flags.
#[allow(clippy::too_many_arguments)]
fn build_checking(
    pb: &PeriodicBlocking,
    options: &Options,
    fluid: &[bool],
    mut check: Option<&mut super::densities::Deviation>,
    stop: bool,
    want_keys: bool,
    known: Option<SolvedOrbits>,
    flag: Option<Flag>,
) -> Result<Built, MeshError> {
    validate_options(options)?;
    let h = pb.holes.len();
    let ncirc = h + 1;
    let is_fluid = |k: usize| fluid.get(k).copied().unwrap_or(false);
    let cluster = |k: usize| {
        if is_fluid(k) {
            super::inserted::FLUID_CLUSTERING
        } else {
            clustering_of(options, k as CircleId)
        }
    };
    let (mut verts, mut geoms, mut slots, inconsistent_arcs) = orbits_of(pb, known.as_ref())?;
    // Not held through the grids (many small vectors: freed on the pool).
    if let Some(k) = known {
        rayon::spawn(move || drop(k));
    }
    if stop && !inconsistent_arcs.is_empty() {
        return Ok(Built::Backwards(inconsistent_arcs));
    }
    // The densities of every arc orbit, in parallel; in orbit order the first error and the
    // density check. With a fixed grid per block (`--block-cells`), the counts need only each
    // arc's lower bound and its nodes the parameters for the count it will have
    // (`uniform_arc_count`, with `nbar` the fixed count): each arc's densities are reduced to
    // those at once (its summary) instead of being held for the whole build (issue 8: 4 KB an
    // arc orbit, 1.2 GB at 1e5 holes). An arc whose count turns out otherwise (imposed counts,
    // the templates' ties) computes its densities again, and a split arc holds those of its
    // half ([`orbit_params`]).
    let uniform = options
        .block_cells
        .filter(|_| check.is_none())
        .map(|n| n.clamp(1, MAX_CELLS_PER_SIDE));
    let made: Vec<Option<(ArcTarget, Option<Summary>)>> = geoms
        .par_iter()
        .zip(&pb.arcs)
        .map(|(g, arc)| {
            let (sq, ang) = g.densities()?;
            let mut t = ArcTarget {
                circles: arc.circles.map(|c| c.0 as usize + 1),
                sq,
                ang,
                known: None,
            };
            let summary = uniform.map(|n| {
                let min_cells = t.min_cells();
                let count = super::counts::uniform_arc_count(n, min_cells);
                // As `orbit_params` forms it from two circle counts `n`.
                let nbar = 0.5 * (n + n) as f64;
                let summary = summarise(&mut t, nbar, count);
                t.known = Some(Known {
                    min_cells,
                    target: None,
                    ends: None,
                });
                summary
            });
            Some((t, summary))
        })
        .collect();
    let mut targets = Vec::with_capacity(pb.arcs.len());
    let mut summaries = Vec::with_capacity(pb.arcs.len());
    for (o, m) in made.into_iter().enumerate() {
        let (t, summary) = m.ok_or_else(|| undefined_arc(o))?;
        if let Some(d) = check.as_deref_mut() {
            d.add(&geoms[o]);
        }
        targets.push(t);
        summaries.push(summary);
    }
    // 2b. Inserted holes: split arc orbits until each fits its template.
    let split = if fluid.iter().any(|&f| f) {
        Some(split_for_templates(
            pb,
            &mut verts,
            &mut geoms,
            &mut targets,
            &mut slots,
            fluid,
        )?)
    } else {
        None
    };
    let split_arcs = split.as_ref().map_or(0, |s| s.1);
    let owned;
    let pb = match split {
        Some((split_pb, _)) => {
            owned = split_pb;
            &owned
        }
        None => pb,
    };
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
        if *c >= 0 && (*c as usize) < h && !is_fluid(*c as usize) {
            circle_fixed[*c as usize + 1] = Some(*n);
        }
    }
    // The median Apollonius radius of the vertices touching each hole (independent of the
    // target size).
    // One pass over the vertices (issue 8: a scan of every vertex per hole took 2 s at 10 000
    // holes), each vertex once per hole it touches, in vertex order.
    let mut near: Vec<Vec<f64>> = vec![Vec::new(); pb.holes.len()];
    for v in &verts {
        for (i, c) in v.circles.iter().enumerate() {
            let first = v.circles[..i].iter().all(|d| d.0 != c.0);
            if let Some(list) = near.get_mut(c.0 as usize).filter(|_| first) {
                list.push(v.radius);
            }
        }
    }
    let near_len: Vec<f64> = near
        .into_iter()
        .map(|n| median(n).unwrap_or(f64::NAN))
        .collect();
    let solve = |cell: f64, arcs: &mut Vec<ArcTarget>| -> Result<Counts, MeshError> {
        let mut circle_target = vec![1.0; ncirc];
        for (k, hole) in pb.holes.iter().enumerate() {
            let len = if near_len[k].is_finite() {
                near_len[k]
            } else {
                cell
            };
            let cl = cluster(k);
            let first = cl.first_height(hole.radius);
            circle_target[k + 1] = clustering::cells_for(len, cell, first, cl.growth) as f64;
        }
        // Holes facing each other across an arc orbit, both equally spaced along their spokes:
        // counts within `counts::MAX_COUNT_RATIO` of each other, as in bounded domains.
        let equally_spaced = |slot: usize| {
            slot >= 1
                && pb
                    .holes
                    .get(slot - 1)
                    .is_some_and(|hole| cluster(slot - 1).first_height(hole.radius).is_none())
        };
        let neighbours =
            super::counts::facing_pairs(arcs.iter().map(|a| a.circles), equally_spaced);
        let problem = CountProblem {
            circle_target,
            circle_fixed: circle_fixed.clone(),
            template: vec![false; ncirc],
            arcs: std::mem::take(arcs),
            neighbours,
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
    // The layout with the inserted holes' templates (its edges and blocks do not depend on
    // the counts) is made beside the counts and the keys: a serial pass, which would
    // otherwise leave a core idle (issue 8: 0.5 s at 1e5 holes).
    let has_fluid = fluid.iter().any(|&f| f);
    let (made, templates) = rayon::join(
        || -> Result<(Counts, Vec<BlockKey>), MeshError> {
            let counts = solve(cell, &mut targets)?;
            // Imposed counts read the keys (on layouts without templates).
            let keys = if want_keys || (options.imposed_counts.is_some() && !has_fluid) {
                block_keys(pb, &verts)
            } else {
                Vec::new()
            };
            Ok((counts, keys))
        },
        || -> Result<Option<Templated>, MeshError> {
            if !has_fluid {
                return Ok(None);
            }
            let parts = Parts {
                pb,
                verts: &verts,
                geoms: &geoms,
                targets: &[],
                summaries: &[],
                slots: &slots,
                cluster: &cluster,
                rho: &[],
            };
            // Without the arcs' nodes (its medial polylines are set for the grids at the
            // end: issue 8, the layout was made twice).
            let mut a = layout_pass(&parts)?;
            let first = a.layout.blocks.len();
            let holes: Vec<(CircleId, crate::domain::Circle)> = (0..h)
                .filter(|&k| is_fluid(k))
                .map(|k| (k as CircleId, pb.holes[k]))
                .collect();
            let filled = crate::templates::fill_inserted_holes(&mut a.layout, &holes)
                .map_err(|(c, m)| internal(format!("inserted hole {c}: {m}")))?;
            let classes = crate::grid::edge_classes(&a.layout);
            let sides = super::inserted::TemplateSides::new(&a.layout, &classes, first);
            let medial_edge: Vec<u32> = a.medial_edges.iter().map(|e| e[0]).collect();
            Ok(Some((a, classes, medial_edge, first, filled, sides)))
        },
    );
    let (mut counts, keys) = made?;
    let templates = templates?;
    // Inserted holes: the template layout's conformity classes tie arc counts in pairs
    // around every hole.
    let tie = |counts: &mut Counts| {
        if let Some((_, classes, medial_edge, _, _, _)) = &templates {
            super::inserted::tie_counts(classes, medial_edge, &mut counts.arc);
        }
    };
    tie(&mut counts);
    let mut imposed_used = false;
    if let (Some(imp), false) = (&options.imposed_counts, has_fluid) {
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
    let total_of = |counts: &Counts, cell: f64| {
        let mut total: usize = 0;
        for (o, arc) in pb.arcs.iter().enumerate() {
            for c in arc.circles {
                let nj = counts.circle[c.0 as usize + 1];
                total = total.saturating_add((counts.arc[o] + 1).saturating_mul(nj + 1));
            }
        }
        if let Some((a, classes, _, first, _, sides)) = &templates {
            let layout = &a.layout;
            // Medial block `2o + s`: sides 0 and 2 along arc orbit `o`, 1 and 3 along spokes.
            let side_count = |b: usize, k: usize| {
                let o = b / 2;
                if k.is_multiple_of(2) {
                    counts.arc[o]
                } else {
                    counts.circle[pb.arcs[o].circles[b % 2].0 as usize + 1]
                }
            };
            total = total.saturating_add(super::inserted::template_nodes(
                layout, classes, sides, *first, cell, side_count,
            ));
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
        let total = total_of(&counts, cell);
        if total <= budget || user_sized || coarsened >= super::MAX_COARSENING {
            break total;
        }
        cell *= super::coarsening_step(total, budget);
        coarsened += 1;
        counts = solve(cell, &mut targets)?;
        tie(&mut counts);
    };
    if total > MAX_TOTAL_NODES {
        return Err(MeshError::Grid(GridError::TooManyNodes {
            nodes: total,
            limit: MAX_TOTAL_NODES,
        }));
    }
    // The counts are final: every arc orbit that still holds its densities (size-driven
    // counts; a split arc's half) is reduced to the node parameters of its count, in
    // parallel, and its densities are freed before the grids are made (issue 8: 4 KB an arc
    // orbit, 1.2 GB at 1e5 holes, held through the grids). The end grading and the nodes
    // then read those parameters ([`orbit_params`]: the same bits). The density check
    // (`check`) keeps them.
    if check.is_none() {
        summarise_held(pb, &mut targets, &mut summaries, &counts);
    }
    // 4. Layout and grids, instance by instance; then the templates of the inserted holes.
    // The arcs' end grading first, for size-driven counts (as in bounded domains).
    let rho = if options.block_cells.is_none() {
        end_ratios(pb, &verts, &geoms, &targets, &summaries, &slots, &counts)?
    } else {
        Vec::new()
    };
    let parts = Parts {
        pb,
        verts: &verts,
        geoms: &geoms,
        targets: &targets,
        summaries: &summaries,
        slots: &slots,
        cluster: &cluster,
        rho: &rho,
    };
    // The nodes of the arcs, and without templates the layout beside them (a serial pass:
    // issue 8, it left a core idle); the layout's medial polylines are set from the nodes.
    let (nodes, (mut a, templated)) = match templates {
        Some((a, classes, _, first, filled, _)) => (
            arc_nodes(&parts, &counts)?,
            (a, Some((classes, first, filled))),
        ),
        None => {
            let (nodes, a) = rayon::join(|| arc_nodes(&parts, &counts), || layout_pass(&parts));
            (nodes?, (a?, None))
        }
    };
    set_medial_nodes(pb, &nodes, &mut a);
    // Nodes not kept ([`Options::keep_nodes`]): every grid measured as it is made (not with
    // smoothing, which moves the nodes after), as bounded exact mode does.
    let measurer = (!options.keep_nodes && options.smooth == 0).then(crate::quality::Measurer::new);
    // The medial blocks' grids, smoothed and flagged each on its own (see `grids_pass`).
    let grids = grids_pass(
        &parts,
        &counts,
        &nodes,
        &a,
        options.smooth,
        flag,
        measurer.as_ref(),
    );
    let (layout, (mut grids, mut flagged, figures)) = (a.layout, grids?);
    drop(nodes);
    let mut template_blocks = 0;
    let split = grids.len();
    let mut more = Vec::new();
    if let Some((classes, first, filled)) = &templated {
        template_blocks = *filled;
        let mut t = super::inserted::template_grids(&layout, classes, &grids, *first, cell)?;
        // Which templates `flag` flags: their inverted cells are counted by the measurement
        // when there is one, other flags are read from the nodes before they go.
        let counted = matches!(flag, Some(Flag::Inverted)) && measurer.is_some();
        let mut marks: Vec<bool> = match flag {
            Some(f) if !counted => t.iter().map(|g| f.flags(g)).collect(),
            _ => Vec::new(),
        };
        if let Some(m) = &measurer {
            let (figures, inverted) = crate::quality::measure_templates_and_drop(
                m,
                &layout,
                &mut t,
                &mut grids,
                split,
                MERGED_MIN_ANGLE_DEG,
            );
            more = figures;
            if counted {
                marks = inverted;
            }
        }
        flagged.extend((0..marks.len()).filter(|&k| marks[k]).map(|k| split + k));
        grids.extend(t);
    }
    let measured =
        measurer.map(|_| std::sync::Arc::new(crate::quality::Measured::new(figures, split, more)));
    Ok(Built::Mesh(Box::new(PeriodicExact {
        layout,
        grids,
        counts,
        cell_size: cell,
        coarsened_from: (coarsened > 0).then_some(default_cell),
        inconsistent_arcs,
        keys,
        split_arcs,
        template_blocks,
        flagged,
        measured,
    })))
}

/// The key ([`BlockKey`]) of block `2o + s` (side `s` of arc orbit `o`): in the frame where
/// its wall is the canonical copy, each circle counted from its copy nearest to the wall's
/// ([`super::imposed::nearest_copy`], so that the key does not depend on the box's choice of
/// copies).
fn block_keys(pb: &PeriodicBlocking, verts: &[Vertex]) -> Vec<BlockKey> {
    let cycle = |w: usize, s: Shift, wall: u32| -> Vec<CircleTag> {
        let Some(v) = verts.get(w) else {
            return Vec::new();
        };
        let touching: Vec<(CircleTag, Point)> = v
            .circles
            .iter()
            .zip(&v.tangent)
            .map(|(c, &p)| {
                let near = super::imposed::nearest_copy_of(&pb.holes, pb.size, wall, c.0);
                let tag = (
                    c.0 as i64,
                    i64::from(c.1 + s.0) - i64::from(near.0),
                    i64::from(c.2 + s.1) - i64::from(near.1),
                );
                (tag, p)
            })
            .collect();
        vertex_cycle(v.center, &touching)
    };
    // Each arc orbit's two keys on their own, in parallel, in block order (issue 8).
    pb.arcs
        .par_iter()
        .flat_map_iter(|arc| {
            (0..2).map(move |side| {
                let c = arc.circles[side];
                let d = (-c.1, -c.2);
                let [(w0, e0), (w1, e1)] = arc.ends;
                let (a, b) = (cycle(w0, add(e0, d), c.0), cycle(w1, add(e1, d), c.0));
                let wall = (c.0 as i64, 0, 0);
                if side == 0 {
                    (wall, a, b)
                } else {
                    (wall, b, a)
                }
            })
        })
        .collect()
}

/// A vertex instance: orbit and shift.
type Instance = (usize, Shift);

/// Ids per vertex instance `(orbit, shift)` and slot `k < slots(orbit)`: those of each
/// orbit's first instance (the first one given an id) in dense arrays, the others (the copies
/// by the box's edges) in a map (issue 8: a map for all, 0.3 s of cache misses in the serial
/// [`layout_pass`] at 1e5 holes). What a lookup gives does not depend on where it is kept.
struct InstanceIds {
    /// Per orbit, its first instance's shift.
    first: Vec<Option<Shift>>,
    /// Per orbit, where its slots start in `ids` (one more entry: the end).
    offset: Vec<usize>,
    /// Per slot of a first instance, its id ([`InstanceIds::NONE`] until given).
    ids: Vec<u32>,
    others: HashMap<(Instance, usize), u32>,
}

impl InstanceIds {
    const NONE: u32 = u32::MAX;

    /// For orbits with `slots` slots each.
    fn new(slots: impl Iterator<Item = usize>) -> InstanceIds {
        let mut offset = vec![0];
        for n in slots {
            offset.push(offset[offset.len() - 1] + n);
        }
        let orbits = offset.len() - 1;
        InstanceIds {
            first: vec![None; orbits],
            ids: vec![Self::NONE; offset[orbits]],
            offset,
            others: HashMap::default(),
        }
    }

    /// The dense slot of `(i, k)` and whether `i` is its orbit's first instance (`Some(None)`:
    /// the orbit has no first instance yet); `None` when `(i, k)` has no dense slot.
    fn slot(&self, (w, s): Instance, k: usize) -> Option<(usize, Option<bool>)> {
        let (lo, hi) = (*self.offset.get(w)?, *self.offset.get(w + 1)?);
        (k < hi - lo).then(|| (lo + k, self.first[w].map(|f| f == s)))
    }

    fn get(&self, i: Instance, k: usize) -> Option<u32> {
        match self.slot(i, k) {
            Some((x, Some(true))) => Some(self.ids[x]).filter(|&id| id != Self::NONE),
            _ => self.others.get(&(i, k)).copied(),
        }
    }

    /// Gives `(i, k)` its id; `i` becomes its orbit's first instance when the orbit has none.
    fn insert(&mut self, i: Instance, k: usize, id: u32) {
        match self.slot(i, k) {
            Some((x, Some(true))) => self.ids[x] = id,
            Some((x, None)) => {
                self.first[i.0] = Some(i.1);
                self.ids[x] = id;
            }
            _ => {
                self.others.insert((i, k), id);
            }
        }
    }
}

/// The layout under construction: every vertex instance, tangent point and spoke once.
struct Builder<'a> {
    pb: &'a PeriodicBlocking,
    verts: &'a [Vertex],
    layout: BlockLayout,
    /// Centre vertex per vertex instance (one slot).
    centre: InstanceIds,
    /// Tangent point vertex per vertex instance and slot.
    tangent: InstanceIds,
    /// Spoke edge (centre to wall) per tangent point instance.
    spokes: InstanceIds,
}

impl Builder<'_> {
    fn push(&mut self, p: Point) -> u32 {
        self.layout.vertices.push(p);
        (self.layout.vertices.len() - 1) as u32
    }
    fn centre_vertex(&mut self, w: usize, s: Shift) -> u32 {
        if let Some(v) = self.centre.get((w, s), 0) {
            return v;
        }
        let v = self.push(shifted(self.verts[w].center, s, self.pb.size));
        self.centre.insert((w, s), 0, v);
        v
    }
    fn tangent_vertex(&mut self, i: Instance, k: usize) -> u32 {
        if let Some(v) = self.tangent.get(i, k) {
            return v;
        }
        let v = self.push(shifted(self.verts[i.0].tangent[k], i.1, self.pb.size));
        self.tangent.insert(i, k, v);
        v
    }
    /// The spoke edge of tangent point `k` of instance `i` (its nodes are its blocks' end
    /// columns, made with the grids from the positions of its two ends).
    fn spoke(&mut self, i: Instance, k: usize) -> u32 {
        if let Some(e) = self.spokes.get(i, k) {
            return e;
        }
        let c = self.centre_vertex(i.0, i.1);
        let t = self.tangent_vertex(i, k);
        self.layout.edges.push(Edge {
            ends: [c, t],
            curve: Curve::Segment,
            kind: EdgeKind::Spoke,
        });
        let e = (self.layout.edges.len() - 1) as u32;
        self.spokes.insert(i, k, e);
        e
    }
}

/// The natural node parameters of arc orbit `o` for the counts `counts` into `params`
/// ([`arc_params_into`] of its weights for its `nbar`): from its held densities, else from
/// its summary when that is for the same `nbar` and count, else from its densities computed
/// again (`None` only if they cannot be, which they could the first time). The same
/// parameters, bit for bit, whichever way.
fn orbit_params(
    pb: &PeriodicBlocking,
    geoms: &[ArcGeometry],
    targets: &[ArcTarget],
    summaries: &[Option<Summary>],
    counts: &Counts,
    o: usize,
    params: &mut Vec<f64>,
) -> Option<()> {
    let nbar = orbit_nbar(pb, counts, o);
    let n = counts.arc[o];
    let t = &targets[o];
    let computed;
    // Held densities first: a split arc holds its half's, and its summary (if any) is the
    // whole arc's.
    let (sq, ang) = if t.holds_densities() {
        (&t.sq[..], &t.ang[..])
    } else {
        if let Some(Some((nb, p))) = summaries.get(o) {
            if nb.to_bits() == nbar.to_bits() && p.len() == n + 1 {
                params.clear();
                params.extend_from_slice(p);
                return Some(());
            }
        }
        computed = geoms.get(o)?.densities()?;
        (&computed.0[..], &computed.1[..])
    };
    *params = params_of(sq, ang, nbar, n);
    Some(())
}

/// The error of an arc orbit `o` whose exact medial arc is not defined.
fn undefined_arc(o: usize) -> MeshError {
    internal(format!(
        "arc orbit {o}: the exact medial arc is not defined"
    ))
}

/// The mean wall-normal count `nbar` of arc orbit `o` for the counts `counts`: that of its
/// two holes.
fn orbit_nbar(pb: &PeriodicBlocking, counts: &Counts, o: usize) -> f64 {
    let c = pb.arcs[o].circles;
    0.5 * (counts.circle[c[0].0 as usize + 1] + counts.circle[c[1].0 as usize + 1]) as f64
}

/// Every arc orbit of `targets` that holds its densities gets the summary of its final count
/// (its `nbar` and the node parameters [`orbit_params`] would compute from them) and lets
/// them go, in parallel; the others are left as they are.
fn summarise_held(
    pb: &PeriodicBlocking,
    targets: &mut [ArcTarget],
    summaries: &mut [Option<Summary>],
    counts: &Counts,
) {
    targets
        .par_iter_mut()
        .zip(summaries.par_iter_mut())
        .enumerate()
        .filter(|(_, (t, _))| t.holds_densities())
        .for_each(|(o, (t, summary))| {
            *summary = Some(summarise(t, orbit_nbar(pb, counts, o), counts.arc[o]));
        });
}

/// The summary of `t` (which holds its densities) for `nbar` and `n` cells, its densities let
/// go.
fn summarise(t: &mut ArcTarget, nbar: f64, n: usize) -> Summary {
    let params = params_of(&t.sq, &t.ang, nbar, n);
    (t.sq, t.ang) = (Vec::new(), Vec::new());
    (nbar, params)
}

/// What an arc orbit's densities are reduced to with a fixed grid per block: the `nbar` and
/// the node parameters of the count it gets (its lower bound goes to its target's
/// [`Known`]); for size-driven counts, once the counts are final ([`summarise_held`]).
type Summary = (f64, Vec<f64>);

/// The node parameters of an arc of densities `sq`, `ang` with `n` cells for a mean
/// wall-normal count `nbar` ([`arc_params_into`] of its weights).
fn params_of(sq: &[f64], ang: &[f64], nbar: f64, n: usize) -> Vec<f64> {
    let mut weights: Vec<f64> = sq
        .iter()
        .zip(ang)
        .map(|(&s, &a)| super::counts::weight(nbar, s, a))
        .collect();
    let mut params = Vec::with_capacity(n + 1);
    arc_params_into(&mut weights, ang, n, &mut params, &mut Vec::new());
    params
}

/// The end grading's ratios of every arc orbit ([`super::grading::end_ratios`]), from its
/// natural node parameters for the counts `counts` (those [`arc_nodes`] starts from). A spoke
/// orbit is a slot of a vertex orbit, so the orbits' vertex indices and slots pose the same
/// per-vertex problems as a bounded domain's vertices.
fn end_ratios(
    pb: &PeriodicBlocking,
    verts: &[Vertex],
    geoms: &[ArcGeometry],
    targets: &[ArcTarget],
    summaries: &[Option<Summary>],
    slots: &[[[usize; 2]; 2]],
    counts: &Counts,
) -> Result<Vec<[f64; 2]>, MeshError> {
    let mut inputs = Vec::with_capacity(pb.arcs.len());
    let mut params = Vec::new();
    for (o, arc) in pb.arcs.iter().enumerate() {
        let n = counts.arc[o];
        orbit_params(pb, geoms, targets, summaries, counts, o, &mut params)
            .ok_or_else(|| undefined_arc(o))?;
        // `slots[o][end][side]`; the grading reads `[side][end]`.
        let s = slots[o];
        inputs.push(super::grading::EndInput {
            ends: arc.ends.map(|(w, _)| w),
            slots: [[s[0][0], s[1][0]], [s[0][1], s[1][1]]],
            n,
            widths: super::grading::end_widths(&geoms[o], &params),
        });
    }
    Ok(super::grading::end_ratios(&inputs, verts.len()))
}

/// What [`arc_nodes`], [`layout_pass`] and [`grids_pass`] read: the orbits' geometry, targets and slots, the clustering per hole.
struct Parts<'a> {
    pb: &'a PeriodicBlocking,
    verts: &'a [Vertex],
    geoms: &'a [ArcGeometry],
    targets: &'a [ArcTarget],
    /// Per arc orbit, the node parameters computed with its densities for `(nbar, count)`
    /// (the count is their length less one), when the densities were not kept.
    summaries: &'a [Option<Summary>],
    slots: &'a [[[usize; 2]; 2]],
    cluster: &'a (dyn Fn(usize) -> super::Clustering + Sync),
    /// The end grading's ratios per arc orbit ([`super::grading`]); empty: not graded.
    rho: &'a [[f64; 2]],
}

/// The layout with the inserted holes' templates, before the counts: the assembled layout,
/// its conformity classes, each arc orbit's first medial edge, the number of medial blocks,
/// the number of template blocks and the template sides' classes
/// ([`super::inserted::TemplateSides`]).
type Templated = (
    Assembled,
    (Vec<usize>, usize),
    Vec<u32>,
    usize,
    usize,
    super::inserted::TemplateSides,
);

/// Per arc orbit: its medial nodes and the nodes of its two walls.
type ArcNodes = (Vec<Point>, [Vec<Point>; 2]);

/// The nodes of every arc orbit with the counts `counts`, in parallel: node parameters
/// (graded by `parts.rho`), then the exact geometry's evaluations (most of the build's work).
fn arc_nodes(parts: &Parts, counts: &Counts) -> Result<Vec<ArcNodes>, MeshError> {
    let Parts {
        pb,
        geoms,
        targets,
        summaries,
        rho,
        ..
    } = *parts;
    (0..pb.arcs.len())
        .into_par_iter()
        .map_init(
            super::grading::Scratch::default,
            |graded, o| -> Result<ArcNodes, MeshError> {
                let g = &geoms[o];
                let n = counts.arc[o];
                let mut params = Vec::with_capacity(n + 1);
                orbit_params(pb, geoms, targets, summaries, counts, o, &mut params)
                    .ok_or_else(|| undefined_arc(o))?;
                if let Some(&r) = rho.get(o) {
                    params = super::grading::grade_piece(g, params, r, graded);
                }
                let mut m_nodes = Vec::with_capacity(n + 1);
                let mut a_nodes = [Vec::with_capacity(n + 1), Vec::with_capacity(n + 1)];
                g.nodes_into(&params, &mut m_nodes, &mut a_nodes)
                    .ok_or_else(|| {
                        internal(format!("arc orbit {o}: a medial node is not defined"))
                    })?;
                Ok((m_nodes, a_nodes))
            },
        )
        .collect::<Result<_, _>>()
}

/// The layout of one period (vertices and edges numbered in first-use order, serially),
/// with what each block's grid needs. Its vertices, edges and blocks do not depend on the
/// counts; the medial edges' polylines do: each is made with its two ends only, and given its
/// nodes by [`set_medial_nodes`] before the grids.
fn layout_pass(parts: &Parts) -> Result<Assembled, MeshError> {
    let Parts {
        pb,
        verts,
        geoms,
        slots,
        cluster,
        ..
    } = *parts;
    let size = pb.size;
    let mut jobs: Vec<GridJob> = Vec::with_capacity(2 * pb.arcs.len());
    let mut medial_edges_of = Vec::with_capacity(pb.arcs.len());
    // Sized once (issue 8: growing them copied them): a vertex orbit has one instance per
    // copy it is used in, mostly one, and a tangent point and a spoke per circle; an eighth
    // more for the copies by the box's edges.
    let centres = verts.len() + verts.len() / 8;
    let tangents: usize = verts.iter().map(|v| v.circles.len()).sum();
    let tangents = tangents + tangents / 8;
    let mut layout = BlockLayout::default();
    layout.vertices.reserve(centres + tangents);
    layout.edges.reserve(4 * pb.arcs.len() + tangents);
    layout.blocks.reserve(2 * pb.arcs.len());
    let degrees = || verts.iter().map(|v| v.circles.len());
    let mut b = Builder {
        pb,
        verts,
        layout,
        centre: InstanceIds::new(verts.iter().map(|_| 1)),
        tangent: InstanceIds::new(degrees()),
        spokes: InstanceIds::new(degrees()),
    };
    for (o, arc) in pb.arcs.iter().enumerate() {
        let g = &geoms[o];
        let shifts = arc.circles.map(|c| (-c.1, -c.2));
        let mut medial_edges = [0u32; 2];
        for side in 0..2 {
            let d = shifts[side];
            if side == 1 && shifts[1] == shifts[0] {
                medial_edges[1] = medial_edges[0];
                continue;
            }
            let v = arc.ends.map(|(w, s)| b.centre_vertex(w, add(s, d)));
            let pts = v.map(|k| b.layout.vertices[k as usize]).to_vec();
            b.layout.edges.push(Edge {
                ends: v,
                curve: Curve::Polyline(pts),
                kind: EdgeKind::Medial,
            });
            medial_edges[side] = (b.layout.edges.len() - 1) as u32;
        }
        medial_edges_of.push(medial_edges);
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
            let cl = cluster(hole as usize);
            let first = cl.first_height(pb.holes[hole as usize].radius);
            let [(w0, e0), (w1, e1)] = arc.ends;
            let (i0, i1) = ((w0, add(e0, d)), (w1, add(e1, d)));
            let (k0, k1) = (slots[o][0][side], slots[o][1][side]);
            let sp0 = b.spoke(i0, k0);
            let sp1 = b.spoke(i1, k1);
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
            jobs.push(GridJob {
                o,
                side,
                d,
                first,
                growth: cl.growth,
                spokes: [sp0, sp1],
            });
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
    Ok(Assembled {
        layout: b.layout,
        jobs,
        medial_edges: medial_edges_of,
    })
}

/// The medial polyline of an arc orbit's instance moved by `d`: its nodes `m_nodes`
/// translated, the two ends exactly the instance's end vertices `ends`.
fn medial_polyline(m_nodes: &[Point], d: Shift, size: [f64; 2], ends: [Point; 2]) -> Vec<Point> {
    let mut pts: Vec<Point> = m_nodes.iter().map(|&p| shifted(p, d, size)).collect();
    if let Some(f) = pts.first_mut() {
        *f = ends[0];
    }
    if let Some(l) = pts.last_mut() {
        *l = ends[1];
    }
    pts
}

/// Give the medial edges of `a` (made by [`layout_pass`] with their ends only) their
/// polylines from `nodes`.
fn set_medial_nodes(pb: &PeriodicBlocking, nodes: &[ArcNodes], a: &mut Assembled) {
    // The polylines in parallel, then moved into their edges.
    let layout = &a.layout;
    let lines: Vec<(usize, Vec<Point>)> = pb
        .arcs
        .par_iter()
        .zip(&a.medial_edges)
        .zip(nodes)
        .flat_map_iter(|((arc, medial_edges), node)| {
            let shifts = arc.circles.map(|c| (-c.1, -c.2));
            let sides = if shifts[1] == shifts[0] { 1 } else { 2 };
            (0..sides).map(move |side| {
                let e = medial_edges[side] as usize;
                let ends = layout.edges[e].ends.map(|k| layout.vertices[k as usize]);
                (e, medial_polyline(&node.0, shifts[side], pb.size, ends))
            })
        })
        .collect();
    for (e, pts) in lines {
        a.layout.edges[e].curve = Curve::Polyline(pts);
    }
}

/// The grids of the medial blocks of `a` (whose medial polylines are `nodes`'), in parallel,
/// in block order.
///
/// With `smooth > 0` each grid then takes that many Winslow sweeps (as in bounded exact mode;
/// it keeps the block's boundary, which the templates copy), and with `flag` the blocks
/// flagged ([`Flag`], increasing) are listed, each measured right after it is made (and
/// smoothed), while its nodes are in cache.
///
/// With `measurer` (and no smoothing), each block is also measured for the report right
/// after it is made ([`crate::quality::Measured`]), in chunks of the quality pass's blocks,
/// its wall sides from the layout, and its nodes dropped unless a template block lies on one
/// of its sides (the templates are made from them): the chunks' figures are returned.
fn grids_pass(
    parts: &Parts,
    counts: &Counts,
    nodes: &[ArcNodes],
    a: &Assembled,
    smooth: usize,
    flag: Option<Flag>,
    measurer: Option<&crate::quality::Measurer>,
) -> Result<GridsMade, MeshError> {
    // Column `i` of a block is the spoke from its wall node to its medial node; its end
    // columns are the spokes of its end vertices (the tangent point to the centre), the same
    // nodes in both blocks at a spoke (`GridScratch` gives each column exactly the nodes of
    // `super::spoke_column`, as the spokes' own nodes were computed before, issue 8).
    let size = parts.pb.size;
    let layout = &a.layout;
    let spoke_ends = |o: usize, e: u32| -> Result<(Point, Point), MeshError> {
        let edge = layout
            .edges
            .get(e as usize)
            .filter(|edge| edge.kind == EdgeKind::Spoke)
            .ok_or_else(|| internal(format!("arc orbit {o}: a spoke not made")))?;
        let [c, t] = edge.ends;
        Ok((layout.vertices[t as usize], layout.vertices[c as usize]))
    };
    let mut flags = vec![false; a.jobs.len()];
    let make = |scratch: &mut super::grid_nodes::GridScratch,
                (job, flagged): (&GridJob, &mut bool)|
     -> Result<BlockGrid, MeshError> {
        let n = counts.arc[job.o];
        let nj = counts.circle[parts.pb.arcs[job.o].circles[job.side].0 as usize + 1];
        let (m_nodes, a_nodes) = &nodes[job.o];
        scratch.clear();
        for i in 0..=n {
            let k = if job.side == 0 { i } else { n - i };
            let (a, m) = if k == 0 || k == n {
                spoke_ends(job.o, job.spokes[if k == 0 { 0 } else { 1 }])?
            } else {
                (
                    shifted(a_nodes[job.side][k], job.d, size),
                    shifted(m_nodes[k], job.d, size),
                )
            };
            scratch.push(a, m);
        }
        let mut g = BlockGrid {
            ni: n,
            nj,
            nodes: scratch.nodes(nj, job.first, job.growth),
        };
        if smooth > 0 {
            let rows = super::smoothing::boundary_layer_rows(&g);
            super::smoothing::winslow(&mut g, smooth, rows);
        }
        *flagged = flag.is_some_and(|f| f.flags(&g));
        Ok(g)
    };
    let (grids, figures) = match measurer.filter(|_| smooth == 0) {
        None => (
            a.jobs
                .par_iter()
                .zip(flags.par_iter_mut())
                .map_init(super::grid_nodes::GridScratch::default, make)
                .collect::<Result<Vec<_>, MeshError>>()?,
            Vec::new(),
        ),
        Some(m) => {
            // The edges template blocks lie on (after the medial blocks, when holes were
            // inserted): the medial blocks on them keep their nodes.
            let medial = a.jobs.len();
            let on_template = super::inserted::template_edges(layout, medial);
            let chunk = crate::quality::CHUNK;
            let parts: Vec<(Vec<BlockGrid>, crate::quality::ChunkFigures)> = a
                .jobs
                .par_chunks(chunk)
                .zip(flags.par_chunks_mut(chunk))
                .enumerate()
                .map_init(
                    super::grid_nodes::GridScratch::default,
                    |scratch, (c, (jobs, fl))| {
                        let mut cm = m.chunk();
                        let mut out = Vec::with_capacity(jobs.len());
                        for (k, item) in jobs.iter().zip(fl.iter_mut()).enumerate() {
                            let mut g = make(scratch, item)?;
                            let block = &layout.blocks[c * chunk + k];
                            cm.block_in(layout, block, &g, MERGED_MIN_ANGLE_DEG);
                            let keep = block.sides.iter().any(|s| {
                                on_template.get(s.edge as usize).copied().unwrap_or(false)
                            });
                            if !keep {
                                g.nodes = Vec::new();
                            }
                            out.push(g);
                        }
                        Ok((out, cm.finish()))
                    },
                )
                .collect::<Result<_, MeshError>>()?;
            let mut grids = Vec::with_capacity(medial);
            let mut figures = Vec::with_capacity(parts.len());
            for (g, f) in parts {
                grids.extend(g);
                figures.push(f);
            }
            (grids, figures)
        }
    };
    let flagged = (0..flags.len()).filter(|&b| flags[b]).collect();
    Ok((grids, flagged, figures))
}

/// What [`grids_pass`] made: the medial blocks' grids, the blocks flagged, and when measured
/// the chunks' figures.
type GridsMade = (
    Vec<BlockGrid>,
    Vec<usize>,
    Vec<crate::quality::ChunkFigures>,
);

/// What [`layout_pass`] made.
struct Assembled {
    layout: BlockLayout,
    /// One per medial block, in block order.
    jobs: Vec<GridJob>,
    /// The medial edges of each arc orbit: its side-0 block's, its side-1 block's (the same
    /// edge when both sides are in one instance).
    medial_edges: Vec<[u32; 2]>,
}

/// What [`grids_pass`] needs to make the grid of the block on side `side` of arc orbit `o`
/// (instance shifted by `d`), once the layout is made.
struct GridJob {
    o: usize,
    side: usize,
    d: Shift,
    first: Option<f64>,
    growth: f64,
    /// The spoke edges at its ends, end `A` then end `B`.
    spokes: [u32; 2],
}

/// The orbits being split for the templates ([`split_for_templates`]).
struct Splitter<'a> {
    arcs: Vec<PeriodicArc>,
    vertices: Vec<PeriodicVertex>,
    verts: &'a mut Vec<Vertex>,
    geoms: &'a mut Vec<ArcGeometry>,
    targets: &'a mut Vec<ArcTarget>,
    slots: &'a mut Vec<[[usize; 2]; 2]>,
    fluid: &'a [bool],
    /// The arc orbits on each inserted hole.
    on: HashMap<u32, Vec<usize>>,
    splits: usize,
}

impl Splitter<'_> {
    fn is_fluid(&self, k: u32) -> bool {
        self.fluid.get(k as usize).copied().unwrap_or(false)
    }

    fn note(&mut self, o: usize) {
        for c in self.arcs[o].circles {
            if self.is_fluid(c.0) {
                self.on.entry(c.0).or_default().push(o);
            }
        }
    }

    /// `(orbit, sweep on hole k)` for every arc around hole `k` (an orbit between a hole and
    /// its own image twice).
    fn sweeps(&self, k: u32) -> Vec<(usize, f64)> {
        let mut list = self.on.get(&k).cloned().unwrap_or_default();
        list.sort_unstable();
        list.dedup();
        let mut out = Vec::new();
        for o in list {
            for side in 0..2 {
                if self.arcs[o].circles[side].0 == k {
                    out.push((o, self.geoms[o].sweep[side].abs()));
                }
            }
        }
        out
    }

    /// The circle of arc orbit `o` other than hole `k`.
    fn other(&self, o: usize, k: u32) -> u32 {
        let c = self.arcs[o].circles;
        if c[0].0 == k {
            c[1].0
        } else {
            c[0].0
        }
    }

    fn odd(&self, k: u32) -> bool {
        self.sweeps(k).len() % 2 == 1
    }

    /// Split arc orbit `o` at its middle: `o` keeps the first half, a new orbit the second.
    fn split(&mut self, o: usize) -> Result<(), MeshError> {
        let (m, a, rho, first, second) = self.geoms[o]
            .split()
            .ok_or_else(|| internal(format!("arc orbit {o}: no middle to split at")))?;
        let densities = |g: &ArcGeometry| {
            g.densities()
                .ok_or_else(|| internal(format!("arc orbit {o}: a split half is not defined")))
        };
        let (d1, d2) = (densities(&first)?, densities(&second)?);
        let circles = self.arcs[o].circles;
        let w = self.verts.len();
        self.verts.push(Vertex {
            center: m,
            radius: rho,
            tangent: a.to_vec(),
            circles: circles.to_vec(),
        });
        self.vertices.push(PeriodicVertex {
            circles: circles.to_vec(),
            near: m,
        });
        let end = self.arcs[o].ends[1];
        let hint = self.arcs[o].hint.map(|x| 0.5 * x);
        self.arcs[o].ends[1] = (w, (0, 0));
        self.arcs[o].hint = hint;
        self.arcs.push(PeriodicArc {
            circles,
            ends: [(w, (0, 0)), end],
            hint,
        });
        self.note(self.arcs.len() - 1);
        let s = self.slots[o];
        self.slots[o] = [s[0], [0, 1]];
        self.slots.push([[0, 1], s[1]]);
        self.geoms[o] = first;
        self.geoms.push(second);
        let target = |(sq, ang)| ArcTarget {
            circles: circles.map(|c| c.0 as usize + 1),
            sq,
            ang,
            known: None,
        };
        self.targets[o] = target(d1);
        self.targets.push(target(d2));
        self.splits += 1;
        Ok(())
    }
}

/// The widest of `list` (`(orbit, sweep)`; the first of equal ones).
fn widest(list: &[(usize, f64)]) -> Option<(usize, f64)> {
    list.iter().copied().fold(None, |best, x| match best {
        Some(b) if b.1 >= x.1 => Some(b),
        _ => Some(x),
    })
}

/// Split arc orbits at their middle (an exact medial point with its two exact spokes, a
/// vertex orbit of two circles) until every inserted hole (`fluid`) has an even number
/// `k >= 4` of arcs around its canonical copy, none wider than [`MAX_TEMPLATE_SWEEP`]:
/// first the widest arc on each hole while it has fewer than 4 or one too wide, then, for a
/// hole left with an odd count, its widest arc to a circle that needs no parity (a real hole),
/// else to another inserted hole with an odd count (both become even). The split orbits are
/// in the returned blocking (`verts`, `geoms`, `targets` and `slots` extended alike), with the
/// number of splits. `Err` when a hole cannot be made to fit (the caller meshes without the
/// inserted holes).
fn split_for_templates(
    pb: &PeriodicBlocking,
    verts: &mut Vec<Vertex>,
    geoms: &mut Vec<ArcGeometry>,
    targets: &mut Vec<ArcTarget>,
    slots: &mut Vec<[[usize; 2]; 2]>,
    fluid: &[bool],
) -> Result<(PeriodicBlocking, usize), MeshError> {
    let mut sp = Splitter {
        arcs: pb.arcs.clone(),
        vertices: pb.vertices.clone(),
        verts,
        geoms,
        targets,
        slots,
        fluid,
        on: HashMap::default(),
        splits: 0,
    };
    for o in 0..sp.arcs.len() {
        sp.note(o);
    }
    let mut holes: Vec<u32> = sp.on.keys().copied().collect();
    holes.sort_unstable();
    // 1. Widths and at least four arcs.
    for &k in &holes {
        for _ in 0..=super::inserted::MAX_SPLITS_PER_HOLE {
            let list = sp.sweeps(k);
            let Some((o, w)) = widest(&list) else {
                break;
            };
            if list.len() >= 4 && w <= MAX_TEMPLATE_SWEEP {
                break;
            }
            sp.split(o)?;
        }
    }
    // 2. Parity: from each hole left with an odd count, a breadth-first search over the arc
    //    orbits (widest first; not those between a hole and its own image, which add two arcs
    //    to it) to a real hole (which needs no parity) or another inserted hole with an odd
    //    count; splitting every orbit on the path flips the parity of its two ends only.
    for &k in &holes {
        if !sp.odd(k) {
            continue;
        }
        let mut from: HashMap<u32, (u32, usize)> = HashMap::default();
        let mut queue = std::collections::VecDeque::from([k]);
        let mut end = None;
        while let Some(u) = queue.pop_front() {
            let mut list = sp.sweeps(u);
            list.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            for (o, _) in list {
                let j = sp.other(o, u);
                if j == u || j == k || from.contains_key(&j) {
                    continue;
                }
                from.insert(j, (u, o));
                if !sp.is_fluid(j) || sp.odd(j) {
                    end = Some(j);
                    break;
                }
                queue.push_back(j);
            }
            if end.is_some() {
                break;
            }
        }
        let Some(mut j) = end else {
            return Err(internal(format!(
                "inserted hole {k} keeps an odd number of arcs"
            )));
        };
        while j != k {
            let (u, o) = from[&j];
            sp.split(o)?;
            j = u;
        }
    }
    for &k in &holes {
        let list = sp.sweeps(k);
        let w = widest(&list).map_or(0.0, |x| x.1);
        if list.len() < 4 || list.len() % 2 == 1 || w > MAX_TEMPLATE_SWEEP {
            return Err(internal(format!(
                "inserted hole {k} does not fit its template ({} arcs, widest {w} rad)",
                list.len()
            )));
        }
    }
    let splits = sp.splits;
    Ok((
        PeriodicBlocking {
            size: pb.size,
            holes: pb.holes.clone(),
            vertices: sp.vertices,
            arcs: sp.arcs,
        },
        splits,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bits(grids: &[crate::mesh::BlockGrid]) -> Vec<u64> {
        grids
            .iter()
            .flat_map(|g| g.nodes.iter().flat_map(|p| p.map(f64::to_bits)))
            .collect()
    }

    /// A build without block keys (`mesh_periodic`'s) is the build with them, less the keys;
    /// with imposed counts it still reads them (the same counts as the keyed build's).
    #[test]
    fn a_build_without_keys_is_the_keyed_build() {
        let pd = crate::layouts::periodic_bubbles(40, 2).expect("layout");
        let options = Options {
            block_cells: Some(4),
            ..Options::default()
        };
        let p = crate::periodic::periodic_layout(&pd, &options).expect("layout");
        let pb = p.blocking.as_ref().expect("exact input");
        let (Built::Mesh(a), Built::Mesh(b)) = (
            build_unless_backwards_with(pb, &options, &[], true, None, None).unwrap(),
            build_unless_backwards_with(pb, &options, &[], false, None, None).unwrap(),
        ) else {
            panic!("no arc runs backwards here");
        };
        assert_eq!(a.keys.len(), a.layout.blocks.len());
        assert!(b.keys.is_empty());
        assert_eq!(a.layout, b.layout);
        assert_eq!(bits(&a.grids), bits(&b.grids));
        // Imposed counts: the keyed build's counts, one more cell on every arc.
        let arcs: Vec<[usize; 2]> = pb
            .arcs
            .iter()
            .map(|arc| arc.circles.map(|c| c.0 as usize + 1))
            .collect();
        let mut arc = a.counts.arc.clone();
        arc.iter_mut().for_each(|n| *n += 1);
        let counts = a
            .keys
            .iter()
            .enumerate()
            .map(|(b, k)| (k.clone(), [arc[b / 2], a.counts.circle[arcs[b / 2][b % 2]]]))
            .collect();
        let imposed = crate::exact_mode::imposed::ImposedCounts::new(counts);
        let with = Options {
            block_cells: None,
            imposed_counts: Some(std::sync::Arc::new(imposed)),
            ..options.clone()
        };
        let Built::Mesh(c) =
            build_unless_backwards_with(pb, &with, &[], false, None, None).unwrap()
        else {
            panic!("no arc runs backwards here");
        };
        assert_eq!(c.counts.arc, arc);
        assert!(!c.keys.is_empty());
    }

    proptest::proptest! {
        /// [`InstanceIds`] answers as one map of every `(instance, slot)` would, whatever the
        /// order of the instances (first ones dense, the others in its map), slots out of
        /// range and unknown orbits included.
        #[test]
        fn instance_ids_answer_as_a_map(
            degrees in proptest::collection::vec(1usize..5, 1..6),
            ops in proptest::collection::vec(
                (0usize..7, -1i32..2, -1i32..2, 0usize..6, proptest::bool::ANY),
                0..80,
            ),
        ) {
            let mut ids = InstanceIds::new(degrees.iter().copied());
            let mut model: std::collections::HashMap<(Instance, usize), u32> = Default::default();
            for (n, &(w, a, b, k, insert)) in ops.iter().enumerate() {
                let i = (w, (a, b));
                if insert {
                    ids.insert(i, k, n as u32);
                    model.insert((i, k), n as u32);
                } else {
                    proptest::prop_assert_eq!(ids.get(i, k), model.get(&(i, k)).copied());
                }
            }
            for (&(i, k), &id) in &model {
                proptest::prop_assert_eq!(ids.get(i, k), Some(id));
            }
        }
    }

    /// The box whose first layout has arcs running backwards
    /// (`tests/data/periodic_backwards_100.json`), then random boxes of 60 holes from the
    /// seeds `1..seeds`.
    fn test_boxes(seeds: u64) -> Vec<crate::periodic::PeriodicDomain> {
        let backwards_box = match crate::domain::AnyDomain::from_json_str(include_str!(
            "../../tests/data/periodic_backwards_100.json"
        ))
        .unwrap()
        {
            crate::domain::AnyDomain::Periodic(pd) => pd,
            _ => panic!("not a periodic domain"),
        };
        let mut boxes = vec![backwards_box];
        for seed in 1..seeds {
            boxes.push(crate::layouts::periodic_bubbles(60, seed).expect("layout"));
        }
        boxes
    }

    /// A build that takes the vertex orbits solved for a blocking of the same period
    /// ([`SolvedOrbits`]) finds every orbit there and is the build that solves them: the same
    /// circles bit for bit, the same grids and layout (random boxes and the box whose first
    /// layout has arcs running backwards); orbits solved for another period are not taken.
    #[test]
    fn known_vertex_orbits_give_the_same_build() {
        let boxes = test_boxes(3);
        let options = Options {
            collapse_fraction: crate::periodic::EXACT_COLLAPSE_FRACTION,
            block_cells: Some(4),
            ..Options::default()
        };
        let bits = |v: &Vertex| {
            (
                v.center.map(f64::to_bits),
                v.radius.to_bits(),
                v.tangent
                    .iter()
                    .map(|p| p.map(f64::to_bits))
                    .collect::<Vec<_>>(),
                v.circles.clone(),
            )
        };
        let mut built = 0;
        for pd in &boxes {
            let p = crate::periodic::periodic_layout(pd, &options).expect("layout");
            let Some(pb) = &p.blocking else { continue };
            let (_, solved) = backwards_orbits(pb).expect("solved");
            let table = solved.table(pb).expect("the same period");
            assert!(pb
                .vertices
                .iter()
                .all(|v| table.contains_key(&(v.circles.as_slice(), v.near.map(f64::to_bits)))));
            let (fresh, ..) = orbits_of(pb, None).unwrap();
            let (taken, ..) = orbits_of(pb, Some(&solved)).unwrap();
            assert_eq!(
                fresh.iter().map(bits).collect::<Vec<_>>(),
                taken.iter().map(bits).collect::<Vec<_>>()
            );
            let mut other = pb.clone();
            other.size[0] *= 1.5;
            assert!(solved.table(&other).is_none());
            match (
                build_unless_backwards_with(pb, &options, &[], true, None, None).unwrap(),
                build_unless_backwards_with(pb, &options, &[], true, Some(solved), None).unwrap(),
            ) {
                (Built::Mesh(a), Built::Mesh(b)) => {
                    assert_eq!(a.grids, b.grids);
                    assert_eq!(a.layout, b.layout);
                    built += 1;
                }
                (Built::Backwards(a), Built::Backwards(b)) => assert_eq!(a, b),
                _ => panic!("one build stopped, the other did not"),
            }
        }
        assert!(built > 0);
    }

    /// [`poor_and_backwards`] (one solve per vertex orbit) answers as [`poor_vertices`] and
    /// [`backwards_orbits`] separately, bit for bit: random boxes at several ratios, and a box
    /// whose first layout has arcs running backwards.
    #[test]
    fn poor_and_backwards_from_one_solve_are_the_separate_answers() {
        let boxes = test_boxes(4);
        let options = Options {
            collapse_fraction: crate::periodic::EXACT_COLLAPSE_FRACTION,
            ..Options::default()
        };
        let (mut poor_seen, mut backwards_seen) = (0, 0);
        for pd in &boxes {
            let p = crate::periodic::periodic_layout(pd, &options).expect("layout");
            let Some(pb) = &p.blocking else { continue };
            for limit in [0.8, 1.0, 1.5, 2.0] {
                let (poor, backwards) = poor_and_backwards(pb, limit);
                let expected = poor_vertices(pb, limit);
                assert_eq!(
                    poor.iter()
                        .map(|x| (x.0.to_bits(), x.1.map(f64::to_bits), x.2.to_bits()))
                        .collect::<Vec<_>>(),
                    expected
                        .iter()
                        .map(|x| (x.0.to_bits(), x.1.map(f64::to_bits), x.2.to_bits()))
                        .collect::<Vec<_>>()
                );
                let separate = backwards_orbits(pb).map(|b| b.0);
                assert_eq!(backwards.map(|b| b.0).ok(), separate.clone().ok());
                poor_seen += poor.len();
                backwards_seen += separate.map_or(0, |b| b.len());
            }
        }
        assert!(
            poor_seen > 0 && backwards_seen > 0,
            "{poor_seen} {backwards_seen}"
        );
    }

    /// With a fixed grid per block the arcs' densities are reduced to summaries (lower bound
    /// and node parameters) as they are computed, with size-driven counts once the counts are
    /// final ([`summarise_held`]); the density check keeps them held. Both give the same
    /// mesh, bit for bit: plain boxes, and boxes with a hole taken as inserted (its arcs split
    /// and their counts tied by the template, so that some parameters are computed again from
    /// the geometry, or summarised from a half's densities).
    #[test]
    fn summarised_densities_give_the_mesh_of_held_ones() {
        let mut templated = 0;
        let sized = |cells: usize| Options {
            cells,
            ..Options::default()
        };
        let fixed = |n: usize| Options {
            block_cells: Some(n),
            ..Options::default()
        };
        for seed in 1..4 {
            let pd = crate::layouts::periodic_bubbles(40, seed).expect("layout");
            for options in [fixed(3), fixed(6), sized(3), sized(6)] {
                let n = options.block_cells.unwrap_or(options.cells);
                let p = crate::periodic::periodic_layout(&pd, &options).expect("layout");
                let Some(pb) = &p.blocking else { continue };
                for fluid in [vec![], vec![true], vec![false, true, true]] {
                    let summarised =
                        build_checking(pb, &options, &fluid, None, false, true, None, None);
                    let mut d = super::super::densities::Deviation::default();
                    let held =
                        build_checking(pb, &options, &fluid, Some(&mut d), false, true, None, None);
                    match (summarised, held) {
                        (Ok(Built::Mesh(a)), Ok(Built::Mesh(b))) => {
                            assert_eq!(a.layout, b.layout, "seed {seed}, n {n}, {fluid:?}");
                            assert_eq!(a.counts, b.counts);
                            assert_eq!(bits(&a.grids), bits(&b.grids));
                            templated += usize::from(a.template_blocks > 0);
                        }
                        (Ok(Built::Backwards(a)), Ok(Built::Backwards(b))) => assert_eq!(a, b),
                        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                        (a, b) => panic!("seed {seed}, n {n}: {a:?} against {b:?}"),
                    }
                }
            }
        }
        assert!(templated >= 2, "{templated}");
    }

    /// The blocks a build flags as it makes each grid ([`Flag`]) are those a pass over the
    /// finished grids finds (`quality::inverted_blocks`, `quality::has_corner_below`), from
    /// none to most blocks flagged, the templates of inserted holes included; and smoothing
    /// each grid as it is made gives the grids of smoothing them all after the build (the
    /// medial blocks; the templates copy their boundaries, which smoothing keeps).
    #[test]
    fn blocks_flagged_while_made_are_those_of_a_pass_over_the_grids() {
        let (mut flagged, mut clean, mut templated) = (0, 0, 0);
        for seed in 1..4 {
            let pd = crate::layouts::periodic_bubbles(40, seed).expect("layout");
            let plain = Options {
                block_cells: Some(5),
                ..Options::default()
            };
            let p = crate::periodic::periodic_layout(&pd, &plain).expect("layout");
            let Some(pb) = &p.blocking else { continue };
            for fluid in [vec![], vec![false, true, true]] {
                let build = |options: &Options, flag| match build_checking(
                    pb, options, &fluid, None, false, false, None, flag,
                ) {
                    Ok(Built::Mesh(x)) => Some(x),
                    _ => None,
                };
                let Some(unsmoothed) = build(&plain, None) else {
                    continue;
                };
                assert!(unsmoothed.flagged.is_empty());
                for smooth in [0, 2] {
                    let options = Options {
                        smooth,
                        ..plain.clone()
                    };
                    // Smoothed after the build, as before the pass smoothed each grid.
                    let mut after = unsmoothed.grids.clone();
                    let medial = after.len() - unsmoothed.template_blocks;
                    for g in &mut after[..medial] {
                        let rows = crate::exact_mode::smoothing::boundary_layer_rows(g);
                        crate::exact_mode::smoothing::winslow(g, smooth, rows);
                    }
                    for flag in [
                        Flag::Inverted,
                        Flag::CornerBelow(1.0),
                        Flag::CornerBelow(50.0),
                        Flag::CornerBelow(89.0),
                    ] {
                        let x = build(&options, Some(flag)).expect("the same build");
                        assert_eq!(bits(&x.grids), bits(&after), "seed {seed}, {fluid:?}");
                        let want = match flag {
                            Flag::Inverted => crate::quality::inverted_blocks(&x.grids),
                            Flag::CornerBelow(deg) => (0..x.grids.len())
                                .filter(|&b| crate::quality::has_corner_below(&x.grids[b], deg))
                                .collect(),
                        };
                        assert_eq!(x.flagged, want, "seed {seed}, {fluid:?}, {flag:?}");
                        if want.is_empty() {
                            clean += 1;
                        } else {
                            flagged += 1;
                        }
                        if x.template_blocks > 0 && want.iter().any(|&b| b >= medial) {
                            templated += 1;
                        }
                    }
                }
            }
        }
        assert!(
            flagged > 0 && clean > 0 && templated > 0,
            "{flagged} {clean} {templated}"
        );
    }
}
