//! Triangle classification and the approximate medial graph (paper section 2, Algorithm 1).
//!
//! Triangles of the Delaunay triangulation of the boundary samples are classified
//! combinatorially, from the circle of each vertex only:
//! - [`TriangleKind::Hole`]: three vertices on one hole (inside that hole);
//! - [`TriangleKind::Outside`]: three vertices on the bounding circle (not a triangle of the
//!   domain; cannot be Delaunay when a hole exists, reported as a sampling violation);
//! - in the domain: [`TriangleKind::Interior`] (no boundary edge), [`TriangleKind::Boundary`]
//!   (exactly one), [`TriangleKind::MultiBoundary`] (two or more: a sampling violation).
//!
//! A *boundary edge* joins two consecutive samples of one circle.
//!
//! Algorithm 1: medial vertices are the interior triangles, placed at their circumcentres;
//! a medial arc is the chain of boundary triangles met when walking from one interior
//! triangle through one of its edges until the next interior triangle. Under the sampling
//! invariants (a)-(c) ([`crate::sampling::check_invariants`]) every walk stays in the domain,
//! separates exactly two circles (the circles of the two ends of the crossed edges), and ends
//! at an interior triangle; each arc is found once. For `h >= 2` holes the graph has
//! `V = 2(h-1)` vertices and `E = 3(h-1)` arcs (Euler's formula on the triangulated domain,
//! DESIGN section 4).

use crate::domain::CircleId;
use crate::geometry::{Point, Triangulation};
use crate::mesher::MeshError;
use crate::sampling::Samples;

pub mod reuse;

/// The class of one Delaunay triangle (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TriangleKind {
    /// Three vertices on the bounding circle: not in the domain.
    Outside,
    /// Three vertices on this hole: inside it.
    Hole(CircleId),
    /// In the domain, no boundary edge: a medial vertex.
    Interior,
    /// In the domain, exactly one boundary edge, the one opposite vertex `edge` (0..3).
    Boundary { edge: u8 },
    /// In the domain with two or more boundary edges (breaks sampling invariant (b)).
    MultiBoundary,
}

impl TriangleKind {
    /// True for triangles of the domain (interior, boundary, or the invalid multi-boundary).
    pub fn in_domain(self) -> bool {
        matches!(
            self,
            TriangleKind::Interior | TriangleKind::Boundary { .. } | TriangleKind::MultiBoundary
        )
    }
}

/// Classify every triangle of `tri` (a triangulation of `samples.points`).
///
/// # Panics
/// When `tri` is not a triangulation of `samples.points` (an index out of range); the
/// pipeline ([`crate::sampling::sample_and_triangulate`]) always passes a matching pair.
pub fn classify(samples: &Samples, tri: &Triangulation) -> Vec<TriangleKind> {
    (0..tri.len())
        .map(|t| classify_one(samples, tri.triangle(t)))
        .collect()
}

/// The class of the triangle with vertices `v` (sample indices): a function of the circles,
/// indices on their circles and circle counts of its three samples only.
pub fn classify_one(samples: &Samples, v: [u32; 3]) -> TriangleKind {
    let c = v.map(|s| samples.circle_of[s as usize]);
    if c[0] == c[1] && c[1] == c[2] {
        // All samples of one circle are (nearly) co-circular; 3 vertices on a hole
        // means inside it.
        return if c[0] < 0 {
            TriangleKind::Outside
        } else {
            TriangleKind::Hole(c[0])
        };
    }
    let mut count = 0;
    let mut edge = 0u8;
    for k in 0..3 {
        if samples.is_boundary_edge(v[(k + 1) % 3], v[(k + 2) % 3]) {
            count += 1;
            edge = k as u8;
        }
    }
    match count {
        0 => TriangleKind::Interior,
        1 => TriangleKind::Boundary { edge },
        _ => TriangleKind::MultiBoundary,
    }
}

