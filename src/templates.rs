//! Block layouts for the cases without a medial vertex: the disk (h = 0) and the annulus
//! (h = 1). The medial-axis blocking (paper Algorithm 2) needs at least two holes; these two
//! templates cover the rest.
//!
//! Both templates follow the conventions of [`crate::layout`]: corners counter-clockwise with
//! positive area, side `k` from corner `k` to corner `k + 1`, a wall (if any) on side 0, and
//! every edge stored once. Arc vertices are computed with the same formula as the arc curve
//! (`center + radius * (cos a, sin a)`), so they lie on their circle to rounding.
//!
//! The templates trust their input geometry: a non-finite or non-positive radius, or a hole not
//! strictly inside the bounding circle, gives a layout whose grid [`crate::quality`] reports as
//! degenerate or inverted; they never panic. Validate the [`crate::Domain`] first.

use crate::domain::{Circle, CircleId, BOUNDING};
use crate::geometry::Point;
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

/// Size of the disk template's core square: its corners lie at this fraction of the bounding
/// radius from the center (so its half side is `CORE_FRACTION / sqrt(2)` of the radius).
pub const CORE_FRACTION: f64 = 0.55;

/// The hole id used by [`annulus`] for its (only) hole.
pub const ANNULUS_HOLE: CircleId = 0;

fn on_circle(center: Point, radius: f64, angle: f64) -> Point {
    [
        center[0] + radius * angle.cos(),
        center[1] + radius * angle.sin(),
    ]
}

fn side(edge: usize, reversed: bool) -> SideRef {
    SideRef {
        edge: edge as u32,
        reversed,
    }
}

/// The disk template (h = 0): five blocks, an O-grid.
///
/// Block 0..4 are the outer blocks: block `k` has side 0 on the bounding circle (kind
/// `Wall(-1)`, from the angle `pi/4 + k pi/2` counter-clockwise over a quarter turn), sides 1
/// and 3 on straight diagonal spokes and side 2 on an edge of the core square. Block 4 is the
/// core square (no wall), whose corners lie at [`CORE_FRACTION`] of the radius on the
/// diagonals.
///
/// Vertices: `0..4` on the circle, `4..8` the core corners. Edges: `0..4` the wall arcs,
/// `4..8` the spokes (core corner to circle), `8..12` the core edges.
pub fn disk(bounding: Circle) -> BlockLayout {
    let c = bounding.center;
    let r = bounding.radius;
    let angles: [f64; 4] = [0, 1, 2, 3].map(|k| FRAC_PI_4 + k as f64 * FRAC_PI_2);
    let mut vertices = Vec::with_capacity(8);
    for &a in &angles {
        vertices.push(on_circle(c, r, a));
    }
    for &a in &angles {
        vertices.push(on_circle(c, CORE_FRACTION * r, a));
    }
    let outer = |k: usize| (k % 4) as u32;
    let inner = |k: usize| (4 + k % 4) as u32;

    let mut edges = Vec::with_capacity(12);
    // 0..4: wall arcs o_k -> o_{k+1}, counter-clockwise.
    for (k, &start) in angles.iter().enumerate() {
        edges.push(Edge {
            ends: [outer(k), outer(k + 1)],
            curve: Curve::Arc {
                center: c,
                radius: r,
                start,
                sweep: FRAC_PI_2,
            },
            kind: EdgeKind::Wall(BOUNDING),
        });
    }
    // 4..8: spokes q_k -> o_k.
    for k in 0..4 {
        edges.push(Edge {
            ends: [inner(k), outer(k)],
            curve: Curve::Segment,
            kind: EdgeKind::Interface,
        });
    }
    // 8..12: core edges q_k -> q_{k+1}.
    for k in 0..4 {
        edges.push(Edge {
            ends: [inner(k), inner(k + 1)],
            curve: Curve::Segment,
            kind: EdgeKind::Interface,
        });
    }

    let mut blocks = Vec::with_capacity(5);
    for k in 0..4 {
        blocks.push(Block {
            corners: [outer(k), outer(k + 1), inner(k + 1), inner(k)],
            sides: [
                side(k, false),
                side(4 + (k + 1) % 4, true),
                side(8 + k, true),
                side(4 + k, false),
            ],
            wall: Some(BOUNDING),
        });
    }
    blocks.push(Block {
        corners: [inner(0), inner(1), inner(2), inner(3)],
        sides: [
            side(8, false),
            side(9, false),
            side(10, false),
            side(11, false),
        ],
        wall: None,
    });
    BlockLayout {
        vertices,
        edges,
        blocks,
    }
}

