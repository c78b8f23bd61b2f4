//! Arc collapse ("zipping", paper section 4.2): contract zero-length and short medial arcs so
//! that no zero- or near-zero-area block reaches the output.
//!
//! Collapsing an arc merges its two medial vertices into one. Over a set of collapsed arcs
//! the medial vertices fall into *clusters* (trees of collapsed arcs); a cluster of `c`
//! vertices becomes one vertex of degree `n = c + 2` (each vertex has three arc ends, each
//! collapsed arc removes two), with `2n` blocks around it, and every collapsed arc removes its
//! two blocks: `blocks = 6(h - 1) - 2 x collapsed` for `h >= 2` holes.
//!
//! Geometry. Around a medial vertex, each circle it touches is reached by one spoke, shared by
//! the two blocks on that circle meeting there (their *corner*). The two blocks of a collapsed
//! arc join two corners on each of its circles into a *sector*; a sector's deleted walls form a
//! run of consecutive samples `S = [x_0, ..., x_L]` from the end of the kept block before it
//! (on that circle, in wall direction) to the start of the kept block after it. The sector's
//! spoke goes to the *pivot* sample `x_{L/2}`: the kept block before extends its wall to the
//! pivot and the one after starts there, so walls still tile every circle and the spoke is
//! shared by exactly two blocks. For a zero-length arc between two adjacent co-circular
//! triangles `L = 0` and nothing moves. The merged vertex sits at the mean of its members'
//! circumcentres; the arcs incident to it have their end points moved there.
//!
//! Selection ([`select`]): zero-length arcs ([`crate::cocircular::is_zero_length`]) always,
//! then the *forced* arcs of [`select_forced`] (arcs with a single-sample wall that sampling
//! could not remove) always, then arcs whose sampled length is below `fraction` times the smaller empty-circle radius of
//! its two ends, shortest (relative) first. An arc is skipped when its ends are already in one
//! cluster (collapsing a cycle would delete every block around a hole) or when another
//! remaining arc joins the same two clusters (it would become a loop). The blocking checks
//! the result and gives up short (non-zero) collapses that leave a block with non-positive
//! area ([`crate::blocking`]).

use crate::apollonius::Apollonius;
use crate::cocircular::{arc_length, group_of, is_zero_length, local_radius, CocircularGroup};
use crate::geometry::{Point, Triangulation};
use crate::medial::{MedialArc, MedialGraph, MedialVertex};
use crate::mesher::MeshError;

/// One arc chosen for collapse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The arc id in the medial graph.
    pub arc: u32,
    /// True for an arc that is always collapsed: a zero-length arc, or a *forced* one (an arc
    /// the sampling left with a single-sample wall, [`crate::sampling::thin_walls`]); false
    /// for a short one (given up when its collapse leaves a block without area).
    pub zero: bool,
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let up = parent[parent[x as usize] as usize];
        parent[x as usize] = up;
        x = up;
    }
    x
}

/// The arcs to collapse (see the module documentation), in acceptance order. `circles` are
/// the vertex circles ([`crate::cocircular::vertex_circles`]), `points` the sample
/// coordinates, `exclude` arcs never to collapse as short arcs (zero-length arcs are always
/// taken). Deterministic.
pub fn select(
    medial: &MedialGraph,
    tri: &Triangulation,
    circles: &[Option<Apollonius>],
    groups: &[CocircularGroup],
    points: &[Point],
    fraction: f64,
    exclude: &[bool],
) -> Vec<Candidate> {
    select_forced(medial, tri, circles, groups, points, fraction, exclude, &[])
}

