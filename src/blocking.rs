//! Blocking2D (paper section 3, Algorithm 2): two blocks per medial arc.
//!
//! For a medial arc from vertex `m0` to `m1` with sample chains `C1` (on circle `A`, on the
//! right of the walk) and `C2` (on circle `B`, on the left), the pair of blocks is, with the
//! conventions of [`crate::layout`] (corners counter-clockwise, side `k` from corner `k` to
//! `k + 1`):
//!
//! ```text
//! block on A: corners [C1.first, C1.last, m1, m0]
//!             sides   [wall A (C1 forward), spoke(m1 -> C1.last) reversed,
//!                      medial (m0 -> m1) reversed, spoke(m0 -> C1.first)]
//! block on B: corners [C2.last, C2.first, m0, m1]
//!             sides   [wall B (C2 backward), spoke(m0 -> C2.first) reversed,
//!                      medial (m0 -> m1), spoke(m1 -> C2.last)]
//! ```
//!
//! Side 0 is the wall (the paper's xi1 curve): an arc of the *true* circle between the two
//! samples, with the fluid on the block's left, so it runs clockwise about a hole's centre
//! (negative sweep) and counter-clockwise about the bounding circle's (positive sweep). Side 2
//! is the medial arc (xi0), a polyline of circumcentres stored once from `m0` to `m1` and
//! shared by the pair. Sides 1 and 3 are spokes (eta curves), straight segments stored once
//! from the medial vertex to the sample and shared by the two blocks on that sample's circle
//! meeting at that medial vertex. Layout vertices: the medial vertices first (vertex `i` is
//! medial vertex `i`), then one per sample used as a corner, in order of first use.

use crate::domain::{CircleId, Domain};
use crate::geometry::Triangulation;
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use crate::medial::{MedialGraph, TriangleKind};
use crate::mesher::{MeshError, Options};
use crate::sampling::{sample_and_triangulate, Samples, SamplingOptions};
use std::collections::HashMap;
use std::f64::consts::TAU;

/// Everything the front end of the pipeline produced.
#[derive(Debug, Clone)]
pub struct Blocking {
    /// The blocks (two per medial arc: block `2e` on the arc's `C1` circle, `2e + 1` on its
    /// `C2` circle).
    pub layout: BlockLayout,
    /// The medial graph (its counts are the medial counts of the mesh).
    pub medial: MedialGraph,
    /// The boundary samples.
    pub samples: Samples,
    /// The Delaunay triangulation of the samples.
    pub triangulation: Triangulation,
    /// The class of each triangle.
    pub kinds: Vec<TriangleKind>,
    /// For each layout vertex, the sample it stands for (`None` for medial vertices).
    pub vertex_samples: Vec<Option<u32>>,
    /// Resampling rounds the sampling needed.
    pub rounds: usize,
    /// Arcs left with a single-sample (zero-length) wall: see
    /// [`crate::sampling::thin_walls`].
    pub thin_walls: Vec<crate::sampling::Violation>,
}

/// Run the front end for a domain with at least two holes: sampling with invariant checks
/// and resampling, exact Delaunay triangulation, classification, medial graph (Algorithm 1)
/// and Blocking2D (Algorithm 2), with the default [`SamplingOptions`].
///
/// Errors: [`MeshError::Options`] when the domain has fewer than two holes (the disk and
/// the annulus have no medial vertex and are meshed by templates), [`MeshError::Sampling`]
/// and [`MeshError::Triangulation`] from sampling, [`MeshError::Internal`] for a broken
/// invariant. Never panics.
pub fn build_layout(domain: &Domain, options: &Options) -> Result<Blocking, MeshError> {
    build_layout_with(domain, options, &SamplingOptions::default())
}

/// [`build_layout`] with explicit sampling options.
pub fn build_layout_with(
    domain: &Domain,
    options: &Options,
    sampling: &SamplingOptions,
) -> Result<Blocking, MeshError> {
    let _ = options;
    let h = domain.hole_count();
    if h < 2 {
        return Err(MeshError::Options(format!(
            "medial blocking needs at least 2 holes, the domain has {h} (use the disk/annulus \
             templates)"
        )));
    }
    let sampled = sample_and_triangulate(domain, sampling)?;
    let (layout, vertex_samples) = blocks(domain, &sampled.samples, &sampled.medial)?;
    Ok(Blocking {
        layout,
        medial: sampled.medial,
        rounds: sampled.rounds,
        thin_walls: sampled.thin_walls,
        samples: sampled.samples,
        triangulation: sampled.triangulation,
        kinds: sampled.kinds,
        vertex_samples,
    })
}