/// The annulus template (h = 1): a ring of four blocks between the hole (id
/// [`ANNULUS_HOLE`]) and the bounding circle. Paper mode's mesh of one hole, and exact mode's
/// fallback; exact mode meshes one hole on its medial loop instead
/// ([`crate::exact_mode::annulus`]: spoke-aligned, clustered, eight blocks).
///
/// With `phi` the direction from the bounding center to the hole center (0 when concentric),
/// spoke `k` leaves the hole at angle `theta_k = phi + pi/4 + k pi/2` and runs straight along
/// the ray from the hole center to the bounding circle, so spokes are orthogonal to the hole's
/// wall and the narrowest gap lies in the middle of a block, not on a spoke. Both walls are
/// divided with equal angle steps about their own centers.
///
/// Quality: for a concentric annulus the grid is polar (all angles 90 degrees). Off-centre the
/// cells skew; the worst case is a small hole very close to the bounding circle (a hole of 1%
/// of the radius with a gap of 1% gives minimum angles of a few degrees, no inverted cells
/// in the tested range). A four-block ring cannot do much better there.
///
/// Block `k` has corners `[a_{k+1}, a_k, b_k, b_{k+1}]` (`a` on the hole, `b` on the bounding
/// circle): side 0 is the hole arc traversed clockwise (kind `Wall(0)`, stored
/// counter-clockwise so the side is `reversed`), side 1 the spoke `a_k -> b_k`, side 2 the
/// bounding arc counter-clockwise (kind `Wall(-1)`), side 3 the spoke `b_{k+1} -> a_{k+1}`.
///
/// Vertices: `0..4` on the hole, `4..8` on the bounding circle. Edges: `0..4` hole arcs,
/// `4..8` bounding arcs, `8..12` spokes (hole to bounding circle, kind `Interface`).
pub fn annulus(bounding: Circle, hole: Circle) -> BlockLayout {
    use std::f64::consts::{PI, TAU};
    let c = bounding.center;
    let big_r = bounding.radius;
    let h = hole.center;
    let r = hole.radius;
    let d = [h[0] - c[0], h[1] - c[1]];
    let phi = if d[0] == 0.0 && d[1] == 0.0 {
        0.0
    } else {
        d[1].atan2(d[0])
    };
    let angles: [f64; 4] = [0, 1, 2, 3].map(|k| phi + FRAC_PI_4 + k as f64 * FRAC_PI_2);
    // Where the ray from the hole center at angle t meets the bounding circle, as an angle
    // about the bounding center, taken within pi of t (so the four are increasing).
    let dd = d[0] * d[0] + d[1] * d[1];
    let outer_angles = angles.map(|t| {
        let u = [t.cos(), t.sin()];
        let du = d[0] * u[0] + d[1] * u[1];
        let s = -du + (du * du - dd + big_r * big_r).max(0.0).sqrt();
        let q = [d[0] + s * u[0], d[1] + s * u[1]];
        let mut a = q[1].atan2(q[0]);
        if a < t - PI {
            a += TAU;
        } else if a > t + PI {
            a -= TAU;
        }
        a
    });
    let mut vertices = Vec::with_capacity(8);
    for &t in &angles {
        vertices.push(on_circle(h, r, t));
    }
    for &t in &outer_angles {
        vertices.push(on_circle(c, big_r, t));
    }
    let a = |k: usize| (k % 4) as u32;
    let b = |k: usize| (4 + k % 4) as u32;

    let mut edges = Vec::with_capacity(12);
    for (k, &start) in angles.iter().enumerate() {
        edges.push(Edge {
            ends: [a(k), a(k + 1)],
            curve: Curve::Arc {
                center: h,
                radius: r,
                start,
                sweep: FRAC_PI_2,
            },
            kind: EdgeKind::Wall(ANNULUS_HOLE),
        });
    }
    for (k, &start) in outer_angles.iter().enumerate() {
        // The counter-clockwise sweep to the next corner, in (0, 2 pi).
        let sweep = (outer_angles[(k + 1) % 4] - start).rem_euclid(TAU);
        edges.push(Edge {
            ends: [b(k), b(k + 1)],
            curve: Curve::Arc {
                center: c,
                radius: big_r,
                start,
                sweep,
            },
            kind: EdgeKind::Wall(BOUNDING),
        });
    }
    for k in 0..4 {
        edges.push(Edge {
            ends: [a(k), b(k)],
            curve: Curve::Segment,
            kind: EdgeKind::Interface,
        });
    }

    let blocks = (0..4)
        .map(|k| Block {
            corners: [a(k + 1), a(k), b(k), b(k + 1)],
            sides: [
                side(k, true),
                side(8 + k, false),
                side(4 + k, false),
                side(8 + (k + 1) % 4, true),
            ],
            wall: Some(ANNULUS_HOLE),
        })
        .collect();
    BlockLayout {
        vertices,
        edges,
        blocks,
    }
}

/// Radius of the core polygon of an inserted-hole template, as a fraction of the hole radius.
pub const INSERTED_CORE_FRACTION: f64 = 0.5;

/// The smallest angle gaps between neighbouring core vertices [`core_angles`] tries, as
/// fractions of the regular polygon's gap `2 pi / k`. (Measured on 242 random layouts with
/// inserted holes, exact mode: cells under 10 degrees 43 054 -> 372, under 20 degrees
/// 502 605 -> 80 775, the smallest angle higher in 53 layouts and lower in none; trying 0.75
/// as well made the smallest angle of 40 of the first 104 lower: beside a wide arc the ring
/// block's cells shear.)
pub const INSERTED_CORE_MIN_GAPS: [f64; 2] = [0.25, 0.5];

/// A template on the rays whose blocks' corners are all at least this many degrees is kept
/// as it is by [`core_angles`].
pub const INSERTED_CORE_GOOD_ANGLE_DEG: f64 = 20.0;

