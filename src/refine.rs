//! Macro Delaunay refinement (paper section 4.1, Algorithm 3).
//!
//! While some interior triangle is *poor*, insert a circular hole at the centre of its empty
//! circle with half its radius, and recompute everything (sampling, triangulation, medial
//! graph).
//!
//! Quality measure (our choice, documented): the triangle of the three *tangent points* of the
//! medial vertex's exact Apollonius circle ([`crate::cocircular::vertex_circles`]), not the
//! triangle of the three sample points. By the Angle Lemma (paper Lemma 1) the block corners
//! at a medial vertex are the angles of that triangle, and the tangent points are where the
//! spokes meet the walls, so this is the quantity the blocks inherit, independent of how
//! densely the circles happen to be sampled. Its circumradius is the Apollonius radius `rho`,
//! so the ratio is `rho / l` with `l` the shortest distance between two tangent points, and
//! `rho / l > 2` is equivalent to a smallest angle below `arcsin(1/4) ~ 14.48` degrees. When
//! the exact solve has no answer for a vertex, the sample triangle is used instead.
//!
//! Inserted hole: centre the Apollonius centre (the tangent triangle's circumcentre), radius
//! `rho / 2`. Lemma 2: the empty circle touches the three circles and overlaps none, so the new
//! hole's gap to every circle is at least `rho / 2 > l >= G` (`l` is at least the gap between
//! the two circles it joins, `G` the current minimum gap): the minimum gap never decreases,
//! and Delaunay-refinement packing arguments give termination. Every candidate is checked
//! against this before insertion (a rounding or sampling artefact that would break it skips the
//! candidate), several non-conflicting holes are inserted per round (worst ratio first; each
//! must keep the gap `>= G` to the others too), and a typed error
//! ([`MeshError::Refinement`]) stops the loop when more than the configured number of holes
//! would be inserted.

use crate::apollonius::Apollonius;
use crate::cocircular::vertex_circles_taking;
use crate::domain::{dist, gap, Circle, Domain};
use crate::geometry::Point;
use crate::medial::{circumcenter, MedialGraph};
use crate::mesher::MeshError;
use crate::sampling::{
    nearest_gaps, sample_and_triangulate_taking, SampledDomain, SamplingOptions,
};
use std::collections::HashSet;

/// The poorness ratio `circumradius / shortest edge` of medial vertex `v`: from the tangent
/// points of its Apollonius circle (`circle`), else from its sample triangle (`points` the
/// sample coordinates). `f64::INFINITY` for a degenerate triangle.
pub fn vertex_ratio(
    medial: &MedialGraph,
    v: usize,
    circle: Option<&Apollonius>,
    points: &[Point],
) -> f64 {
    let (tri, radius) = match circle {
        Some(c) => (c.tangent_points, c.radius),
        None => {
            let Some(mv) = medial.vertices.get(v) else {
                return f64::INFINITY;
            };
            let p = mv
                .samples
                .map(|s| points.get(s as usize).copied().unwrap_or([0.0; 2]));
            let Some(cc) = circumcenter(p[0], p[1], p[2]) else {
                return f64::INFINITY;
            };
            (p, dist(cc, p[0]))
        }
    };
    let l = dist(tri[0], tri[1])
        .min(dist(tri[1], tri[2]))
        .min(dist(tri[2], tri[0]));
    if l > 0.0 {
        radius / l
    } else {
        f64::INFINITY
    }
}

/// The smallest gap between any two circles of `domain` (holes and the bounding circle).
pub fn min_gap(domain: &Domain) -> f64 {
    nearest_gaps(domain)
        .into_iter()
        .fold(f64::INFINITY, f64::min)
}

/// The result of [`refine`].
#[derive(Debug, Clone)]
pub struct Refined {
    /// The domain with the inserted holes appended (hole ids `h..h + m` are the inserted
    /// holes, in insertion order).
    pub domain: Domain,
    /// The inserted holes, in insertion order.
    pub inserted: Vec<Circle>,
    /// Sampling, triangulation and medial graph of the final domain.
    pub sampled: SampledDomain,
    /// Exact Apollonius circle per medial vertex of the final graph.
    pub circles: Vec<Option<Apollonius>>,
    /// The minimum gap of the domain before each round and after the last (non-decreasing:
    /// paper Lemma 2).
    pub min_gaps: Vec<f64>,
}

/// Macro Delaunay refinement of `domain` (see the module documentation): `ratio` the poorness
/// threshold (`None`: no refinement), `max_inserted` the most holes that may be inserted.
pub fn refine(
    domain: &Domain,
    ratio: Option<f64>,
    max_inserted: usize,
    sampling: &SamplingOptions,
) -> Result<Refined, MeshError> {
    refine_seeded(domain, ratio, max_inserted, sampling, &[])
}

