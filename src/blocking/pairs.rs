//! Blocking2D's pairs of blocks ([`super::blocks`]): the curves of each arc (its medial
//! polyline and two walls, the costly part) computed in parallel, the layout vertices, spokes,
//! edges and blocks numbered one arc after the other as before (issue 8).

use super::wall_curve;
use crate::domain::{CircleId, Domain};
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use crate::medial::{MedialArc, MedialGraph};
use crate::mesher::MeshError;
use crate::sampling::Samples;
use rayon::prelude::*;

/// The curves of the blocks `2k` and `2k + 1` of `old` (Blocking2D of arc `k` of an earlier
/// graph), moved out: the medial polyline and the two walls, when they have the shape
/// Blocking2D gives them (a polyline of `points` points, walls on `circles`).
fn take_pair_curves(
    old: &mut BlockLayout,
    k: usize,
    points: usize,
    circles: [CircleId; 2],
) -> Option<[Curve; 3]> {
    let (a, b) = (old.blocks.get(2 * k)?, old.blocks.get(2 * k + 1)?);
    let (medial, wall_a, wall_b) = (a.sides[2].edge, a.sides[0].edge, b.sides[0].edge);
    if b.sides[2].edge != medial || [a.wall, b.wall] != [Some(circles[0]), Some(circles[1])] {
        return None;
    }
    let ok = |e: u32, kind: EdgeKind, polyline: bool| {
        old.edges.get(e as usize).is_some_and(|edge| {
            edge.kind == kind
                && match &edge.curve {
                    Curve::Polyline(p) => polyline && p.len() == points,
                    Curve::Arc { .. } => !polyline,
                    Curve::Segment => false,
                }
        })
    };
    if !(ok(medial, EdgeKind::Medial, true)
        && ok(wall_a, EdgeKind::Wall(circles[0]), false)
        && ok(wall_b, EdgeKind::Wall(circles[1]), false))
    {
        return None;
    }
    let mut take = |e: u32| std::mem::replace(&mut old.edges[e as usize].curve, Curve::Segment);
    Some([take(medial), take(wall_a), take(wall_b)])
}

/// Arcs per wave of [`blocks_reusing`]: the curves of one wave are computed (in parallel)
/// while the previous wave is numbered into the layout, and at most two waves of curves are
/// held at once.
const WAVE: usize = 2048;

/// [`super::blocks`], taking the curves of arc `a` of `medial` from the pair of blocks
/// `2k, 2k + 1` of `old` where `taken[a] = k` (`u32::MAX`: computed): the previous Blocking2D
/// of a contraction that handed arc `k` over unchanged
/// ([`crate::collapse::Selection::contract_reusing`]), so its polyline and wall chains, hence
/// its curves, are those of arc `a`. The curves taken are left as segments in `old`.
///
/// Arcs go in waves of [`wave_len`] arcs: the curves taken from `old` (one after the other,
/// in arc order, as the one-by-one construction takes them), then the others computed in parallel
/// ([`arc_curves`], a function of the arc alone, its checks and errors included), while the
/// wave before is numbered into the layout one arc after the other ([`Assembly::add`]). The
/// layout and the error (the first failing arc's, its checks in the one-by-one order) are
/// those of the one-by-one construction ([`blocks_one_by_one`]) for every thread count (tested in
/// `tests/perf_blocks_parallel.rs`).
///
/// Graphs of fewer than [`PARALLEL_FROM`] arcs go one arc at a time through the same pieces
/// ([`arc_curves`], then [`Assembly::add_pair`]): there the buffers and joins cost more than
/// the overlap saves.
pub(super) fn blocks_reusing(
    domain: &Domain,
    samples: &Samples,
    medial: &MedialGraph,
    mut old: Option<(&mut BlockLayout, &[u32])>,
) -> Result<(BlockLayout, Vec<Option<u32>>), MeshError> {
    if medial.arcs.len() >= PARALLEL_FROM {
        return in_waves(domain, samples, medial, old, wave_len(medial.arcs.len()));
    }
    let mut asm = Assembly::new(samples, medial);
    let mut back = Vec::new();
    for (a, arc) in medial.arcs.iter().enumerate() {
        let reused = taken_over(&mut old, medial, a);
        let curves = arc_curves(domain, samples, medial, a, reused, &mut back)?;
        asm.add_pair(arc, curves);
    }
    Ok((asm.layout, asm.vertex_samples))
}