/// The angles of the core polygon's vertices `q_i` of an inserted-hole template whose arc ends
/// `p_i` are at the increasing angles `theta` (radians, within one turn).
///
/// By default `q_i` lies on the ray through `p_i`. But an arc a few degrees wide (a medial arc
/// that barely touches the hole) then puts two core vertices almost on top of each other, and
/// the ring and core blocks beside them become slivers (cells of 3 degrees). So when a corner
/// of that template is below [`INSERTED_CORE_GOOD_ANGLE_DEG`], the angles are also moved as
/// little as possible (least squares, [`spread_angles`]) to gaps of at least each fraction of
/// [`INSERTED_CORE_MIN_GAPS`] of `2 pi / k`, and the candidate whose template has the largest
/// smallest corner angle ([`template_min_angle`]) is taken (the rays win ties). Leaning `p_i
/// q_i` away from the ray is not always better: beside a wide arc the ring blocks' angles at
/// `q_i` are close to half a turn, and a lean makes one of them sharp or reflex and that
/// block's many cells shear (that is why the gaps are not simply made equal).
pub fn core_angles(theta: &[f64]) -> Vec<f64> {
    let mut best = theta.to_vec();
    let mut best_score = template_min_angle(theta, theta);
    let k = theta.len().max(1) as f64;
    if best_score >= INSERTED_CORE_GOOD_ANGLE_DEG.to_radians() {
        return best;
    }
    for fraction in INSERTED_CORE_MIN_GAPS {
        let Some(phi) = spread_angles(theta, fraction * std::f64::consts::TAU / k) else {
            continue;
        };
        let score = template_min_angle(theta, &phi);
        if score > best_score {
            (best, best_score) = (phi, score);
        }
    }
    best
}

/// The increasing angles `theta` (within one turn) taken from index `r` on, those before `r`
/// one turn up: the arcs as seen by a ladder that starts at arc `r`.
fn turned_angles(theta: &[f64], r: usize) -> Vec<f64> {
    use std::f64::consts::TAU;
    let k = theta.len();
    (0..k)
        .map(|i| theta[(i + r) % k] + if i + r >= k { TAU } else { 0.0 })
        .collect()
}

/// Where the ladder of an inserted-hole template starts, and its core angles
/// ([`core_angles`]): the arcs whose ends are at the increasing angles `theta` (within one
/// turn) are taken from arc `turn` on (`turn < k / 2`; turning by `k / 2` gives the same
/// ladder), for the `turn` whose template has the largest smallest corner angle
/// ([`template_min_angle`]; ties: the smallest `turn`). The returned angles are in that order
/// (those of the arcs before `turn` one turn up).
///
/// Why: the ladder's chords `q_j q_{k-1-j}` are parallel to the chord `q_0 q_{k-1}`, so its end
/// blocks are the thin ones, and where they sit matters when the arcs are unequal (a hole split
/// to an even count has two half-width arcs). Starting at the arc of least angle made that a
/// matter of rounding on symmetric layouts: 23 holes on a ring around an inserted centre hole
/// gave a smallest angle of 15.7 or 7.8 degrees depending on which arc's start rounded below
/// zero.
pub fn ladder_turn(theta: &[f64]) -> (usize, Vec<f64>) {
    let k = theta.len();
    let turned = |r: usize| turned_angles(theta, r);
    let mut best = (0, core_angles(theta));
    let mut best_score = template_min_angle(theta, &best.1);
    for r in 1..k / 2 {
        let t = turned(r);
        let phi = core_angles(&t);
        let score = template_min_angle(&t, &phi);
        if score > best_score {
            (best, best_score) = ((r, phi), score);
        }
    }
    best
}

/// The least-squares nearest angles to the increasing `theta` (within one turn) whose cyclic
/// gaps are all at least `gap`: pool-adjacent-violators on `theta_i - i gap`, cut open after
/// the widest gap (where nothing needs moving). `None` when the gap across the cut ends up
/// below `gap` too, or the input is not increasing.
pub fn spread_angles(theta: &[f64], gap: f64) -> Option<Vec<f64>> {
    use std::f64::consts::TAU;
    let k = theta.len();
    let increasing = theta.windows(2).all(|w| w[0] < w[1]);
    if k < 2 || gap.is_nan() || gap <= 0.0 || !increasing {
        return None;
    }
    let gap_after = |i: usize| {
        let next = if i + 1 < k {
            theta[i + 1]
        } else {
            theta[0] + TAU
        };
        next - theta[i]
    };
    // Cut after the widest gap: the sequence starts at `s`.
    let s = (0..k).fold(0, |b, i| if gap_after(i) > gap_after(b) { i } else { b }) + 1;
    let unwrapped: Vec<f64> = (0..k)
        .map(|i| {
            let j = (s + i) % k;
            theta[j] + if j < s % k { TAU } else { 0.0 }
        })
        .collect();
    // Isotonic (non-decreasing) least squares of `y_i = unwrapped_i - i gap`: blocks of
    // (sum, count), merged while a block's mean is below the previous one's.
    let mut blocks: Vec<(f64, usize)> = Vec::with_capacity(k);
    for (i, t) in unwrapped.iter().enumerate() {
        blocks.push((t - i as f64 * gap, 1));
        while blocks.len() >= 2 {
            let (s1, n1) = blocks[blocks.len() - 1];
            let (s0, n0) = blocks[blocks.len() - 2];
            if s1 / n1 as f64 >= s0 / n0 as f64 {
                break;
            }
            blocks.pop();
            let last = blocks.len() - 1;
            blocks[last] = (s0 + s1, n0 + n1);
        }
    }
    // The pooled angles; an angle left alone (a block of one) is the input's, bit for bit.
    let mut spread: Vec<Option<f64>> = Vec::with_capacity(k);
    for (sum, n) in blocks {
        let mean = sum / n as f64;
        for _ in 0..n {
            let i = spread.len();
            spread.push((n > 1).then_some(mean + i as f64 * gap));
        }
    }
    let at = |i: usize| spread[i].unwrap_or(unwrapped[i]);
    let across = at(0) + TAU - at(k - 1);
    if across.is_nan() || across < gap {
        return None;
    }
    // Back to the input's order, within [0, 2 pi) where the input was.
    let mut phi = theta.to_vec();
    for (i, a) in spread.into_iter().enumerate() {
        if let Some(a) = a {
            let j = (s + i) % k;
            phi[j] = a - if j < s % k { TAU } else { 0.0 };
        }
    }
    Some(phi)
}