/// The circumcentre of triangle `abc`, computed relative to `a` with the determinant from
/// Shewchuk's adaptive `orient2d` (accurate sign and magnitude even for flat triangles).
/// Returns `None` for a degenerate (collinear) triangle or a non-finite result.
pub fn circumcenter(a: Point, b: Point, c: Point) -> Option<Point> {
    let det = robust::orient2d(
        robust::Coord { x: a[0], y: a[1] },
        robust::Coord { x: b[0], y: b[1] },
        robust::Coord { x: c[0], y: c[1] },
    );
    if det == 0.0 {
        return None;
    }
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let (cx, cy) = (c[0] - a[0], c[1] - a[1]);
    let b2 = bx * bx + by * by;
    let c2 = cx * cx + cy * cy;
    let den = 2.0 * det;
    let x = a[0] + (cy * b2 - by * c2) / den;
    let y = a[1] + (bx * c2 - cx * b2) / den;
    (x.is_finite() && y.is_finite()).then_some([x, y])
}

/// A medial vertex: an interior triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct MedialVertex {
    /// The interior triangle.
    pub triangle: u32,
    /// Its circumcentre.
    pub position: Point,
    /// Its three samples (counter-clockwise, as in the triangulation).
    pub samples: [u32; 3],
    /// The circles of those samples (three different circles).
    pub circles: [CircleId; 3],
}

/// A medial arc: the chain of boundary triangles between two interior triangles.
/// (`Default`: an empty placeholder, what a taken arc leaves.)
///
/// Orientation (paper Algorithm 2): the arc leaves `ends[0]` through the edge `(a, b)` of its
/// triangle, `a` on `circles[0]` (the paper's `C1` side) and `b` on `circles[1]` (`C2`).
/// Walking from `ends[0]` to `ends[1]`, `circles[0]` is on the right and `circles[1]` on the
/// left.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MedialArc {
    /// Medial vertex ids of its start and end.
    pub ends: [u32; 2],
    /// The slot (vertex index 0..3 opposite the crossed edge) in each end triangle.
    pub end_slots: [u8; 2],
    /// The boundary triangles between the ends, in walking order (empty for an arc between
    /// two adjacent interior triangles).
    pub triangles: Vec<u32>,
    /// Circumcentres from `ends[0]` to `ends[1]`, both included.
    pub polyline: Vec<Point>,
    /// The two circles it separates: `[C1 side, C2 side]`.
    pub circles: [CircleId; 2],
    /// `C1`: samples on `circles[0]` from the start triangle's vertex to the end triangle's.
    pub c1: Vec<u32>,
    /// `C2`: samples on `circles[1]` likewise.
    pub c2: Vec<u32>,
}

/// The approximate medial axis (paper Algorithm 1).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MedialGraph {
    pub vertices: Vec<MedialVertex>,
    pub arcs: Vec<MedialArc>,
}

impl MedialGraph {
    /// Number of medial vertices (interior triangles).
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }
    /// Number of medial arcs.
    pub fn arc_count(&self) -> usize {
        self.arcs.len()
    }
    /// Arcs of zero length (both ends at the same point), from co-circular interior
    /// triangles (paper section 4.2).
    pub fn zero_length_arcs(&self) -> usize {
        self.arcs
            .iter()
            .filter(|a| a.polyline.windows(2).all(|w| w[0] == w[1]))
            .count()
    }
}

fn internal(msg: String) -> MeshError {
    MeshError::Internal(msg)
}

/// Build the medial graph (paper Algorithm 1, traversed as in Algorithm 2) from a
/// triangulation of `samples` classified by `kinds` and meeting the sampling invariants.
/// Arcs are found in a deterministic order: interior triangles by index, then their edge
/// slots `0, 1, 2`. Errors are [`MeshError::Internal`] (a walk leaving the domain, which the
/// invariants exclude), never panics.
pub fn medial_graph(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
) -> Result<MedialGraph, MeshError> {
    let n = tri.len();
    if kinds.len() != n {
        return Err(internal(format!(
            "{} triangle kinds for {n} triangles",
            kinds.len()
        )));
    }
    if samples.len() != tri.points().len() || samples.circle_of.len() != samples.len() {
        return Err(internal(format!(
            "{} samples for a triangulation of {} points",
            samples.len(),
            tri.points().len()
        )));
    }
    let mut g = MedialGraph {
        vertices: medial_vertices(samples, tri, kinds)?,
        arcs: Vec::new(),
    };
    // The circumcentre of a walked triangle: no cache (issue 8: a per-triangle cache was
    // 24 bytes x 2 per sample, zeroed): a boundary triangle is walked through once (by the
    // one arc it belongs to), and an interior one's is its vertex's `position`, the same
    // computation on the same points.
    // The vertex of an interior triangle: vertices are in triangle order, so a binary search
    // (issue 8: a per-triangle table was 4 bytes per triangle of fresh memory, for 2 interior
    // triangles per hole among about 2 per sample).
    // Below three cells' worth of vertices the grid has one cell: the one-by-one walk, without
    // the parallel walk's bookkeeping.
    let parallel = (g.vertices.len() >= 3 * ARC_CHUNK)
        .then(|| medial_arcs_parallel(samples, tri, kinds, &g.vertices, ARC_CHUNK))
        .flatten();
    g.arcs = match parallel {
        Some(arcs) => arcs,
        None => medial_arcs_serial(samples, tri, kinds, &g.vertices)?,
    };
    Ok(g)
}

