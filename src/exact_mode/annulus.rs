//! Exact mode for one hole (h = 1): the flow around a single particle.
//!
//! The medial axis of a bounding circle `(c, R)` with one hole `(h, r)` inside has no vertex:
//! it is the closed ellipse `|m - c| + |m - h| = R + r` (foci `c` and `h`; a circle when they
//! coincide). The paper's Blocking2D needs medial vertices, so paper mode meshes this case
//! with the four-block template ring [`crate::templates::annulus`], whose straight spokes
//! ignore clustering options. Exact mode instead cuts the loop at [`ANNULUS_ARCS`] points
//! (degree-2 vertices, as a split arc's middle, [`super::inserted`]) and builds the arcs with
//! the machinery of every other layout ([`super::assemble`]): two blocks per arc, one on each
//! wall, gridded along spokes (every wall-normal line exactly normal to its wall), with the
//! circles' clustering (`--first-height`, `--growth`, `--wall-cells`, ...) and smoothing. The
//! blocks count `2 * ANNULUS_ARCS`: the identity `6(h - 1) + 2 split arcs` with the loop's
//! `ANNULUS_ARCS` pieces counted as split arcs.
//!
//! Where the loop is cut: at the points where `f = (theta + psi) / 2` takes the values
//! `phi + pi/4 - j pi/2`, with `theta` the touching angle on the hole, `psi` the one on the
//! bounding circle (both about their own centres, `psi` within `pi` of `theta`) and `phi` the
//! direction from `c` to `h` (0 when concentric). `f` increases along the loop (the ellipse is
//! star-shaped about both foci), so each point is found by bisection; each arc then sweeps a
//! quarter of a turn *on average over its two walls*, and the narrowest gap (at `theta = psi =
//! phi`) lies in the middle of a block, by symmetry about the line through both centres. Cutting
//! at equal angles of the hole alone would give a small hole near the bounding circle an arc
//! whose outer wall spans almost the whole turn.

use super::{assemble, medial_point, ExactMesh, ExactVertex, Skeleton, Wall};
use crate::domain::{CircleId, Domain, BOUNDING};
use crate::geometry::Point;
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use crate::medial::MedialArc;
use crate::mesher::{MeshError, Options};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI, TAU};

/// The number of arcs the medial loop of one hole is cut into (blocks: twice as many).
pub const ANNULUS_ARCS: usize = 4;

/// The hole's circle id.
const HOLE: CircleId = 0;

/// A point of the medial loop: the touching angles `(theta, psi)` (`psi` within `pi` of
/// `theta`), the medial point and both touching points `[hole, bounding]`.
struct LoopPoint {
    theta: f64,
    psi: f64,
    m: Point,
    a: [Point; 2],
}

/// The loop point whose touching angle on the hole is `theta` (`None` when not finite).
fn loop_point(hole: &Wall, bounding: &Wall, theta: f64) -> Option<LoopPoint> {
    let (a, m, _) = medial_point(hole, bounding, theta)?;
    let b = bounding.project(m);
    let raw = bounding.angle_of(m);
    let psi = raw + ((theta - raw) / TAU).round() * TAU;
    (b[0].is_finite() && b[1].is_finite() && psi.is_finite()).then_some(LoopPoint {
        theta,
        psi,
        m,
        a: [a, b],
    })
}

/// The loop point where `(theta + psi) / 2 = target` (bisection on `theta`; `f - theta` lies in
/// `(-pi/2, pi/2)`, so the root is within `pi/2` of `target`).
fn cut_at(hole: &Wall, bounding: &Wall, target: f64) -> Option<LoopPoint> {
    let (mut lo, mut hi) = (target - FRAC_PI_2, target + FRAC_PI_2);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let p = loop_point(hole, bounding, mid)?;
        if 0.5 * (p.theta + p.psi) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    loop_point(hole, bounding, 0.5 * (lo + hi))
}

