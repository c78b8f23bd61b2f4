//! Exact circle geometry at medial vertices and co-circular hole groups (DESIGN sections 5
//! and 6, paper section 4.2).
//!
//! Every medial vertex is an interior Delaunay triangle whose three samples lie on three
//! different circles `i, j, k`. Its *exact* position is the Apollonius circle tangent to those
//! three circles (externally to holes, internally to the bounding circle), computed by
//! [`crate::apollonius`] in `Q(sqrt D)`. Of the (at most two) valid roots we take the one whose
//! tangent points turn counter-clockwise in the triangle's vertex order (the triangle's own
//! orientation) and, if both do, the one nearest the triangle's circumcentre
//! ([`vertex_circles`]). A vertex whose solve fails (no valid root with that orientation,
//! which only happens when the sampled combinatorics disagree with the true medial axis) has
//! `None` and is treated with its sampled circumcircle elsewhere.
//!
//! A *co-circular group* is a maximal set of medial vertices joined by medial arcs whose two
//! Apollonius circles are exactly the same circle ([`crate::apollonius::same_circle`]): `n >= 4`
//! circles tangent to one empty circle, which the sampled triangulation shows as `n - 2`
//! interior triangles joined by `n - 3` zero-length (or, after rounding, tiny) arcs. Groups are
//! reported with their circles (ids as in the input: holes `0..`, the bounding circle `-1`),
//! and the rounded centre and radius of the common circle ([`cocircular_groups`]).
//!
//! A medial arc is *degenerate* (its true length is zero, [`is_zero_length`]) when its ends are
//! in one group, when all its sampled points coincide, or when it crosses a single Delaunay
//! edge whose four points are exactly co-circular (the engine's sample-level tie,
//! [`crate::geometry::Triangulation::is_cocircular_edge`]). Degenerate arcs are always
//! collapsed ([`crate::collapse`]).

use crate::apollonius::{apollonius, same_circle, Apollonius, Choice, Sign, Site};
use crate::domain::{CircleId, Domain};
use crate::geometry::{Point, Triangulation};
use crate::medial::{MedialArc, MedialGraph, MedialVertex};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;

/// The tangency site of circle `id` of `domain` (a hole, or the bounding circle for `-1`).
pub fn site(domain: &Domain, id: CircleId) -> Site {
    let c = domain.circle(id);
    if id < 0 {
        Site::bounding(c)
    } else {
        Site::hole(c)
    }
}

/// The exact Apollonius circle of every medial vertex (see the module documentation), or
/// `None` where no valid root has the triangle's orientation. Circle ids of the graph must
/// be ids of `domain` (the graph was built from its samples).
pub fn vertex_circles(domain: &Domain, medial: &MedialGraph) -> Vec<Option<Apollonius>> {
    vertex_circles_reusing(domain, medial, None)
}

/// [`vertex_circles`] of the vertices `vs` of `medial` only, in the order of `vs` (in
/// parallel; the same answers).
pub fn vertex_circles_of(
    domain: &Domain,
    medial: &MedialGraph,
    vs: &[u32],
) -> Vec<Option<Apollonius>> {
    vs.par_iter()
        .map(|&v| {
            medial
                .vertices
                .get(v as usize)
                .and_then(|m| vertex_circle(domain, m))
        })
        .collect()
}

/// The solve of one medial vertex: a function of its circle ids (in order), the circles of
/// `domain` they name, and its position (the hint).
fn vertex_circle(domain: &Domain, v: &MedialVertex) -> Option<Apollonius> {
    let n = domain.hole_count() as CircleId;
    if v.circles.iter().any(|&c| c < -1 || c >= n) {
        return None;
    }
    let sites = v.circles.map(|c| site(domain, c));
    let choice = Choice {
        orientation: Some(Sign::Positive),
        hint: None,
    }
    .near(v.position);
    apollonius(sites, choice).ok()
}

/// The key a vertex's solve depends on besides the circles themselves: circle ids in order
/// and the position's bits.
fn solve_key(v: &MedialVertex) -> ([CircleId; 3], [u64; 2]) {
    (v.circles, v.position.map(f64::to_bits))
}

/// [`vertex_circles`], taking the answer of a vertex of `previous` (a medial graph of an
/// earlier domain, with its vertex circles) with the same circle ids in the same order and the
/// same position bits instead of solving again.
///
/// Exact when every circle id of the earlier domain names the same circle in `domain`: macro
/// refinement ([`crate::refine`]) only appends holes, so the ids, the sites and the hint of such
/// a vertex are those of the earlier solve, which is deterministic. Refinement re-samples only
/// near inserted holes in effect, so nearly every vertex is found (issue 8: the second solve of
/// every Apollonius circle of the domain was about half the blocking stage at 3e4 holes).
pub fn vertex_circles_reusing(
    domain: &Domain,
    medial: &MedialGraph,
    previous: Option<(&MedialGraph, &[Option<Apollonius>])>,
) -> Vec<Option<Apollonius>> {
    let Some((graph, circles)) = previous.filter(|(g, c)| g.vertices.len() == c.len()) else {
        // One independent solve per vertex, in parallel, collected in vertex order.
        return medial
            .vertices
            .par_iter()
            .map(|v| vertex_circle(domain, v))
            .collect();
    };
    let matched = matching_vertices(medial, graph);
    medial
        .vertices
        .par_iter()
        .zip(matched.par_iter())
        .map(|(v, m)| match *m {
            Some(i) => circles[i as usize].clone(),
            None => vertex_circle(domain, v),
        })
        .collect()
}