/// The smallest corner angle (radians) of the template blocks of a unit hole whose arc ends
/// are at angles `theta` and core vertices at angles `phi` (radius
/// [`INSERTED_CORE_FRACTION`]): the ring blocks (the arc's tangent at its ends) and the
/// ladder's core blocks. Negative when a corner is reflex or the blocks fold.
pub fn template_min_angle(theta: &[f64], phi: &[f64]) -> f64 {
    let k = theta.len();
    if k < 4 || phi.len() != k {
        return -1.0;
    }
    let q: Vec<Point> = phi
        .iter()
        .map(|&a| on_circle([0.0; 2], INSERTED_CORE_FRACTION, a))
        .collect();
    template_extremes(theta, &q, ladder_quads(&q)).0
}

/// The ladder's core blocks `q_j q_{j+1} q_{k-2-j} q_{k-1-j}` on the core polygon `q`.
fn ladder_quads(q: &[Point]) -> impl Iterator<Item = [Point; 4]> + '_ {
    let k = q.len();
    (0..(k / 2).saturating_sub(1)).map(move |j| [q[j], q[j + 1], q[k - 2 - j], q[k - 1 - j]])
}

/// Interior angle at a corner of a counter-clockwise polygon entered along `a`, left along
/// `b`: half a turn less the left turn; `-1` for a reflex corner or no turn.
fn interior_angle(a: [f64; 2], b: [f64; 2]) -> f64 {
    let turn = (a[0] * b[1] - a[1] * b[0]).atan2(a[0] * b[0] + a[1] * b[1]);
    if turn <= 0.0 {
        -1.0
    } else {
        std::f64::consts::PI - turn
    }
}

/// The smallest and largest corner angles (radians) of the template blocks of a unit hole
/// whose arc ends are at angles `theta`, core polygon `ring` (`q_i`) and core blocks `core`
/// (counter-clockwise quadrilaterals): the ring blocks `p_i p_{i+1} q_{i+1} q_i` take the
/// arc's tangent at `p_i` and `p_{i+1}`. The smallest is negative when a corner is reflex or
/// a block folds. The caller checks `ring.len() == theta.len() >= 4`.
fn template_extremes(
    theta: &[f64],
    ring: &[Point],
    core: impl Iterator<Item = [Point; 4]>,
) -> (f64, f64) {
    let k = theta.len();
    let p = |i: usize| on_circle([0.0; 2], 1.0, theta[i % k]);
    let sub = |a: Point, b: Point| [a[0] - b[0], a[1] - b[1]];
    let tangent = |i: usize| [-theta[i % k].sin(), theta[i % k].cos()];
    let (mut least, mut most) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut add = |angle: f64| {
        least = least.min(angle);
        most = most.max(angle);
    };
    for i in 0..k {
        let j = i + 1;
        let (pi, pj, qi, qj) = (p(i), p(j), ring[i], ring[j % k]);
        add(interior_angle(sub(pi, qi), tangent(i)));
        add(interior_angle(tangent(j), sub(qj, pj)));
        add(interior_angle(sub(qj, pj), sub(qi, qj)));
        add(interior_angle(sub(qi, qj), sub(pi, qi)));
    }
    for c in core {
        for t in 0..4 {
            add(interior_angle(
                sub(c[t], c[(t + 3) % 4]),
                sub(c[(t + 1) % 4], c[t]),
            ));
        }
    }
    (least, most)
}

/// How far the corners of a template are from the worst a quadrilateral can have: the
/// smaller of its smallest corner angle and half a turn less its largest (radians; negative
/// when a block folds), see [`template_extremes`].
fn template_score(theta: &[f64], ring: &[Point], core: impl Iterator<Item = [Point; 4]>) -> f64 {
    if theta.len() < 4 || ring.len() != theta.len() {
        return -1.0;
    }
    let (least, most) = template_extremes(theta, ring, core);
    if least < 0.0 {
        least
    } else {
        least.min(std::f64::consts::PI - most)
    }
}

/// The `a x b` grid core of an inserted-hole template (see [`grid_cores`]): the core
/// polygon's `k = 2 (a + b)` vertices on the four sides of a quadrilateral, and the blocks of
/// an `a x b` arrangement inside it.
#[derive(Debug, Clone, PartialEq)]
pub struct GridCore {
    /// Blocks along the sides `q_0 .. q_a` and `q_{a+b} .. q_{2a+b}`.
    pub a: usize,
    /// Blocks along the sides `q_a .. q_{a+b}` and `q_{2a+b} .. q_0`.
    pub b: usize,
    /// Vertex `(x, y)` (`x <= a`, `y <= b`) at `x + y (a + 1)`, for a unit hole at the
    /// origin: `(x, 0)` is `q_x`, `(a, y)` is `q_{a+y}`, `(x, b)` is `q_{2a+b-x}` and `(0, y)`
    /// is `q_{(k-y) mod k}`.
    pub nodes: Vec<Point>,
}

