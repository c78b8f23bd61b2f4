//! Exact mode (the default): blocks on the exact medial axis of the circles, gridded along
//! spokes (DESIGN.md sections 5 and 7; the paper's section 6 wish, node matching by the
//! maximal empty circle).
//!
//! The *topology* is that of paper mode (the Delaunay triangulation of boundary samples gives
//! the medial graph and Blocking2D its blocks, [`crate::blocking`]); the *geometry* comes from
//! the circles themselves:
//! - medial vertex `v` of circles `(i, j, k)` = the Apollonius circle tangent to all three
//!   ([`crate::apollonius::apollonius`], the root whose tangent points turn counter-clockwise
//!   like the triangle's samples, nearest the triangle's circumcentre); its tangent points are
//!   the block corners on the circles;
//! - medial arc between circles `p` and `q` from vertex `A` to `B`: the exact bisector
//!   `|m - c_p| - s_p = |m - c_q| - s_q` (`s = +r` for a hole, `-R` for the bounding circle), a
//!   hyperbola branch between two holes and an ellipse arc between a hole and the bounding
//!   circle. It is parametrised by the angle `theta` of the touching point `a = c_p + r_p u`,
//!   `u = (cos theta, sin theta)`, moving from its value at `A` to its value at `B` (the sweep's
//!   turn count is taken from the sampled wall of paper mode). With `n` the unit normal into the
//!   fluid at `a` (`u` for a hole, `-u` for the bounding circle), the medial point is
//!   `m = a + rho n` where the empty circle's radius `rho` solves `|m - c_q|^2 = (rho + s_q)^2`,
//!   linear in `rho` after squaring: `rho = (s_q^2 - |d|^2) / (2 (d . n - s_q))`, `d = a - c_q`.
//!   The touching point on `q` is `c_q + |s_q| (m - c_q) / |m - c_q|`. An end off the
//!   bisector (a vertex merged by short-arc collapse, [`collapsed`]) has its offset faded out
//!   over the whole arc towards the other end's (`ArcGeometry::offset`, `blend`; the touching
//!   points of such an arc are the radial projections of the shifted point);
//! - each block (side 0 on a circle, side 2 on the arc) is the ruled surface of the spokes from
//!   its wall to the arc's nodes: the grid line `i` runs straight from the touching point
//!   `a(m_i)` to `m_i`, along the circle's normal. All spokes of one circle pass through its
//!   centre and never cross, so every cell is a convex quadrilateral between two spokes with
//!   positive Jacobians, and the first grid line off the wall is exactly normal to it;
//! - nodes along a spoke follow the circle's [`Clustering`]; nodes along the arc equidistribute
//!   `max(nbar ds / rho, dtheta / 15 deg)` (`ds` along the spoke mid-curves, `nbar` the mean
//!   wall-normal count of the two circles), so cells are near square on average and no cell
//!   spans more than about 15 degrees of wall, also when a count is below its target
//!   (`equidistribution::arc_params_into`); counts come from [`counts::CountProblem`].
//!
//! Shared sides are bitwise identical: each arc's medial nodes and each vertex spoke's nodes
//! are computed once and copied into both blocks; the ends of every arc are exactly the
//! rounded Apollonius centres and tangent points.

pub mod annulus;
pub mod benchmarks;
pub mod clustering;
pub mod collapsed;
pub mod counts;
pub mod densities;
pub mod equidistribution;
pub(crate) mod grading;
pub mod grid_nodes;
pub mod imposed;
pub mod inserted;
pub mod inverted;
pub mod metrics;
mod near_median;
pub mod periodic;
pub mod piece_cache;
pub mod smoothing;

pub use clustering::{Clustering, FirstCell};
pub use piece_cache::PieceCache;

use crate::apollonius::{apollonius, Choice, Site};
use crate::blocking::Blocking;
use crate::domain::{CircleId, Domain};
use crate::geometry::{length, Point};
use crate::grid::{GridError, MAX_CELLS_PER_SIDE, MAX_TOTAL_NODES};
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use crate::mesh::BlockGrid;
use crate::mesher::{MeshError, Options, MERGED_MIN_ANGLE_DEG};
use counts::{ArcTarget, CountProblem, Counts, Known};
use equidistribution::arc_params_into;
#[cfg(test)]
use equidistribution::{equidistribute, equidistribute_into};
use piece_cache::{GeomKey, GridKey, Params, Payload};
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

/// Sub-steps used to sample each medial arc for the node distribution: all of them where the
/// densities are not smooth, else [`densities::COARSE_SUBSTEPS`] (see [`densities`]).
pub const ARC_SUBSTEPS: usize = 256;

/// The largest wall angle one cell should span (15 degrees, as in paper mode).
pub const MAX_WALL_ANGLE: f64 = PI / 12.0;

/// A medial vertex in exact geometry: the Apollonius circle of its three circles, or for a
/// collapsed vertex of degree `n` the circle of its co-circular group or the merge of its
/// members ([`collapsed`]); a split vertex ([`inserted`]) has two circles.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactVertex {
    pub center: Point,
    pub radius: f64,
    /// The circles (for an Apollonius vertex, in the order of the interior triangle's
    /// samples).
    pub circles: Vec<CircleId>,
    /// The tangent point on each circle (the spoke ends), same order.
    pub tangent: Vec<Point>,
}

impl ExactVertex {
    /// The slot (0..3) of circle `c`.
    pub fn slot(&self, c: CircleId) -> Option<usize> {
        self.circles.iter().position(|&x| x == c)
    }
}

/// One wall: centre, radius and the tangency sense `s` (`+r` hole, `-R` bounding circle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Wall {
    c: Point,
    r: f64,
    s: f64,
}

impl Wall {
    fn of(domain: &Domain, id: CircleId) -> Wall {
        let circle = domain.circle(id);
        Wall {
            c: circle.center,
            r: circle.radius,
            s: if id < 0 {
                -circle.radius
            } else {
                circle.radius
            },
        }
    }
    fn site(&self) -> Site {
        Site {
            center: self.c,
            s: self.s,
        }
    }
    fn angle_of(&self, p: Point) -> f64 {
        (p[1] - self.c[1]).atan2(p[0] - self.c[0])
    }
    /// The touching point of the empty circle centred at `m`.
    fn project(&self, m: Point) -> Point {
        let d = [m[0] - self.c[0], m[1] - self.c[1]];
        let l = length(d[0], d[1]);
        [self.c[0] + self.r * d[0] / l, self.c[1] + self.r * d[1] / l]
    }
}

/// The medial point of walls `p` and `q` whose touching point on `p` is at angle `theta`:
/// `(a, m, rho)` (see the module docs). `None` when it is not finite or `rho < 0`.
fn medial_point(p: &Wall, q: &Wall, theta: f64) -> Option<(Point, Point, f64)> {
    medial_point_u(p, q, [theta.cos(), theta.sin()])
}

/// [`medial_point`] for the unit vector `u` of the touching angle.
fn medial_point_u(p: &Wall, q: &Wall, u: Point) -> Option<(Point, Point, f64)> {
    let a = [p.c[0] + p.r * u[0], p.c[1] + p.r * u[1]];
    let n = if p.s < 0.0 { [-u[0], -u[1]] } else { u };
    let d = [a[0] - q.c[0], a[1] - q.c[1]];
    let den = 2.0 * (d[0] * n[0] + d[1] * n[1] - q.s);
    let rho = (q.s * q.s - (d[0] * d[0] + d[1] * d[1])) / den;
    let m = [a[0] + rho * n[0], a[1] + rho * n[1]];
    (rho.is_finite() && rho >= 0.0 && m[0].is_finite() && m[1].is_finite()).then_some((a, m, rho))
}

/// `|a - b|` by [`crate::geometry::length`] (`sqrt(x² + y²)`, `hypot` only near underflow or
/// overflow), as [`Wall::project`]'s: libm's `hypot` took 3% of the CPU at 1e4 and 1e5
/// bubbles (issue 8), for the touching points and spoke lengths of every arc node and the
/// blended arcs' densities.
fn dist(a: Point, b: Point) -> f64 {
    length(a[0] - b[0], a[1] - b[1])
}

fn mid(a: Point, b: Point) -> Point {
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
}

/// The angle from `a - c` to `b - c`, in `(-pi, pi]` (the densities use [`larger_turn`]).
#[cfg(test)]
fn turn(c: Point, a: Point, b: Point) -> f64 {
    let (cross, dot) = turn_parts(c, a, b);
    cross.atan2(dot)
}

/// `(cross, dot)` of `a - c` and `b - c`: `turn` (kept for the tests) is `cross.atan2(dot)`.
fn turn_parts(c: Point, a: Point, b: Point) -> (f64, f64) {
    let u = [a[0] - c[0], a[1] - c[1]];
    let v = [b[0] - c[0], b[1] - c[1]];
    (u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1])
}

/// `max(|atan2(c0, d0)|, |atan2(c1, d1)|)`, bit for bit, with one `atan2` when the larger
/// angle is clear: both below 90 degrees (`d > 0`) and `tan` of one more than `1 + 1e-9` times
/// the other's (compared as `|c0| d1` against `|c1| d0`, each rounded once). `atan2` is
/// accurate to about one ulp, far below that margin, so the larger angle's `atan2` is the
/// larger value. Otherwise (ties, obtuse or non-finite cases) both are computed.
fn larger_turn(c0: f64, d0: f64, c1: f64, d1: f64) -> f64 {
    const MARGIN: f64 = 1.0 + 1e-9;
    if d0 > 0.0 && d1 > 0.0 {
        let (p0, p1) = (c0.abs() * d1, c1.abs() * d0);
        if p0 > p1 * MARGIN && p1.is_finite() {
            return c0.atan2(d0).abs();
        }
        if p1 > p0 * MARGIN && p0.is_finite() {
            return c1.atan2(d1).abs();
        }
    }
    c0.atan2(d0).abs().max(c1.atan2(d1).abs())
}

fn internal(msg: String) -> MeshError {
    MeshError::Internal(format!("exact mode: {msg}"))
}

/// The exact medial vertices of a medial graph: one Apollonius circle per interior triangle.
/// Errors ([`MeshError::Internal`]) when a triangle's circles are not three different circles
/// or no tangent circle exists (the sampled combinatorics disagree with the circles).
pub fn exact_vertices(
    domain: &Domain,
    medial: &crate::medial::MedialGraph,
) -> Result<Vec<ExactVertex>, MeshError> {
    exact_vertices_with(domain, medial, &[])
}

/// [`exact_vertices`], reusing `known[k]` when it is `Some`: the counter-clockwise Apollonius
/// circle of vertex `k` nearest its position, as [`crate::cocircular::vertex_circles`] solves
/// it (the same sites and the same choice as the first try here, so the same result; the
/// refinement has them already). Missing or `None` entries are solved.
pub fn exact_vertices_with(
    domain: &Domain,
    medial: &crate::medial::MedialGraph,
    known: &[Option<crate::apollonius::Apollonius>],
) -> Result<Vec<ExactVertex>, MeshError> {
    use rayon::prelude::*;
    let nh = domain.hole_count() as CircleId;
    // Solved in parallel, collected in vertex order: the first error is that of the first
    // failing vertex, for every thread count.
    let solved: Vec<Result<ExactVertex, MeshError>> = medial
        .vertices
        .par_iter()
        .enumerate()
        .with_max_len(crate::tasks::PIECES)
        .map(|(k, v)| {
            let c = v.circles;
            if c.iter().any(|&x| x < -1 || x >= nh) || c[0] == c[1] || c[1] == c[2] || c[0] == c[2]
            {
                return Err(internal(format!(
                    "medial vertex {k} does not touch three different circles: {c:?}"
                )));
            }
            if let Some(Some(ap)) = known.get(k) {
                return Ok(ExactVertex {
                    center: ap.center,
                    radius: ap.radius,
                    circles: c.to_vec(),
                    tangent: ap.tangent_points.to_vec(),
                });
            }
            let sites = c.map(|x| Wall::of(domain, x).site());
            let ap = apollonius(sites, Choice::ccw().near(v.position))
                .or_else(|_| apollonius(sites, Choice::any().near(v.position)))
                .map_err(|e| {
                    internal(format!("no Apollonius circle for medial vertex {k}: {e}"))
                })?;
            Ok(ExactVertex {
                center: ap.center,
                radius: ap.radius,
                circles: c.to_vec(),
                tangent: ap.tangent_points.to_vec(),
            })
        })
        .collect();
    solved.into_iter().collect()
}

/// Per circle slot (`c + 1`, `ncirc` slots), the radii of the vertices touching circle `c`,
/// in vertex order: the list `vertices.filter(|v| v.circles.contains(&c)).map(radius)` for
/// every circle at once, in one pass (O(vertices), not O(circles x vertices); a vertex listing
/// a circle twice counts once, as in the filter). Circles outside `-1..ncirc - 1` are ignored.
/// Tested against the filter in `tests/perf_scale.rs`.
pub fn radii_by_circle(vertices: &[ExactVertex], ncirc: usize) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = vec![Vec::new(); ncirc];
    for v in vertices {
        for (k, &c) in v.circles.iter().enumerate() {
            if v.circles[..k].contains(&c) {
                continue;
            }
            if let Some(list) = usize::try_from(c + 1).ok().and_then(|i| out.get_mut(i)) {
                list.push(v.radius);
            }
        }
    }
    out
}

/// One medial arc sampled in exact geometry.
#[derive(Debug, Clone)]
pub(crate) struct ArcGeometry {
    /// The walls of `circles[0]` and `circles[1]`.
    walls: [Wall; 2],
    /// Which wall is parametrised by its touching angle.
    param: usize,
    /// Start angle and sweep (from vertex `A` to `B`) of each wall's touching point.
    start: [f64; 2],
    sweep: [f64; 2],
    /// End vertices, exact: centres and tangent points `[wall 0, wall 1]`.
    ends_m: [Point; 2],
    ends_a: [[Point; 2]; 2],
    /// Per end, how far its centre is off the bisector: `ends_m[k]` minus the bisector point
    /// with the same touching point on the parametrised wall ([`ArcGeometry::end_offsets`]);
    /// zero for an end on the bisector (an Apollonius vertex, a co-circular group's centre),
    /// non-zero at a vertex merged by short-arc collapse. [`ArcGeometry::at`] fades it out
    /// over the arc towards the other end's ([`blend`]).
    offset: [Point; 2],
}