/// The medial vertices of [`medial_graph`]: the interior triangles in triangle order, with
/// their circumcentres. Triangles are read in parallel in fixed chunks of [`VERTEX_CHUNK`] and
/// the chunks joined in order, so the vertices, and the error (that of the first degenerate
/// interior triangle), are those of one pass in triangle order, for every thread count.
fn medial_vertices(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
) -> Result<Vec<MedialVertex>, MeshError> {
    use rayon::prelude::*;
    let chunks: Vec<Result<Vec<MedialVertex>, MeshError>> = kinds
        .par_chunks(VERTEX_CHUNK)
        .enumerate()
        .with_max_len(1)
        .map(|(ci, chunk)| {
            let mut out = Vec::new();
            for (k, kind) in chunk.iter().enumerate() {
                if *kind == TriangleKind::Interior {
                    let t = ci * VERTEX_CHUNK + k;
                    let v = tri.triangle(t);
                    let p = v.map(|s| samples.points[s as usize]);
                    let position = circumcenter(p[0], p[1], p[2])
                        .ok_or_else(|| internal(format!("interior triangle {t} is degenerate")))?;
                    out.push(MedialVertex {
                        triangle: t as u32,
                        position,
                        samples: v,
                        circles: v.map(|s| samples.circle_of[s as usize]),
                    });
                }
            }
            Ok(out)
        })
        .collect();
    let mut vertices =
        Vec::with_capacity(chunks.iter().map(|c| c.as_ref().map_or(0, Vec::len)).sum());
    for chunk in chunks {
        vertices.extend(chunk?);
    }
    Ok(vertices)
}

/// Triangles per parallel task of [`medial_vertices`].
const VERTEX_CHUNK: usize = 1 << 15;

/// The arcs of [`medial_graph`] walked one after the other ([`arcs_in_walk_order`]): the
/// reference of the parallel walk ([`arcs_in_walk_order_par`]), and the construction that
/// reports the error when the parallel walk finds anything wrong.
#[doc(hidden)]
pub fn medial_arcs_serial(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    vertices: &[MedialVertex],
) -> Result<Vec<MedialArc>, MeshError> {
    let vertex_of = |t: usize| vertex_of(vertices, kinds, t);
    let mut walk = Walk::default();
    arcs_in_walk_order(
        vertices.len(),
        |v0, k0| walk.arc(samples, tri, kinds, vertices, vertex_of, v0, k0),
        |v1, k1| internal(format!("medial arc into vertex {v1} slot {k1} found twice")),
    )
}

/// The arcs of [`medial_graph`] walked in parallel ([`arcs_in_walk_order_par`] with cells of
/// about `per_cell` vertices), `None` when the one-by-one walk ([`medial_arcs_serial`]) might
/// give anything else (an error). Public for the tests, which compare the two.
#[doc(hidden)]
pub fn medial_arcs_parallel(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
    vertices: &[MedialVertex],
    per_cell: usize,
) -> Option<Vec<MedialArc>> {
    let vertex_of = |t: usize| vertex_of(vertices, kinds, t);
    let positions: Vec<Point> = vertices.iter().map(|v| v.position).collect();
    arcs_in_walk_order_par(&positions, per_cell.max(1), |walk, v0, k0| {
        walk.arc(samples, tri, kinds, vertices, vertex_of, v0, k0)
    })
}