/// A sampled layout for [`Skeleton::sampled`], of which only the sweep of each block's side-0
/// wall is read (its turn count): block `2e` on the hole sweeps `hole[e]`, block `2e + 1` on
/// the bounding circle `bounding[e]`, in the side's direction.
fn hint_layout(hole: &[f64], bounding: &[f64]) -> BlockLayout {
    let mut layout = BlockLayout::default();
    for (e, (&s0, &s1)) in hole.iter().zip(bounding).enumerate() {
        for (k, (c, sweep)) in [(HOLE, s0), (BOUNDING, s1)].into_iter().enumerate() {
            layout.edges.push(Edge {
                ends: [0, 0],
                curve: Curve::Arc {
                    center: [0.0, 0.0],
                    radius: 1.0,
                    start: 0.0,
                    sweep,
                },
                kind: EdgeKind::Wall(c),
            });
            let side = SideRef {
                edge: (2 * e + k) as u32,
                reversed: false,
            };
            layout.blocks.push(Block {
                corners: [0; 4],
                sides: [side; 4],
                wall: Some(c),
            });
        }
    }
    layout
}

/// Exact mode for a domain with exactly one hole (see the module docs): `Ok(None)` when the
/// domain has another number of holes, or the exact construction cannot be made or gives an
/// inverted cell (the caller then uses the template ring). Errors other than
/// [`MeshError::Internal`] (options, too many nodes) are returned.
pub fn build_annulus(domain: &Domain, options: &Options) -> Result<Option<ExactMesh>, MeshError> {
    if domain.hole_count() != 1 {
        return Ok(None);
    }
    let hole = Wall::of(domain, HOLE);
    let bounding = Wall::of(domain, BOUNDING);
    let d = [hole.c[0] - bounding.c[0], hole.c[1] - bounding.c[1]];
    let phi = if d == [0.0, 0.0] {
        0.0
    } else {
        d[1].atan2(d[0])
    };
    // The cuts, clockwise (decreasing angles): every block's wall then runs with the fluid on
    // its left, as the blocks of Blocking2D do.
    let mut cuts = Vec::with_capacity(ANNULUS_ARCS);
    for j in 0..ANNULUS_ARCS {
        let target = phi + FRAC_PI_4 - j as f64 * (TAU / ANNULUS_ARCS as f64);
        match cut_at(&hole, &bounding, target) {
            Some(p) => cuts.push(p),
            None => return Ok(None),
        }
    }
    // Strictly decreasing angles on both walls, the last cut less than a turn below the first.
    let ok = cuts
        .windows(2)
        .all(|w| w[1].theta < w[0].theta && w[1].psi < w[0].psi)
        && cuts
            .last()
            .is_some_and(|l| l.theta > cuts[0].theta - TAU && l.psi > cuts[0].psi - TAU);
    if !ok {
        return Ok(None);
    }
    let vertices: Vec<ExactVertex> = cuts
        .iter()
        .map(|p| ExactVertex {
            center: p.m,
            radius: 0.5 * (super::dist(p.m, p.a[0]) + super::dist(p.m, p.a[1])),
            circles: vec![HOLE, BOUNDING],
            tangent: p.a.to_vec(),
        })
        .collect();
    let n = ANNULUS_ARCS;
    let next = |e: usize| (e + 1) % n;
    // The angle of cut `e + 1` as seen from cut `e` (the last arc closes the loop a turn lower).
    let unwrap = |e: usize, x: f64| if e + 1 == n { x - TAU } else { x };
    let hole_sweeps: Vec<f64> = (0..n)
        .map(|e| unwrap(e, cuts[next(e)].theta) - cuts[e].theta)
        .collect();
    // Block `2e + 1`'s wall runs from cut `e + 1` back to cut `e` (counter-clockwise).
    let bounding_sweeps: Vec<f64> = (0..n)
        .map(|e| cuts[e].psi - unwrap(e, cuts[next(e)].psi))
        .collect();
    if hole_sweeps
        .iter()
        .chain(&bounding_sweeps)
        .any(|s| !(s.is_finite() && s.abs() < PI + FRAC_PI_2 && (*s != 0.0)))
    {
        return Ok(None);
    }
    let sampled = hint_layout(&hole_sweeps, &bounding_sweeps);
    let arcs: Vec<MedialArc> = (0..n)
        .map(|e| MedialArc {
            ends: [e as u32, next(e) as u32],
            circles: [HOLE, BOUNDING],
            ..MedialArc::default()
        })
        .collect();
    let built = assemble(
        Skeleton {
            domain,
            arcs: &arcs,
            vertices,
            sampled: &sampled,
            fluid: Vec::new(),
        },
        options,
    );
    match built {
        Ok(m) if m.inconsistent_arcs.is_empty() && m.inverted_blocks.is_empty() => Ok(Some(m)),
        Ok(_) | Err(MeshError::Internal(_)) => Ok(None),
        Err(e) => Err(e),
    }
}