/// [`select`], with the arcs flagged in `forced` (one flag per arc; missing flags are false)
/// collapsed like zero-length arcs: right after them, shortest sampled length first, ties by
/// arc id. Used for the arcs with a single-sample (zero-sweep) wall that resampling could not
/// remove ([`crate::sampling::thin_walls`]): collapsing such an arc moves no wall corner on the
/// thin side (`L = 0` there), and the blocks left all have walls of positive sweep.
#[allow(clippy::too_many_arguments)]
pub fn select_forced(
    medial: &MedialGraph,
    tri: &Triangulation,
    circles: &[Option<Apollonius>],
    groups: &[CocircularGroup],
    points: &[Point],
    fraction: f64,
    exclude: &[bool],
    forced: &[bool],
) -> Vec<Candidate> {
    Selection::new(medial, tri, circles, groups, points, fraction).select(exclude, forced)
}

/// The part of [`select_forced`] that depends on neither `exclude` nor `forced`, computed once
/// and kept for the local rebuilds ([`crate::blocking::CollapsedBlocking::recollapse`]): the
/// zero-length arcs, every arc's sampled length, and the short candidates (relative length
/// below the fraction) already sorted. Filtering a sorted list keeps it sorted, so
/// [`Selection::select`] is [`select_forced`] exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// Zero-length arcs, in arc order.
    zero: Vec<u32>,
    is_zero: Vec<bool>,
    /// Sampled length per arc.
    length: Vec<f64>,
    /// `(relative length, arc)` of the non-zero arcs below the fraction, sorted.
    short: Vec<(f64, u32)>,
    ends: Vec<[u32; 2]>,
    vertices: usize,
}

impl Selection {
    /// The per-arc data of [`select_forced`] (same arguments less `exclude` and `forced`).
    pub fn new(
        medial: &MedialGraph,
        tri: &Triangulation,
        circles: &[Option<Apollonius>],
        groups: &[CocircularGroup],
        points: &[Point],
        fraction: f64,
    ) -> Selection {
        let group = group_of(medial, groups);
        let m = medial.arcs.len();
        let (mut zero, mut is_zero) = (Vec::new(), vec![false; m]);
        let mut length = vec![0.0; m];
        let mut short: Vec<(f64, u32)> = Vec::new();
        for (e, arc) in medial.arcs.iter().enumerate() {
            if is_zero_length(arc, medial, tri, &group) {
                zero.push(e as u32);
                is_zero[e] = true;
                continue;
            }
            length[e] = arc_length(arc);
            if fraction > 0.0 {
                let r = local_radius(medial, circles, points, arc.ends[0]).min(local_radius(
                    medial,
                    circles,
                    points,
                    arc.ends[1],
                ));
                let rel = length[e] / r;
                if rel.is_finite() && rel < fraction {
                    short.push((rel, e as u32));
                }
            }
        }
        short.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        Selection {
            zero,
            is_zero,
            length,
            short,
            ends: medial.arcs.iter().map(|a| a.ends).collect(),
            vertices: medial.vertices.len(),
        }
    }

    /// [`select_forced`] with these per-arc data.
    pub fn select(&self, exclude: &[bool], forced: &[bool]) -> Vec<Candidate> {
        let flag = |f: &[bool], e: usize| f.get(e).copied().unwrap_or(false);
        let mut must: Vec<(f64, u32)> = (0..self.length.len())
            .filter(|&e| !self.is_zero[e] && flag(forced, e))
            .map(|e| (self.length[e], e as u32))
            .collect();
        must.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let short = self.short.iter().filter(|&&(_, e)| {
            let e = e as usize;
            !flag(forced, e) && !flag(exclude, e)
        });
        let order = self
            .zero
            .iter()
            .map(|&e| (e, true))
            .chain(must.into_iter().map(|(_, e)| (e, true)))
            .chain(short.map(|&(_, e)| (e, false)));
        accept(order, &self.ends, self.vertices)
    }
}