impl GridCore {
    /// Grid coordinates `(x, y)` of core polygon vertex `q_i`.
    pub fn of_ring(a: usize, b: usize, i: usize) -> (usize, usize) {
        let k = 2 * (a + b);
        let i = i % k;
        if i <= a {
            (i, 0)
        } else if i <= a + b {
            (a, i - a)
        } else if i <= 2 * a + b {
            (2 * a + b - i, b)
        } else {
            (0, k - i)
        }
    }

    /// Vertex `(x, y)`.
    pub fn at(&self, x: usize, y: usize) -> Point {
        self.nodes[x + y * (self.a + 1)]
    }

    /// The core polygon's vertices `q_0 .. q_{k-1}`.
    pub fn ring(&self) -> Vec<Point> {
        (0..2 * (self.a + self.b))
            .map(|i| {
                let (x, y) = Self::of_ring(self.a, self.b, i);
                self.at(x, y)
            })
            .collect()
    }

    /// The core blocks, counter-clockwise corners `(x, y), (x + 1, y), (x + 1, y + 1),
    /// (x, y + 1)`.
    pub fn blocks(&self) -> impl Iterator<Item = [Point; 4]> + '_ {
        (0..self.b).flat_map(move |y| {
            (0..self.a).map(move |x| {
                [
                    self.at(x, y),
                    self.at(x + 1, y),
                    self.at(x + 1, y + 1),
                    self.at(x, y + 1),
                ]
            })
        })
    }
}

/// Sizes (fractions of the hole radius) of the quadrilaterals [`grid_cores`] tries: how far
/// their corners are from the centre.
pub const GRID_CORE_REACH: [f64; 3] = [0.45, 0.55, 0.65];

/// The grid cores [`ladder_core`] tries for arcs whose ends are at the increasing angles
/// `theta` (a unit hole at the origin; `k = theta.len()` even, at least 4; `m = k / 2`):
/// for each split `a + b = m` (`a >= b >= 1`; all of them up to `m = 8`, beyond that the
/// two most nearly square and the ladder `b = 1`) and each size of [`GRID_CORE_REACH`], the
/// quadrilateral whose corners lie on the rays through the arc ends `p_0, p_a, p_{a+b},
/// p_{2a+b}` at that distance, the other core vertices on its sides, where the rays through
/// their arc ends cross them (or, second, equally spaced along each side), and the inner
/// vertices by transfinite interpolation of the sides ([`crate::grid::tfi`]). A
/// quadrilateral with a corner of half a turn or more is skipped.
///
/// Why: the ladder on the circle ([`core_angles`]) has end blocks with two corners of about
/// `2 pi / k`, so a hole that many arcs reach (a ring of 41 holes around an inserted one)
/// gave cells of 8.8 degrees; on a quadrilateral every core block is a quadrilateral with
/// corners near right angles.
pub fn grid_cores(theta: &[f64]) -> Vec<GridCore> {
    let k = theta.len();
    if k < 4 || k % 2 == 1 || theta.iter().any(|t| !t.is_finite()) {
        return Vec::new();
    }
    let m = k / 2;
    let splits: Vec<usize> = if m <= 8 {
        (1..=m / 2).collect()
    } else {
        let mut b = vec![1, m / 2 - 1, m / 2];
        b.dedup();
        b
    };
    let dir = |t: f64| [t.cos(), t.sin()];
    let mut out = Vec::new();
    for &b in &splits {
        let a = m - b;
        let corners = [0, a, a + b, 2 * a + b];
        let corner_angle = |j: usize| {
            let i = corners[j % 4];
            theta[i] + if j >= 4 { std::f64::consts::TAU } else { 0.0 }
        };
        if (0..4).any(|j| corner_angle(j + 1) - corner_angle(j) >= 0.95 * std::f64::consts::PI) {
            continue;
        }
        for &reach in &GRID_CORE_REACH {
            let c: Vec<Point> = (0..4)
                .map(|j| {
                    let d = dir(corner_angle(j));
                    [reach * d[0], reach * d[1]]
                })
                .collect();
            for along_rays in [true, false] {
                let mut q = vec![[0.0; 2]; k];
                for j in 0..4 {
                    let (i0, i1) = (corners[j], if j == 3 { k } else { corners[j + 1] });
                    let (c0, c1) = (c[j], c[(j + 1) % 4]);
                    let e = [c1[0] - c0[0], c1[1] - c0[1]];
                    for (n, i) in (i0..i1).enumerate() {
                        let t = if n == 0 {
                            0.0
                        } else if along_rays {
                            // The ray at theta_i meets c0 + t e where cross(c0 + t e, d) = 0.
                            let d = dir(theta[i]);
                            let den = d[0] * e[1] - d[1] * e[0];
                            let t = (c0[0] * d[1] - c0[1] * d[0]) / den;
                            if t.is_finite() {
                                t.clamp(0.0, 1.0)
                            } else {
                                n as f64 / (i1 - i0) as f64
                            }
                        } else {
                            n as f64 / (i1 - i0) as f64
                        };
                        q[i] = if n == 0 {
                            c0
                        } else {
                            [c0[0] + t * e[0], c0[1] + t * e[1]]
                        };
                    }
                }
                let side = |from: usize, to: usize| -> Vec<Point> {
                    (from..=to).map(|i| q[i % k]).collect()
                };
                let Some(g) = crate::grid::tfi(
                    &side(0, a),
                    &side(a, a + b),
                    &side(a + b, 2 * a + b),
                    &side(2 * a + b, k),
                ) else {
                    continue;
                };
                out.push(GridCore {
                    a,
                    b,
                    nodes: g.nodes,
                });
            }
        }
    }
    out
}

