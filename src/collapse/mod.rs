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
//! could not remove) always, then arcs whose length ([`ArcLength`]) is below `fraction` times
//! the smaller empty-circle radius of its two ends, shortest (relative) first. An arc is
//! skipped when its ends are already in one cluster (collapsing a cycle would delete every
//! block around a hole) or when another remaining arc joins the same two clusters (it would
//! become a loop). The blocking checks
//! the result and gives up short (non-zero) collapses that leave a block with non-positive
//! area ([`crate::blocking`]).

use crate::apollonius::Apollonius;
use crate::cocircular::{arc_length, group_of, is_zero_length, local_radius, CocircularGroup};
use crate::geometry::{Point, Triangulation};
use crate::medial::MedialGraph;
use crate::mesher::MeshError;

mod contraction;
#[doc(hidden)]
pub mod reference;

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

/// How a medial arc is measured for the short-arc test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ArcLength {
    /// The sampled polyline through the circumcentres of its triangles
    /// ([`crate::cocircular::arc_length`]): the paper pipeline, whose blocks follow it.
    #[default]
    Polyline,
    /// The chord between the exact Apollonius centres of its two ends (the polyline when
    /// either end has none): exact mode, whose blocks are built on those centres. It depends
    /// only on the arc's circles, not on how finely they are sampled, so the same layout
    /// collapses the same arcs at every sampling density (and after a local resampling);
    /// for an arc short enough to be collapsed, it is the exact arc's length to within
    /// its tiny curvature.
    Chord,
}

/// The length of `arc` measured as `how` says; `centre(v)` is the Apollonius centre of medial
/// vertex `v`, when solved.
pub fn measured_length(
    arc: &crate::medial::MedialArc,
    centre: impl Fn(u32) -> Option<Point>,
    how: ArcLength,
) -> f64 {
    match (how, centre(arc.ends[0]), centre(arc.ends[1])) {
        (ArcLength::Chord, Some(a), Some(b)) => crate::geometry::length(b[0] - a[0], b[1] - a[1]),
        _ => arc_length(arc),
    }
}

/// The Apollonius centre of vertex `v` from the vertex circles `circles`, when solved.
fn centre_in(circles: &[Option<Apollonius>], v: u32) -> Option<Point> {
    circles
        .get(v as usize)
        .and_then(|c| c.as_ref())
        .map(|c| c.center)
}

/// The union-find forest of the arcs marked in `collapse` (one flag per arc): each root is the
/// smallest vertex of its cluster once paths are compressed by [`find`]. An
/// [`MeshError::Internal`] when the flags do not match the arcs, an arc is malformed, or the
/// marked arcs contain a cycle. Shared by the contraction and its reference.
fn union_collapsed(medial: &MedialGraph, collapse: &[bool]) -> Result<Vec<u32>, MeshError> {
    let n = medial.vertices.len();
    if collapse.len() != medial.arcs.len() {
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
    Ok(parent)
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

/// [`select`] (arcs measured by their sampled polylines, [`ArcLength::Polyline`]), with the
/// arcs flagged in `forced` (one flag per arc; missing flags are false)
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
    Selection::new(
        medial,
        tri,
        circles,
        groups,
        points,
        fraction,
        ArcLength::Polyline,
    )
    .select(exclude, forced)
}

/// The part of [`select_forced`] that depends on neither `exclude` nor `forced`, computed once
/// and kept for the local rebuilds ([`crate::blocking::CollapsedBlocking::recollapse`]): the
/// zero-length arcs, every arc's measured length ([`ArcLength`]), and the short candidates
/// (relative length below the fraction) already sorted. Filtering a sorted list keeps it
/// sorted, so with [`ArcLength::Polyline`] [`Selection::select`] is [`select_forced`] exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// Zero-length arcs, in arc order.
    zero: Vec<u32>,
    is_zero: Vec<bool>,
    /// Length per arc, measured as [`ArcLength`] says.
    length: Vec<f64>,
    /// `(relative length, arc)` of the non-zero arcs below the fraction, sorted.
    short: Vec<(f64, u32)>,
    ends: Vec<[u32; 2]>,
    vertices: usize,
    /// The block after each block end ([`contraction::successors`]), for every contraction
    /// of this graph; `None` for a malformed graph or two blocks at one corner (the
    /// contraction then finds the error itself).
    next: Option<Vec<u32>>,
}