/// The acceptance loop of [`select_forced`]: take the arcs of `order` (arc id, always-taken
/// flag) one by one, skipping an arc whose ends are already in one cluster (no cycles: the
/// taken arcs form a forest) or which has a *parallel* arc, another arc not taken joining the
/// same two clusters (contracting one of two parallel arcs would turn the other into a loop).
/// `ends[e]` are arc `e`'s end vertices; an arc with an end `>= n` is ignored.
///
/// Each cluster keeps the list of arcs incident to its vertices (merged smaller into larger on
/// every union), so the parallel check scans the smaller of the two clusters' lists instead of
/// every arc: O(m log m) list moves in all, where a scan of every arc per candidate was
/// O(candidates x arcs) (90% of a 100 000-bubble run). Same result as that scan (tested
/// against it on random multigraphs).
fn accept(order: impl Iterator<Item = (u32, bool)>, ends: &[[u32; 2]], n: usize) -> Vec<Candidate> {
    let valid = |e: usize| ends[e].iter().all(|&v| (v as usize) < n);
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut incident: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (e, &[a, b]) in ends.iter().enumerate() {
        if valid(e) {
            incident[a as usize].push(e as u32);
            if b != a {
                incident[b as usize].push(e as u32);
            }
        }
    }
    let mut taken = vec![false; ends.len()];
    let mut out = Vec::new();
    for (e, is_zero) in order {
        if e as usize >= ends.len() || !valid(e as usize) {
            continue;
        }
        let [a, b] = ends[e as usize];
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra == rb {
            continue;
        }
        let (small, large) = if incident[ra as usize].len() <= incident[rb as usize].len() {
            (ra, rb)
        } else {
            (rb, ra)
        };
        let parallel = (0..incident[small as usize].len()).any(|i| {
            let f = incident[small as usize][i];
            if f == e || taken[f as usize] {
                return false;
            }
            let [x, y] = ends[f as usize];
            let (rx, ry) = (find(&mut parent, x), find(&mut parent, y));
            (rx == small && ry == large) || (rx == large && ry == small)
        });
        if parallel {
            continue;
        }
        let (root, child) = (ra.min(rb), ra.max(rb));
        parent[child as usize] = root;
        let (mut kept, moved) = (
            std::mem::take(&mut incident[large as usize]),
            std::mem::take(&mut incident[small as usize]),
        );
        kept.extend(moved);
        incident[root as usize] = kept;
        taken[e as usize] = true;
        out.push(Candidate {
            arc: e,
            zero: is_zero,
        });
    }
    out
}

/// The medial graph with the given arcs contracted.
#[derive(Debug, Clone, PartialEq)]
pub struct Contracted {
    /// Vertices are clusters (numbered by their smallest original vertex), arcs the kept arcs
    /// in their original order with re-targeted ends, extended sample chains and moved
    /// polyline ends. A merged vertex keeps the triangle, samples and circles of its first
    /// member (only its position and arcs are meaningful).
    pub graph: MedialGraph,
    /// For each original vertex, its vertex in `graph`.
    pub cluster_of: Vec<u32>,
    /// For each arc of `graph`, its id in the original graph.
    pub kept: Vec<u32>,
    /// Number of original vertices in each vertex of `graph`.
    pub cluster_size: Vec<u32>,
}

fn internal(msg: &str) -> MeshError {
    MeshError::Internal(format!("arc collapse: {msg}"))
}