/// The core of an inserted-hole template: where its vertices are and how it is cut.
#[derive(Debug, Clone, PartialEq)]
pub enum Core {
    /// On the circle of [`INSERTED_CORE_FRACTION`] of the radius, at these angles
    /// ([`core_angles`]), cut by the ladder.
    Circle(Vec<f64>),
    /// An `a x b` grid core ([`grid_cores`]).
    Grid(GridCore),
}

/// Where the ladder of an inserted-hole template starts and its core: [`ladder_turn`]'s
/// circle core, unless its smallest corner angle is below [`INSERTED_CORE_GOOD_ANGLE_DEG`]
/// and a grid core ([`grid_cores`]) of some start scores better: the smaller of its smallest
/// corner angle and half a turn less its largest (ties: the circle, then the smaller start
/// and the earlier candidate). Returns the start and the core (vertices for the arcs taken
/// from that start).
pub fn ladder_core(theta: &[f64]) -> (usize, Core) {
    let k = theta.len();
    let (turn, phi) = ladder_turn(theta);
    let turned = |r: usize| turned_angles(theta, r);
    let t = turned(turn);
    if k < 4 || template_min_angle(&t, &phi) >= INSERTED_CORE_GOOD_ANGLE_DEG.to_radians() {
        return (turn, Core::Circle(phi));
    }
    let q: Vec<Point> = phi
        .iter()
        .map(|&a| on_circle([0.0; 2], INSERTED_CORE_FRACTION, a))
        .collect();
    let m = k / 2;
    let mut best_score = template_score(&t, &q, ladder_quads(&q));
    let mut best = (turn, Core::Circle(phi));
    for r in 0..m {
        let t = turned(r);
        for g in grid_cores(&t) {
            let score = template_score(&t, &g.ring(), g.blocks());
            if score > best_score {
                best_score = score;
                best = (r, Core::Grid(g));
            }
        }
    }
    best
}

/// Fill inserted hole `hole` (a hole added by macro Delaunay refinement, paper Algorithm 3;
/// it is fluid, not a wall) with template blocks conforming to the blocks around it. Returns
/// the number of blocks added.
///
/// The blocks outside split the hole's circle into `k` arcs (edges of kind `Wall(hole)`).
/// The template is a generalised O-grid:
/// - a *ring* of `k` blocks, block `i` between arc `i` (its side 0, the outer edge reversed)
///   and the chord `q_i q_{i+1}` of a concentric core polygon (side 2) whose vertices `q_i`
///   lie at [`INSERTED_CORE_FRACTION`] of the radius on the rays through the arc ends `p_i`,
///   moved apart where two are too close ([`core_angles`]); sides 1 and 3 are the segments
///   `p_i q_i`;
/// - the *core* `k`-gon cut into `k/2 - 1` quadrilaterals by the chords `q_j q_{k-1-j}`
///   (a ladder; for `k = 4` the single core square of the standard O-grid).
///
/// When a block of that template has a corner below [`INSERTED_CORE_GOOD_ANGLE_DEG`] (many
/// arcs: the ladder's end blocks have corners of about `2 pi / k`), the core vertices may
/// instead lie on the sides of a quadrilateral and the core be an `a x b` arrangement of
/// blocks (`a + b = k / 2`, new inner vertices), whichever [`ladder_core`] scores better
/// ([`GridCore`]); its opposite sides tie arcs in pairs just as the ladder's chords do.
///
/// Every template edge is a whole block side, so conformity only adds equal-count classes
/// (arc `i` with core edge `i`, opposite core edges, all segments `p_i q_i`): no node-count
/// arithmetic is needed. A quadrangulation without boundary Steiner points needs `k` even, so
/// the caller first splits a block pair outside when `k` is odd
/// ([`crate::blocking::split_block_pair`]). The hole's arcs become [`EdgeKind::Interface`] and
/// the outer blocks on them get `wall: None`.
///
/// Errors (layout unchanged): fewer than 4 or an odd number of arcs, arcs that do not close
/// up into one counter-clockwise cycle, or an arc of half a turn or more.
pub fn fill_inserted_hole(
    layout: &mut BlockLayout,
    hole: CircleId,
    circle: Circle,
) -> Result<usize, String> {
    let walls: Vec<usize> = (0..layout.edges.len())
        .filter(|&e| layout.edges[e].kind == EdgeKind::Wall(hole))
        .collect();
    let first_block = layout.blocks.len();
    let (n, mut hole_edges) = fill_with_walls(layout, circle, &walls)?;
    hole_edges.sort_unstable();
    for b in layout.blocks[..first_block].iter_mut() {
        if hole_edges
            .binary_search(&(b.sides[0].edge as usize))
            .is_ok()
        {
            b.wall = None;
        }
    }
    Ok(n)
}