/// The curves of arc `a` taken over from `old` ([`take_pair_curves`] of the pair `taken[a]`),
/// `None` when the arc is computed afresh (no earlier layout, `taken[a] = u32::MAX`, or a pair
/// not of Blocking2D's shape).
fn taken_over(
    old: &mut Option<(&mut BlockLayout, &[u32])>,
    medial: &MedialGraph,
    a: usize,
) -> Option<[Curve; 3]> {
    let arc = &medial.arcs[a];
    let (old, taken) = old.as_mut()?;
    let k = *taken.get(a)?;
    (k != u32::MAX).then(|| take_pair_curves(old, k as usize, arc.polyline.len(), arc.circles))?
}

/// How far ahead (in arcs) [`Assembly::add`] prefetches.
const PREFETCH_ARCS: usize = 16;

/// Arc count from which [`blocks_reusing`] goes in waves.
///
/// Issue 8, measured with the pipeline on a pool worker: 1e3 bubbles (about 3 000 arcs, 15
/// runs, medians) build in 1.26 ms one arc at a time, 1.04 ms in waves of 2 048 and 0.89 ms
/// in waves of 512 (a recollapse: 1.46, 1.17 and 1.03 ms); 1e4 and 1e5 are fastest in waves
/// of [`WAVE`].
const PARALLEL_FROM: usize = 1024;

/// The wave length for `arcs` arcs: about a sixth of them, from 256 up to [`WAVE`] (a few
/// waves on small graphs, so that the numbering of one overlaps the curves of the next).
fn wave_len(arcs: usize) -> usize {
    (arcs / 6).clamp(256, WAVE)
}

/// [`super::blocks`] in waves of `wave` arcs (at least 1) whatever the graph's size: what
/// [`blocks_reusing`] does from [`PARALLEL_FROM`] arcs on, for the tests to compare with
/// [`blocks_one_by_one`] on small graphs too.
#[doc(hidden)]
pub fn blocks_in_waves(
    domain: &Domain,
    samples: &Samples,
    medial: &MedialGraph,
    wave: usize,
) -> Result<(BlockLayout, Vec<Option<u32>>), MeshError> {
    in_waves(domain, samples, medial, None, wave.max(1))
}

/// The wave construction of [`blocks_reusing`] with waves of `wave_len >= 1` arcs.
fn in_waves(
    domain: &Domain,
    samples: &Samples,
    medial: &MedialGraph,
    mut old: Option<(&mut BlockLayout, &[u32])>,
    wave_len: usize,
) -> Result<(BlockLayout, Vec<Option<u32>>), MeshError> {
    let m = medial.arcs.len();
    let mut asm = Assembly::new(samples, medial);
    // Two buffers of curves (the wave being numbered, the wave being computed) and one of
    // curves taken over, allocated once and reused by every wave (a fresh ~300 KB per wave
    // was fresh pages to fault in, issue 8).
    let mut reused_buf: Vec<Option<[Curve; 3]>> = Vec::with_capacity(wave_len.min(m));
    let mut reused = |mut buf: Vec<Option<[Curve; 3]>>,
                      range: std::ops::Range<usize>|
     -> Vec<Option<[Curve; 3]>> {
        buf.clear();
        buf.extend(range.map(|a| taken_over(&mut old, medial, a)));
        buf
    };
    let compute = |start: usize,
                   mut reused: Vec<Option<[Curve; 3]>>,
                   out: &mut Vec<Result<[Curve; 3], MeshError>>| {
        reused
            .par_drain(..)
            .enumerate()
            .with_min_len(64)
            .map_init(Vec::new, |back, (i, r)| {
                arc_curves(domain, samples, medial, start + i, r, back)
            })
            .collect_into_vec(out);
        reused
    };
    let waves = m.div_ceil(wave_len);
    let wave = |w: usize| w * wave_len..((w + 1) * wave_len).min(m);
    let mut current = Vec::with_capacity(wave_len.min(m));
    let mut next_out = Vec::with_capacity(wave_len.min(m));
    if waves > 0 {
        let r = reused(std::mem::take(&mut reused_buf), wave(0));
        reused_buf = compute(0, r, &mut current);
    }
    for w in 0..waves {
        let next = (w + 1 < waves).then(|| {
            let buf = std::mem::take(&mut reused_buf);
            (wave(w + 1).start, reused(buf, wave(w + 1)))
        });
        let (added, back) = rayon::join(
            || asm.add(wave(w).start, &mut current),
            || next.map(|(start, r)| compute(start, r, &mut next_out)),
        );
        added?;
        if let Some(back) = back {
            reused_buf = back;
        }
        std::mem::swap(&mut current, &mut next_out);
    }
    Ok((asm.layout, asm.vertex_samples))
}