/// Contract the arcs marked in `collapse` (one flag per arc; they must form a forest, as
/// [`select`] guarantees; a cycle or a kept arc with both ends in one cluster is an
/// [`MeshError::Internal`]).
pub fn contract(medial: &MedialGraph, collapse: &[bool]) -> Result<Contracted, MeshError> {
    let n = medial.vertices.len();
    let m = medial.arcs.len();
    if collapse.len() != m {
        return Err(internal("one flag per arc expected"));
    }
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for (e, arc) in medial.arcs.iter().enumerate() {
        let [a, b] = arc.ends;
        if a as usize >= n || b as usize >= n || arc.c1.is_empty() || arc.c2.is_empty() {
            return Err(internal("malformed arc"));
        }
        if collapse[e] {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra == rb {
                return Err(internal("collapsed arcs form a cycle"));
            }
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut id_of_root = vec![u32::MAX; n];
    let mut cluster_of = vec![0u32; n];
    let mut members: Vec<Vec<u32>> = Vec::new();
    for (v, cluster) in cluster_of.iter_mut().enumerate() {
        let r = find(&mut parent, v as u32) as usize;
        if id_of_root[r] == u32::MAX {
            id_of_root[r] = members.len() as u32;
            members.push(Vec::new());
        }
        *cluster = id_of_root[r];
        members[id_of_root[r] as usize].push(v as u32);
    }
    let vertices: Vec<MedialVertex> = members
        .iter()
        .map(|ms| {
            let mut v = medial.vertices[ms[0] as usize].clone();
            if ms.len() > 1 {
                let k = ms.len() as f64;
                let sx: f64 = ms
                    .iter()
                    .map(|&i| medial.vertices[i as usize].position[0])
                    .sum();
                let sy: f64 = ms
                    .iter()
                    .map(|&i| medial.vertices[i as usize].position[1])
                    .sum();
                v.position = [sx / k, sy / k];
            }
            v
        })
        .collect();

    // Blocks: 2e on C1 (wall c1, from corner (v0, c1[0]) to (v1, c1.last)), 2e + 1 on C2
    // (wall c2 reversed, from (v1, c2.last) to (v0, c2[0])).
    let wall = |b: usize| -> Vec<u32> {
        let arc = &medial.arcs[b / 2];
        if b % 2 == 0 {
            arc.c1.clone()
        } else {
            arc.c2.iter().rev().copied().collect()
        }
    };
    let corners = |b: usize| -> [(u32, u32); 2] {
        let arc = &medial.arcs[b / 2];
        let [v0, v1] = arc.ends;
        let (c1f, c1l) = (arc.c1[0], arc.c1[arc.c1.len() - 1]);
        let (c2f, c2l) = (arc.c2[0], arc.c2[arc.c2.len() - 1]);
        if b % 2 == 0 {
            [(v0, c1f), (v1, c1l)]
        } else {
            [(v1, c2l), (v0, c2f)]
        }
    };
    // The block starting at each corner: sorted by corner, found by binary search (no
    // hashing of 2m keys, issue 8).
    let mut start_block: Vec<((u32, u32), usize)> =
        (0..2 * m).map(|b| (corners(b)[0], b)).collect();
    start_block.sort_unstable();
    if start_block.windows(2).any(|w| w[0].0 == w[1].0) {
        return Err(internal("two blocks start at one corner"));
    }
    let block_at = |corner: (u32, u32)| -> Option<usize> {
        let i = start_block.binary_search_by(|x| x.0.cmp(&corner)).ok()?;
        Some(start_block[i].1)
    };
    let mut ext_end: Vec<Vec<u32>> = vec![Vec::new(); 2 * m];
    let mut ext_start: Vec<Vec<u32>> = vec![Vec::new(); 2 * m];
    for p in 0..2 * m {
        if collapse[p / 2] {
            continue;
        }
        let mut corner = corners(p)[1];
        let mut run = vec![corner.1];
        let mut steps = 0;
        let q = loop {
            let b = block_at(corner).ok_or_else(|| internal("no block starts at a corner"))?;
            if !collapse[b / 2] {
                break b;
            }
            steps += 1;
            if steps > 2 * m {
                return Err(internal("a sector does not end"));
            }
            run.extend_from_slice(&wall(b)[1..]);
            corner = corners(b)[1];
        };
        if run.len() > 1 {
            let mid = (run.len() - 1) / 2;
            ext_end[p] = run[1..=mid].to_vec();
            ext_start[q] = run[mid..run.len() - 1].to_vec();
        }
    }

    let mut arcs = Vec::with_capacity(m);
    let mut kept = Vec::with_capacity(m);
    for (e, arc) in medial.arcs.iter().enumerate() {
        if collapse[e] {
            continue;
        }
        let [v0, v1] = arc.ends.map(|v| cluster_of[v as usize]);
        if v0 == v1 {
            return Err(internal("a kept arc became a loop"));
        }
        let build = |b: usize| -> Vec<u32> {
            let mut w = ext_start[b].clone();
            w.extend(wall(b));
            w.extend_from_slice(&ext_end[b]);
            w
        };
        let c1 = build(2 * e);
        let mut c2 = build(2 * e + 1);
        c2.reverse();
        let mut polyline = arc.polyline.clone();
        let last = polyline.len() - 1;
        if members[v0 as usize].len() > 1 {
            polyline[0] = vertices[v0 as usize].position;
        }
        if members[v1 as usize].len() > 1 {
            polyline[last] = vertices[v1 as usize].position;
        }
        arcs.push(MedialArc {
            ends: [v0, v1],
            end_slots: arc.end_slots,
            triangles: arc.triangles.clone(),
            polyline,
            circles: arc.circles,
            c1,
            c2,
        });
        kept.push(e as u32);
    }
    Ok(Contracted {
        graph: MedialGraph { vertices, arcs },
        cluster_of,
        kept,
        cluster_size: members.iter().map(|m| m.len() as u32).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The acceptance loop as first written: the parallel check scans every arc.
    fn accept_by_scan(order: &[(u32, bool)], ends: &[[u32; 2]], n: usize) -> Vec<Candidate> {
        let mut parent: Vec<u32> = (0..n as u32).collect();
        let mut taken = vec![false; ends.len()];
        let mut out = Vec::new();
        for &(e, is_zero) in order {
            let Some(&[a, b]) = ends.get(e as usize) else {
                continue;
            };
            if a as usize >= n || b as usize >= n {
                continue;
            }
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra == rb {
                continue;
            }
            let parallel = ends.iter().enumerate().any(|(f, &[x, y])| {
                if f == e as usize || taken[f] || x as usize >= n || y as usize >= n {
                    return false;
                }
                let (rx, ry) = (find(&mut parent, x), find(&mut parent, y));
                (rx == ra && ry == rb) || (rx == rb && ry == ra)
            });
            if parallel {
                continue;
            }
            parent[ra.max(rb) as usize] = ra.min(rb);
            taken[e as usize] = true;
            out.push(Candidate {
                arc: e,
                zero: is_zero,
            });
        }
        out
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]
        /// Random multigraphs (parallel arcs, loops, ends out of range, repeated and unknown
        /// arcs in the order): the indexed loop takes exactly the arcs the full scan takes.
        #[test]
        fn accept_equals_the_full_scan(
            n in 1usize..40,
            raw in proptest::collection::vec((0u32..45, 0u32..45), 0..120),
            order in proptest::collection::vec((0u32..130, any::<bool>()), 0..150),
        ) {
            let ends: Vec<[u32; 2]> = raw.iter().map(|&(a, b)| [a, b]).collect();
            let fast = accept(order.iter().copied(), &ends, n);
            prop_assert_eq!(fast, accept_by_scan(&order, &ends, n));
        }
    }

    /// Two parallel arcs between two vertices: only one collapse is refused, the first taken
    /// arc forbids neither (the other is parallel), and a triangle closes no cycle.
    #[test]
    fn parallel_arcs_and_cycles_are_refused() {
        let ends = [[0, 1], [0, 1], [1, 2], [2, 0]];
        let order = [(0, false), (1, false), (2, false), (3, false)];
        let got = accept(order.iter().copied(), &ends, 3);
        // Arc 0 has the parallel arc 1 (not taken): refused; so is 1 (parallel to 0). Arc 2
        // joins {1} and {2}; arc 3 then joins {0} to {1, 2}, but arcs 0 and 1 are parallel to
        // it there: refused.
        assert_eq!(
            got,
            vec![Candidate {
                arc: 2,
                zero: false
            }]
        );
    }
}