/// An end offset below this fraction of the end's spoke length is rounding (an Apollonius
/// vertex computed apart from the bisector points): taken as zero.
const OFFSET_NOISE: f64 = 1e-9;

/// The weight of an end's offset at parameter distance `s` from that end (`0 <= s <= 1`):
/// `1` at the end, `0` at the other end, with zero slope at both (`1 - smoothstep(s)`).
/// [`ArcGeometry::at`] adds `blend(t) o0 + blend(1 - t) o1` to the bisector point at `t`: the
/// two weights add up to one, so the arc's offset from the bisector moves smoothly from one
/// end's to the other's over the whole arc.
///
/// Zero slope at an end makes the arc leave a merged vertex along the bisector's tangent:
/// with the offset dropped at once, the first cell's side ran from the merged centre along
/// the parametrised wall's normal and the corner cell flattened (or folded) as more cells
/// brought the first node closer. The fade spans the whole arc, not half of it (the
/// twenty-fourth session's choice): the offset's rate of change along the arc is halved, and
/// a large offset on a short arc no longer bends the arc into cells of 4-6 degrees (1 000
/// bubbles: a flat block at 16 and 32 cells but not at 4 and 8, so the local fixes made the
/// block topology depend on the resolution; 1e4 bubbles: smallest angle 5.5 -> 14.7 degrees;
/// 1e5: no local-fix round left, smallest angle 7.6 -> 14.4 degrees).
fn blend(s: f64) -> f64 {
    if s >= 1.0 {
        return 0.0;
    }
    if s <= 0.0 {
        return 1.0;
    }
    1.0 - s * s * (3.0 - 2.0 * s)
}

impl ArcGeometry {
    /// The arc between the exact ends `ends_m` (centres) with touching points `ends_a[end][wall]`;
    /// `hints[k]` is the sampled sweep of wall `k` from end 0 to end 1 (its turn count is kept,
    /// [`exact_sweep`]).
    fn new(walls: [Wall; 2], ends_m: [Point; 2], ends_a: [[Point; 2]; 2], hints: [f64; 2]) -> Self {
        let (s0, w0) = exact_sweep(&walls[0], ends_a[0][0], ends_a[1][0], hints[0]);
        let (s1, w1) = exact_sweep(&walls[1], ends_a[0][1], ends_a[1][1], hints[1]);
        ArcGeometry {
            walls,
            param: if w1.abs() > w0.abs() { 1 } else { 0 },
            start: [s0, s1],
            sweep: [w0, w1],
            ends_m,
            ends_a,
            offset: [[0.0; 2]; 2],
        }
        .with_offsets()
    }

    /// `self` with [`ArcGeometry::offset`] computed from its ends.
    pub(crate) fn with_offsets(mut self) -> Self {
        self.offset = self.end_offsets();
        self
    }

    /// Per end `k`, `ends_m[k]` minus the bisector point whose touching point on the
    /// parametrised wall is at the end's angle (`start[p] + k sweep[p]`); zero when that point
    /// is not defined or the difference is rounding ([`OFFSET_NOISE`]).
    fn end_offsets(&self) -> [Point; 2] {
        let p = self.param;
        let q = 1 - p;
        let mut out = [[0.0; 2]; 2];
        for (k, o) in out.iter_mut().enumerate() {
            let theta = self.start[p] + k as f64 * self.sweep[p];
            let Some((_, m, rho)) = medial_point(&self.walls[p], &self.walls[q], theta) else {
                continue;
            };
            let d = [self.ends_m[k][0] - m[0], self.ends_m[k][1] - m[1]];
            if d[0].hypot(d[1]) > OFFSET_NOISE * rho && d[0].is_finite() && d[1].is_finite() {
                *o = d;
            }
        }
        out
    }

    /// True when an end is off the bisector ([`ArcGeometry::offset`]).
    pub(crate) fn blended(&self) -> bool {
        self.offset != [[0.0; 2]; 2]
    }

    /// Split at parameter `1/2`: the middle medial point, its touching points and empty-circle
    /// radius, and the two halves (each exactly the same curve as its part of `self`, since the
    /// bisector does not depend on the parametrisation, when no end is off the bisector; else
    /// the middle point is off the bisector too, by the mean of the ends' offsets, and each
    /// half fades between its own two ends' offsets: the halves meet at the middle point).
    /// `None` when the middle is undefined.
    pub(crate) fn split(&self) -> Option<(Point, [Point; 2], f64, ArcGeometry, ArcGeometry)> {
        let (m, a, rho) = self.at(0.5)?;
        let half = [0.5 * self.sweep[0], 0.5 * self.sweep[1]];
        let first = ArcGeometry::new(self.walls, [self.ends_m[0], m], [self.ends_a[0], a], half);
        let second = ArcGeometry::new(self.walls, [m, self.ends_m[1]], [a, self.ends_a[1]], half);
        Some((m, a, rho, first, second))
    }

    /// [`ArcGeometry::at`] of every parameter of `params`, appended: the medial points to `m`,
    /// the touching points on the two walls to `a[0]` and `a[1]`. `None` (the vectors then
    /// partly filled) where a point is not defined.
    fn nodes_into(
        &self,
        params: &[f64],
        m: &mut Vec<Point>,
        a: &mut [Vec<Point>; 2],
    ) -> Option<()> {
        for &t in params {
            let (mt, at, _) = self.at(t)?;
            m.push(mt);
            a[0].push(at[0]);
            a[1].push(at[1]);
        }
        Some(())
    }

    /// Medial point and both touching points at parameter `t` in `[0, 1]` (exact ends).
    ///
    /// At an end the empty circle's radius is the mean of the distances to both touching
    /// points: equal for an exact Apollonius vertex, but not at a vertex merged by short-arc
    /// collapse, where the distance to one wall alone made the arc's first or last sub-step
    /// density depend on which of its circles the numbering put first (1% of that sub-step,
    /// 1e-5 of the node parameters; issue 8: the same layout triangulated with another
    /// numbering must give the same mesh).
    fn at(&self, t: f64) -> Option<(Point, [Point; 2], f64)> {
        let end = |k: usize| {
            let (m, a) = (self.ends_m[k], self.ends_a[k]);
            (m, a, 0.5 * (dist(m, a[0]) + dist(m, a[1])))
        };
        if t <= 0.0 {
            return Some(end(0));
        }
        if t >= 1.0 {
            return Some(end(1));
        }
        let p = self.param;
        let q = 1 - p;
        let theta = self.start[p] + t * self.sweep[p];
        let (a, m, rho) = medial_point(&self.walls[p], &self.walls[q], theta)?;
        if self.blended() {
            // Off the bisector near a merged end: the offset faded out, the touching points
            // the radial projections (spokes stay normal to their walls).
            let (w0, w1) = (blend(t), blend(1.0 - t));
            let [o0, o1] = self.offset;
            let m = [
                m[0] + w0 * o0[0] + w1 * o1[0],
                m[1] + w0 * o0[1] + w1 * o1[1],
            ];
            let both = [self.walls[0].project(m), self.walls[1].project(m)];
            let rho = 0.5 * (dist(m, both[0]) + dist(m, both[1]));
            let ok = both.iter().flatten().chain(&m).all(|x| x.is_finite()) && rho.is_finite();
            return ok.then_some((m, both, rho));
        }
        let b = self.walls[q].project(m);
        if !(b[0].is_finite() && b[1].is_finite()) {
            return None;
        }
        let mut both = [a, a];
        both[q] = b;
        Some((m, both, rho))
    }
}

/// Exact sweep of a wall's touching point from `a0` to `a1`, with the turn count from `hint`
/// (the sampled wall's sweep in the same direction).
fn exact_sweep(w: &Wall, a0: Point, a1: Point, hint: f64) -> (f64, f64) {
    let start = w.angle_of(a0);
    let raw = w.angle_of(a1) - start;
    let k = ((hint - raw) / TAU).round();
    (start, raw + k * TAU)
}

/// The sweep of a block's side-0 wall in the paper layout, in the side's direction.
fn wall_hint(layout: &BlockLayout, block: usize) -> Option<f64> {
    let side = layout.blocks.get(block)?.sides[0];
    match layout.edges.get(side.edge as usize)?.curve {
        Curve::Arc { sweep, .. } => Some(if side.reversed { -sweep } else { sweep }),
        _ => None,
    }
}

/// Index of circle `id` in per-circle arrays: the bounding circle first.
fn cidx(id: CircleId) -> usize {
    (id + 1) as usize
}

/// The most times the default target cell size is coarsened to bring a mesh under
/// [`node_budget`] (see the limits in [`assemble`]).
pub const MAX_COARSENING: usize = 8;

/// How many times the nodes of `cells` x `cells` per block a mesh at the default target size
/// may have before that size is coarsened ([`node_budget`]): on average 8x finer per block
/// side than asked for.
pub const BUDGET_FACTOR: usize = 64;

/// The fewest nodes [`node_budget`] allows (`2^22`, about 4.2 M): layouts of a few blocks
/// keep their counts from geometry up to this size.
pub const BUDGET_MIN_NODES: usize = 1 << 22;

/// The most nodes a mesh of `blocks` blocks at the default target size (exact mode, no
/// `cell_size`, `block_cells` or imposed counts) may have before that size is coarsened:
/// [`BUDGET_FACTOR`] times `blocks (cells + 1)^2`, at least [`BUDGET_MIN_NODES`], at most
/// [`MAX_TOTAL_NODES`].
///
/// The default size comes from the median Apollonius radius; where most medial vertices
/// are tiny (tiny holes and the holes refinement inserts around them, near-touching close
/// packs) it is tiny everywhere, and the large blocks got hundreds of times the cells the
/// median block has (two holes of 1e-4 R in a disk: 160 M cells). Layouts without such
/// vertices stay below it: random bubbles have about 2.5x the nominal nodes, the median of
/// 328 random layouts of a sweep (clusters, lattices, near-touching and near-wall circles,
/// rings, mixed sizes) 6.7x and its 90th percentile 42x; the few above had 60x to 3000x
/// (307 M cells for 400 blocks).
///
/// ```
/// use medial_blocks::exact_mode::{node_budget, BUDGET_MIN_NODES};
/// assert_eq!(node_budget(8, 16), BUDGET_MIN_NODES);
/// assert_eq!(node_budget(10_000, 16), 64 * 10_000 * 17 * 17);
/// assert_eq!(node_budget(10_000_000, 16), medial_blocks::grid::MAX_TOTAL_NODES);
/// ```
pub fn node_budget(blocks: usize, cells: usize) -> usize {
    let per_block = cells
        .saturating_add(1)
        .saturating_mul(cells.saturating_add(1));
    BUDGET_FACTOR
        .saturating_mul(blocks)
        .saturating_mul(per_block)
        .clamp(BUDGET_MIN_NODES, MAX_TOTAL_NODES)
}

/// The factor one coarsening step multiplies the target size by, for a mesh of `total`
/// nodes over `budget` ([`node_budget`]; bounded and periodic domains): nodes scale about as
/// `1 / h^2` where counts are above their floors, so aim a little under the budget, by at
/// least 1.25x per step (floors make the steps smaller).
pub(crate) fn coarsening_step(total: usize, budget: usize) -> f64 {
    let ratio = total as f64 / budget as f64;
    (1.02 * ratio.sqrt()).max(1.25)
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    // The element a full sort by `total_cmp` puts at `len / 2` (a total order: the same
    // value, bit for bit), found in linear time.
    let k = v.len() / 2;
    Some(*v.select_nth_unstable_by(k, f64::total_cmp).1)
}

/// The clustering of circle `id`: a per-circle override, else the domain's.
pub fn clustering_of(options: &Options, id: CircleId) -> Clustering {
    options
        .circle_clustering
        .iter()
        .find(|(c, _)| *c == id)
        .map(|(_, k)| *k)
        .unwrap_or(options.clustering)
}

/// The most Winslow sweeps per block [`Options::smooth`] may ask for (each sweep visits every
/// node of the mesh; more is refused before any work, like an absurd `--cells`).
pub const MAX_SMOOTH_SWEEPS: usize = 1000;

/// Check the exact-mode options.
pub fn validate_options(options: &Options) -> Result<(), MeshError> {
    if options.smooth > MAX_SMOOTH_SWEEPS {
        return Err(MeshError::Options(format!(
            "--smooth {} is more than the limit of {MAX_SMOOTH_SWEEPS} sweeps",
            options.smooth
        )));
    }
    if let Some(h) = options.cell_size {
        if !(h.is_finite() && h > 0.0) {
            return Err(MeshError::Options(format!(
                "--cell-size must be a positive length, not {h}"
            )));
        }
    }
    options
        .clustering
        .validate()
        .map_err(|e| MeshError::Options(format!("clustering: {e}")))?;
    for (c, k) in &options.circle_clustering {
        k.validate()
            .map_err(|e| MeshError::Options(format!("clustering of circle {c}: {e}")))?;
    }
    for (c, n) in &options.wall_cells {
        if *n == 0 || *n > MAX_CELLS_PER_SIDE {
            return Err(MeshError::Options(format!(
                "wall-normal cells of circle {c} must be in 1..={MAX_CELLS_PER_SIDE}, not {n}"
            )));
        }
    }
    Ok(())
}

/// The nodes of one spoke from the wall point `a` (`j = 0`) to the medial point `m`
/// (`j = n`), `n + 1` nodes with the given clustering; the ends are exactly `a` and `m`
/// (the tests' single-spoke form of [`spoke_column`]).
#[cfg(test)]
fn spoke_nodes(a: Point, m: Point, n: usize, first: Option<f64>, growth: f64) -> Vec<Point> {
    let mut out = vec![[0.0; 2]; n + 1];
    let mut d = Vec::with_capacity(n + 1);
    spoke_column(a, m, n, first, growth, &mut d, &mut out, 0, 1);
    out
}

