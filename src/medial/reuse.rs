//! The sampling round after macro refinement inserted holes, reusing the round before
//! (issue 8).
//!
//! When no circle was resampled, the new samples extend the earlier ones and the triangulation
//! is the earlier one with the new samples inserted ([`Triangulation::extended`]). A triangle
//! whose id and three vertices (in order) are those of an earlier triangle ([`Kept`]) has the
//! same class ([`classify_one`] reads only the circles, indices and circle counts of its
//! samples, unchanged for every earlier sample), the same circumcentre, and the same
//! neighbours across each of its edges (a directed edge lies in one triangle only). So only
//! the triangles the insertion changed are classified and checked again, and a medial arc
//! whose triangles are all kept is the earlier arc, renumbered: vertices are interior
//! triangles in id order, and kept triangles keep their ids, so the earlier vertex order (and
//! with it every kept arc's orientation and place in the walk order) is kept. Each function
//! here equals the full computation of [`crate::medial`] and
//! [`crate::sampling::check_invariants`] (tested against them in `tests/perf_front.rs`); the
//! numbering of the extended triangulation only decides how much is reused.

use super::{circumcenter, classify_one, MedialArc, MedialGraph, MedialVertex};
use super::{TriangleKind, Walk};
use crate::geometry::{Changes, Triangulation};
use crate::sampling::{SampledDomain, Samples, Violation};
use rayon::prelude::*;
use std::collections::HashSet;

/// The triangles of `after` that are those of `before` (same id, same vertices in the same
/// order), as a bit set, and the others in increasing id order; with what is read of `before`
/// afterwards (the earlier triangle and neighbours of each changed earlier slot, whether it
/// had duplicates), so that `before` itself may be gone.
#[derive(Debug, Clone, PartialEq)]
pub struct Kept {
    bits: Vec<u64>,
    changed: Vec<u32>,
    /// Per changed slot below `before.len()`, in order: its triangle and neighbours there.
    before: Vec<([u32; 3], [Option<u32>; 3])>,
    before_duplicates: bool,
}

impl Kept {
    /// Compare the two triangulations triangle by triangle.
    pub fn new(before: &Triangulation, after: &Triangulation) -> Kept {
        let n = after.len();
        let mut bits = vec![0u64; n.div_ceil(64)];
        let mut changed = Vec::new();
        for t in 0..n {
            if t < before.len() && before.triangle(t) == after.triangle(t) {
                bits[t / 64] |= 1 << (t % 64);
            } else {
                changed.push(t as u32);
            }
        }
        let old = changed
            .iter()
            .take_while(|&&t| (t as usize) < before.len())
            .map(|&t| (before.triangle(t as usize), before.neighbors(t as usize)))
            .collect();
        Kept {
            bits,
            changed,
            before: old,
            before_duplicates: !before.duplicates().is_empty(),
        }
    }
    /// [`Self::new`] of the triangulation [`Triangulation::extended_taking`] took and `after`,
    /// its result, from the `changes` it gave (the same value, without the earlier
    /// triangulation: tested in `tests/geometry_sparse_extend.rs`).
    pub fn from_changes(changes: &Changes, after: &Triangulation) -> Kept {
        let n = after.len();
        let mut bits = vec![u64::MAX; n.div_ceil(64)];
        if !n.is_multiple_of(64) {
            *bits.last_mut().expect("n > 0") = (1 << (n % 64)) - 1;
        }
        for &t in changes.changed() {
            bits[t as usize / 64] &= !(1 << (t % 64));
        }
        let old = changes
            .changed()
            .iter()
            .take_while(|&&t| (t as usize) < changes.before_len());
        Kept {
            bits,
            changed: changes.changed().to_vec(),
            before: (0..old.count()).map(|i| changes.before(i)).collect(),
            before_duplicates: changes.before_had_duplicates(),
        }
    }
    /// True when triangle `t` of the later triangulation is kept.
    pub fn contains(&self, t: usize) -> bool {
        self.bits
            .get(t / 64)
            .is_some_and(|w| w >> (t % 64) & 1 == 1)
    }
    /// The triangles that are not kept, in increasing order.
    pub fn changed(&self) -> &[u32] {
        &self.changed
    }
}

/// True when every circle of `before` is sampled in `after` exactly as in `before` (same
/// circle, first sample and count, slot by slot): then every earlier sample has the same
/// circle, index on it and successor. The caller guarantees the points themselves (the
/// triangulation was extended from `before`'s, which compares them bit for bit).
pub fn same_earlier_circles(before: &Samples, after: &Samples) -> bool {
    before.circles.len() <= after.circles.len()
        && before.len() <= after.len()
        && before
            .circles
            .iter()
            .zip(&after.circles)
            .all(|(a, b)| a.circle == b.circle && a.first == b.first && a.count == b.count)
}