/// The wall arc of a chain of consecutive samples on one circle, in side direction.
/// Checks that every step goes the same way round and that the way is `expected` (`-1`
/// clockwise, `+1` counter-clockwise) when the chain has at least one step.
fn wall_curve(
    domain: &Domain,
    samples: &Samples,
    circle: CircleId,
    chain: &[u32],
    expected: i64,
) -> Result<Curve, MeshError> {
    let c = domain.circle(circle);
    let first = *chain
        .first()
        .ok_or_else(|| MeshError::Internal("empty wall chain".into()))?;
    let n = samples.count_of(first) as i64;
    let mut dir = 0i64;
    for w in chain.windows(2) {
        let (i, j) = (
            samples.index_of[w[0] as usize] as i64,
            samples.index_of[w[1] as usize] as i64,
        );
        let step = if (i + 1) % n == j {
            1
        } else if (j + 1) % n == i {
            -1
        } else {
            0
        };
        if step == 0 || (dir != 0 && step != dir) || samples.circle_of[w[1] as usize] != circle {
            return Err(MeshError::Internal(format!(
                "wall chain on circle {circle} is not a run of consecutive samples"
            )));
        }
        dir = step;
    }
    if dir != 0 && dir != expected {
        return Err(MeshError::Internal(format!(
            "wall on circle {circle} runs the wrong way round"
        )));
    }
    let steps = (chain.len() - 1) as f64;
    Ok(Curve::Arc {
        center: c.center,
        radius: c.radius,
        start: samples.angle(first),
        sweep: dir as f64 * steps * TAU / n as f64,
    })
}

/// Blocking2D (Algorithm 2) on a medial graph: the layout and, per layout vertex, the sample
/// it stands for.
pub fn blocks(
    domain: &Domain,
    samples: &Samples,
    medial: &MedialGraph,
) -> Result<(BlockLayout, Vec<Option<u32>>), MeshError> {
    let mut layout = BlockLayout {
        vertices: medial.vertices.iter().map(|v| v.position).collect(),
        edges: Vec::with_capacity(5 * medial.arcs.len()),
        blocks: Vec::with_capacity(2 * medial.arcs.len()),
    };
    let mut vertex_samples: Vec<Option<u32>> = vec![None; layout.vertices.len()];
    let mut sample_vertex: HashMap<u32, u32> = HashMap::new();
    let mut spokes: HashMap<(u32, u32), u32> = HashMap::new();

    let mut sample_vertex_of = |s: u32, layout: &mut BlockLayout| -> u32 {
        *sample_vertex.entry(s).or_insert_with(|| {
            layout.vertices.push(samples.points[s as usize]);
            vertex_samples.push(Some(s));
            (layout.vertices.len() - 1) as u32
        })
    };
    let add_edge = |layout: &mut BlockLayout, ends: [u32; 2], curve: Curve, kind| -> u32 {
        layout.edges.push(Edge { ends, curve, kind });
        (layout.edges.len() - 1) as u32
    };
    let mut spoke = |layout: &mut BlockLayout, mv: u32, s: u32, sv: u32| -> u32 {
        *spokes.entry((mv, s)).or_insert_with(|| {
            layout.edges.push(Edge {
                ends: [mv, sv],
                curve: Curve::Segment,
                kind: EdgeKind::Spoke,
            });
            (layout.edges.len() - 1) as u32
        })
    };
    let fwd = |edge| SideRef {
        edge,
        reversed: false,
    };
    let rev = |edge| SideRef {
        edge,
        reversed: true,
    };

    for arc in &medial.arcs {
        let [m0, m1] = arc.ends;
        let [ca, cb] = arc.circles;
        let ends = |c: &[u32]| match (c.first(), c.last()) {
            (Some(&f), Some(&l)) if (f.max(l) as usize) < samples.len() => Ok((f, l)),
            _ => Err(MeshError::Internal(
                "medial arc with an empty or out-of-range sample chain".into(),
            )),
        };
        let (a0, a1) = ends(&arc.c1)?;
        let (b0, b1) = ends(&arc.c2)?;
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
        let va0 = sample_vertex_of(a0, &mut layout);
        let va1 = sample_vertex_of(a1, &mut layout);
        let vb0 = sample_vertex_of(b0, &mut layout);
        let vb1 = sample_vertex_of(b1, &mut layout);
        let medial_edge = add_edge(
            &mut layout,
            [m0, m1],
            Curve::Polyline(arc.polyline.clone()),
            EdgeKind::Medial,
        );
        // Block on A: wall along C1 forward, fluid on the left.
        let expect = |c: CircleId| if c < 0 { 1 } else { -1 };
        let wall_a = wall_curve(domain, samples, ca, &arc.c1, expect(ca))?;
        let wall_a = add_edge(&mut layout, [va0, va1], wall_a, EdgeKind::Wall(ca));
        let s_a1 = spoke(&mut layout, m1, a1, va1);
        let s_a0 = spoke(&mut layout, m0, a0, va0);
        layout.blocks.push(Block {
            corners: [va0, va1, m1, m0],
            sides: [fwd(wall_a), rev(s_a1), rev(medial_edge), fwd(s_a0)],
            wall: Some(ca),
        });
        // Block on B: wall along C2 backward.
        let c2_back: Vec<u32> = arc.c2.iter().rev().copied().collect();
        let wall_b = wall_curve(domain, samples, cb, &c2_back, expect(cb))?;
        let wall_b = add_edge(&mut layout, [vb1, vb0], wall_b, EdgeKind::Wall(cb));
        let s_b0 = spoke(&mut layout, m0, b0, vb0);
        let s_b1 = spoke(&mut layout, m1, b1, vb1);
        layout.blocks.push(Block {
            corners: [vb1, vb0, m0, m1],
            sides: [fwd(wall_b), rev(s_b0), fwd(medial_edge), fwd(s_b1)],
            wall: Some(cb),
        });
    }
    Ok((layout, vertex_samples))
}