/// The nodes of one spoke (wall point `a` at `j = 0`, medial point `m` at `j = n`, the ends
/// exactly `a` and `m`) written into `nodes[i + j * stride]` for `j` in `0..=n` (a grid's column
/// `i`, without allocating: `d` is the distances' buffer, reused from spoke to spoke).
#[allow(clippy::too_many_arguments)]
fn spoke_column(
    a: Point,
    m: Point,
    n: usize,
    first: Option<f64>,
    growth: f64,
    d: &mut Vec<f64>,
    nodes: &mut [Point],
    i: usize,
    stride: usize,
) {
    let len = dist(a, m);
    clustering::spoke_distances_into(len, n, first, growth, d);
    for (j, &x) in d.iter().enumerate() {
        let t = if len > 0.0 { x / len } else { 0.0 };
        nodes[i + j * stride] = [a[0] + t * (m[0] - a[0]), a[1] + t * (m[1] - a[1])];
    }
    nodes[i] = a;
    nodes[i + n * stride] = m;
}

/// Per-task buffers of the grid loop of [`assemble_cached`] (rayon's `map_init`): the arc
/// nodes' touching points, the block columns (`grid_nodes::GridScratch`), the weights, their
/// running sums and node parameters of a piece whose parameters are computed there. Reused from piece to piece instead of allocated and
/// freed by each (issue 8: the allocator's lock was contended between the threads); nothing
/// in them outlives a piece.
#[derive(Default)]
struct PieceScratch {
    a_nodes: [Vec<Point>; 2],
    grid: grid_nodes::GridScratch,
    weights: Vec<f64>,
    prefix: Vec<f64>,
    params: Vec<f64>,
    graded: grading::Scratch,
}

thread_local! {
    /// The weights' running sums of [`summarize`] (one buffer per worker thread).
    static SUMMARY_PREFIX: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// A piece's densities reduced to what its counts and nodes need: the lower bound and the
/// target for `nbar` ([`Known`]), and the node parameters `(nbar, n, params)` for the count `n`
/// it gets before template ties (`uniform`: a fixed grid of that many cells per block, else
/// the size-driven count). The same values, bit for bit, as from the densities later.
/// `scratch` holds the densities and weights (reused from piece to piece: only the parameters
/// stay allocated, so the heap does not fragment between them).
fn summarize(
    g: &ArcGeometry,
    nbar: f64,
    uniform: Option<usize>,
    scratch: &mut ArcTarget,
) -> Option<(Known, Params)> {
    scratch.known = None;
    g.densities_into(&mut scratch.sq, &mut scratch.ang)?;
    let lb = scratch.min_cells();
    let target = scratch.target(nbar);
    let n = match uniform {
        Some(n) => counts::uniform_arc_count(n, lb),
        None => counts::arc_count(target, lb),
    };
    // The weights replace `sq` in place (the same values as collected into a new vector).
    for (s, a) in scratch.sq.iter_mut().zip(&scratch.ang) {
        *s = counts::weight(nbar, *s, *a);
    }
    let known = Known {
        min_cells: lb,
        target: Some((nbar, target)),
        ends: None,
    };
    let mut params = Vec::with_capacity(n + 1);
    SUMMARY_PREFIX.with_borrow_mut(|prefix| {
        arc_params_into(&mut scratch.sq, &scratch.ang, n, &mut params, prefix)
    });
    Some((known, (nbar, n, params)))
}

/// The natural node parameters of piece `e` (geometry `g`, densities held by `t` or computed
/// here) for `nbar` and `n` cells ([`arc_params_into`] of its weights), and its target for
/// `nbar` (the sum of the weights, as [`ArcTarget::target`]).
fn natural_params(
    e: usize,
    g: &ArcGeometry,
    t: &ArcTarget,
    nbar: f64,
    n: usize,
    scratch: &mut PieceScratch,
) -> Result<(Vec<f64>, f64), MeshError> {
    let computed;
    let (sq, ang): (&[f64], &[f64]) = if t.holds_densities() {
        (&t.sq, &t.ang)
    } else {
        computed = g
            .densities()
            .ok_or_else(|| internal(format!("arc {e}: the exact medial arc is not defined")))?;
        (&computed.0, &computed.1)
    };
    let weights = &mut scratch.weights;
    weights.clear();
    weights.extend(
        sq.iter()
            .zip(ang)
            .map(|(&s, &a)| counts::weight(nbar, s, a)),
    );
    let target = weights.iter().sum();
    arc_params_into(weights, ang, n, &mut scratch.params, &mut scratch.prefix);
    Ok((std::mem::take(&mut scratch.params), target))
}

/// What exact mode built, beyond the mesh.
#[derive(Debug, Clone)]
pub struct ExactMesh {
    pub layout: BlockLayout,
    pub grids: Vec<BlockGrid>,
    /// The exact vertices: those of the skeleton, then one per split arc.
    pub vertices: Vec<ExactVertex>,
    /// The solved counts: `circle[c + 1]` wall-normal cells of circle `c`, `arc[e]` cells along
    /// arc piece `e` (after the template ties of `inserted::tie_counts`).
    pub counts: Counts,
    /// The target cell size used.
    pub cell_size: f64,
    /// The default target size before [`node_budget`] coarsened it to `cell_size`
    /// (`None`: not coarsened).
    pub coarsened_from: Option<f64>,
    /// Arcs whose exact walls run against their block's orientation: the sampled Delaunay
    /// combinatorics disagree with the exact medial axis there (nearly co-circular circles
    /// not resolved by the sampling); their blocks are inverted. Empty on a consistent layout.
    pub inconsistent_arcs: Vec<usize>,
    /// Arcs split in two so that an inserted hole fits its template (`inserted::prepare`).
    pub split_arcs: usize,
    /// Blocks inside inserted holes (the last ones of the layout).
    pub template_blocks: usize,
    /// The blocks with an inverted cell, in increasing order: [`crate::quality::inverted_blocks`]
    /// of `grids`, found as each grid is made (a grid taken from the memo keeps the finding
    /// of the build that made it), so the mesher's check needs no pass over every grid.
    pub inverted_blocks: Vec<usize>,
    /// The report's figures of every block when its nodes were not kept
    /// ([`Options::keep_nodes`]; [`crate::Mesh::measured`]); `None` when the grids hold
    /// their nodes.
    pub measured: Option<std::sync::Arc<crate::quality::Measured>>,
}

/// Sweeps at most this small (radians) count as zero when checking orientations (a
/// co-circular group's zero-length arcs, up to rounding).
pub const ZERO_SWEEP: f64 = 1e-12;

/// The expected sign of a block's wall sweep in its side-0 direction: clockwise (negative)
/// about a hole, counter-clockwise about the bounding circle (fluid on the left).
fn expected_sign(c: CircleId) -> f64 {
    if c < 0 {
        1.0
    } else {
        -1.0
    }
}

/// One medial arc (or half of a split one) with its exact geometry: its blocks are `2e` (on
/// `circles[0]`) and `2e + 1` (on `circles[1]`).
#[derive(Debug, Clone)]
pub(crate) struct Piece {
    /// Vertex ids (into the exact vertices) of its start and end.
    pub ends: [usize; 2],
    pub circles: [CircleId; 2],
    /// `slots[side][end]`: the slot of `circles[side]` in end vertex `ends[end]`
    /// ([`ExactVertex::slot`], looked up once).
    pub slots: [[usize; 2]; 2],
    pub geom: ArcGeometry,
}

impl Piece {
    /// The entry [`pieces_of`] writes for an arc whose piece failed (never returned).
    fn placeholder() -> Piece {
        let wall = Wall {
            c: [0.0; 2],
            r: 0.0,
            s: 0.0,
        };
        Piece {
            ends: [0; 2],
            circles: [0; 2],
            slots: [[0; 2]; 2],
            geom: ArcGeometry {
                walls: [wall; 2],
                param: 0,
                start: [0.0; 2],
                sweep: [0.0; 2],
                ends_m: [[0.0; 2]; 2],
                ends_a: [[[0.0; 2]; 2]; 2],
                offset: [[0.0; 2]; 2],
            },
        }
    }

    /// True when both walls run the way their blocks need (see [`expected_sign`]).
    fn consistent(&self) -> bool {
        let wrong = |w: f64, c: CircleId| w.abs() > ZERO_SWEEP && w * expected_sign(c) < 0.0;
        !(wrong(self.geom.sweep[0], self.circles[0]) || wrong(-self.geom.sweep[1], self.circles[1]))
    }
}

/// The combinatorics and exact vertices exact mode builds on.
#[derive(Debug, Clone)]
pub struct Skeleton<'a> {
    /// The domain the circle ids refer to (inserted holes appended after the input holes).
    pub domain: &'a Domain,
    /// The medial arcs: `ends` index `vertices`, `circles` as in [`crate::medial`].
    pub arcs: &'a [crate::medial::MedialArc],
    pub vertices: Vec<ExactVertex>,
    /// Blocking2D of `arcs` (blocks `2e`, `2e + 1`): only the turn count of each sampled wall
    /// is read.
    pub sampled: &'a BlockLayout,
    /// Inserted holes (fluid): spokes without wall clustering, filled by templates.
    pub fluid: Vec<CircleId>,
}

/// Build the exact-mode layout and grids from the front end's [`Blocking`] (read only), without
/// collapse or inserted holes ([`collapsed::build_collapsed`] handles both).
///
/// Errors: [`MeshError::Options`] for bad options, [`MeshError::Grid`] for too many nodes,
/// [`MeshError::Internal`] when the exact geometry disagrees with the sampled combinatorics.
/// Never panics.
pub fn build(
    domain: &Domain,
    blocking: &Blocking,
    options: &Options,
) -> Result<ExactMesh, MeshError> {
    validate_options(options)?;
    let vertices = exact_vertices(domain, &blocking.medial)?;
    assemble(
        Skeleton {
            domain,
            arcs: &blocking.medial.arcs,
            vertices,
            sampled: &blocking.layout,
            fluid: Vec::new(),
        },
        options,
    )
}

/// The pieces of a skeleton's arcs (one per arc, in arc order) and the arcs running backwards
/// ([`Piece::consistent`]). Errors ([`MeshError::Internal`]) as [`assemble`].
fn pieces_of(sk: &Skeleton<'_>) -> Result<(Vec<Piece>, Vec<usize>), MeshError> {
    let (domain, vertices) = (sk.domain, &sk.vertices);
    let ncirc = domain.hole_count() + 1;
    // Geometry of every arc: independent per arc, computed in parallel and written in arc
    // order into one vector of pieces (not a vector of results copied into another). The error
    // returned is that of the first failing arc in arc order (each arc's result does not
    // depend on the others; a failed arc leaves a placeholder, never returned), so nothing
    // depends on the thread count.
    let first_error = std::sync::Mutex::new(None::<(usize, MeshError)>);
    let piece = |e: usize, arc: &crate::medial::MedialArc| -> Result<Piece, MeshError> {
        let [v0, v1] = arc.ends.map(|v| v as usize);
        let (Some(x0), Some(x1)) = (vertices.get(v0), vertices.get(v1)) else {
            return Err(internal(format!("arc {e} has an unknown end vertex")));
        };
        if arc.circles.iter().any(|&c| c < -1 || cidx(c) >= ncirc) {
            return Err(internal(format!("arc {e} has an unknown circle")));
        }
        let walls = arc.circles.map(|c| Wall::of(domain, c));
        let mut ends_a = [[[0.0; 2]; 2]; 2];
        let mut slots = [[0; 2]; 2];
        for (side, &c) in arc.circles.iter().enumerate() {
            let (Some(s0), Some(s1)) = (x0.slot(c), x1.slot(c)) else {
                return Err(internal(format!(
                    "arc {e}: an end vertex does not touch circle {c}"
                )));
            };
            ends_a[0][side] = x0.tangent[s0];
            ends_a[1][side] = x1.tangent[s1];
            slots[side] = [s0, s1];
        }
        let hint_a = wall_hint(sk.sampled, 2 * e)
            .ok_or_else(|| internal(format!("arc {e}: no sampled wall")))?;
        let hint_b = wall_hint(sk.sampled, 2 * e + 1)
            .ok_or_else(|| internal(format!("arc {e}: no sampled wall")))?;
        Ok(Piece {
            ends: [v0, v1],
            circles: arc.circles,
            slots,
            geom: ArcGeometry::new(walls, [x0.center, x1.center], ends_a, [hint_a, -hint_b]),
        })
    };
    let mut pieces = Vec::new();
    sk.arcs
        .par_iter()
        .enumerate()
        .with_max_len(crate::tasks::PIECES)
        .map(|(e, arc)| {
            piece(e, arc).unwrap_or_else(|err| {
                let mut first = first_error.lock().unwrap_or_else(|p| p.into_inner());
                if first.as_ref().is_none_or(|(at, _)| e < *at) {
                    *first = Some((e, err));
                }
                Piece::placeholder()
            })
        })
        .collect_into_vec(&mut pieces);
    if let Some((_, err)) = first_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(err);
    }
    let inconsistent_arcs = (0..pieces.len())
        .filter(|&e| !pieces[e].consistent())
        .collect();
    Ok((pieces, inconsistent_arcs))
}

/// Build the exact-mode layout and grids of a [`Skeleton`].
///
/// Block `2e` lies on piece `e`'s `circles[0]`, block `2e + 1` on `circles[1]`, with the corner
/// and side conventions of [`crate::blocking`]; template blocks of the inserted holes follow.
/// Layout vertices: the exact vertex centres, then their tangent points (vertex by vertex, in
/// circle order). Edges: walls are exact [`Curve::Arc`]s, spokes [`Curve::Segment`]s, medial
/// arcs [`Curve::Polyline`]s through the grid's medial nodes.
pub fn assemble(sk: Skeleton<'_>, options: &Options) -> Result<ExactMesh, MeshError> {
    assemble_cached(sk, options, &mut PieceCache::default())
}

