//! [`super::medial_graph`] on several threads, equal to [`super::medial_graph_serial`] (issue 8:
//! the front end ran on one core while the other idled).
//!
//! The serial walk visits the vertex slots `(v, k)` in order and walks the arc from every slot
//! not yet reached; an arc is thus walked from the smaller of its two end slots. Here the vertices
//! are cut into contiguous ranges, each walked apart with its own reached slots: an arc whose far
//! end lies in a later range is kept (that range walks it too, from the larger end, and drops it),
//! one whose far end lies in an earlier range is dropped. The kept arcs, range after range, are
//! the serial list when every slot ends exactly one kept arc and every kept arc starts at its
//! smaller end: by induction over the slots, a slot starts a kept arc exactly when no smaller
//! slot's arc reached it, which is when the serial walk starts one there. That is checked; on
//! any failure (a walk error, a check failing) the caller runs the serial construction, whose
//! result and errors are then the answer.

use super::{interior_vertex, MedialArc, MedialGraph, MedialVertex, TriangleKind, Walk};
use crate::geometry::Triangulation;
use crate::sampling::Samples;
use rayon::prelude::*;

/// Fewest triangles for which the split is worth the threads (1e3 particles, 65 k triangles,
/// take 2-4 ms serially, less than a hand-off to a busy second core costs; 1e4 take 50-60).
const MIN_TRIANGLES: usize = 1 << 18;

/// The medial graph by ranges of vertices (see the module documentation), `None` when it is
/// not attempted (one thread, a small triangulation) or does not check out.
pub(super) fn medial_graph_split(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
) -> Option<MedialGraph> {
    let threads = rayon::current_num_threads();
    if threads < 2 || tri.len() < MIN_TRIANGLES {
        return None;
    }
    split_with(samples, tri, kinds, 2 * threads)
}

/// `medial_graph_split` (the multi-threaded [`super::medial_graph`]) with `parts` ranges of triangles for the vertices and `parts` strips
/// of vertices for the arcs, whatever the size: the result does not depend on `parts` (tests
/// vary it).
pub fn split_with(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    parts: usize,
) -> Option<MedialGraph> {
    let n = tri.len();
    if kinds.len() != n
        || samples.len() != tri.points().len()
        || samples.circle_of.len() != samples.len()
    {
        return None;
    }
    let parts = parts.max(1);
    let step = n.div_ceil(parts).max(1);
    // Vertices: interior triangles in order, range after range.
    let chunks: Vec<Option<Vec<MedialVertex>>> = (0..n.div_ceil(step))
        .into_par_iter()
        .map(|c| {
            (c * step..((c + 1) * step).min(n))
                .filter(|&t| kinds[t] == TriangleKind::Interior)
                .map(|t| interior_vertex(samples, tri, t))
                .collect()
        })
        .collect();
    let mut g = MedialGraph::default();
    for c in chunks {
        g.vertices.extend(c?);
    }
    let nv = g.vertices.len();
    let part = strips(&g.vertices, parts);
    let vertices = &g.vertices;
    let vertex_of = |t: usize| super::vertex_of(vertices, kinds, t);
    let ranges: Vec<Option<Vec<MedialArc>>> = (0..parts)
        .into_par_iter()
        .map(|c| {
            let mut reached = vec![[false; 3]; nv];
            let mut walk = Walk::default();
            let mut arcs = Vec::new();
            for v0 in (0..nv).filter(|&v| part[v] as usize == c) {
                for k0 in 0..3 {
                    if reached[v0][k0] {
                        continue;
                    }
                    reached[v0][k0] = true;
                    let arc = walk
                        .arc(samples, tri, kinds, vertices, vertex_of, v0, k0)
                        .ok()?;
                    let (v1, k1) = (arc.ends[1] as usize, arc.end_slots[1] as usize);
                    if v1 >= nv || k1 >= 3 {
                        return None;
                    }
                    if part[v1] as usize != c {
                        // Walked from both parts; kept by the one holding the smaller end.
                        if (v1, k1) > (v0, k0) {
                            arcs.push(arc);
                        }
                        continue;
                    }
                    if (v1, k1) <= (v0, k0) || reached[v1][k1] {
                        return None;
                    }
                    reached[v1][k1] = true;
                    arcs.push(arc);
                }
            }
            Some(arcs)
        })
        .collect();
    let mut all = Vec::with_capacity(3 * nv / 2);
    for r in ranges {
        all.extend(r?);
    }
    all.sort_unstable_by_key(|a| (a.ends[0], a.end_slots[0]));
    let mut ends = vec![[0u8; 3]; nv];
    for arc in &all {
        let [a, b] = [0, 1].map(|i| (arc.ends[i] as usize, arc.end_slots[i] as usize));
        if a >= b {
            return None;
        }
        ends[a.0][a.1] = ends[a.0][a.1].saturating_add(1);
        ends[b.0][b.1] = ends[b.0][b.1].saturating_add(1);
    }
    // Copied on this thread: the arcs outlive the front end, and memory of the workers' own
    // malloc arenas stays theirs (issue 8: kept there, the peak memory of a 1e4 mesh rose by
    // a tenth); the workers' copies are freed here for their later use.
    g.arcs = all.iter().map(MedialArc::clone).collect();
    drop(all);
    ends.iter().flatten().all(|&e| e == 1).then_some(g)
}

/// Part of each vertex: `parts` vertical strips of about equal counts, by the circumcentre's
/// `x` (arcs join nearby vertices, so few cross a strip; the vertex numbering follows the
/// triangles, which are not in spatial order). Any partition gives the same graph.
fn strips(vertices: &[MedialVertex], parts: usize) -> Vec<u16> {
    let parts = parts.clamp(1, u16::MAX as usize);
    let mut xs: Vec<f64> = vertices.iter().map(|v| v.position[0]).collect();
    if xs.is_empty() {
        return Vec::new();
    }
    xs.sort_unstable_by(f64::total_cmp);
    let cuts: Vec<f64> = (1..parts).map(|i| xs[i * xs.len() / parts]).collect();
    vertices
        .iter()
        .map(|v| cuts.partition_point(|c| c.total_cmp(&v.position[0]).is_le()) as u16)
        .collect()
}