/// Vertices per parallel task of [`arcs_in_walk_order_par`] (on average: the tasks are the
/// cells of a square grid over the vertices).
///
/// Issue 8, measured with the pipeline on a pool worker (medians of the `medial_graph`
/// stage): 1e3 bubbles (2 000 vertices, one thread with cells of 2 048, the parallel walk
/// starting at three cells) 1.41 ms, 1.11 ms with cells of 512; 1e4 22.8 ms with 2048, 20.0 ms with 512; 1e5 alike within the noise.
/// The arcs are those of the one-by-one walk whatever the cells (tested).
const ARC_CHUNK: usize = 512;

/// [`arcs_in_walk_order`] with the walks done in parallel, `None` whenever the one-by-one
/// construction might differ (then the caller runs it, for its result or its error).
///
/// In the one-by-one walk each arc is walked from the smaller (in vertex then slot order) of
/// its two end slots, and the arcs come out in the order of that slot, provided every slot
/// ends exactly one arc. Here the vertices are cut into spatial cells (vertex ids, interior
/// triangle ids, carry no locality) of about `per_cell` vertices, and each cell does the
/// one-by-one walk on its own slots in increasing order; an arc ending in another cell is
/// kept when it starts at its smaller slot, else dropped (the other cell keeps it): only the
/// few arcs crossing a cell boundary are walked twice. The kept arcs are then put in
/// start-slot order. They are the one-by-one walk's when they cover every slot exactly once
/// (checked): by induction on the slots, the one-by-one walk then walks exactly the kept arcs,
/// from the same slots, with the same deterministic `arc_from`. Any walk error or slot met
/// twice gives `None`, so the result never depends on the thread count.
fn arcs_in_walk_order_par<E>(
    positions: &[Point],
    per_cell: usize,
    arc_from: impl Fn(&mut Walk, usize, usize) -> Result<MedialArc, E> + Sync,
) -> Option<Vec<MedialArc>> {
    use rayon::prelude::*;
    let n = positions.len();
    let cells = spatial_cells(positions, per_cell);
    let (cell_of, members) = (&cells.cell_of, &cells.members);
    let chunks: Vec<Option<Vec<MedialArc>>> = (0..cells.starts.len() - 1)
        .into_par_iter()
        .map(|c| {
            let own = &members[cells.starts[c] as usize..cells.starts[c + 1] as usize];
            let mut visited = vec![[false; 3]; own.len()];
            let local = |v: usize| own.binary_search(&(v as u32)).ok();
            let mut walk = Walk::default();
            let mut kept = Vec::with_capacity(3 * own.len() / 2 + 16);
            for (i0, &v0) in own.iter().enumerate() {
                for k0 in 0..3 {
                    if visited[i0][k0] {
                        continue;
                    }
                    visited[i0][k0] = true;
                    let arc = arc_from(&mut walk, v0 as usize, k0).ok()?;
                    let [v1, k1] = [arc.ends[1] as usize, arc.end_slots[1] as usize];
                    if k1 >= 3 || v1 >= n {
                        return None;
                    }
                    if cell_of[v1] as usize == c {
                        let i1 = local(v1)?;
                        if visited[i1][k1] {
                            return None;
                        }
                        visited[i1][k1] = true;
                        kept.push(arc);
                    } else if (v1, k1) > (v0 as usize, k0) {
                        kept.push(arc);
                    }
                }
            }
            Some(kept)
        })
        .collect();
    // Flat index + 1 (among the kept arcs, cell by cell) of the arc starting at each slot.
    let mut start = vec![[0u32; 3]; n];
    let mut covered = vec![[false; 3]; n];
    let mut total = 0u32;
    for chunk in &chunks {
        for arc in chunk.as_ref()? {
            for end in 0..2 {
                let (v, k) = (arc.ends[end] as usize, arc.end_slots[end] as usize);
                let slot = covered.get_mut(v)?.get_mut(k)?;
                if *slot {
                    return None;
                }
                *slot = true;
            }
            total += 1;
            start[arc.ends[0] as usize][arc.end_slots[0] as usize] = total;
        }
    }
    if 2 * total as usize != 3 * n {
        return None;
    }
    // The kept arcs in start-slot order: the place of each (by its flat index), then the
    // arcs moved there in parallel.
    let mut dest = vec![0u32; total as usize];
    let mut next = 0;
    for slots in &start {
        for &at in slots.iter().filter(|&&at| at != 0) {
            dest[at as usize - 1] = next;
            next += 1;
        }
    }
    let parts: Vec<Vec<MedialArc>> = chunks.into_iter().collect::<Option<_>>()?;
    crate::tasks::scatter(parts, &dest)
}