/// The layout skeleton of the medial blocks: the Apollonius centres and tangent points as
/// vertices, per piece its medial edge (an empty polyline until the grids give its nodes),
/// the spokes at its ends (numbered in first-use order) and its two wall arcs, and its two
/// blocks. Built into `layout` (a rejected mesh's vectors, [`PieceCache::spare_layout`]),
/// with room for the templates of `fluid_walls` inserted-hole walls. Returns the layout and
/// each piece's medial edge.
fn skeleton_layout(
    layout: BlockLayout,
    vertices: &[ExactVertex],
    pieces: &[Piece],
    fluid_walls: usize,
) -> (BlockLayout, Vec<u32>) {
    if pieces.len() >= PARALLEL_SKELETON && rayon::current_num_threads() > 1 {
        skeleton_layout_par(layout, vertices, pieces, fluid_walls)
    } else {
        skeleton_layout_serial(layout, vertices, pieces, fluid_walls)
    }
}

/// Pieces from which [`skeleton_layout`] is built in parallel ([`skeleton_layout_par`]);
/// below, the one loop of [`skeleton_layout_serial`] is as fast. Issue 8: at 1e5 bubbles,
/// whose refinement inserts holes (so the skeleton comes before the grids, alone), the loop
/// kept one CPU busy and the other idle for 80 ms.
const PARALLEL_SKELETON: usize = 16_384;

/// The vertices of [`skeleton_layout`] (the Apollonius centres, then each vertex's tangent
/// points), with room for the rest; returns where each vertex's tangent points start.
fn skeleton_vertices(
    layout: &mut BlockLayout,
    vertices: &[ExactVertex],
    pieces: &[Piece],
    fluid_walls: usize,
) -> Vec<usize> {
    let nv = vertices.len();
    let tangents: usize = vertices.iter().map(|v| v.tangent.len()).sum();
    // Room for the templates too, so that filling the inserted holes does not move the
    // vectors (issue 8: a copy of every block and edge, into fresh pages): a hole with `k`
    // wall arcs gets `k` vertices, fewer than `3k` edges and `2k` blocks
    // (`templates::fill_inserted_holes`). Capacity only: nothing else depends on it.
    layout.vertices.reserve_exact(nv + tangents + fluid_walls);
    layout.vertices.extend(vertices.iter().map(|v| v.center));
    layout
        .edges
        .reserve_exact(3 * pieces.len() + tangents.max(3 * nv) + 3 * fluid_walls);
    layout
        .blocks
        .reserve_exact(2 * pieces.len() + 2 * fluid_walls);
    let mut tangent_base = Vec::with_capacity(nv);
    for v in vertices {
        tangent_base.push(layout.vertices.len());
        layout.vertices.extend_from_slice(&v.tangent);
    }
    tangent_base
}

/// The two blocks of piece `p` in the layout: `medial_edge`, its wall edges `walls` (sides 0
/// and 1) and the spokes `spokes[side][end]` of its tangent vertices `tv[side][end]`.
fn piece_blocks(
    p: &Piece,
    medial_edge: u32,
    walls: [u32; 2],
    spokes: [[u32; 2]; 2],
    tv: [[u32; 2]; 2],
) -> [Block; 2] {
    let (fwd, rev) = (SideRef::along, SideRef::against);
    let [v0, v1] = p.ends.map(|v| v as u32);
    let ([t00, t01], [t10, t11]) = (tv[0], tv[1]);
    let ([sp00, sp01], [sp10, sp11]) = (spokes[0], spokes[1]);
    [
        Block {
            corners: [t00, t01, v1, v0],
            sides: [fwd(walls[0]), rev(sp01), rev(medial_edge), fwd(sp00)],
            wall: Some(p.circles[0]),
        },
        Block {
            corners: [t11, t10, v0, v1],
            sides: [fwd(walls[1]), rev(sp10), fwd(medial_edge), fwd(sp11)],
            wall: Some(p.circles[1]),
        },
    ]
}

/// Piece `p`'s medial edge: an empty polyline until the grids give its nodes (nothing reads
/// it before).
fn piece_medial_edge(p: &Piece) -> Edge {
    let [v0, v1] = p.ends;
    Edge {
        ends: [v0 as u32, v1 as u32],
        curve: Curve::Polyline(Vec::new()),
        kind: EdgeKind::Medial,
    }
}

/// Piece `p`'s wall edge on `side`, in its block's side-0 direction (`tv` as in
/// [`piece_blocks`]).
fn piece_wall_edge(p: &Piece, side: usize, tv: [[u32; 2]; 2]) -> Edge {
    let g = &p.geom;
    let (ends, start, sweep) = if side == 0 {
        ([tv[0][0], tv[0][1]], g.start[0], g.sweep[0])
    } else {
        ([tv[1][1], tv[1][0]], g.start[1] + g.sweep[1], -g.sweep[1])
    };
    Edge {
        ends,
        curve: Curve::Arc {
            center: g.walls[side].c,
            radius: g.walls[side].r,
            start,
            sweep,
        },
        kind: EdgeKind::Wall(p.circles[side]),
    }
}

/// The spoke edge from vertex `v` to its tangent vertex `t`.
fn spoke_edge(v: usize, t: u32) -> Edge {
    Edge {
        ends: [v as u32, t],
        curve: Curve::Segment,
        kind: EdgeKind::Spoke,
    }
}

/// Piece `p`'s tangent vertices: `[side][end]` that of `circles[side]` at `ends[end]`.
fn piece_tangents(p: &Piece, tangent_base: &[usize]) -> [[u32; 2]; 2] {
    [0, 1].map(|side| [0, 1].map(|end| (tangent_base[p.ends[end]] + p.slots[side][end]) as u32))
}

/// [`skeleton_layout`] in one loop over the pieces (the reference of
/// [`skeleton_layout_par`]).
pub(crate) fn skeleton_layout_serial(
    mut layout: BlockLayout,
    vertices: &[ExactVertex],
    pieces: &[Piece],
    fluid_walls: usize,
) -> (BlockLayout, Vec<u32>) {
    let tangent_base = skeleton_vertices(&mut layout, vertices, pieces, fluid_walls);
    // The spoke edge of each tangent vertex (`NO_EDGE` until made): a lookup, not a hash map
    // (issue 8); edges are numbered in first-use order.
    let mut spoke: Vec<u32> = vec![NO_EDGE; layout.vertices.len()];
    let mut medial_edges = Vec::with_capacity(pieces.len());
    for p in pieces {
        let tv = piece_tangents(p, &tangent_base);
        let medial_edge = layout.edges.len() as u32;
        medial_edges.push(medial_edge);
        // The medial nodes replace the empty polyline once the grids are made (nothing reads
        // it before: one allocation and one free per piece fewer in this serial loop).
        layout.edges.push(piece_medial_edge(p));
        let mut walls = [0; 2];
        for side in 0..2 {
            for (end, &t) in tv[side].iter().enumerate() {
                if spoke[t as usize] == NO_EDGE {
                    spoke[t as usize] = layout.edges.len() as u32;
                    layout.edges.push(spoke_edge(p.ends[end], t));
                }
            }
            walls[side] = layout.edges.len() as u32;
            layout.edges.push(piece_wall_edge(p, side, tv));
        }
        let spokes = tv.map(|ends| ends.map(|t| spoke[t as usize]));
        layout
            .blocks
            .extend(piece_blocks(p, medial_edge, walls, spokes, tv));
    }
    (layout, medial_edges)
}

/// No edge yet (a tangent vertex whose spoke is not made).
const NO_EDGE: u32 = u32::MAX;

/// [`skeleton_layout`] in parallel, the layout of [`skeleton_layout_serial`] (tested): the
/// first use of each tangent vertex (piece `i`, use `2 side + end`, key `4 i + use`, the
/// loop's order) is found first (one pass over the keys, in order), so that each piece
/// knows which spokes it makes, hence how many edges; their prefix sums number the edges,
/// and the pieces then write their edges and blocks in parallel, each into its own part.
pub(crate) fn skeleton_layout_par(
    mut layout: BlockLayout,
    vertices: &[ExactVertex],
    pieces: &[Piece],
    fluid_walls: usize,
) -> (BlockLayout, Vec<u32>) {
    let tangent_base = skeleton_vertices(&mut layout, vertices, pieces, fluid_walls);
    let tvs: Vec<[[u32; 2]; 2]> = pieces
        .par_iter()
        .with_max_len(crate::tasks::PIECES)
        .map(|p| piece_tangents(p, &tangent_base))
        .collect();
    let mut first: Vec<u32> = vec![NO_EDGE; layout.vertices.len()];
    for (i, tv) in tvs.iter().enumerate() {
        for (u, &t) in tv.iter().flatten().enumerate() {
            let f = &mut first[t as usize];
            if *f == NO_EDGE {
                *f = (4 * i + u) as u32;
            }
        }
    }
    // Which of piece i's uses make their spoke (bit `u`), and its edges' offset.
    let makes = |i: usize, tv: &[[u32; 2]; 2]| -> u8 {
        let mut bits = 0;
        for (u, &t) in tv.iter().flatten().enumerate() {
            bits |= u8::from(first[t as usize] == (4 * i + u) as u32) << u;
        }
        bits
    };
    let bits: Vec<u8> = tvs
        .par_iter()
        .enumerate()
        .with_max_len(crate::tasks::PIECES)
        .map(|(i, tv)| makes(i, tv))
        .collect();
    let base = layout.edges.len() as u32;
    let mut offsets = Vec::with_capacity(pieces.len() + 1);
    let mut next = base;
    for b in &bits {
        offsets.push(next);
        next += 3 + b.count_ones();
    }
    offsets.push(next);
    // Within a piece: medial, [spoke 0], [spoke 1], wall 0, [spoke 2], [spoke 3], wall 1.
    let position = |b: u8, u: usize| -> u32 {
        let made = |k: usize| u32::from(b >> k & 1);
        match u {
            0 => 1,
            1 => 1 + made(0),
            2 => 2 + made(0) + made(1),
            _ => 2 + made(0) + made(1) + made(2),
        }
    };
    let spoke_of = |t: u32| -> u32 {
        let k = first[t as usize] as usize;
        let (c, u) = (k / 4, k % 4);
        offsets[c] + position(bits[c], u)
    };
    let np = pieces.len();
    let edge_count = (next - base) as usize;
    // Room reserved by `skeleton_vertices` already (a no-op then), made certain here.
    layout.edges.reserve(edge_count);
    layout.blocks.reserve(2 * np);
    {
        let edges = &mut layout.edges.spare_capacity_mut()[..edge_count];
        let blocks = &mut layout.blocks.spare_capacity_mut()[..2 * np];
        let fill = |range: std::ops::Range<usize>,
                    edges: &mut [std::mem::MaybeUninit<Edge>],
                    blocks: &mut [std::mem::MaybeUninit<Block>]| {
            let at0 = offsets[range.start];
            for i in range.clone() {
                let (p, tv, b) = (&pieces[i], tvs[i], bits[i]);
                let mut at = (offsets[i] - at0) as usize;
                let mut put = |e: Edge| {
                    edges[at].write(e);
                    at += 1;
                };
                put(piece_medial_edge(p));
                for side in 0..2 {
                    for (end, &t) in tv[side].iter().enumerate() {
                        if b >> (2 * side + end) & 1 == 1 {
                            put(spoke_edge(p.ends[end], t));
                        }
                    }
                    put(piece_wall_edge(p, side, tv));
                }
                // Each wall right after its side's spokes: wall 1 ends the piece's edges.
                let walls = [offsets[i] + position(b, 2) - 1, offsets[i + 1] - 1];
                let spokes = tv.map(|ends| ends.map(spoke_of));
                let pair = piece_blocks(p, offsets[i], walls, spokes, tv);
                let k = 2 * (i - range.start);
                let [b0, b1] = pair;
                blocks[k].write(b0);
                blocks[k + 1].write(b1);
            }
        };
        split_fill(0..np, edges, blocks, &offsets, &fill);
    }
    // SAFETY: `split_fill` gave every piece its own part of the spare capacity (its edges at
    // `offsets[i] - base..offsets[i + 1] - base`, its blocks at `2 i..2 i + 2`) and each piece
    // wrote every slot of its part: `3 + bits.count_ones()` edges and two blocks.
    unsafe {
        layout.edges.set_len(base as usize + edge_count);
        layout.blocks.set_len(layout.blocks.len() + 2 * np);
    }
    let medial_edges = offsets[..np].to_vec();
    (layout, medial_edges)
}

/// The exact vertices and pieces of the exact build of `cb`, as
/// [`collapsed::build_collapsed`] makes them (no inserted hole prepared): what the test hooks
/// [`densities::deviation`] and [`skeletons_agree`] look at.
fn build_pieces(
    cb: &crate::blocking::CollapsedBlocking,
) -> Result<(Vec<ExactVertex>, Vec<Piece>), MeshError> {
    let single = exact_vertices_with(
        &cb.refined.domain,
        &cb.refined.sampled.medial,
        &cb.refined.circles,
    )?;
    let vertices = collapsed::cluster_vertices_on(cb, &single)?;
    let sk = Skeleton {
        domain: &cb.refined.domain,
        arcs: &cb.contracted.graph.arcs,
        vertices,
        sampled: &cb.layout,
        fluid: Vec::new(),
    };
    let (pieces, _) = pieces_of(&sk)?;
    Ok((sk.vertices, pieces))
}

/// The layout skeleton of the exact build of `cb` ([`build_pieces`]), built by
/// [`skeleton_layout_serial`] and by [`skeleton_layout_par`] on the current pool: true when
/// the two are equal, layout and medial edges (test hook).
#[doc(hidden)]
pub fn skeletons_agree(cb: &crate::blocking::CollapsedBlocking) -> Result<bool, MeshError> {
    let (vertices, pieces) = build_pieces(cb)?;
    let serial = skeleton_layout_serial(BlockLayout::default(), &vertices, &pieces, 3);
    let par = skeleton_layout_par(BlockLayout::default(), &vertices, &pieces, 3);
    Ok(serial == par)
}

/// Pieces per task of [`split_fill`].
const FILL_PIECES: usize = 2048;