/// For each vertex of `medial`, the vertex of `previous` with the same [`solve_key`] (the
/// last one when several share it), if any.
fn matching_vertices(medial: &MedialGraph, previous: &MedialGraph) -> Vec<Option<u32>> {
    use std::hash::BuildHasher;
    type Key = ([CircleId; 3], [u64; 2]);
    // Looked up, never iterated: a fixed fast hasher (SipHash made this serial build ~15 ms
    // at 1e5 particles' 200 000 vertices). The keys are cut into shards by their hash, each
    // shard's map built by its own task from every vertex of its shard in vertex order (the
    // last one of a key wins, as in one map), in parallel (issue 8: one map took 30-50 ms on
    // one CPU at 1e5 bubbles while the other waited).
    let state = foldhash::fast::FixedState::default();
    let shard = |k: &Key| (state.hash_one(k) >> 32) as usize % MATCH_SHARDS;
    let per_shard = previous.vertices.len() / MATCH_SHARDS + 16;
    let known: Vec<HashMap<Key, u32, foldhash::fast::FixedState>> = (0..MATCH_SHARDS)
        .into_par_iter()
        .map(|s| {
            let mut known = HashMap::with_capacity_and_hasher(per_shard, state.clone());
            for (i, v) in previous.vertices.iter().enumerate() {
                let k = solve_key(v);
                if shard(&k) == s {
                    known.insert(k, i as u32);
                }
            }
            known
        })
        .collect();
    medial
        .vertices
        .par_iter()
        .map(|v| {
            let k = solve_key(v);
            known[shard(&k)].get(&k).copied()
        })
        .collect()
}

/// Shards of [`matching_vertices`]'s map (a few per thread; the matches do not depend on it).
const MATCH_SHARDS: usize = 4;

/// [`vertex_circles_reusing`], taking the answers out of `previous` instead of cloning them
/// (refinement drops the previous round right after; a clone copies every exact big-integer
/// field, issue 8). A previous answer matched by several vertices (never seen: the key names
/// one vertex) is cloned for each. Same circles as [`vertex_circles_reusing`].
pub fn vertex_circles_taking(
    domain: &Domain,
    medial: &MedialGraph,
    previous: Option<(&MedialGraph, Vec<Option<Apollonius>>)>,
) -> Vec<Option<Apollonius>> {
    let Some((graph, mut circles)) = previous.filter(|(g, c)| g.vertices.len() == c.len()) else {
        return vertex_circles(domain, medial);
    };
    let matched = matching_vertices(medial, graph);
    let mut uses = vec![0u8; circles.len()];
    for &i in matched.iter().flatten() {
        uses[i as usize] = uses[i as usize].saturating_add(1);
    }
    // The answers used once are moved in the parallel pass (each claimed by its one user:
    // issue 8, a serial pass of moves took 15 ms at 1e5 bubbles), those used more often are
    // cloned after it.
    let mut out: Vec<Option<Apollonius>> = {
        let claims = crate::tasks::Claims::new(&mut circles);
        medial
            .vertices
            .par_iter()
            .zip(matched.par_iter())
            .map(|(v, m)| match *m {
                Some(i) if uses[i as usize] == 1 => claims.take(i as usize).flatten(),
                Some(_) => None,
                None => vertex_circle(domain, v),
            })
            .collect()
    };
    for (slot, m) in out.iter_mut().zip(&matched) {
        if let Some(i) = *m {
            if uses[i as usize] > 1 {
                *slot = circles[i as usize].clone();
            }
        }
    }
    out
}

/// `n >= 4` circles tangent to one empty circle (paper section 4.2).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CocircularGroup {
    /// The circles, sorted (`-1` the bounding circle, holes by index).
    pub holes: Vec<CircleId>,
    /// Centre of the common tangent circle (correctly rounded from the exact value).
    pub center: Point,
    /// Its radius (correctly rounded).
    pub radius: f64,
    /// The medial vertices (interior triangles) of the group, sorted; `holes.len() - 2` of
    /// them when the sampled triangulation resolved the group as a fan of triangles.
    #[serde(skip)]
    pub vertices: Vec<u32>,
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let up = parent[parent[x as usize] as usize];
        parent[x as usize] = up;
        x = up;
    }
    x
}

/// For each medial vertex, the index of its group in `groups` (`None` when in no group).
pub fn group_of(medial: &MedialGraph, groups: &[CocircularGroup]) -> Vec<Option<usize>> {
    let mut out = vec![None; medial.vertices.len()];
    for (g, group) in groups.iter().enumerate() {
        for &v in &group.vertices {
            if let Some(slot) = out.get_mut(v as usize) {
                *slot = Some(g);
            }
        }
    }
    out
}