/// The first and last samples of a wall chain, checked non-empty and in range.
fn chain_ends(samples: &Samples, c: &[u32]) -> Result<(u32, u32), MeshError> {
    match (c.first(), c.last()) {
        (Some(&f), Some(&l)) if (f.max(l) as usize) < samples.len() => Ok((f, l)),
        _ => Err(MeshError::Internal(
            "medial arc with an empty or out-of-range sample chain".into(),
        )),
    }
}

/// The first and last samples of the arc's chains C1 and C2, after the checks of an arc in
/// the one-by-one construction's order: both chains non-empty and in range, then its medial
/// vertices and circles in range.
fn checked_ends(
    domain: &Domain,
    samples: &Samples,
    medial: &MedialGraph,
    arc: &MedialArc,
) -> Result<[(u32, u32); 2], MeshError> {
    let ends = [chain_ends(samples, &arc.c1)?, chain_ends(samples, &arc.c2)?];
    let [m0, m1] = arc.ends;
    if m0.max(m1) as usize >= medial.vertices.len()
        || arc
            .circles
            .iter()
            .any(|&c| c < -1 || c >= domain.hole_count() as CircleId)
    {
        return Err(MeshError::Internal(
            "medial arc with an out-of-range vertex or circle".into(),
        ));
    }
    Ok(ends)
}

/// The checks of arc `a` and its curves `[medial polyline, wall on circles[0] (C1 forward),
/// wall on circles[1] (C2 backward)]`, `reused` when given: what the one-by-one construction
/// checks and computes for the arc, in its order (chains, vertex and circle range, wall A,
/// wall B). `back`: a buffer for the reversed C2 chain.
fn arc_curves(
    domain: &Domain,
    samples: &Samples,
    medial: &MedialGraph,
    a: usize,
    reused: Option<[Curve; 3]>,
    back: &mut Vec<u32>,
) -> Result<[Curve; 3], MeshError> {
    let arc = &medial.arcs[a];
    checked_ends(domain, samples, medial, arc)?;
    if let Some(curves) = reused {
        return Ok(curves);
    }
    let [ca, cb] = arc.circles;
    let expect = |c: CircleId| if c < 0 { 1 } else { -1 };
    let polyline = Curve::Polyline(arc.polyline.clone());
    let wall_a = wall_curve(domain, samples, ca, &arc.c1, expect(ca))?;
    back.clear();
    back.extend(arc.c2.iter().rev());
    let wall_b = wall_curve(domain, samples, cb, back, expect(cb))?;
    Ok([polyline, wall_a, wall_b])
}

/// The layout being numbered: vertices (the medial ones, then one per sample corner in order
/// of first use), edges and blocks, one arc after the other.
struct Assembly<'a> {
    samples: &'a Samples,
    medial: &'a MedialGraph,
    layout: BlockLayout,
    vertex_samples: Vec<Option<u32>>,
    /// Indexed by sample id (checked `< samples.len()`) instead of hashed, per sample its
    /// layout vertex + 1 (0: none; zero-initialised, so the allocation maps zero pages
    /// instead of filling an array, issue 8).
    slots: Vec<u32>,
    /// Per sample corner vertex (layout vertex minus the medial vertex count, in order of
    /// creation), the head + 1 of its list of spokes in `spoke_list` (0: none). Kept per
    /// corner rather than per sample: 4 bytes per sample less (issue 8: 33 MB per blocking
    /// at 1e5 particles).
    spoke_heads: Vec<u32>,
    /// `(medial vertex, edge, next + 1)`: a sample has a spoke from one to three medial
    /// vertices.
    spoke_list: Vec<(u32, u32, u32)>,
}