/// The block successors of `medial` ([`contraction::successors`]) when its arcs are well
/// formed, computed once per selection for the contractions.
fn block_successors(medial: &MedialGraph) -> Option<Vec<u32>> {
    contraction::well_formed(medial)
        .then(|| contraction::successors(medial).ok())
        .flatten()
}

/// Sort `(relative length, arc)` pairs by length, equal lengths by the arc's circles
/// ([`crate::blocking::arc_key`]), then by arc: symmetric layouts have many arcs of the same
/// length, and the greedy acceptance takes the first of two that exclude each other, so the
/// tie is broken by the geometry rather than by the arc numbers (which follow the
/// triangulation's numbering, not the layout).
fn sort_by_length(medial: &MedialGraph, short: &mut [(f64, u32)]) {
    let mut keyed: Vec<(f64, Vec<crate::domain::CircleId>, u32)> = short
        .iter()
        .map(|&(r, e)| (r, crate::blocking::arc_key(medial, e as usize), e))
        .collect();
    keyed.sort_by(|a, b| {
        a.0.total_cmp(&b.0)
            .then_with(|| a.1.cmp(&b.1))
            .then(a.2.cmp(&b.2))
    });
    for (slot, (r, _, e)) in short.iter_mut().zip(keyed) {
        *slot = (r, e);
    }
}

impl Selection {
    /// The per-arc data of [`select_forced`] (same arguments less `exclude` and `forced`).
    ///
    /// Each arc's zero-length test, measured length and relative length are functions of the
    /// arc alone, computed in parallel (and the block successors meanwhile), then gathered in
    /// arc order: the selection of [`Selection::new_one_by_one`] (tested equal in
    /// `tests/perf_blocks_parallel.rs`), for every thread count.
    pub fn new(
        medial: &MedialGraph,
        tri: &Triangulation,
        circles: &[Option<Apollonius>],
        groups: &[CocircularGroup],
        points: &[Point],
        fraction: f64,
        lengths: ArcLength,
    ) -> Selection {
        use rayon::prelude::*;
        let group = group_of(medial, groups);
        let m = medial.arcs.len();
        let relative = fraction > 0.0;
        // Per arc: zero-length, measured length, relative length (NaN when not asked for).
        let (per_arc, next): (Vec<(bool, f64, f64)>, _) = rayon::join(
            || {
                medial
                    .arcs
                    .par_iter()
                    .with_min_len(1024)
                    .map(|arc| {
                        if is_zero_length(arc, medial, tri, &group) {
                            return (true, 0.0, f64::NAN);
                        }
                        let length = measured_length(arc, |v| centre_in(circles, v), lengths);
                        if !relative {
                            return (false, length, f64::NAN);
                        }
                        let r = local_radius(medial, circles, points, arc.ends[0])
                            .min(local_radius(medial, circles, points, arc.ends[1]));
                        (false, length, length / r)
                    })
                    .collect()
            },
            || block_successors(medial),
        );
        let (mut zero, mut is_zero) = (Vec::new(), vec![false; m]);
        let mut length = vec![0.0; m];
        let mut short: Vec<(f64, u32)> = Vec::new();
        for (e, &(z, len, rel)) in per_arc.iter().enumerate() {
            if z {
                zero.push(e as u32);
                is_zero[e] = true;
                continue;
            }
            length[e] = len;
            if rel.is_finite() && rel < fraction {
                short.push((rel, e as u32));
            }
        }
        Selection::from_figures(medial, zero, is_zero, length, short, next)
    }

    /// [`Selection::new`] one arc after the other, as first written: the oracle of the tests.
    #[doc(hidden)]
    pub fn new_one_by_one(
        medial: &MedialGraph,
        tri: &Triangulation,
        circles: &[Option<Apollonius>],
        groups: &[CocircularGroup],
        points: &[Point],
        fraction: f64,
        lengths: ArcLength,
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
            length[e] = measured_length(arc, |v| centre_in(circles, v), lengths);
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
        let next = block_successors(medial);
        Selection::from_figures(medial, zero, is_zero, length, short, next)
    }

    /// The selection from its per-arc figures (`short` in any order: sorted here by relative
    /// length, then arc), shared by [`Selection::new`] and its oracle.
    fn from_figures(
        medial: &MedialGraph,
        zero: Vec<u32>,
        is_zero: Vec<bool>,
        length: Vec<f64>,
        mut short: Vec<(f64, u32)>,
        next: Option<Vec<u32>>,
    ) -> Selection {
        sort_by_length(medial, &mut short);
        Selection {
            zero,
            is_zero,
            length,
            short,
            ends: medial.arcs.iter().map(|a| a.ends).collect(),
            vertices: medial.vertices.len(),
            next,
        }
    }