/// Run `fill` on ranges of pieces in parallel, each with its own part of `edges` (piece
/// `i`'s edges at `offsets[i]..offsets[i + 1]`, relative to `offsets[range.start]`) and of
/// `blocks` (two per piece), cut by `split_at_mut`.
fn split_fill<F>(
    range: std::ops::Range<usize>,
    edges: &mut [std::mem::MaybeUninit<Edge>],
    blocks: &mut [std::mem::MaybeUninit<Block>],
    offsets: &[u32],
    fill: &F,
) where
    F: Fn(
            std::ops::Range<usize>,
            &mut [std::mem::MaybeUninit<Edge>],
            &mut [std::mem::MaybeUninit<Block>],
        ) + Sync,
{
    if range.len() <= FILL_PIECES {
        fill(range, edges, blocks);
        return;
    }
    let mid = range.start + range.len() / 2;
    let (el, er) = edges.split_at_mut((offsets[mid] - offsets[range.start]) as usize);
    let (bl, br) = blocks.split_at_mut(2 * (mid - range.start));
    rayon::join(
        || split_fill(range.start..mid, el, bl, offsets, fill),
        || split_fill(mid..range.end, er, br, offsets, fill),
    );
}

/// [`assemble`], taking the densities and arc-node parameters of pieces an earlier build
/// already computed from `cache` ([`piece_cache`]) and leaving this build's there: the same
/// mesh as [`assemble`] whatever the cache holds.
pub fn assemble_cached(
    mut sk: Skeleton<'_>,
    options: &Options,
    cache: &mut PieceCache,
) -> Result<ExactMesh, MeshError> {
    validate_options(options)?;
    let domain = sk.domain;
    let ncirc = domain.hole_count() + 1;
    if sk.sampled.blocks.len() != 2 * sk.arcs.len() {
        return Err(internal(
            "the blocking does not have two blocks per arc".into(),
        ));
    }
    if let Some(&c) = sk.fluid.iter().find(|&&c| c < 0 || cidx(c) >= ncirc) {
        return Err(internal(format!("unknown inserted hole {c}")));
    }
    // Inserted holes by circle slot (a lookup, not a scan of `sk.fluid` per query).
    let mut is_fluid = vec![false; ncirc];
    for &c in &sk.fluid {
        is_fluid[cidx(c)] = true;
    }
    let fluid = |c: CircleId| c >= -1 && is_fluid.get(cidx(c)).copied().unwrap_or(false);

    let (mut pieces, inconsistent_arcs) = pieces_of(&sk)?;
    let mut vertices = std::mem::take(&mut sk.vertices);
    let mut split_arcs = 0;
    // A split for one hole can change a neighbouring inserted hole's count: repeat until no
    // hole asks for a split (bounded).
    if !sk.fluid.is_empty() {
        let mut index = inserted::PiecesByCircle::new(&pieces, &is_fluid);
        for _round in 0..4 {
            let before = split_arcs;
            for &c in &sk.fluid {
                split_arcs +=
                    inserted::prepare(&mut pieces, &mut vertices, c, &is_fluid, &mut index);
            }
            if split_arcs == before {
                break;
            }
        }
        // Hole by hole did not make every hole fit (splits between inserted holes flip the
        // parity of both): prepare them together. Layouts the rounds above fit are unchanged.
        if !sk.fluid.iter().all(|&c| inserted::fits(&pieces, c, &index)) {
            split_arcs += inserted::prepare_jointly(
                &mut pieces,
                &mut vertices,
                &sk.fluid,
                &is_fluid,
                &mut index,
            );
        }
    }

    // Target size and the count problem.
    let radii: Vec<f64> = vertices.iter().map(|v| v.radius).collect();
    let radii_max = radii
        .iter()
        .copied()
        .filter(|r| r.is_finite())
        .fold(0.0, f64::max);
    let mut h = match options.cell_size {
        Some(h) => h,
        None => median(radii).unwrap_or(1.0) / options.cells.max(1) as f64,
    };
    let cluster = |id: CircleId| {
        if fluid(id) {
            inserted::FLUID_CLUSTERING
        } else {
            clustering_of(options, id)
        }
    };
    let mut circle_fixed = vec![None; ncirc];
    for (c, n) in &options.wall_cells {
        if *c >= -1 && ((*c + 1) as usize) < ncirc && !fluid(*c) {
            circle_fixed[cidx(*c)] = Some(*n);
        }
    }
    // Circles facing each other across a medial arc, both equally spaced along their spokes
    // (no first height): their counts stay within `counts::MAX_COUNT_RATIO` of each other, so
    // the cells facing each other across the arc do too. Beside the medians (issue 8: two
    // serial passes of 15-20 ms each at 1e5 particles, one CPU idle).
    let (near_median, neighbours) = rayon::join(
        // The median radius of the vertices touching each circle ([`radii_by_circle`] and
        // [`median`] of each list, in one array: `near_median::near_medians`).
        || near_median::near_medians(&vertices, ncirc),
        || {
            let equally_spaced: Vec<bool> = (0..ncirc)
                .map(|slot| {
                    let id = slot as CircleId - 1;
                    cluster(id).first_height(domain.circle(id).radius).is_none()
                })
                .collect();
            counts::facing_pairs(pieces.iter().map(|p| p.circles.map(cidx)), |c| {
                equally_spaced[c]
            })
        },
    );
    // The count problem for target cell size `h`, without its arcs.
    let circle_problem = |h: f64| {
        let mut circle_target = vec![1.0; ncirc];
        for id in domain.circle_ids() {
            let len = near_median[cidx(id)].unwrap_or(h);
            let cl = cluster(id);
            let first = cl.first_height(domain.circle(id).radius);
            circle_target[cidx(id)] = clustering::cells_for(len, h, first, cl.growth) as f64;
        }
        CountProblem {
            circle_target,
            circle_fixed: circle_fixed.clone(),
            // The templates' ties ([`inserted::tie_counts`]) pair the sides of every inserted
            // hole, which makes its perimeter even without the parity repair.
            template: vec![false; ncirc],
            arcs: Vec::new(),
            neighbours: neighbours.clone(),
        }
    };

    // Sub-step densities per piece, in parallel, collected in piece order. Each piece keeps
    // only what the counts and its nodes need (issue 8: the densities of all pieces at once
    // were 4 KB per piece): its lower bound, its target for the `nbar` its circles' counts
    // give, and the node parameters for that `nbar` and the count it would get before the
    // template ties. Where the final `nbar` or count differ (ties, imposed counts,
    // coarsening), the densities are computed again. A piece whose geometry the cache
    // knows takes that from the cache instead.
    let uniform_n = options
        .block_cells
        .map(|n| n.clamp(1, crate::grid::MAX_CELLS_PER_SIDE));
    let first_circle = match uniform_n {
        Some(n) => vec![n; ncirc],
        None => circle_problem(h).circle_counts(),
    };
    let keys: Vec<GeomKey> = pieces.par_iter().map(|p| GeomKey::of(&p.geom)).collect();
    // Into the rejected mesh's vectors when there is one ([`PieceCache::keep`]).
    let mut spare = cache.spare_layout();
    let fluid_walls: usize = pieces
        .iter()
        .map(|p| p.circles.iter().filter(|&&c| fluid(c)).count())
        .sum();
    // Where holes were inserted, their templates change the counts (ties) and the node
    // budget, so the layout skeleton with the templates and its conformity classes come
    // before the grids: built beside the summaries below, which they do not read (issue 8:
    // at 1e5 bubbles 100 ms, much of it on one CPU, while the other waited). Their error, if
    // any, is returned where it was met before: after the summaries' and the counts'.
    let first_template = 2 * pieces.len();
    let templated = || {
        let layout = std::mem::take(&mut spare);
        let (mut layout, medial_edges) = skeleton_layout(layout, &vertices, &pieces, fluid_walls);
        let holes: Vec<(CircleId, crate::domain::Circle)> =
            sk.fluid.iter().map(|&c| (c, domain.circle(c))).collect();
        crate::templates::fill_inserted_holes(&mut layout, &holes)
            .map_err(|(c, m)| internal(format!("inserted hole {c}: {m}")))?;
        let template_blocks = layout.blocks.len() - first_template;
        // The conformity classes, once: the edges and blocks do not change from here on.
        let (classes, sides) = if template_blocks > 0 {
            let classes = crate::grid::edge_classes(&layout);
            let sides = inserted::TemplateSides::new(&layout, &classes, first_template);
            (classes, sides)
        } else {
            Default::default()
        };
        Ok::<_, MeshError>((layout, medial_edges, template_blocks, classes, sides))
    };
    // The latest build's piece of each geometry, looked up once for the summaries and grids.
    let found = cache.find_all(&keys);
    type Summary = (ArcTarget, Option<Params>);
    let scratch = || ArcTarget {
        circles: [0, 0],
        sq: Vec::with_capacity(ARC_SUBSTEPS),
        ang: Vec::with_capacity(ARC_SUBSTEPS),
        known: None,
    };
    // Per piece its target, its node parameters when computed and whether its exact arc is
    // defined, unzipped in place (issue 8: a vector of the pairs, then two copies of it, were
    // 50 MB of fresh pages and about 25 ms on one CPU at 1e5 particles).
    type Summaries = (Vec<ArcTarget>, (Vec<Option<Params>>, Vec<bool>));
    let summarized = || -> Summaries {
        pieces
            .par_iter()
            .zip(&found)
            .with_max_len(crate::tasks::PIECES)
            .map_init(scratch, |scratch, (p, &at)| {
                let mut summary = || -> Option<Summary> {
                    let circles = p.circles.map(cidx);
                    if let Some(known) = cache.known(at) {
                        let t = ArcTarget {
                            circles,
                            sq: Vec::new(),
                            ang: Vec::new(),
                            known: Some(known),
                        };
                        return Some((t, None));
                    }
                    if cache.is_reference() {
                        let (sq, ang) = p.geom.densities()?;
                        let t = ArcTarget {
                            circles,
                            sq,
                            ang,
                            known: None,
                        };
                        return Some((t, None));
                    }
                    let nbar = 0.5 * (first_circle[circles[0]] + first_circle[circles[1]]) as f64;
                    let (known, params) = summarize(&p.geom, nbar, uniform_n, scratch)?;
                    let t = ArcTarget {
                        circles,
                        sq: Vec::new(),
                        ang: Vec::new(),
                        known: Some(known),
                    };
                    Some((t, Some(params)))
                };
                // A piece whose exact arc is not defined: flagged, with an empty target.
                match summary() {
                    Some((t, params)) => (t, (params, true)),
                    None => (ArcTarget::default(), (None, false)),
                }
            })
            .unzip()
    };
    let ((mut targets, (first_params, defined)), templated) = if sk.fluid.is_empty() {
        (summarized(), None)
    } else {
        let (s, t) = rayon::join(summarized, templated);
        (s, Some(t))
    };
    if let Some(e) = defined.par_iter().position_first(|&d| !d) {
        return Err(internal(format!(
            "arc {e}: the exact medial arc is not defined"
        )));
    }
    let reused = targets
        .par_iter()
        .zip(&first_params)
        .filter(|(t, p)| p.is_none() && !t.holds_densities())
        .count();

    // The node counts for target cell size `h`.
    // The arc targets are lent to each count problem and given back (no copy: an arc whose
    // densities had to be computed again holds 2 x ARC_SUBSTEPS f64).
    let solve_counts = |h: f64, arcs: &mut Vec<ArcTarget>| -> Result<Counts, MeshError> {
        let mut problem = CountProblem {
            arcs: std::mem::take(arcs),
            ..circle_problem(h)
        };
        if options.block_cells.is_none() {
            // Size-driven counts need each arc's target for its `nbar`: compute the densities
            // of the arcs whose target the cache does not know for it.
            let circle = problem.circle_counts();
            let nbar = |a: &ArcTarget| {
                let n = |c: usize| circle.get(c).copied().unwrap_or(0);
                0.5 * (n(a.circles[0]) + n(a.circles[1])) as f64
            };
            let need: Vec<usize> = (0..problem.arcs.len())
                .filter(|&e| {
                    problem.arcs[e]
                        .known_target(nbar(&problem.arcs[e]))
                        .is_none()
                })
                .collect();
            let filled: Vec<Option<(Vec<f64>, Vec<f64>)>> = need
                .par_iter()
                .with_max_len(crate::tasks::PIECES)
                .map(|&e| pieces[e].geom.densities())
                .collect();
            for (&e, d) in need.iter().zip(filled) {
                let (sq, ang) = d.ok_or_else(|| {
                    internal(format!("arc {e}: the exact medial arc is not defined"))
                })?;
                let t = &mut problem.arcs[e];
                (t.sq, t.ang, t.known) = (sq, ang, None);
            }
        }
        let solved = crate::timings::span("node_counts", || match options.block_cells {
            Some(n) => problem.solve_uniform(n),
            None => problem.solve(),
        });
        *arcs = problem.arcs;
        solved.map_err(internal)
    };
    let mut counts = solve_counts(h, &mut targets)?;
    // Counts imposed by a sequence (issue 6): all or nothing.
    let mut imposed_used = false;
    if let Some(imp) = &options.imposed_counts {
        let ends: Vec<([usize; 2], [CircleId; 2])> =
            pieces.iter().map(|p| (p.ends, p.circles)).collect();
        let arcs: Vec<[usize; 2]> = pieces.iter().map(|p| p.circles.map(cidx)).collect();
        if let Some((circle, arc)) = imposed::bounded_keys(&vertices, &ends)
            .and_then(|keys| imp.counts_for(&keys, &arcs, ncirc))
        {
            counts = Counts { circle, arc };
            imposed_used = true;
        }
    }

    // Layout skeleton and grids (stage "grids" until the end).
    let _grids = crate::timings::enter("grids");
    // The skeleton was built beside the summaries where inserted holes need it (above), else
    // it is built beside the grids (below), which do not read it: its serial loop then
    // overlaps their parallel work (issue 8: 0.8 ms at 1e3 bubbles).
    let mut built: Option<(BlockLayout, Vec<u32>)> = None;

    // Templates in the inserted holes, and the count ties they bring.
    let mut template_blocks = 0;
    let mut classes = (Vec::new(), 0);
    let mut template_sides = inserted::TemplateSides::default();
    if let Some(templated) = templated {
        let (layout, medial_edges, blocks, cls, sides) = templated?;
        template_blocks = blocks;
        if template_blocks > 0 {
            (classes, template_sides) = (cls, sides);
            inserted::tie_counts(&classes, &medial_edges, &mut counts.arc);
        }
        built = Some((layout, medial_edges));
    }

    // Limits before allocating. The default target size is the median Apollonius radius over
    // `cells`: where most medial vertices are tiny (tiny holes, and the holes refinement
    // inserts around them, issue #9; near-touching close packs) it is tiny for every circle,
    // and the counts of the large blocks explode (two holes of 1e-4 R gave 160 M cells, a
    // 10-hole layout billions of nodes) although nothing needs them. Only when the size was
    // not chosen by the user (`cell_size`, `block_cells`, imposed counts) and the mesh
    // exceeds [`node_budget`] (a multiple of what `cells` per block side would give, at
    // least a few million nodes), the target size is coarsened step by step (at most
    // [`MAX_COARSENING`] steps) towards that budget; a layout within it never gets here, so
    // its counts are unchanged. Above [`MAX_TOTAL_NODES`] a mesh the coarsening cannot bring
    // under it is refused, also when `cells` itself is too large even for the largest
    // Apollonius radius (e.g. `--cells 100000`).
    // Saturating sums of non-negative terms: `min(sum, usize::MAX)` in any grouping, so the
    // pieces' part in parallel (issue 8: 8-16 ms on one CPU at 1e5 bubbles).
    let total_of = |counts: &Counts, h: f64| {
        let mut total: usize = pieces
            .par_iter()
            .enumerate()
            .with_min_len(crate::tasks::ARCS)
            .map(|(e, p)| {
                let n = counts.arc[e];
                p.circles
                    .iter()
                    .map(|&c| (n + 1).saturating_mul(counts.circle[cidx(c)] + 1))
                    .fold(0usize, usize::saturating_add)
            })
            .reduce(|| 0, usize::saturating_add);
        if let Some((layout, _)) = built.as_ref().filter(|_| template_blocks > 0) {
            // Block `b` of piece `b / 2` is on `circles[b % 2]`: sides 0 and 2 have the
            // arc's count, sides 1 and 3 the circle's.
            let side_count = |b: usize, k: usize| {
                let e = b / 2;
                if k.is_multiple_of(2) {
                    counts.arc[e]
                } else {
                    counts.circle[cidx(pieces[e].circles[b % 2])]
                }
            };
            total = total.saturating_add(inserted::template_nodes(
                layout,
                &classes,
                &template_sides,
                first_template,
                h,
                side_count,
            ));
        }
        total
    };
    let budget = node_budget(2 * pieces.len() + template_blocks, options.cells);
    let user_sized = options.cell_size.is_some() || options.block_cells.is_some() || imposed_used;
    let mut coarsened = 0;
    let default_h = h;
    loop {
        let total = total_of(&counts, h);
        if total <= budget
            || (total <= MAX_TOTAL_NODES && (user_sized || coarsened >= MAX_COARSENING))
        {
            break;
        }
        let mut refused = user_sized || coarsened >= MAX_COARSENING;
        if !refused && coarsened == 0 && total > MAX_TOTAL_NODES {
            // `cells` itself asks for too much when even the largest Apollonius radius over
            // `cells` does not fit (e.g. `--cells 100000`): refused, not coarsened.
            let largest = radii_max / options.cells.max(1) as f64;
            let mut c = solve_counts(largest.max(h), &mut targets)?;
            if let Some((_, medial_edges)) = built.as_ref().filter(|_| template_blocks > 0) {
                inserted::tie_counts(&classes, medial_edges, &mut c.arc);
            }
            refused = total_of(&c, largest.max(h)) > MAX_TOTAL_NODES;
        }
        if refused {
            return Err(MeshError::Grid(GridError::TooManyNodes {
                nodes: total,
                limit: MAX_TOTAL_NODES,
            }));
        }
        h *= coarsening_step(total, budget);
        coarsened += 1;
        counts = solve_counts(h, &mut targets)?;
        if let Some((_, medial_edges)) = built.as_ref().filter(|_| template_blocks > 0) {
            inserted::tie_counts(&classes, medial_edges, &mut counts.arc);
        }
    }

    // Per piece: medial nodes, grids, what the memo keeps and, once known, which of the two grids has
    // an inverted cell (checked here while the grid is in cache; `None` until smoothed).
    type PieceGrids = Result<(Vec<Point>, [BlockGrid; 2], Known, Option<[bool; 2]>), MeshError>;
    /// The same, moved apart: medial nodes and grids, what the memo keeps and the checks.
    type PieceParts = (
        (Vec<Vec<Point>>, Vec<[BlockGrid; 2]>),
        (Vec<Known>, Vec<Option<[bool; 2]>>),
    );
    // Nodes not kept ([`Options::keep_nodes`]): every grid is measured as it is made (not
    // with smoothing, which moves the nodes after). The medial blocks on an inserted hole
    // keep theirs until its template's grids, made from them, are measured.
    let measurer = (!options.keep_nodes && options.smooth == 0).then(crate::quality::Measurer::new);
    type Made = (
        Vec<GridKey>,
        Vec<PieceGrids>,
        Vec<crate::quality::ChunkFigures>,
    );
    let work = || -> Result<Made, MeshError> {
        // Grids of the medial blocks, one piece (two blocks) per task in parallel on the current
        // rayon pool, collected in piece order (the first error in piece order is returned). A
        // piece's corner spokes are computed by each piece that uses them, from the same inputs
        // (vertex `v`'s tangent point `s` determines the circle, hence the count and clustering),
        // so the blocks sharing a spoke hold bitwise identical nodes whatever the thread count.
        // A piece whose geometry, counts and clustering the cache holds grids for takes them
        // (moved); else it takes its node parameters from its summary or the cache when drawn
        // for its final `nbar` and count; else it computes its densities again (held only by
        // that task, 2 x ARC_SUBSTEPS f64, freed once turned into parameters).
        let arc_targets = targets;
        let uniform = options.block_cells.is_some();
        let side_inputs = |p: &Piece, side: usize| {
            let c = p.circles[side];
            let cl = cluster(c);
            let first = cl.first_height(domain.circle(c).radius);
            (counts.circle[cidx(c)], first, cl.growth)
        };
        let nbar_of = |p: &Piece| {
            0.5 * (counts.circle[cidx(p.circles[0])] + counts.circle[cidx(p.circles[1])]) as f64
        };
        // End grading ([`grading`]): the natural end widths of every piece for its final `nbar`
        // and count (known to the memo, or from the parameters of its summary, or computed here
        // from its densities: those parameters then serve the grids as the summary's), then one
        // small least-squares problem per vertex for the ratios of the end cells. Only for
        // size-driven counts: a fixed grid per block (`--block-cells`) keeps its equidistributed
        // nodes, bit for bit.
        let graded = options.block_cells.is_none();
        let mut arc_targets = arc_targets;
        let mut first_params = first_params;
        let natural: Vec<Option<[[f64; 2]; 2]>> = if graded {
            pieces
                .par_iter()
                .zip(arc_targets.par_iter_mut())
                .zip(first_params.par_iter_mut())
                .enumerate()
                .with_max_len(crate::tasks::PIECES)
                .map_init(PieceScratch::default, |scratch, (e, ((p, t), first))| {
                    let (n, nbar) = (counts.arc[e], nbar_of(p));
                    if let Some(w) = t.known_ends(nbar, n) {
                        return Ok(Some(w));
                    }
                    if let Some((nb, m, params)) = first {
                        if nb.to_bits() == nbar.to_bits() && *m == n {
                            return Ok(grading::end_widths(&p.geom, params));
                        }
                    }
                    // The grids then take these parameters as the summary's, and the memo the
                    // target (as when the grids compute them).
                    let (params, target) = natural_params(e, &p.geom, t, nbar, n, scratch)?;
                    let w = grading::end_widths(&p.geom, &params);
                    if !t.holds_densities() {
                        t.known = Some(Known {
                            min_cells: t.min_cells(),
                            target: Some((nbar, target)),
                            ends: None,
                        });
                    }
                    *first = Some((nbar, n, params));
                    Ok(w)
                })
                .collect::<Result<_, MeshError>>()?
        } else {
            Vec::new()
        };
        let rho: Vec<[f64; 2]> = if graded {
            let inputs: Vec<grading::EndInput> = pieces
                .iter()
                .zip(&natural)
                .enumerate()
                .map(|(e, (p, nat))| grading::EndInput {
                    ends: p.ends,
                    slots: [p.slots[0], p.slots[1]],
                    n: counts.arc[e],
                    widths: *nat,
                })
                .collect();
            grading::end_ratios(&inputs, vertices.len())
        } else {
            vec![[1.0; 2]; pieces.len()]
        };
        let grid_keys: Vec<GridKey> = pieces
            .par_iter()
            .enumerate()
            .map(|(e, p)| {
                let sides = [side_inputs(p, 0), side_inputs(p, 1)];
                GridKey::of(counts.arc[e], sides, options.smooth, rho[e])
            })
            .collect();
        let reuse = match cache.take_grids(&found, &grid_keys) {
            Some(taken) => rayon::iter::Either::Left(taken.into_par_iter()),
            None => rayon::iter::Either::Right(rayon::iter::repeat_n(None, pieces.len())),
        };
        drop(found);
        type Item<'p> = (
            usize,
            (((&'p Piece, ArcTarget), Option<Payload>), Option<Params>),
        );
        let make = |scratch: &mut PieceScratch, (e, (((p, t), reused), first)): Item<'_>| {
            let g = &p.geom;
            let n = counts.arc[e];
            let nbar = nbar_of(p);
            let mut known = Known {
                min_cells: t.min_cells(),
                target: None,
                ends: natural.get(e).copied().flatten().map(|w| (nbar, n, w)),
            };
            if let Some((m_nodes, pair, inverted)) = reused {
                if !uniform {
                    known.target = t.known_target(nbar).map(|x| (nbar, x));
                }
                return Ok((m_nodes, pair, known, Some(inverted)));
            }
            let cached = match first {
                Some((nb, m, params)) if nb.to_bits() == nbar.to_bits() && m == n => Some(params),
                _ => None,
            };
            let params = match cached {
                Some(params) => {
                    if !uniform {
                        known.target = t.known_target(nbar).map(|x| (nbar, x));
                    }
                    params
                }
                None => {
                    let (params, target) = natural_params(e, g, &t, nbar, n, scratch)?;
                    if !uniform {
                        known.target = Some((nbar, target));
                    }
                    drop(t);
                    params
                }
            };
            // End grading (the natural parameters stay what the summaries and the memo
            // compare).
            let params = grading::grade_piece(g, params, rho[e], &mut scratch.graded);
            let mut m_nodes = Vec::with_capacity(n + 1);
            let PieceScratch {
                a_nodes, grid: gs, ..
            } = scratch;
            for a in a_nodes.iter_mut() {
                a.clear();
            }
            g.nodes_into(&params, &mut m_nodes, a_nodes)
                .ok_or_else(|| internal(format!("arc {e}: a medial node is not defined")))?;
            // The parameters go back to the scratch (their buffer serves the next piece).
            scratch.params = params;
            let mut grid = |side: usize| {
                let (nj, first, growth) = side_inputs(p, side);
                // Column i is arc node k = i (side 0) or n - i (side 1). The corner spokes run
                // from the piece's exact ends: its end vertices' tangent points on this circle
                // and centres (`ends_a`, `ends_m` are taken from them by the same slots), so
                // every block at a vertex gets the same nodes and the cache key (the
                // geometry) covers them.
                gs.clear();
                for i in 0..=n {
                    let k = if side == 0 { i } else { n - i };
                    let (a, m) = if k == 0 {
                        (g.ends_a[0][side], g.ends_m[0])
                    } else if k == n {
                        (g.ends_a[1][side], g.ends_m[1])
                    } else {
                        (a_nodes[side][k], m_nodes[k])
                    };
                    gs.push(a, m);
                }
                let nodes = gs.nodes(nj, first, growth);
                BlockGrid { ni: n, nj, nodes }
            };
            let pair = [grid(0), grid(1)];
            // Measured grids learn it from their measurement (below).
            let check = options.smooth == 0 && measurer.is_none();
            let inverted = check.then(|| pair.each_ref().map(has_inverted_cell));
            Ok((m_nodes, pair, known, inverted))
        };
        let items = pieces
            .par_iter()
            .zip(arc_targets.into_par_iter())
            .zip(reuse)
            .zip(first_params.into_par_iter())
            .enumerate();
        let Some(measurer) = measurer.as_ref() else {
            let per_piece: Vec<PieceGrids> = items
                .with_max_len(crate::tasks::PIECES)
                .map_init(PieceScratch::default, make)
                .collect();
            return Ok((grid_keys, per_piece, Vec::new()));
        };
        // Nodes not kept: the pieces in chunks of the quality pass's blocks, each block
        // measured right after its grid is made and its nodes dropped (their memory then
        // serves the next block's: no fresh pages, issue 8).
        const CHUNK_PIECES: usize = crate::quality::CHUNK / 2;
        let (per_chunk, figures): (Vec<Vec<PieceGrids>>, Vec<crate::quality::ChunkFigures>) = items
            .chunks(CHUNK_PIECES)
            .with_max_len(crate::tasks::PIECES.div_ceil(CHUNK_PIECES))
            .map_init(PieceScratch::default, |scratch, chunk| {
                let mut m = measurer.chunk();
                let out: Vec<PieceGrids> = chunk
                    .into_iter()
                    .map(|item| {
                        let p = &pieces[item.0];
                        let mut made = make(scratch, item);
                        if let Ok((_, pair, _, inverted)) = &mut made {
                            let mut bad = [false; 2];
                            for (side, g) in pair.iter_mut().enumerate() {
                                let c = p.circles[side];
                                // An inserted hole's arcs are interfaces with its template's
                                // blocks, which are made from these nodes (kept until then).
                                if fluid(c) {
                                    bad[side] = m.piece_block(g, &[], MERGED_MIN_ANGLE_DEG, side);
                                    continue;
                                }
                                let wall = [(0, p.geom.walls[side].c, c < 0)];
                                bad[side] = m.piece_block(g, &wall, MERGED_MIN_ANGLE_DEG, side);
                                g.nodes = Vec::new();
                            }
                            // The cell pass counts the cells `has_inverted_cell` finds.
                            *inverted = Some(bad);
                        }
                        made
                    })
                    .collect();
                (out, m.finish())
            })
            .unzip();
        Ok((grid_keys, crate::tasks::concat(per_chunk), figures))
    };
    let ((mut layout, medial_edges), work) = match built {
        Some(built) => (built, work()),
        None => {
            let (w, sk) = rayon::join(work, || {
                skeleton_layout(spare, &vertices, &pieces, fluid_walls)
            });
            (sk, w)
        }
    };
    let (grid_keys, mut per_piece, figures) = work?;
    // The first error in piece order.
    if let Some(at) = per_piece.iter().position(Result::is_err) {
        per_piece.swap_remove(at)?;
    }
    // Moved apart in parallel (issue 8: one loop over the pieces took 42 ms at 1e5 particles
    // on one thread, mostly the first touch of the vectors it filled). Room for the
    // templates' grids too (`layout` has their blocks when holes were inserted).
    let n = per_piece.len();
    let mut moved: PieceParts = (
        (
            Vec::with_capacity(n),
            Vec::with_capacity(layout.blocks.len().div_ceil(2)),
        ),
        (Vec::with_capacity(n), Vec::with_capacity(n)),
    );
    moved.par_extend(
        per_piece
            .into_par_iter()
            .with_max_len(crate::tasks::PIECES)
            .map(|r| match r {
                Ok((m_nodes, pair, entry, inverted)) => ((m_nodes, pair), (entry, inverted)),
                // None left (checked above).
                Err(_) => Default::default(),
            }),
    );
    let ((medial_nodes, pairs), (entries, checked)) = moved;
    let mut grids = pairs.into_flattened();
    cache.replace(keys, entries, medial_edges.clone(), grid_keys, reused);
    // The medial nodes into the layout, beside the check of the grids: which medial blocks
    // have an inverted cell, known for every piece but those still to smooth (grids taken
    // from the cache were smoothed and checked by the build that made them). Each block
    // smooths alone (its sides fixed): in parallel, same result for any pool.
    let mut inverted: Vec<bool> = vec![false; grids.len()];
    rayon::join(
        || {
            for (e, m_nodes) in medial_nodes.into_iter().enumerate() {
                layout.edges[medial_edges[e] as usize].curve = Curve::Polyline(m_nodes);
            }
        },
        || {
            grids
                .par_iter_mut()
                .zip(inverted.par_iter_mut())
                .enumerate()
                .with_max_len(crate::tasks::BLOCKS)
                .for_each(|(b, (g, bad))| {
                    *bad = match checked[b / 2] {
                        Some(pair) => pair[b % 2],
                        None => {
                            let rows = smoothing::boundary_layer_rows(g);
                            smoothing::winslow(g, options.smooth, rows);
                            has_inverted_cell(g)
                        }
                    };
                })
        },
    );
    drop(checked);
    let split = grids.len();
    let mut more = Vec::new();
    if template_blocks > 0 {
        let mut t = inserted::template_grids(&layout, &classes, &grids, first_template, h)?;
        match &measurer {
            Some(m) => {
                // Measured (the inverted cells among the figures), then every node dropped.
                let (figures, bad) = crate::quality::measure_templates_and_drop(
                    m,
                    &layout,
                    &mut t,
                    &mut grids,
                    split,
                    MERGED_MIN_ANGLE_DEG,
                );
                more = figures;
                inverted.extend(bad);
            }
            None => inverted.extend(t.iter().map(has_inverted_cell)),
        }
        grids.extend(t);
    }
    let measured =
        measurer.map(|_| std::sync::Arc::new(crate::quality::Measured::new(figures, split, more)));
    let inverted_blocks = (0..inverted.len()).filter(|&b| inverted[b]).collect();
    Ok(ExactMesh {
        layout,
        grids,
        vertices,
        counts,
        cell_size: h,
        coarsened_from: (coarsened > 0).then_some(default_h),
        inconsistent_arcs,
        split_arcs,
        template_blocks,
        inverted_blocks,
        measured,
    })
}

/// True when `g` has an inverted cell: `g` is one of [`crate::quality::inverted_blocks`]
/// ([`inverted::has_inverted_cell`]).
fn has_inverted_cell(g: &BlockGrid) -> bool {
    inverted::has_inverted_cell(g)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hole(x: f64, y: f64, r: f64) -> Wall {
        Wall { c: [x, y], r, s: r }
    }

    #[test]
    fn medial_point_between_equal_holes_is_on_the_bisector() {
        let (p, q) = (hole(0.0, 0.0, 0.5), hole(3.0, 0.0, 0.5));
        for k in -5..=5 {
            let theta = 0.2 * k as f64;
            let (a, m, rho) = medial_point(&p, &q, theta).unwrap();
            assert!((m[0] - 1.5).abs() < 1e-12, "{m:?}");
            assert!((dist(a, m) - rho).abs() < 1e-12);
            assert!((dist(m, q.c) - q.r - rho).abs() < 1e-12);
        }
    }

    #[test]
    fn medial_point_between_hole_and_bounding_circle_is_on_an_ellipse() {
        // |m - c_i| - r = R - |m - c_B|: an ellipse with foci c_i, c_B and major axis R + r.
        let p = hole(1.0, 0.5, 0.3);
        let b = Wall {
            c: [0.0, 0.0],
            r: 3.0,
            s: -3.0,
        };
        for k in 0..12 {
            let theta = 0.5 * k as f64;
            let (_, m, rho) = medial_point(&p, &b, theta).unwrap();
            assert!(((dist(m, p.c) + dist(m, b.c)) - 3.3).abs() < 1e-12);
            assert!((3.0 - dist(m, b.c) - rho).abs() < 1e-12);
            // And parametrised from the bounding circle's side.
            let (a, m2, rho2) = medial_point(&b, &p, theta).unwrap();
            assert!((dist(a, b.c) - 3.0).abs() < 1e-12);
            assert!(((dist(m2, p.c) + dist(m2, b.c)) - 3.3).abs() < 1e-12);
            assert!((dist(m2, p.c) - 0.3 - rho2).abs() < 1e-12);
        }
    }

    /// [`median`] (selection) against the sorted list's middle element, bit for bit: ties,
    /// signed zeros, infinities and NaNs (dropped) included.
    #[test]
    fn median_is_the_middle_of_the_sorted_list() {
        let mut rng = crate::layouts::SplitMix64(9);
        for n in 0..300usize {
            let v: Vec<f64> = (0..n)
                .map(|k| match k % 7 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => (rng.next_f64() * 4.0).round(),
                    3 if n % 3 == 0 => f64::NAN,
                    4 if n % 5 == 0 => f64::INFINITY,
                    _ => rng.next_f64() - 0.5,
                })
                .collect();
            let mut sorted: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
            sorted.sort_by(f64::total_cmp);
            let want = sorted.get(sorted.len() / 2).map(|x| x.to_bits());
            assert_eq!(median(v).map(f64::to_bits), want, "n = {n}");
        }
    }

    /// [`equidistribute_into`] on a buffer left over from another piece (longer, shorter,
    /// holding other values) gives the fresh [`equidistribute`] values bit for bit.
    #[test]
    fn equidistribution_into_a_used_buffer_is_the_fresh_one() {
        let mut rng = crate::layouts::SplitMix64(4);
        let mut buf: Vec<f64> = vec![f64::NAN; 40];
        let mut prefix: Vec<f64> = vec![f64::NAN; 3];
        for case in 0..200usize {
            let k = case % 13;
            let w: Vec<f64> = (0..k)
                .map(|i| match (case + i) % 5 {
                    0 => 0.0,
                    _ => rng.next_f64() * 3.0,
                })
                .collect();
            let n = 1 + case % 23;
            equidistribute_into(&w, n, &mut buf, &mut prefix);
            let fresh = equidistribute(&w, n);
            assert_eq!(buf.len(), n + 1);
            assert!(buf
                .iter()
                .zip(&fresh)
                .all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }

    #[test]
    fn equidistribution_has_exact_ends_and_is_monotone() {
        let w = vec![1.0, 0.0, 3.0, 0.5, 0.5];
        let t = equidistribute(&w, 7);
        assert_eq!(t.len(), 8);
        assert_eq!((t[0], t[7]), (0.0, 1.0));
        assert!(t.windows(2).all(|x| x[0] <= x[1]));
        assert_eq!(equidistribute(&[0.0; 4], 2), vec![0.0, 0.5, 1.0]);
    }

    /// [`larger_turn`] against both `atan2`s, bit for bit: random vectors of all sizes and
    /// quadrants, and near ties (one or a few ulps apart, equal, mirrored).
    #[test]
    fn larger_turn_is_the_max_of_both_turns() {
        let reference =
            |c0: f64, d0: f64, c1: f64, d1: f64| c0.atan2(d0).abs().max(c1.atan2(d1).abs());
        let mut rng = crate::layouts::SplitMix64(7);
        let mut next = |scale: f64| (rng.next_f64() - 0.5) * scale;
        let mut checked = 0;
        for k in 0..200_000 {
            let scale = 10f64.powi((k % 40) - 20);
            let (c0, d0) = (next(scale), next(1.0).abs() + next(scale));
            let (c1, d1) = match k % 5 {
                0 => (next(scale), next(1.0)),
                1 => (c0, d0),
                2 => (-c0, f64::from_bits(d0.to_bits() + 1)),
                3 => (f64::from_bits(c0.to_bits().wrapping_add(k as u64 % 7)), d0),
                _ => (c0 * (1.0 + 1e-9 * next(4.0)), d0 * (1.0 + 1e-9 * next(4.0))),
            };
            let (a, b) = (larger_turn(c0, d0, c1, d1), reference(c0, d0, c1, d1));
            assert_eq!(a.to_bits(), b.to_bits(), "{c0} {d0} {c1} {d1}");
            let (a, b) = (larger_turn(c1, d1, c0, d0), reference(c1, d1, c0, d0));
            assert_eq!(a.to_bits(), b.to_bits(), "{c1} {d1} {c0} {d0}");
            checked += 1;
        }
        assert_eq!(checked, 200_000);
    }

    /// The plain densities of sampled arcs (holes and bounding circle, both
    /// parametrisations) against the formula written out with both `atan2`s, and the fast
    /// ones against the plain ones (to rounding: `tests/perf_densities.rs` on real layouts).
    #[test]
    fn densities_match_the_plain_formula() {
        let mut rng = crate::layouts::SplitMix64(11);
        let mut tested = 0;
        for _ in 0..400 {
            let p = hole(rng.next_f64(), rng.next_f64(), 0.05 + 0.3 * rng.next_f64());
            let q = if rng.next_f64() < 0.3 {
                Wall {
                    c: [0.5, 0.5],
                    r: 3.0,
                    s: -3.0,
                }
            } else {
                hole(
                    1.5 + rng.next_f64(),
                    rng.next_f64(),
                    0.05 + 0.3 * rng.next_f64(),
                )
            };
            let (t0, t1) = (6.0 * rng.next_f64(), 6.0 * rng.next_f64());
            let (Some((a0, m0, _)), Some((a1, m1, _))) =
                (medial_point(&p, &q, t0), medial_point(&p, &q, t1))
            else {
                continue;
            };
            let ends_a = [[a0, q.project(m0)], [a1, q.project(m1)]];
            let hints = [t1 - t0, turn(q.c, ends_a[0][1], ends_a[1][1])];
            let g = ArcGeometry::new([p, q], [m0, m1], ends_a, hints);
            let Some((sq, ang)) = g.densities_plain() else {
                continue;
            };
            let (fsq, fang) = g.densities().unwrap();
            let close = |f: &[f64], p: &[f64]| {
                let mean = p.iter().sum::<f64>() / p.len() as f64;
                f.iter().zip(p).all(|(a, b)| (a - b).abs() <= 1e-9 * mean)
            };
            assert!(close(&fsq, &sq) && close(&fang, &ang));
            // The sub-steps the densities chose (`densities::COARSE_SUBSTEPS` or all).
            let k = sq.len();
            assert!(k == ARC_SUBSTEPS || k == densities::COARSE_SUBSTEPS, "{k}");
            let pts: Vec<_> = (0..=k)
                .map(|s| g.at(s as f64 / k as f64).unwrap())
                .collect();
            for (s, w) in pts.windows(2).enumerate() {
                let t0 = turn(g.walls[0].c, w[0].1[0], w[1].1[0]).abs();
                let t1 = turn(g.walls[1].c, w[0].1[1], w[1].1[1]).abs();
                assert_eq!(ang[s].to_bits(), (t0.max(t1) / MAX_WALL_ANGLE).to_bits());
            }
            tested += 1;
        }
        assert!(tested > 100, "{tested}");
    }

    /// The adaptive sub-steps ([`densities::COARSE_SUBSTEPS`] where the densities are smooth):
    /// an arc across a gap of 1e-6 of the radius (the length density peaks there) keeps every
    /// sub-step, an arc between far holes takes the coarse ones, and those stand for the fine
    /// ones (the plain formula at [`ARC_SUBSTEPS`]): the same total turn, the length density's
    /// sum within 1e-3.
    #[test]
    fn densities_take_coarse_substeps_only_where_smooth() {
        let arc = |p: Wall, q: Wall, t0: f64, t1: f64| {
            let (a0, m0, _) = medial_point(&p, &q, t0).unwrap();
            let (a1, m1, _) = medial_point(&p, &q, t1).unwrap();
            let ends_a = [[a0, q.project(m0)], [a1, q.project(m1)]];
            let hints = [t1 - t0, turn(q.c, ends_a[0][1], ends_a[1][1])];
            ArcGeometry::new([p, q], [m0, m1], ends_a, hints)
        };
        let narrow = arc(hole(0.0, 0.0, 1.0), hole(2.0 + 1e-6, 0.0, 1.0), -1.0, 1.0);
        let (sq, _) = narrow.densities().unwrap();
        assert_eq!(sq.len(), ARC_SUBSTEPS);
        assert!(!densities::smooth(
            &narrow.densities_plain_of(64).unwrap().0
        ));
        for (q, sweep) in [(hole(4.0, 0.0, 1.0), 0.3), (hole(3.0, 1.0, 0.4), 0.5)] {
            let g = arc(hole(0.0, 0.0, 1.0), q, -sweep, sweep);
            let (sq, ang) = g.densities().unwrap();
            assert_eq!(sq.len(), densities::COARSE_SUBSTEPS);
            let (fsq, fang) = g.densities_plain_of(ARC_SUBSTEPS).unwrap();
            let sum = |x: &[f64]| x.iter().sum::<f64>();
            assert!((sum(&ang) - sum(&fang)).abs() <= 1e-9 * sum(&fang));
            assert!((sum(&sq) - sum(&fsq)).abs() <= 1e-3 * sum(&fsq));
        }
        // The test itself: gentle changes pass, a jump, a zero or a non-number do not.
        assert!(densities::smooth(&[1.0, 1.04, 1.0, 0.97]));
        assert!(!densities::smooth(&[1.0, 1.06]));
        assert!(!densities::smooth(&[1.0, 0.0, 1.0]));
        assert!(!densities::smooth(&[1.0, f64::NAN]));
        assert!(!densities::smooth(&[f64::INFINITY, f64::INFINITY]));
    }

    /// [`spoke_column`] (one distance buffer for every spoke, written in place) against the
    /// allocating form it replaced, bit for bit: uniform and clustered spokes (both regimes,
    /// and first heights too large to fit), zero length, one and many cells.
    #[test]
    fn spoke_column_matches_the_allocating_spoke() {
        fn reference(a: Point, m: Point, n: usize, first: Option<f64>, growth: f64) -> Vec<Point> {
            let len = dist(a, m);
            let d = clustering::spoke_distances(len, n, first, growth);
            let mut out: Vec<Point> = d
                .iter()
                .map(|&x| {
                    let t = if len > 0.0 { x / len } else { 0.0 };
                    [a[0] + t * (m[0] - a[0]), a[1] + t * (m[1] - a[1])]
                })
                .collect();
            out[0] = a;
            out[n] = m;
            out
        }
        let mut rng = crate::layouts::SplitMix64(5);
        let mut d = Vec::new();
        for k in 0..3000 {
            let a = [rng.next_f64() * 4.0 - 2.0, rng.next_f64() * 4.0 - 2.0];
            let m = if k % 97 == 0 {
                a
            } else {
                [rng.next_f64() * 4.0 - 2.0, rng.next_f64() * 4.0 - 2.0]
            };
            let n = 1 + k % 40;
            let first = match k % 4 {
                0 => None,
                1 => Some(1e-4 * (1.0 + rng.next_f64())),
                2 => Some(0.05 * rng.next_f64()),
                _ => Some(2.0),
            };
            let growth = 1.0 + 0.5 * rng.next_f64();
            let want = reference(a, m, n, first, growth);
            let (ni, i) = (k % 5, k % 5 / 2);
            let mut nodes = vec![[f64::NAN; 2]; (ni + 1) * (n + 1)];
            spoke_column(a, m, n, first, growth, &mut d, &mut nodes, i, ni + 1);
            for (j, w) in want.iter().enumerate() {
                assert_eq!(
                    nodes[i + j * (ni + 1)].map(f64::to_bits),
                    w.map(f64::to_bits)
                );
            }
            assert_eq!(spoke_nodes(a, m, n, first, growth), want);
        }
    }

    #[test]
    fn spoke_nodes_end_exactly() {
        let (a, m) = ([0.1, 0.2], [1.3, -0.7]);
        let n = spoke_nodes(a, m, 9, Some(1e-3), 1.2);
        assert_eq!(n.len(), 10);
        assert_eq!((n[0], n[9]), (a, m));
        assert!((dist(n[0], n[1]) - 1e-3).abs() < 1e-15);
    }
}

/// The fading of a merged end's offset from the bisector ([`ArcGeometry::offset`], [`blend`]).
#[cfg(test)]
mod blend_tests {
    use super::*;
    use crate::layouts::SplitMix64;

    fn hole(x: f64, y: f64, r: f64) -> Wall {
        Wall { c: [x, y], r, s: r }
    }

    /// A random arc between two holes from bisector angle `t0` to `t1` on the first, with end
    /// `k`'s centre moved by `shift[k]` (as a merged centre is): `None` when undefined.
    fn arc(rng: &mut SplitMix64, shift: [Point; 2]) -> Option<ArcGeometry> {
        arc_scaled(rng, shift, 1.0)
    }

    /// [`arc`] with every length times `scale` (`shift` too).
    fn arc_scaled(rng: &mut SplitMix64, shift: [Point; 2], scale: f64) -> Option<ArcGeometry> {
        let p = hole(0.0, 0.0, scale);
        let q = hole(
            scale * (2.5 + rng.next_f64()),
            scale * (rng.next_f64() - 0.5),
            scale * (0.3 + rng.next_f64()),
        );
        let shift = shift.map(|v| v.map(|x| scale * x));
        let t0 = 0.5 * (rng.next_f64() - 0.5);
        let t1 = t0 + 0.3 + 0.4 * rng.next_f64();
        let (_, m0, _) = medial_point(&p, &q, t0)?;
        let (_, m1, _) = medial_point(&p, &q, t1)?;
        let m = [
            [m0[0] + shift[0][0], m0[1] + shift[0][1]],
            [m1[0] + shift[1][0], m1[1] + shift[1][1]],
        ];
        let ends_a = [
            [p.project(m[0]), q.project(m[0])],
            [p.project(m[1]), q.project(m[1])],
        ];
        let hints = [
            turn(p.c, ends_a[0][0], ends_a[1][0]),
            turn(q.c, ends_a[0][1], ends_a[1][1]),
        ];
        Some(ArcGeometry::new([p, q], m, ends_a, hints))
    }

    fn shift(rng: &mut SplitMix64, size: f64) -> Point {
        let a = rng.next_f64() * std::f64::consts::TAU;
        [size * a.cos(), size * a.sin()]
    }

    #[test]
    fn blend_is_one_at_the_end_zero_at_the_other_and_flat_at_both() {
        assert_eq!(blend(0.0), 1.0);
        assert_eq!(blend(1.0), 0.0);
        assert_eq!((blend(-0.5), blend(1.5)), (1.0, 0.0));
        let h = 1e-6;
        assert!((1.0 - blend(h)).abs() < 1e-10, "zero slope at the end");
        assert!(blend(1.0 - h) < 1e-10, "zero slope at the other end");
        let mut last = 1.0;
        for i in 1..=100 {
            let s = i as f64 / 100.0;
            let w = blend(s);
            assert!(w <= last);
            // The two ends' weights add up to one: the offset moves from one to the other.
            assert!((w + blend(1.0 - s) - 1.0).abs() < 1e-15);
            // Its rate of change is at most 1.5 per unit of parameter (the half-arc fade's
            // was 3: twice as sharp a bend for the same offset).
            assert!((blend(s - 0.01) - w) / 0.01 <= 1.5 + 1e-9);
            last = w;
        }
    }

    /// Ends on the bisector (an Apollonius vertex up to rounding) have no offset: the arc's
    /// points are the bisector's, bit for bit.
    #[test]
    fn ends_on_the_bisector_keep_the_bisector_points() {
        let mut rng = SplitMix64(21);
        for _ in 0..200 {
            let Some(g) = arc(&mut rng, [[0.0; 2]; 2]) else {
                continue;
            };
            assert!(!g.blended());
            for i in 1..8 {
                let t = i as f64 / 8.0;
                let (m, a, _) = g.at(t).unwrap();
                let p = g.param;
                let theta = g.start[p] + t * g.sweep[p];
                let (ap, mp, _) = medial_point(&g.walls[p], &g.walls[1 - p], theta).unwrap();
                assert_eq!((m, a[p]), (mp, ap));
            }
        }
    }

    /// With one end off the bisector, the arc starts at that end (no jump onto the bisector),
    /// leaves it along the bisector's tangent, comes closer to the bisector all along (its
    /// distance never grows, and is at most the end's offset), reaches the other end on it,
    /// and every spoke stays normal to its wall.
    #[test]
    fn an_end_off_the_bisector_is_joined_smoothly() {
        let mut rng = SplitMix64(22);
        let mut checked = 0;
        for _ in 0..300 {
            let off = [shift(&mut rng, 0.05), [0.0; 2]];
            let Some(g) = arc(&mut rng, off) else {
                continue;
            };
            assert!(g.blended());
            let (c, _, _) = g.at(0.0).unwrap();
            // Continuity: the first points approach the end (the old jump was the offset).
            let eps = 1e-7;
            let (m, _, _) = g.at(eps).unwrap();
            let (m2, _, _) = g.at(2.0 * eps).unwrap();
            assert!(dist(m, c) < 1e-3 * 0.05, "{} from the end", dist(m, c));
            // The departure direction is the bisector's at the end's touching angle.
            let p = g.param;
            let bis = |t: f64| {
                let theta = g.start[p] + t * g.sweep[p];
                medial_point(&g.walls[p], &g.walls[1 - p], theta).unwrap().1
            };
            let (b0, b1) = (bis(0.0), bis(2.0 * eps));
            let (u, v) = ([m2[0] - c[0], m2[1] - c[1]], [b1[0] - b0[0], b1[1] - b0[1]]);
            let sin = (u[0] * v[1] - u[1] * v[0]) / (dist(m2, c) * dist(b1, b0));
            assert!(
                sin.abs() < 1e-3,
                "departs {} rad off the bisector",
                sin.asin()
            );
            let mut last_off = dist(g.offset[0], [0.0; 2]);
            for i in 0..=20 {
                let t = i as f64 / 20.0;
                let (m, a, _) = g.at(t).unwrap();
                for (k, w) in g.walls.iter().enumerate() {
                    // The touching point is on the ray from the wall's centre through `m`.
                    let (x, y) = (
                        [a[k][0] - w.c[0], a[k][1] - w.c[1]],
                        [m[0] - w.c[0], m[1] - w.c[1]],
                    );
                    let cross = (x[0] * y[1] - x[1] * y[0]) / (w.r * y[0].hypot(y[1]));
                    assert!(cross.abs() < 1e-12 && x[0] * y[0] + x[1] * y[1] > 0.0);
                }
                let b = bis(t);
                let off = dist(m, b);
                let tol = 1e-12 * (1.0 + b[0].hypot(b[1]));
                assert!(off <= last_off + tol, "moves away from the bisector at {t}");
                last_off = off;
            }
            assert!(
                last_off <= 1e-12 * (1.0 + c[0].hypot(c[1])),
                "ends {last_off} off"
            );
            checked += 1;
        }
        assert!(checked > 200, "{checked}");
    }

    /// The densities of an arc with an end off the bisector: the same bits in every build,
    /// and the plain formula's, bit for bit (every point of such an arc is off the bisector;
    /// arcs on it are compared with the plain formula in `tests/perf_densities.rs`).
    #[test]
    fn blended_densities_agree_in_every_build_and_with_the_plain_formula() {
        let mut rng = SplitMix64(23);
        let mut checked = 0;
        for case in 0..60 {
            let mut off = [shift(&mut rng, 0.03), shift(&mut rng, 0.03)];
            off[case % 2] = [0.0; 2]; // one merged end, then the other
            if case % 3 == 0 {
                off = [shift(&mut rng, 0.03), shift(&mut rng, 0.03)];
            }
            let Some(g) = arc(&mut rng, off) else {
                continue;
            };
            assert!(g.blended());
            let (psq, pang) = g.densities_plain().unwrap();
            let bits = |x: &[f64]| x.iter().map(|y| y.to_bits()).collect::<Vec<u64>>();
            let (mut sq, mut ang) = (vec![1.0; 3], Vec::new());
            g.densities_into_scalar(&mut sq, &mut ang).unwrap();
            assert_eq!((bits(&sq), bits(&ang)), (bits(&psq), bits(&pang)));
            assert_eq!(sq.len(), ARC_SUBSTEPS);
            every_build_gives(&g, &sq, &ang);
            checked += 1;
        }
        assert!(checked > 40, "{checked}");
    }

    /// Blended arcs so small or so large that some squared lengths leave `length`'s `sqrt`
    /// range (where it takes `hypot`): every build still gives the plain formula's bits (the
    /// passes hand such an arc to the plain formula), and the arcs are defined.
    #[test]
    fn blended_densities_at_extreme_scales_are_the_plain_formula() {
        let mut rng = SplitMix64(41);
        let mut checked = 0;
        for case in 0..40 {
            let scale = [
                2f64.powi(-480),
                2f64.powi(480),
                2f64.powi(-470),
                2f64.powi(465),
            ][case % 4];
            let off = [shift(&mut rng, 0.03), shift(&mut rng, 0.03)];
            let Some(g) = arc_scaled(&mut rng, off, scale) else {
                continue;
            };
            assert!(g.blended());
            let (psq, pang) = g.densities_plain().unwrap();
            every_build_gives(&g, &psq, &pang);
            checked += 1;
        }
        assert!(checked > 30, "{checked}");
    }

    /// Every vector build's densities of `g` are `sq` and `ang`, bit for bit.
    fn every_build_gives(g: &ArcGeometry, sq: &[f64], ang: &[f64]) {
        let bits = |x: &[f64]| x.iter().map(|y| y.to_bits()).collect::<Vec<u64>>();
        for lanes in crate::lanes::Lanes::ALL {
            let (mut bsq, mut bang) = (Vec::new(), vec![2.0]);
            g.densities_with(lanes, &mut bsq, &mut bang).unwrap();
            assert_eq!(
                (bits(&bsq), bits(&bang)),
                (bits(sq), bits(ang)),
                "{lanes:?}"
            );
        }
    }
}