impl<'a> Assembly<'a> {
    fn new(samples: &'a Samples, medial: &'a MedialGraph) -> Assembly<'a> {
        // Vertices: the medial ones, then at most four sample corners per arc (reserved once:
        // no doubling of a large vector, issue 8).
        let mut vertices = Vec::with_capacity(medial.vertices.len() + 4 * medial.arcs.len());
        vertices.extend(medial.vertices.iter().map(|v| v.position));
        let vertex_samples = vec![None; vertices.len()];
        Assembly {
            samples,
            medial,
            layout: BlockLayout {
                vertices,
                edges: Vec::with_capacity(5 * medial.arcs.len()),
                blocks: Vec::with_capacity(2 * medial.arcs.len()),
            },
            vertex_samples,
            slots: vec![0; samples.len()],
            spoke_heads: Vec::with_capacity(4 * medial.arcs.len()),
            spoke_list: Vec::with_capacity(3 * medial.vertices.len()),
        }
    }

    /// The layout vertex of sample `s` (`< samples.len()`), added at its first use.
    fn sample_vertex(&mut self, s: u32) -> u32 {
        let slot = &mut self.slots[s as usize];
        if *slot == 0 {
            self.layout.vertices.push(self.samples.points[s as usize]);
            self.vertex_samples.push(Some(s));
            self.spoke_heads.push(0);
            *slot = self.layout.vertices.len() as u32;
        }
        *slot - 1
    }

    fn edge(&mut self, ends: [u32; 2], curve: Curve, kind: EdgeKind) -> u32 {
        self.layout.edges.push(Edge { ends, curve, kind });
        (self.layout.edges.len() - 1) as u32
    }

    /// The spoke from medial vertex `mv` to sample `s` (layout vertex `sv`, given by
    /// [`Assembly::sample_vertex`]), added at its first use.
    fn spoke(&mut self, mv: u32, s: u32, sv: u32) -> u32 {
        debug_assert_eq!(self.slots[s as usize], sv + 1);
        let corner = sv as usize - self.medial.vertices.len();
        let mut at = self.spoke_heads[corner];
        while at != 0 {
            let (v, edge, next) = self.spoke_list[at as usize - 1];
            if v == mv {
                return edge;
            }
            at = next;
        }
        let edge = self.edge([mv, sv], Curve::Segment, EdgeKind::Spoke);
        let head = &mut self.spoke_heads[corner];
        self.spoke_list.push((mv, edge, *head));
        *head = self.spoke_list.len() as u32;
        edge
    }

    /// Number the arcs from `start` on, with their curves (or their errors, the first one
    /// returned), taken out of `curves` (left empty, its capacity kept).
    fn add(
        &mut self,
        start: usize,
        curves: &mut Vec<Result<[Curve; 3], MeshError>>,
    ) -> Result<(), MeshError> {
        let medial = self.medial;
        for (i, c) in curves.drain(..).enumerate() {
            self.prefetch_ahead(start + i);
            self.add_pair(&medial.arcs[start + i], c?);
        }
        Ok(())
    }

    /// Prefetches for the arcs ahead of arc `a` in numbering order (issue 8: the slots of
    /// the chain ends are random accesses into an array of one entry per sample, 13 MB at
    /// 1e5 particles, and each chain is its own allocation): the chains' ends of arc
    /// `a + 2 PREFETCH_ARCS`, the slots and positions of arc `a + PREFETCH_ARCS`'s chain
    /// ends, and the spoke list heads of the corners of arc `a + PREFETCH_ARCS / 2`. Hints
    /// only: nothing read here changes what is numbered.
    #[inline(always)]
    fn prefetch_ahead(&self, a: usize) {
        let arcs = &self.medial.arcs;
        if let Some(far) = arcs.get(a + 2 * PREFETCH_ARCS) {
            for c in [&far.c1, &far.c2] {
                crate::prefetch::read(c.as_ptr());
                crate::prefetch::read(c.as_ptr().wrapping_add(c.len().saturating_sub(1)));
            }
        }
        fn ends(arc: &MedialArc) -> [Option<&u32>; 4] {
            [arc.c1.first(), arc.c1.last(), arc.c2.first(), arc.c2.last()]
        }
        if let Some(near) = arcs.get(a + PREFETCH_ARCS) {
            for s in ends(near).into_iter().flatten() {
                crate::prefetch::read(self.slots.as_ptr().wrapping_add(*s as usize));
                crate::prefetch::read(self.samples.points.as_ptr().wrapping_add(*s as usize));
            }
        }
        if let Some(next) = arcs.get(a + PREFETCH_ARCS / 2) {
            let nv = self.medial.vertices.len();
            for s in ends(next).into_iter().flatten() {
                let slot = self.slots.get(*s as usize).copied().unwrap_or(0) as usize;
                if slot > nv {
                    crate::prefetch::read(self.spoke_heads.as_ptr().wrapping_add(slot - 1 - nv));
                }
            }
        }
    }

    /// The two blocks of `arc` (checked by [`arc_curves`]), with its curves.
    fn add_pair(&mut self, arc: &MedialArc, [polyline, wall_a, wall_b]: [Curve; 3]) {
        let (fwd, rev) = (SideRef::along, SideRef::against);
        let [m0, m1] = arc.ends;
        let [ca, cb] = arc.circles;
        let (a0, a1) = (arc.c1[0], arc.c1[arc.c1.len() - 1]);
        let (b0, b1) = (arc.c2[0], arc.c2[arc.c2.len() - 1]);
        let va0 = self.sample_vertex(a0);
        let va1 = self.sample_vertex(a1);
        let vb0 = self.sample_vertex(b0);
        let vb1 = self.sample_vertex(b1);
        let medial_edge = self.edge([m0, m1], polyline, EdgeKind::Medial);
        // Block on A: wall along C1 forward, fluid on the left.
        let wall_a = self.edge([va0, va1], wall_a, EdgeKind::Wall(ca));
        let s_a1 = self.spoke(m1, a1, va1);
        let s_a0 = self.spoke(m0, a0, va0);
        self.layout.blocks.push(Block {
            corners: [va0, va1, m1, m0],
            sides: [fwd(wall_a), rev(s_a1), rev(medial_edge), fwd(s_a0)],
            wall: Some(ca),
        });
        // Block on B: wall along C2 backward.
        let wall_b = self.edge([vb1, vb0], wall_b, EdgeKind::Wall(cb));
        let s_b0 = self.spoke(m0, b0, vb0);
        let s_b1 = self.spoke(m1, b1, vb1);
        self.layout.blocks.push(Block {
            corners: [vb1, vb0, m0, m1],
            sides: [fwd(wall_b), rev(s_b0), fwd(medial_edge), fwd(s_b1)],
            wall: Some(cb),
        });
    }
}