/// Points cut into the cells of a square grid over their bounding box, about `per_cell` a
/// cell on average: the cell of each point, and the points of cell `c` in increasing order at
/// `members[starts[c]..starts[c + 1]]`.
struct SpatialCells {
    cell_of: Vec<u32>,
    members: Vec<u32>,
    starts: Vec<u32>,
}

fn spatial_cells(points: &[Point], per_cell: usize) -> SpatialCells {
    let n = points.len();
    let side = ((n as f64 / per_cell as f64).sqrt().round() as usize).clamp(1, 1 << 10);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let index = |x: f64, d: usize| -> usize {
        let f = (x - lo[d]) / (hi[d] - lo[d]) * side as f64;
        if f.is_finite() {
            (f.max(0.0) as usize).min(side - 1)
        } else {
            0
        }
    };
    let cell_of: Vec<u32> = points
        .iter()
        .map(|p| (index(p[1], 1) * side + index(p[0], 0)) as u32)
        .collect();
    let mut starts = vec![0u32; side * side + 1];
    for &c in &cell_of {
        starts[c as usize + 1] += 1;
    }
    for c in 0..side * side {
        starts[c + 1] += starts[c];
    }
    let mut next = starts.clone();
    let mut members = vec![0u32; n];
    for (v, &c) in cell_of.iter().enumerate() {
        members[next[c as usize] as usize] = v as u32;
        next[c as usize] += 1;
    }
    SpatialCells {
        cell_of,
        members,
        starts,
    }
}

/// The arcs of a graph of `n` vertices in walking order: for each vertex slot `(v, k)` not yet
/// reached, in vertex then slot order, the arc `arc_from(v, k)` that starts there, whose far
/// end `(ends[1], end_slots[1])` is then reached too. Every slot ends exactly one arc, so the
/// result has `3n / 2` arcs; an arc into a slot already reached gives `Err(twice(v1, k1))`.
/// Shared by the full construction and the reusing one ([`reuse`]), which takes some arcs
/// from an earlier graph instead of walking them.
fn arcs_in_walk_order<E>(
    n: usize,
    mut arc_from: impl FnMut(usize, usize) -> Result<MedialArc, E>,
    twice: impl Fn(usize, usize) -> E,
) -> Result<Vec<MedialArc>, E> {
    let mut visited = vec![[false; 3]; n];
    let mut arcs = Vec::with_capacity(3 * n / 2);
    for v0 in 0..n {
        for k0 in 0..3 {
            if visited[v0][k0] {
                continue;
            }
            visited[v0][k0] = true;
            let arc = arc_from(v0, k0)?;
            let [v1, k1] = [arc.ends[1] as usize, arc.end_slots[1] as usize];
            if visited[v1][k1] {
                return Err(twice(v1, k1));
            }
            visited[v1][k1] = true;
            arcs.push(arc);
        }
    }
    Ok(arcs)
}

/// The vertex of triangle `t` among `vertices` (sorted by triangle), `u32::MAX` when it is not
/// an interior triangle.
fn vertex_of(vertices: &[MedialVertex], kinds: &[TriangleKind], t: usize) -> u32 {
    if kinds[t] != TriangleKind::Interior {
        return u32::MAX;
    }
    vertices
        .binary_search_by_key(&(t as u32), |v| v.triangle)
        .map_or(u32::MAX, |v| v as u32)
}

