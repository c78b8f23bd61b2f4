//! Exact mode on the full front end: co-circular groups, collapsed arcs and inserted holes
//! (issue #4's degeneracy handling with issue #5's geometry).
//!
//! The combinatorics are those of [`crate::blocking::collapsed_blocking_with`]: macro Delaunay
//! refinement, co-circular groups, collapse of zero-length and short arcs and Blocking2D on the
//! contracted medial graph. The vertex of a cluster of `n - 2` collapsed medial vertices has
//! degree `n`, one spoke per circle around it, so `2n` blocks meet there. Its exact geometry:
//! - a single medial vertex: its Apollonius circle (as without collapse);
//! - a cluster inside one co-circular group ([`crate::cocircular`]): the group's circle,
//!   exact (every member's Apollonius circle is the same circle, `same_circle`), correctly
//!   rounded;
//! - any other cluster (short arcs collapsed, "zipping"): the centre is the mean of the
//!   members' Apollonius centres and the radius the smallest distance from it to the
//!   cluster's circles. The arcs were short (below `collapse_fraction` of the local radius), so
//!   the centre moves by at most that fraction off the bisectors of its arcs; each arc fades
//!   that offset out over its whole parameter range (towards the other end's offset, zero on
//!   the bisector), leaving the centre along the bisector's tangent (`ArcGeometry::at`;
//!   before, it jumped onto the bisector after its end node, and the corner cell there
//!   flattened as the cells got finer).
//!
//! In every case the tangent point on a circle is the radial projection of the centre, so every
//! spoke at a collapsed vertex is exactly normal to its wall. Inserted holes are handled by
//! [`super::inserted`].

use super::{
    assemble_cached, exact_vertices_with, internal, ExactMesh, ExactVertex, PieceCache, Skeleton,
    Wall,
};
use crate::blocking::CollapsedBlocking;
use crate::domain::{CircleId, Domain};
use crate::geometry::Point;
use crate::mesher::{MeshError, Options};
use rayon::prelude::*;

/// The exact vertices of the contracted graph of `cb` (see the module docs). A cluster's
/// circles are those of its kept arcs, each of which must appear on exactly two of them (one
/// spoke per circle); otherwise [`MeshError::Internal`] (the caller falls back).
pub fn cluster_vertices(cb: &CollapsedBlocking) -> Result<Vec<ExactVertex>, MeshError> {
    let single = exact_vertices_with(
        &cb.refined.domain,
        &cb.refined.sampled.medial,
        &cb.refined.circles,
    )?;
    cluster_vertices_on(cb, &single)
}

/// [`cluster_vertices`] with the exact vertices of the sampled (uncollapsed) medial graph
/// given ([`super::exact_vertices`] of `cb.refined`; they do not depend on the collapse, so exact
/// mode computes them once per sampling).
pub fn cluster_vertices_on(
    cb: &CollapsedBlocking,
    single: &[ExactVertex],
) -> Result<Vec<ExactVertex>, MeshError> {
    let domain = &cb.refined.domain;
    let medial = &cb.refined.sampled.medial;
    let contracted = &cb.contracted;
    if single.len() != medial.vertices.len() {
        return Err(internal(
            "one exact vertex per sampled medial vertex expected".into(),
        ));
    }
    let nclusters = contracted.graph.vertices.len();
    // Members of each cluster, in vertex order (offsets into one array, not a vector per
    // cluster: issue 8).
    let mut start = vec![0usize; nclusters + 1];
    for (v, &c) in contracted.cluster_of.iter().enumerate() {
        match start.get_mut(c as usize + 1) {
            Some(n) => *n += 1,
            None => return Err(internal(format!("vertex {v} in an unknown cluster {c}"))),
        }
    }
    for k in 0..nclusters {
        start[k + 1] += start[k];
    }
    let mut members = vec![0usize; contracted.cluster_of.len()];
    let mut next = start.clone();
    for (v, &c) in contracted.cluster_of.iter().enumerate() {
        members[next[c as usize]] = v;
        next[c as usize] += 1;
    }
    drop(next);
    let members_of = |k: usize| &members[start[k]..start[k + 1]];
    // Circles of each collapsed cluster (two or more members) from its kept arcs, with how
    // many arcs touch each; a single vertex keeps its own circles.
    let mut list_of = vec![usize::MAX; nclusters];
    let mut around: Vec<Vec<(CircleId, usize)>> = Vec::new();
    for (k, slot) in list_of.iter_mut().enumerate() {
        if members_of(k).len() > 1 {
            *slot = around.len();
            around.push(Vec::new());
        }
    }
    for arc in &contracted.graph.arcs {
        for &v in &arc.ends {
            let i = *list_of
                .get(v as usize)
                .ok_or_else(|| internal("a kept arc ends at an unknown cluster".into()))?;
            let Some(list) = around.get_mut(i) else {
                continue;
            };
            for &c in &arc.circles {
                match list.iter_mut().find(|x| x.0 == c) {
                    Some(x) => x.1 += 1,
                    None => list.push((c, 1)),
                }
            }
        }
    }
    let group_of = crate::cocircular::group_of(medial, &cb.groups);
    // One vertex per cluster, in parallel, collected in cluster order (the first error in
    // cluster order is returned, whatever the thread count).
    let out: Vec<Result<ExactVertex, MeshError>> = (0..nclusters)
        .into_par_iter()
        .map(|k| {
            let ms = members_of(k);
            if ms.len() == 1 {
                return Ok(single[ms[0]].clone());
            }
            let around = around.get(list_of[k]).map_or(&[][..], |v| v.as_slice());
            if let Some(&(c, n)) = around.iter().find(|x| x.1 != 2) {
                return Err(internal(format!(
                    "collapsed vertex {k}: circle {c} has {n} spokes there"
                )));
            }
            let circles: Vec<CircleId> = around.iter().map(|x| x.0).collect();
            let group = ms.first().and_then(|&v| group_of.get(v).copied().flatten());
            let one_group = group.is_some() && ms.iter().all(|&v| group_of.get(v) == Some(&group));
            let center: Point = match group {
                Some(g) if one_group => cb.groups[g].center,
                _ => {
                    let n = ms.len() as f64;
                    let sx: f64 = ms.iter().map(|&v| single[v].center[0]).sum();
                    let sy: f64 = ms.iter().map(|&v| single[v].center[1]).sum();
                    [sx / n, sy / n]
                }
            };
            merged(domain, center, circles, k)
        })
        .collect();
    out.into_iter().collect()
}

