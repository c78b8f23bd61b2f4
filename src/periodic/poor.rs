//! Periodic refinement's first question, asked of the sampled medial graph (issue 8): which
//! vertex orbits are poor, before any layout is extracted.
//!
//! A refinement round that finds poor vertices throws its layout away (the holes it inserts
//! change the domain), so the round asks the medial graph of the sampled tiling, as bounded
//! refinement does ([`crate::refine`]): each vertex orbit once, at its canonical instance
//! (the vertex whose orbit key is its own representative, [`super::normalise_vertex`]), with
//! its exact empty circle ([`cocircular::vertex_circles_of`]) and the ratio of
//! [`refine::vertex_ratio`] (circumradius over shortest edge of the triangle of its touching
//! points). Only vertices that are vertices of the infinite periodic tiling are asked: the
//! circumcircle of the sample triangle, widened by the largest radius, lies where every copy
//! of every hole is in the tiling (the test of the extraction's step 4), and the three
//! circles are holes (not the tiling's auxiliary bounding circle).
//!
//! When this finds none, the round extracts the layout and asks its exact input as before
//! ([`crate::exact_mode::periodic::poor_vertices`]: vertex orbits of collapsed clusters can
//! still be poor), so a round that ends the refinement keeps its layout.

use super::{below, disc_needs, normalise_vertex, vertex_key, PeriodicDomain, Sampled, Tiling};
use crate::cocircular;
use crate::domain::CircleId;
use crate::geometry::Point;
use crate::refine;
use rayon::prelude::*;
use std::collections::HashMap;

/// What a vertex's answer depends on besides the circles its ids name: its circle ids in
/// order and its position's bits (as `cocircular`'s solves).
pub(super) type SolveKey = ([CircleId; 3], [u64; 2]);

/// A solved vertex's answer: `(ratio, empty circle centre, radius)`.
pub(super) type Answer = (f64, Point, f64);

/// The poor vertex orbits of `sampled` (a sampling of `pd`) for the ratio `limit`:
/// `(ratio, empty circle centre, radius)` in vertex order, as
/// [`crate::exact_mode::periodic::poor_vertices`] gives them (see the module doc).
///
/// With `previous`, the sampling of the round before (a tiling whose circles are the first
/// ones of this one, bit for bit), a vertex with the same circle ids and position as a vertex
/// solved there takes that answer (the same solve: issue 8, as bounded refinement's
/// `cocircular::vertex_circles_reusing`); the answers solved here are kept in `sampled` for
/// the next round.
pub(super) fn medial_poor(
    pd: &PeriodicDomain,
    sampled: &Sampled,
    limit: f64,
    previous: Option<&Sampled>,
) -> Vec<(f64, Point, f64)> {
    let (t, medial, points) = (&sampled.t, &sampled.medial, &sampled.samples.points);
    let rmax = pd.holes().iter().map(|c| c.radius).fold(0.0, f64::max);
    let reach = rmax + 1e-6 * t.size[0].max(t.size[1]);
    let asked: Vec<u32> = (0..medial.vertices.len() as u32)
        .into_par_iter()
        .filter(|&v| {
            let mv = &medial.vertices[v as usize];
            if mv.circles.iter().any(|&c| c < 0) {
                return false;
            }
            let Some(key) = vertex_key(t, &sampled.samples, medial, v as usize) else {
                return false;
            };
            if normalise_vertex(&key).1 != (0, 0) {
                return false;
            }
            let p = points[mv.samples[0] as usize];
            let r = (mv.position[0] - p[0]).hypot(mv.position[1] - p[1]);
            in_tiling(t, mv.position, r, reach)
        })
        .collect();
    let key = |v: u32| -> SolveKey {
        let mv = &medial.vertices[v as usize];
        (mv.circles, mv.position.map(f64::to_bits))
    };
    // The round before's answers, when its circles are this tiling's first ones.
    let known: Option<HashMap<SolveKey, Answer>> = previous
        .filter(|p| same_first_circles(&p.t, t))
        .and_then(|p| p.solved.get())
        .map(|solved| solved.iter().copied().collect());
    let reused: Vec<Option<Answer>> = asked
        .par_iter()
        .map(|&v| known.as_ref().and_then(|k| k.get(&key(v)).copied()))
        .collect();
    let fresh: Vec<u32> = asked
        .iter()
        .zip(&reused)
        .filter(|(_, r)| r.is_none())
        .map(|(&v, _)| v)
        .collect();
    let circles = cocircular::vertex_circles_of(&t.domain, medial, &fresh);
    // Every asked vertex's answer, in vertex order: reused, or from its solve (`None`
    // without one: the sample triangle's, not kept).
    let mut solved_here = fresh.iter().zip(&circles);
    let answers: Vec<(u32, Answer, bool)> = asked
        .iter()
        .zip(reused)
        .map(|(&v, reused)| match reused {
            Some(a) => (v, a, true),
            None => {
                let (_, circle) = solved_here.next().expect("one solve per fresh vertex");
                let ratio = refine::vertex_ratio(medial, v as usize, circle.as_ref(), points);
                let (centre, rho) = match circle {
                    Some(c) => (c.center, c.radius),
                    None => {
                        let mv = &medial.vertices[v as usize];
                        let p = points[mv.samples[0] as usize];
                        (
                            mv.position,
                            (mv.position[0] - p[0]).hypot(mv.position[1] - p[1]),
                        )
                    }
                };
                (v, (ratio, centre, rho), circle.is_some())
            }
        })
        .collect();
    let _ = sampled.solved.set(
        answers
            .iter()
            .filter(|a| a.2)
            .map(|&(v, a, _)| (key(v), a))
            .collect(),
    );
    answers
        .into_iter()
        .map(|(_, a, _)| a)
        .filter(|a| !a.0.is_nan() && a.0 > limit)
        .collect()
}

/// True when the circles of `before`'s auxiliary domain are the first circles of `after`'s,
/// bit for bit (the bounding circle too): then a circle id names the same circle in both.
fn same_first_circles(before: &Tiling, after: &Tiling) -> bool {
    let bits = |c: &crate::domain::Circle| [c.center[0], c.center[1], c.radius].map(f64::to_bits);
    let (b, a) = (before.domain.holes(), after.domain.holes());
    b.len() <= a.len()
        && bits(&before.domain.bounding()) == bits(&after.domain.bounding())
        && b.par_iter()
            .zip(&a[..b.len()])
            .all(|(x, y)| bits(x) == bits(y))
}

/// True when the disc of centre `c` and radius `r`, widened by `reach`, lies where every copy
/// of every hole is in the tiling `t` (per axis: inside the band's reach, or inside the array
/// of copies), as the extraction's step 4 measures a triangle's circle ([`disc_needs`]).
fn in_tiling(t: &Tiling, c: Point, r: f64, reach: f64) -> bool {
    if !(c[0].is_finite() && c[1].is_finite() && r.is_finite()) {
        return false;
    }
    disc_needs(t.size, c, r, reach)
        .into_iter()
        .enumerate()
        .all(|(a, (m, beyond))| {
            if t.band[a] {
                below(beyond, t.reach[a])
            } else {
                m.is_finite() && m <= t.m[a] as f64
            }
        })
}