/// The buffers of one medial walk: the chains, polyline and triangles of the arc being
/// walked, copied out at exact length (issue 8: growing four fresh vectors per arc was several
/// reallocations each, and up to twice the memory).
#[derive(Debug, Default)]
pub(crate) struct Walk {
    c1: Vec<u32>,
    c2: Vec<u32>,
    polyline: Vec<Point>,
    chain: Vec<u32>,
}

impl Walk {
    /// The arc leaving medial vertex `v0` of `vertices` through edge slot `k0` of its triangle
    /// (Algorithm 1): `vertex_of(t)` is the vertex of interior triangle `t` (`u32::MAX` for
    /// none). Errors as [`medial_graph`]'s.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn arc(
        &mut self,
        samples: &Samples,
        tri: &Triangulation,
        kinds: &[TriangleKind],
        vertices: &[MedialVertex],
        vertex_of: impl Fn(usize) -> u32,
        v0: usize,
        k0: usize,
    ) -> Result<MedialArc, MeshError> {
        let n = tri.len();
        let cc = |t: usize| -> Result<Point, MeshError> {
            let v = vertex_of(t);
            if v != u32::MAX {
                return Ok(vertices[v as usize].position);
            }
            let v = tri.triangle(t);
            let p = v.map(|s| samples.points[s as usize]);
            circumcenter(p[0], p[1], p[2])
                .ok_or_else(|| internal(format!("triangle {t} is degenerate")))
        };
        let Walk {
            c1,
            c2,
            polyline,
            chain,
        } = self;
        let t0 = vertices[v0].triangle as usize;
        let tv = tri.triangle(t0);
        let (mut a, mut b) = (tv[(k0 + 1) % 3], tv[(k0 + 2) % 3]);
        c1.clear();
        c1.push(a);
        c2.clear();
        c2.push(b);
        polyline.clear();
        polyline.push(vertices[v0].position);
        chain.clear();
        let (mut t, mut slot) = (t0, k0);
        let mut steps = 0usize;
        let (v1, k1) = loop {
            steps += 1;
            if steps > n + 1 {
                return Err(internal(format!(
                    "medial walk from triangle {t0} does not end"
                )));
            }
            let nt = tri.neighbors(t)[slot].ok_or_else(|| {
                internal(format!(
                    "medial walk crossed the convex hull at triangle {t} edge {slot}"
                ))
            })? as usize;
            let w = tri.triangle(nt);
            // The mirror edge (b, a) in the CCW order of the next triangle: w = (p, b, a)
            // up to rotation.
            let kp = (0..3)
                .find(|&k| w[(k + 1) % 3] == b && w[(k + 2) % 3] == a)
                .ok_or_else(|| {
                    internal(format!("triangles {t} and {nt} do not share edge {a}-{b}"))
                })?;
            let p = w[kp];
            polyline.push(cc(nt)?);
            match kinds[nt] {
                TriangleKind::Interior => {
                    let v1 = vertex_of(nt);
                    if v1 == u32::MAX {
                        return Err(internal(format!("triangle {nt} has no medial vertex")));
                    }
                    break (v1, kp);
                }
                TriangleKind::Boundary { edge } => {
                    // lambda1 = (a, p) is opposite b (slot kp + 1), lambda2 = (p, b)
                    // is opposite a (slot kp + 2).
                    let (kb, ka) = ((kp + 1) % 3, (kp + 2) % 3);
                    if edge as usize == kb {
                        c1.push(p);
                        a = p;
                        slot = ka;
                    } else if edge as usize == ka {
                        c2.push(p);
                        b = p;
                        slot = kb;
                    } else {
                        return Err(internal(format!(
                            "medial walk entered triangle {nt} through its boundary edge"
                        )));
                    }
                    chain.push(nt as u32);
                    t = nt;
                }
                other => {
                    return Err(internal(format!(
                        "medial walk from triangle {t0} reached triangle {nt} of kind {other:?}"
                    )))
                }
            }
        };
        Ok(MedialArc {
            ends: [v0 as u32, v1],
            end_slots: [k0 as u8, k1 as u8],
            triangles: chain.to_vec(),
            polyline: polyline.to_vec(),
            circles: [
                samples.circle_of[c1[0] as usize],
                samples.circle_of[c2[0] as usize],
            ],
            c1: c1.to_vec(),
            c2: c2.to_vec(),
        })
    }
}