    /// [`contract`] of `medial`, the graph this selection was built from, with the block
    /// successors computed once.
    pub fn contract(
        &self,
        medial: &MedialGraph,
        collapse: &[bool],
    ) -> Result<Contracted, MeshError> {
        Ok(contraction::contract_with(medial, collapse, self.successors(medial), None)?.0)
    }

    /// [`Selection::contract`], taking over from `previous` (a contraction of the same graph
    /// with the collapse flags `previous_flags`) the arcs the changed flags cannot reach; per
    /// arc of the result, the index of the previous arc taken over (`u32::MAX`: built
    /// afresh). The arcs taken are left empty in `previous`. Same contraction as
    /// [`Selection::contract`].
    pub(crate) fn contract_reusing(
        &self,
        medial: &MedialGraph,
        collapse: &[bool],
        previous_flags: &[bool],
        previous: &mut Contracted,
    ) -> Result<(Contracted, Vec<u32>), MeshError> {
        let previous = contraction::Previous {
            flags: previous_flags,
            contracted: previous,
        };
        contraction::contract_with(medial, collapse, self.successors(medial), Some(previous))
    }

    /// The block successor table kept for `medial` (`None` when it is not this graph's: the
    /// contraction computes its own).
    fn successors(&self, medial: &MedialGraph) -> Option<&[u32]> {
        self.next
            .as_deref()
            .filter(|n| n.len() == 2 * medial.arcs.len())
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
/// The parallel check scans the arcs incident to the vertices of the smaller of the two
/// clusters (by the number of those incidences) instead of every arc: O(m log m) visits in
/// all, where a scan of every arc per candidate was O(candidates x arcs) (90% of a
/// 100 000-bubble run). Same result as that scan (tested against it on random multigraphs).
/// The incidences are one flat table by vertex, and a cluster's vertices a cycle of `next`
/// links (two clusters merge by swapping their roots' links): no vector per vertex or
/// cluster (issue 8: building, merging and freeing 200 000 of them was 20 ms on one CPU at
/// 1e5 particles).
fn accept(order: impl Iterator<Item = (u32, bool)>, ends: &[[u32; 2]], n: usize) -> Vec<Candidate> {
    let valid = |e: usize| ends[e].iter().all(|&v| (v as usize) < n);
    let mut parent: Vec<u32> = (0..n as u32).collect();
    // The arcs incident to vertex `v`: `arcs[at[v]..at[v + 1]]` (a loop once).
    let (at, arcs) = crate::buckets::group(n, || {
        ends.iter()
            .enumerate()
            .filter(|&(e, _)| valid(e))
            .flat_map(|(e, &[a, b])| {
                let e = e as u32;
                [(a as usize, e), (b as usize, e)]
                    .into_iter()
                    .take(if b != a { 2 } else { 1 })
            })
    });
    // Per cluster root: its incidences (the sum of its vertices' degrees); per vertex: the
    // next vertex of its cluster (a cycle).
    let mut size: Vec<usize> = (0..n).map(|v| at[v + 1] - at[v]).collect();
    let mut next: Vec<u32> = (0..n as u32).collect();
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
        let (small, large) = if size[ra as usize] <= size[rb as usize] {
            (ra, rb)
        } else {
            (rb, ra)
        };
        let mut parallel = false;
        let mut v = small;
        'scan: loop {
            for &f in &arcs[at[v as usize]..at[v as usize + 1]] {
                if f == e || taken[f as usize] {
                    continue;
                }
                let [x, y] = ends[f as usize];
                let (rx, ry) = (find(&mut parent, x), find(&mut parent, y));
                if (rx == small && ry == large) || (rx == large && ry == small) {
                    parallel = true;
                    break 'scan;
                }
            }
            v = next[v as usize];
            if v == small {
                break;
            }
        }
        if parallel {
            continue;
        }
        let (root, child) = (ra.min(rb), ra.max(rb));
        parent[child as usize] = root;
        size[root as usize] = size[ra as usize] + size[rb as usize];
        next.swap(ra as usize, rb as usize);
        taken[e as usize] = true;
        out.push(Candidate {
            arc: e,
            zero: is_zero,
        });
    }
    out
}

/// The medial graph with the given arcs contracted.
#[derive(Debug, Clone, PartialEq, Default)]
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
    Ok(contraction::contract_with(medial, collapse, None, None)?.0)
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