/// [`super::blocks`] as first written, one arc after the other, every curve computed: the
/// oracle of [`blocks_reusing`] in the tests (written apart from [`Assembly`] and
/// [`arc_curves`] on purpose). The taking over of an earlier layout's curves is checked
/// against the rebuild from scratch instead (`tests/perf_blocking.rs`).
#[doc(hidden)]
pub fn blocks_one_by_one(
    domain: &Domain,
    samples: &Samples,
    medial: &MedialGraph,
) -> Result<(BlockLayout, Vec<Option<u32>>), MeshError> {
    // Vertices: the medial ones, then at most four sample corners per arc (reserved once:
    // no doubling of a large vector, issue 8).
    let mut vertices = Vec::with_capacity(medial.vertices.len() + 4 * medial.arcs.len());
    vertices.extend(medial.vertices.iter().map(|v| v.position));
    let mut layout = BlockLayout {
        vertices,
        edges: Vec::with_capacity(5 * medial.arcs.len()),
        blocks: Vec::with_capacity(2 * medial.arcs.len()),
    };
    let mut vertex_samples: Vec<Option<u32>> = vec![None; layout.vertices.len()];
    // Indexed by sample id (checked `< samples.len()` below) instead of hashed, per sample
    // `[layout vertex + 1, spoke list head + 1]` (0: none; zero-initialised, so the
    // allocation maps zero pages instead of filling an array, issue 8): the layout vertex of
    // each sample used as a corner, and the spokes to it as a list of `(medial vertex, edge,
    // next + 1)` (a sample has a spoke from one to three medial vertices).
    let mut slots: Vec<[u32; 2]> = vec![[0; 2]; samples.len()];
    let mut spoke_list: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * medial.vertices.len());

    let mut sample_vertex_of = |slots: &mut [[u32; 2]], s: u32, layout: &mut BlockLayout| -> u32 {
        let slot = &mut slots[s as usize][0];
        if *slot == 0 {
            layout.vertices.push(samples.points[s as usize]);
            vertex_samples.push(Some(s));
            *slot = layout.vertices.len() as u32;
        }
        *slot - 1
    };
    let add_edge = |layout: &mut BlockLayout, ends: [u32; 2], curve: Curve, kind| -> u32 {
        layout.edges.push(Edge { ends, curve, kind });
        (layout.edges.len() - 1) as u32
    };
    let mut spoke = |slots: &mut [[u32; 2]], layout: &mut BlockLayout, mv: u32, s: u32, sv: u32| {
        let head = &mut slots[s as usize][1];
        let mut at = *head;
        while at != 0 {
            let (v, edge, next) = spoke_list[at as usize - 1];
            if v == mv {
                return edge;
            }
            at = next;
        }
        layout.edges.push(Edge {
            ends: [mv, sv],
            curve: Curve::Segment,
            kind: EdgeKind::Spoke,
        });
        let edge = (layout.edges.len() - 1) as u32;
        spoke_list.push((mv, edge, *head));
        *head = spoke_list.len() as u32;
        edge
    };
    let (fwd, rev) = (SideRef::along, SideRef::against);

    // One buffer for every arc's reversed C2 chain.
    let mut c2_back: Vec<u32> = Vec::new();
    for arc in &medial.arcs {
        let [m0, m1] = arc.ends;
        let [ca, cb] = arc.circles;
        let [(a0, a1), (b0, b1)] = checked_ends(domain, samples, medial, arc)?;
        let va0 = sample_vertex_of(&mut slots, a0, &mut layout);
        let va1 = sample_vertex_of(&mut slots, a1, &mut layout);
        let vb0 = sample_vertex_of(&mut slots, b0, &mut layout);
        let vb1 = sample_vertex_of(&mut slots, b1, &mut layout);
        let polyline = Curve::Polyline(arc.polyline.clone());
        let medial_edge = add_edge(&mut layout, [m0, m1], polyline, EdgeKind::Medial);
        // Block on A: wall along C1 forward, fluid on the left.
        let expect = |c: CircleId| if c < 0 { 1 } else { -1 };
        let wall_a = wall_curve(domain, samples, ca, &arc.c1, expect(ca))?;
        let wall_a = add_edge(&mut layout, [va0, va1], wall_a, EdgeKind::Wall(ca));
        let s_a1 = spoke(&mut slots, &mut layout, m1, a1, va1);
        let s_a0 = spoke(&mut slots, &mut layout, m0, a0, va0);
        layout.blocks.push(Block {
            corners: [va0, va1, m1, m0],
            sides: [fwd(wall_a), rev(s_a1), rev(medial_edge), fwd(s_a0)],
            wall: Some(ca),
        });
        // Block on B: wall along C2 backward.
        c2_back.clear();
        c2_back.extend(arc.c2.iter().rev());
        let wall_b = wall_curve(domain, samples, cb, &c2_back, expect(cb))?;
        let wall_b = add_edge(&mut layout, [vb1, vb0], wall_b, EdgeKind::Wall(cb));
        let s_b0 = spoke(&mut slots, &mut layout, m0, b0, vb0);
        let s_b1 = spoke(&mut slots, &mut layout, m1, b1, vb1);
        layout.blocks.push(Block {
            corners: [vb1, vb0, m0, m1],
            sides: [fwd(wall_b), rev(s_b0), fwd(medial_edge), fwd(s_b1)],
            wall: Some(cb),
        });
    }
    Ok((layout, vertex_samples))
}