/// [`crate::medial::classify`] of `tri`: kept triangles take their class in `before`. In
/// parallel, collected in triangle order (issue 8: 10 ms on one CPU at 1e5 bubbles).
pub fn classify_after(
    samples: &Samples,
    tri: &Triangulation,
    before: &[TriangleKind],
    kept: &Kept,
) -> Vec<TriangleKind> {
    (0..tri.len())
        .into_par_iter()
        .with_min_len(crate::tasks::TRIANGLES)
        .map(|t| match before.get(t) {
            Some(&k) if kept.contains(t) => k,
            _ => classify_one(samples, tri.triangle(t)),
        })
        .collect()
}

/// [`crate::sampling::classify_and_check`] of `tri`, reusing the classes `before_kinds` of
/// the earlier triangulation of `before_samples` samples where `kept` says the triangles were
/// kept ([`classify_after`]; the full check only when [`invariants_hold_after_samples`]
/// cannot decide): the same classes and violations.
pub fn classify_and_check_after(
    samples: &Samples,
    tri: &Triangulation,
    before_kinds: &[TriangleKind],
    before_samples: usize,
    kept: &Kept,
) -> (Vec<TriangleKind>, Vec<Violation>) {
    let kinds = classify_after(samples, tri, before_kinds, kept);
    let hard = if invariants_hold_after_samples(samples, tri, &kinds, before_samples, kept) {
        Vec::new()
    } else {
        crate::sampling::check_invariants(samples, tri, &kinds)
    };
    (kinds, hard)
}

/// True when [`crate::sampling::check_invariants`] of `tri` (classified by `kinds`) finds
/// nothing, decided from the changed triangles; `false` when it may find something (the
/// caller then runs it). `before` is a result of the sampling (its triangulation met every
/// hard invariant) and `tri` extends its triangulation; what is needed of that triangulation
/// is in `kept` (`before.triangulation` is not read: it may have been taken).
///
/// Kept triangles have their earlier class and circles, so the per-triangle conditions need
/// checking only on changed ones. A boundary edge lies in at most two triangles; an earlier
/// one is still present when one of the earlier triangles holding it is kept, or when a changed
/// triangle holds it (a kept triangle holding it is one of the earlier two, by its id). New
/// samples lie in changed triangles only.
pub fn invariants_hold_after(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    before: &SampledDomain,
    kept: &Kept,
) -> bool {
    invariants_hold_after_samples(samples, tri, kinds, before.samples.len(), kept)
}

/// [`invariants_hold_after`] for an earlier sampling of `before_samples` samples (all that
/// is read of it besides `kept`).
pub fn invariants_hold_after_samples(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    before_samples: usize,
    kept: &Kept,
) -> bool {
    if !tri.duplicates().is_empty() || kept.before_duplicates {
        return false;
    }
    // Boundary edges (by their first sample) held by changed triangles.
    let mut held: HashSet<u32> = HashSet::new();
    let from = |a: u32, b: u32| if samples.next(a) == b { a } else { b };
    for &t in kept.changed() {
        let t = t as usize;
        let v = tri.triangle(t);
        match kinds.get(t) {
            Some(TriangleKind::Hole(_) | TriangleKind::Boundary { .. }) => {}
            Some(TriangleKind::Interior) => {
                let c = v.map(|s| samples.circle_of[s as usize]);
                if c[0] == c[1] || c[0] == c[2] || c[1] == c[2] {
                    return false;
                }
            }
            _ => return false,
        }
        for k in 0..3 {
            let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            if samples.is_boundary_edge(a, b) {
                held.insert(from(a, b));
            }
        }
    }
    let n0 = before_samples as u32;
    // Earlier boundary edges of earlier triangles that were replaced.
    for &(v, nb) in &kept.before {
        for k in 0..3 {
            let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            if samples.is_boundary_edge(a, b)
                && !nb[k].is_some_and(|m| kept.contains(m as usize))
                && !held.contains(&from(a, b))
            {
                return false;
            }
        }
    }
    (n0..samples.len() as u32).all(|s| held.contains(&s))
}

/// [`crate::medial::medial_graph`] of `tri` (classified by `kinds`), reusing the medial graph
/// of `before` (see the module documentation). `None` when the walk meets anything the full
/// construction would report as an error (the caller then runs it, for its error).
pub fn medial_graph_after(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    before: &SampledDomain,
    kept: &Kept,
) -> Option<MedialGraph> {
    medial_graph_after_graph(samples, tri, kinds, &before.medial, kept)
}