/// [`fill_inserted_hole`] for every `(hole, circle)` of `holes` in order, with one pass over
/// the edges (each hole's wall arcs) and one over the blocks (`wall: None` on the blocks
/// outside the holes whose side 0 is one of their arcs) instead of one of each per hole
/// (issue 8: O(edges) per inserted hole). The wall arcs of a hole are those present before
/// the call; templates add no wall edges, so this is what the sequential calls see, as long as
/// nothing else changes the layout between holes (exact mode: all arcs split first). Returns
/// the template blocks added, or the first failing hole and its error (the layout is then
/// partly filled and must be discarded). A hole listed twice fails the second time, as it
/// would sequentially (its arcs are no longer walls).
pub fn fill_inserted_holes(
    layout: &mut BlockLayout,
    holes: &[(CircleId, Circle)],
) -> Result<usize, (CircleId, String)> {
    // Looked up per wall edge, never iterated: a fixed fast hasher (SipHash took 8 ms of
    // lookups at 1e5 particles).
    let mut walls: std::collections::HashMap<CircleId, Vec<usize>, foldhash::fast::FixedState> =
        holes.iter().map(|&(c, _)| (c, Vec::new())).collect();
    for (e, edge) in layout.edges.iter().enumerate() {
        if let EdgeKind::Wall(c) = edge.kind {
            if let Some(list) = walls.get_mut(&c) {
                list.push(e);
            }
        }
    }
    let first_block = layout.blocks.len();
    let mut was_wall = vec![false; layout.edges.len()];
    let mut added = 0;
    for &(hole, circle) in holes {
        let list = walls.remove(&hole).unwrap_or_default();
        let (n, hole_edges) = fill_with_walls(layout, circle, &list).map_err(|m| (hole, m))?;
        for e in hole_edges {
            if let Some(w) = was_wall.get_mut(e) {
                *w = true;
            }
        }
        added += n;
    }
    for b in layout.blocks[..first_block].iter_mut() {
        if was_wall.get(b.sides[0].edge as usize) == Some(&true) {
            b.wall = None;
        }
    }
    Ok(added)
}

/// The template of one inserted hole whose wall arcs are the edges `walls` (increasing):
/// blocks and edges appended, the arcs made [`EdgeKind::Interface`]. Returns the blocks added
/// and the arcs (the caller clears `wall` on the blocks outside that sit on them).
fn fill_with_walls(
    layout: &mut BlockLayout,
    circle: Circle,
    walls: &[usize],
) -> Result<(usize, Vec<usize>), String> {
    use std::f64::consts::{PI, TAU};
    // (edge, ccw start angle, ccw sweep, ccw first vertex, ccw last vertex)
    let mut arcs: Vec<(usize, f64, f64, u32, u32)> = Vec::new();
    for &e in walls {
        let edge = &layout.edges[e];
        let Curve::Arc { start, sweep, .. } = edge.curve else {
            return Err(format!("edge {e} on the hole is not an arc"));
        };
        let (a, s, lo, hi) = if sweep < 0.0 {
            (start + sweep, -sweep, edge.ends[1], edge.ends[0])
        } else {
            (start, sweep, edge.ends[0], edge.ends[1])
        };
        arcs.push((e, a.rem_euclid(TAU), s, lo, hi));
    }
    let k = arcs.len();
    if k < 4 || k % 2 == 1 {
        return Err(format!(
            "{k} arcs around the hole (need an even number >= 4)"
        ));
    }
    arcs.sort_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)));
    let total: f64 = arcs.iter().map(|a| a.2).sum();
    if (total - TAU).abs() > 1e-6 {
        return Err(format!("the arcs sweep {total} radians, not a full turn"));
    }
    for i in 0..k {
        if arcs[i].4 != arcs[(i + 1) % k].3 {
            return Err("the arcs do not form one cycle".into());
        }
        if arcs[i].2 >= PI {
            return Err(format!("an arc sweeps {} radians", arcs[i].2));
        }
    }
    let (turn, core) = ladder_core(&arcs.iter().map(|a| a.1).collect::<Vec<f64>>());
    arcs.rotate_left(turn);
    let c = circle.center;
    let p: Vec<u32> = arcs.iter().map(|a| a.3).collect();
    let q0 = layout.vertices.len() as u32;
    let grid = match core {
        Core::Circle(phi) => {
            for phi in phi {
                layout
                    .vertices
                    .push(on_circle(c, INSERTED_CORE_FRACTION * circle.radius, phi));
            }
            None
        }
        Core::Grid(g) => {
            let place = |[x, y]: Point| [c[0] + circle.radius * x, c[1] + circle.radius * y];
            for v in g.ring() {
                layout.vertices.push(place(v));
            }
            for y in 1..g.b {
                for x in 1..g.a {
                    layout.vertices.push(place(g.at(x, y)));
                }
            }
            Some((g.a, g.b))
        }
    };
    let q = |i: usize| q0 + (i % k) as u32;
    let push_edge = |layout: &mut BlockLayout, ends: [u32; 2]| -> usize {
        layout.edges.push(Edge {
            ends,
            curve: Curve::Segment,
            kind: EdgeKind::Interface,
        });
        layout.edges.len() - 1
    };
    let radial: Vec<usize> = (0..k).map(|i| push_edge(layout, [q(i), p[i]])).collect();
    let core: Vec<usize> = (0..k)
        .map(|i| push_edge(layout, [q(i), q(i + 1)]))
        .collect();
    let first_block = layout.blocks.len();
    for i in 0..k {
        let j = (i + 1) % k;
        let outer = arcs[i].0;
        let reversed = layout.edges[outer].ends != [p[i], p[j]];
        layout.blocks.push(Block {
            corners: [p[i], p[j], q(j), q(i)],
            sides: [
                side(outer, reversed),
                side(radial[j], true),
                side(core[i], true),
                side(radial[i], false),
            ],
            wall: None,
        });
    }
    match grid {
        None => ladder_blocks(layout, k, q0, &core, push_edge),
        Some((a, b)) => grid_blocks(layout, a, b, q0, &core, push_edge),
    }
    for a in &arcs {
        layout.edges[a.0].kind = EdgeKind::Interface;
    }
    let hole_edges: Vec<usize> = arcs.iter().map(|a| a.0).collect();
    Ok((layout.blocks.len() - first_block, hole_edges))
}