/// [`refine`] starting with the holes `seed` already inserted (fluid holes appended after the
/// domain's, ids from `domain.hole_count()` on, filled with templates as refinement's own):
/// exact mode seeds one opposite a lone off-centre hole ([`crate::mesher`]), whose medial
/// loop has no vertex to refine. The seeds must keep the domain valid.
pub fn refine_seeded(
    domain: &Domain,
    ratio: Option<f64>,
    max_inserted: usize,
    sampling: &SamplingOptions,
    seed: &[Circle],
) -> Result<Refined, MeshError> {
    if let Some(r) = ratio {
        crate::ranges::check_refine_ratio(r)?;
    }
    let mut current = domain.clone();
    let mut inserted: Vec<Circle> = seed.to_vec();
    if !seed.is_empty() {
        current = current
            .with_holes_added(seed)
            .map_err(|e| MeshError::Internal(format!("a seeded hole broke the domain: {e}")))?;
    }
    let mut min_gaps = Vec::new();
    // Candidate centres found unusable (their insertion would break Lemma 2): not retried.
    // Kept as a set of `==`-classes (`-0.0` as `0.0`; a NaN never equals anything, so it is
    // never stored): the same answers as `Vec::contains`, in O(1) (issue 8).
    let mut refused: HashSet<[u64; 2]> = HashSet::new();
    let key = |p: Point| -> Option<[u64; 2]> {
        (!p[0].is_nan() && !p[1].is_nan()).then(|| [(p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()])
    };
    // The sampling and vertex circles of the previous round. Inserted holes are appended, so
    // a vertex with the same circles and position has the same solve (not redone), and when
    // no other circle is resampled the new samples are inserted into the previous
    // triangulation (the same triangles, renumbered).
    let mut previous: Option<(SampledDomain, Vec<Option<Apollonius>>)> = None;
    loop {
        // The earlier round's arcs are moved into the new graph (only its vertices are read
        // below, to match the vertex circles).
        let sampled =
            sample_and_triangulate_taking(&current, sampling, previous.as_mut().map(|p| &mut p.0))?;
        let circles = match previous.take() {
            Some((before, circles)) => {
                vertex_circles_taking(&current, &sampled.medial, Some((&before.medial, circles)))
            }
            None => vertex_circles_taking(&current, &sampled.medial, None),
        };
        // `min_gap(&current)` without a second nearest-gap search: the sampling recorded
        // every circle's nearest gap, in slot order ([`crate::sampling::CircleSamples::gap`]).
        let g = sampled
            .samples
            .circles
            .iter()
            .map(|c| c.gap)
            .fold(f64::INFINITY, f64::min);
        min_gaps.push(g);
        let Some(limit) = ratio else {
            return Ok(Refined {
                domain: current,
                inserted,
                sampled,
                circles,
                min_gaps,
            });
        };
        // The candidate hole of a poor vertex: the centre and radius of its empty circle.
        let candidate = |v: usize| match &circles[v] {
            Some(c) => (c.center, c.radius),
            None => {
                let mv = &sampled.medial.vertices[v];
                let p = sampled.samples.points[mv.samples[0] as usize];
                (mv.position, dist(mv.position, p))
            }
        };
        let mut poor: Vec<(f64, usize, (Point, f64))> = (0..sampled.medial.vertices.len())
            .map(|v| {
                (
                    vertex_ratio(
                        &sampled.medial,
                        v,
                        circles[v].as_ref(),
                        &sampled.samples.points,
                    ),
                    v,
                )
            })
            .filter(|&(q, _)| q > limit)
            .map(|(q, v)| (q, v, candidate(v)))
            .collect();
        // Poorest first; equal ratios (symmetric layouts have many) by the candidate's centre
        // and radius, not by the vertex number: the holes inserted, and their order, are then
        // a function of the geometry, whatever numbering the triangulation gave the medial
        // vertices (a resampled triangulation numbered as an extension of the earlier one
        // inserts the same holes as one triangulated afresh).
        poor.sort_by(|a, b| {
            let (ca, cb) = (a.2, b.2);
            b.0.total_cmp(&a.0)
                .then(ca.0[0].total_cmp(&cb.0[0]))
                .then(ca.0[1].total_cmp(&cb.0[1]))
                .then(ca.1.total_cmp(&cb.1))
                .then(a.1.cmp(&b.1))
        });
        let mut batch: Vec<Circle> = Vec::new();
        // The holes of this round, indexed: a candidate is checked against its neighbours,
        // not against every hole (O(log n) per candidate instead of O(n)).
        let index = current.hole_index();
        for &(_, _, (center, rho)) in &poor {
            if key(center).is_some_and(|k| refused.contains(&k)) {
                continue;
            }
            let hole = Circle {
                center,
                radius: 0.5 * rho,
            };
            let b = current.bounding();
            // Too small for the coordinates (Domain::MIN_RADIUS_ULPS): not inserted.
            let ok = hole.radius >= Domain::min_radius_for(&b)
                && hole.radius.is_finite()
                && b.radius - dist(b.center, center) - hole.radius >= g
                && !index.any_closer(&hole, g);
            if !ok {
                if let Some(k) = key(center) {
                    refused.insert(k);
                }
                continue;
            }
            if batch.iter().all(|c| gap(c, &hole) >= g) {
                batch.push(hole);
            }
        }
        if batch.is_empty() {
            return Ok(Refined {
                domain: current,
                inserted,
                sampled,
                circles,
                min_gaps,
            });
        }
        if inserted.len() + batch.len() > max_inserted {
            return Err(MeshError::Refinement {
                inserted: inserted.len(),
                limit: max_inserted,
            });
        }
        inserted.extend_from_slice(&batch);
        // Only the inserted holes are checked again (and the gaps they change).
        current = current
            .with_holes_added(&batch)
            .map_err(|e| MeshError::Internal(format!("an inserted hole broke the domain: {e}")))?;
        previous = Some((sampled, circles));
    }
}