/// [`medial_graph_after`] from the earlier medial graph `old` itself (the periodic tiling's
/// refinement rounds keep theirs apart from a [`SampledDomain`]).
pub fn medial_graph_after_graph(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    old: &MedialGraph,
    kept: &Kept,
) -> Option<MedialGraph> {
    reusing(
        samples,
        tri,
        kinds,
        &old.vertices,
        Arcs::Cloned(&old.arcs),
        kept,
    )
}

/// [`medial_graph_after`] with the earlier graph's `vertices` and `arcs` given apart, moving
/// the kept arcs out of `arcs` (left empty in their place) instead of cloning them: for a
/// caller that drops the earlier arcs anyway (macro refinement; issue 8: cloning was four
/// allocations and copies per arc). The same graph.
pub fn medial_graph_taking(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    vertices: &[MedialVertex],
    arcs: &mut [MedialArc],
    kept: &Kept,
) -> Option<MedialGraph> {
    reusing(samples, tri, kinds, vertices, Arcs::Taken(arcs), kept)
}

/// Where the kept arcs come from.
enum Arcs<'a> {
    Cloned(&'a [MedialArc]),
    Taken(&'a mut [MedialArc]),
}

impl Arcs<'_> {
    fn all(&self) -> &[MedialArc] {
        match self {
            Arcs::Cloned(a) => a,
            Arcs::Taken(a) => a,
        }
    }
    fn get(&mut self, e: usize) -> MedialArc {
        match self {
            Arcs::Cloned(a) => a[e].clone(),
            Arcs::Taken(a) => std::mem::take(&mut a[e]),
        }
    }
}

fn reusing(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    old_vertices: &[MedialVertex],
    mut old_arcs: Arcs,
    kept: &Kept,
) -> Option<MedialGraph> {
    if kinds.len() != tri.len() || samples.len() != tri.points().len() {
        return None;
    }
    // Vertices in triangle order: the earlier vertices of kept triangles merged with the
    // interior triangles among the changed ones (both sorted by triangle id).
    let mut g = MedialGraph::default();
    let mut new_of_old = vec![u32::MAX; old_vertices.len()];
    let mut fresh = kept
        .changed()
        .iter()
        .copied()
        .filter(|&t| kinds[t as usize] == TriangleKind::Interior)
        .peekable();
    let mut earlier = old_vertices
        .iter()
        .enumerate()
        .filter(|(_, v)| kept.contains(v.triangle as usize))
        .peekable();
    loop {
        let next_fresh = fresh.peek().copied();
        let next_kept = earlier.peek().map(|(_, v)| v.triangle);
        match (next_fresh, next_kept) {
            (None, None) => break,
            (Some(t), k) if k.is_none_or(|k| t < k) => {
                fresh.next();
                let v = tri.triangle(t as usize);
                let p = v.map(|s| samples.points[s as usize]);
                g.vertices.push(MedialVertex {
                    triangle: t,
                    position: circumcenter(p[0], p[1], p[2])?,
                    samples: v,
                    circles: v.map(|s| samples.circle_of[s as usize]),
                });
            }
            _ => {
                let (i, v) = earlier.next()?;
                if kinds[v.triangle as usize] != TriangleKind::Interior {
                    return None;
                }
                new_of_old[i] = g.vertices.len() as u32;
                g.vertices.push(v.clone());
            }
        }
    }
    // Earlier arcs whose triangles are all kept, by their new start (vertex, slot): which
    // ones, in parallel (reading every arc's triangles: 15 ms on one CPU at 1e5 bubbles,
    // issue 8), then put in place in arc order.
    let starts: Vec<Option<(u32, u8)>> = old_arcs
        .all()
        .par_iter()
        .with_min_len(crate::tasks::ARCS)
        .map(|arc| {
            let ends = arc.ends.map(|v| new_of_old[v as usize]);
            let kept = !ends.contains(&u32::MAX)
                && arc.triangles.iter().all(|&t| kept.contains(t as usize));
            kept.then_some((ends[0], arc.end_slots[0]))
        })
        .collect();
    let mut start_at = vec![[u32::MAX; 3]; g.vertices.len()];
    for (e, start) in starts.into_iter().enumerate() {
        if let Some((v, k)) = start {
            start_at[v as usize][k as usize] = e as u32;
        }
    }
    let vertex_of = |t: usize| super::vertex_of(&g.vertices, kinds, t);
    let mut walk = Walk::default();
    g.arcs = super::arcs_in_walk_order(
        g.vertices.len(),
        |v0, k0| match start_at[v0][k0] {
            u32::MAX => walk
                .arc(samples, tri, kinds, &g.vertices, vertex_of, v0, k0)
                .map_err(|_| ()),
            e => {
                let mut arc = old_arcs.get(e as usize);
                arc.ends = arc.ends.map(|v| new_of_old[v as usize]);
                Ok(arc)
            }
        },
        |_, _| (),
    )
    .ok()?;
    Some(g)
}