/// The ladder's blocks in the core `k`-gon on the circle (`core[i]` the edge `q_i q_{i+1}`).
fn ladder_blocks(
    layout: &mut BlockLayout,
    k: usize,
    q0: u32,
    core: &[usize],
    push_edge: impl Fn(&mut BlockLayout, [u32; 2]) -> usize,
) {
    let q = |i: usize| q0 + (i % k) as u32;
    // Ladder: chord_j joins q_j and q_{k-1-j}; chord_0 is core edge k-1 (q_{k-1} -> q_0),
    // chord_{m-1} is core edge m-1 (q_{m-1} -> q_m).
    let m = k / 2;
    let mut chord: Vec<(usize, bool)> = vec![(core[k - 1], true)];
    for j in 1..m - 1 {
        chord.push((push_edge(layout, [q(j), q(k - 1 - j)]), false));
    }
    chord.push((core[m - 1], false));
    for j in 0..m - 1 {
        // Side 1 runs q_{j+1} -> q_{k-2-j}; side 3 runs q_{k-1-j} -> q_j.
        let (c1, _) = chord[j + 1];
        let (c3, c3_is_core) = chord[j];
        layout.blocks.push(Block {
            corners: [q(j), q(j + 1), q(k - 2 - j), q(k - 1 - j)],
            sides: [
                side(core[j], false),
                side(c1, false),
                side(core[k - 2 - j], false),
                // A stored chord runs q_j -> q_{k-1-j}: reversed here; chord_0 (core edge
                // k-1) already runs q_{k-1} -> q_0.
                side(c3, !c3_is_core),
            ],
            wall: None,
        });
    }
}

/// The blocks of an `a x b` grid core ([`GridCore`]): core polygon vertex `q_i` is layout
/// vertex `q0 + i`, the inner vertex `(x, y)` is `q0 + k + (x - 1) + (y - 1) (a - 1)`, and
/// `core[i]` is the edge `q_i q_{i+1}`. Blocks row by row from `(0, 0)`, corners
/// `(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)`.
fn grid_blocks(
    layout: &mut BlockLayout,
    a: usize,
    b: usize,
    q0: u32,
    core: &[usize],
    push_edge: impl Fn(&mut BlockLayout, [u32; 2]) -> usize,
) {
    let k = 2 * (a + b);
    let vertex = |x: usize, y: usize| -> u32 {
        if y == 0 {
            q0 + x as u32
        } else if x == a {
            q0 + (a + y) as u32
        } else if y == b {
            q0 + (2 * a + b - x) as u32
        } else if x == 0 {
            q0 + ((k - y) % k) as u32
        } else {
            q0 + (k + (x - 1) + (y - 1) * (a - 1)) as u32
        }
    };
    // (edge, whether it is stored from (x, y) to (x + 1, y)) of the horizontal edge at (x, y).
    let mut horizontal: Vec<(usize, bool)> = Vec::with_capacity(a * (b + 1));
    for y in 0..=b {
        for x in 0..a {
            horizontal.push(if y == 0 {
                (core[x], true)
            } else if y == b {
                (core[2 * a + b - 1 - x], false)
            } else {
                (push_edge(layout, [vertex(x, y), vertex(x + 1, y)]), true)
            });
        }
    }
    // Likewise the vertical edge at (x, y): stored from (x, y) to (x, y + 1)?
    let mut vertical: Vec<(usize, bool)> = Vec::with_capacity((a + 1) * b);
    for y in 0..b {
        for x in 0..=a {
            vertical.push(if x == a {
                (core[a + y], true)
            } else if x == 0 {
                (core[k - 1 - y], false)
            } else {
                (push_edge(layout, [vertex(x, y), vertex(x, y + 1)]), true)
            });
        }
    }
    let h = |x: usize, y: usize| horizontal[x + y * a];
    let v = |x: usize, y: usize| vertical[x + y * (a + 1)];
    for y in 0..b {
        for x in 0..a {
            let (s0, f0) = h(x, y);
            let (s1, f1) = v(x + 1, y);
            let (s2, f2) = h(x, y + 1);
            let (s3, f3) = v(x, y);
            layout.blocks.push(Block {
                corners: [
                    vertex(x, y),
                    vertex(x + 1, y),
                    vertex(x + 1, y + 1),
                    vertex(x, y + 1),
                ],
                sides: [side(s0, !f0), side(s1, !f1), side(s2, f2), side(s3, f3)],
                wall: None,
            });
        }
    }
}