/// Arcs per task of the parallel [`same_circle`] tests of [`cocircular_groups`]: most tests
/// are one comparison of rounded values, but on a lattice every arc inside a co-circular group
/// is an exact comparison of quadratic irrationals (some microseconds each).
const SAME_CIRCLE_CHUNK: usize = 512;

/// The co-circular groups of a medial graph with its vertex circles (one per vertex, from
/// [`vertex_circles`]). Vertices are joined across arcs whose two end circles are exactly the
/// same ([`same_circle`]); components of two or more vertices are groups. Deterministic:
/// groups sorted by their circle lists.
///
/// The tests of the arcs run in parallel (issue 8: on a 100 x 100 square lattice, 9 801
/// groups, they were 90 ms of serial exact arithmetic), the joins then in arc order: the same
/// unions as one pass, whatever the thread count.
pub fn cocircular_groups(
    medial: &MedialGraph,
    circles: &[Option<Apollonius>],
) -> Vec<CocircularGroup> {
    let n = medial.vertices.len();
    if circles.len() != n {
        return Vec::new();
    }
    let same: Vec<bool> = medial
        .arcs
        .par_iter()
        .with_min_len(SAME_CIRCLE_CHUNK)
        .map(|arc| {
            let [a, b] = arc.ends;
            if a == b || a as usize >= n || b as usize >= n {
                return false;
            }
            match (&circles[a as usize], &circles[b as usize]) {
                (Some(x), Some(y)) => same_circle(&x.exact, &y.exact),
                _ => false,
            }
        })
        .collect();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for (arc, _) in medial.arcs.iter().zip(&same).filter(|(_, &s)| s) {
        let [a, b] = arc.ends;
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    // Components of two or more vertices, by increasing root, members in vertex order. A
    // root is its component's smallest vertex (unions keep the smaller root), so it is met
    // first: one list per group, not one per vertex (issue 8).
    let mut size = vec![0u32; n];
    let roots: Vec<u32> = (0..n as u32).map(|v| find(&mut parent, v)).collect();
    for &r in &roots {
        size[r as usize] += 1;
    }
    let mut slot = vec![u32::MAX; n];
    let mut members: Vec<(u32, Vec<u32>)> = Vec::new();
    for (v, &r) in roots.iter().enumerate() {
        if size[r as usize] < 2 {
            continue;
        }
        if slot[r as usize] == u32::MAX {
            slot[r as usize] = members.len() as u32;
            members.push((r, Vec::with_capacity(size[r as usize] as usize)));
        }
        members[slot[r as usize] as usize].1.push(v as u32);
    }
    let mut groups: Vec<CocircularGroup> = members
        .into_iter()
        .filter_map(|(root, vertices)| {
            let c = circles[root as usize].as_ref()?;
            let mut holes: Vec<CircleId> = vertices
                .iter()
                .flat_map(|&v| medial.vertices[v as usize].circles)
                .collect();
            holes.sort_unstable();
            holes.dedup();
            Some(CocircularGroup {
                holes,
                center: c.center,
                radius: c.radius,
                vertices,
            })
        })
        .collect();
    groups.sort_by(|a, b| a.holes.cmp(&b.holes));
    groups
}

/// True when the true length of `arc` is zero (see the module documentation): both ends in
/// one co-circular group (`group` from [`group_of`]), all its sampled points equal, or it
/// crosses one exactly co-circular Delaunay edge.
pub fn is_zero_length(
    arc: &MedialArc,
    medial: &MedialGraph,
    tri: &Triangulation,
    group: &[Option<usize>],
) -> bool {
    let [a, b] = arc.ends;
    if let (Some(Some(x)), Some(Some(y))) = (group.get(a as usize), group.get(b as usize)) {
        if x == y {
            return true;
        }
    }
    if arc.polyline.windows(2).all(|w| w[0] == w[1]) {
        return true;
    }
    if arc.triangles.is_empty() {
        if let Some(v) = medial.vertices.get(a as usize) {
            return tri.is_cocircular_edge(v.triangle as usize, arc.end_slots[0] as usize);
        }
    }
    false
}

/// Length of the sampled medial arc (its polyline of circumcentres).
pub fn arc_length(arc: &MedialArc) -> f64 {
    arc.polyline
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// The radius of the empty circle at medial vertex `v`: its Apollonius radius, or the
/// distance from its circumcentre to its first sample when the solve failed.
pub fn local_radius(
    medial: &MedialGraph,
    circles: &[Option<Apollonius>],
    samples: &[Point],
    v: u32,
) -> f64 {
    if let Some(Some(c)) = circles.get(v as usize) {
        return c.radius;
    }
    medial
        .vertices
        .get(v as usize)
        .and_then(|mv| {
            let s = samples.get(mv.samples[0] as usize)?;
            Some((s[0] - mv.position[0]).hypot(s[1] - mv.position[1]))
        })
        .unwrap_or(0.0)
}