/// The vertex at `center` touching `circles` by radial projection; radius the smallest gap.
fn merged(
    domain: &Domain,
    center: Point,
    circles: Vec<CircleId>,
    k: usize,
) -> Result<ExactVertex, MeshError> {
    let mut tangent = Vec::with_capacity(circles.len());
    let mut radius = f64::INFINITY;
    for &c in &circles {
        let w = Wall::of(domain, c);
        let d = (center[0] - w.c[0]).hypot(center[1] - w.c[1]);
        let t = w.project(center);
        if !(d > 0.0 && t[0].is_finite() && t[1].is_finite()) {
            return Err(internal(format!(
                "collapsed vertex {k} sits on the centre of circle {c}"
            )));
        }
        radius = radius.min(if c < 0 { w.r - d } else { d - w.r });
        tangent.push(t);
    }
    if !(radius.is_finite() && radius > 0.0) {
        return Err(internal(format!(
            "collapsed vertex {k} is not in the fluid (radius {radius})"
        )));
    }
    Ok(ExactVertex {
        center,
        radius,
        circles,
        tangent,
    })
}

/// Exact mode on the full front end (see the module docs): the skeleton of `cb` with its
/// cluster vertices and inserted holes.
pub fn build_collapsed(cb: &CollapsedBlocking, options: &Options) -> Result<ExactMesh, MeshError> {
    let single = exact_vertices_with(
        &cb.refined.domain,
        &cb.refined.sampled.medial,
        &cb.refined.circles,
    )?;
    build_collapsed_on(cb, options, &single)
}

/// [`build_collapsed`] with the exact vertices of the sampled medial graph given (see
/// [`cluster_vertices_on`]): the same mesh.
pub fn build_collapsed_on(
    cb: &CollapsedBlocking,
    options: &Options,
    single: &[ExactVertex],
) -> Result<ExactMesh, MeshError> {
    build_collapsed_cached(cb, options, single, &mut PieceCache::default())
}

/// [`build_collapsed_on`] reusing the per-piece work of earlier builds held in `cache` and
/// leaving this build's there ([`super::assemble_cached`]): the same mesh.
pub fn build_collapsed_cached(
    cb: &CollapsedBlocking,
    options: &Options,
    single: &[ExactVertex],
    cache: &mut PieceCache,
) -> Result<ExactMesh, MeshError> {
    let vertices = cluster_vertices_on(cb, single)?;
    let domain = &cb.refined.domain;
    let h = domain.hole_count() - cb.refined.inserted.len();
    let fluid: Vec<CircleId> = (h..domain.hole_count()).map(|i| i as CircleId).collect();
    assemble_cached(
        Skeleton {
            domain,
            arcs: &cb.contracted.graph.arcs,
            vertices,
            sampled: &cb.layout,
            fluid,
        },
        options,
        cache,
    )
}
