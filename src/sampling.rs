//! Boundary sampling (paper section 2; DESIGN section 4).
//!
//! Every circle is sampled with `n` points, `n` a multiple of 8, counter-clockwise from angle 0:
//! sample `k` is `center + r * u_k` with `u_k` the unit vector at angle `2 pi k / n`. The unit
//! offsets are computed with `cos`/`sin` only in the first octant; the other octants are
//! exact reflections and swaps (see [`unit_offsets`]), so a layout mirror-symmetric about
//! `x = 0`, `y = 0` or a diagonal `y = +-x` gets bitwise mirror-symmetric sample coordinates,
//! and symmetric packings produce exact Delaunay ties (which the engine breaks and reports).
//!
//! The density of a circle is driven by its gap to its nearest neighbour (another hole or the
//! bounding circle), found with the k-d tree [`HoleIndex`] (no quadratic loop): the sample
//! spacing `2 pi r / n` is at most [`SamplingOptions::spacing_per_gap`] times that gap, within
//! `[min_per_circle, max_per_circle]`.
//!
//! After triangulation, [`check_invariants`] verifies the three conditions of DESIGN section 4:
//! (a) consecutive samples of a circle are joined by a Delaunay edge; (b) no in-domain triangle
//! has two boundary edges; (c) every interior triangle has its three vertices on three
//! different circles; and also that every triangle lies either inside one hole (three vertices
//! on it) or in the domain. [`sample_and_triangulate`] resamples offending circles (doubling
//! their count) until these hold, within bounded rounds and total samples.

use crate::domain::{circle_name, dist, CircleId, Domain, HoleIndex, BOUNDING};
use crate::geometry::{Point, Triangulation};
use crate::medial::{classify, medial_graph, MedialGraph, TriangleKind};
use crate::mesher::MeshError;
use std::collections::{HashMap, HashSet};
use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_4, TAU};

/// Tuning of the boundary sampling.
#[derive(Debug, Clone, PartialEq)]
pub struct SamplingOptions {
    /// Fewest samples on a circle (rounded up to a multiple of 8, at least 8).
    pub min_per_circle: usize,
    /// Most samples on a circle (rounded down to a multiple of 8).
    pub max_per_circle: usize,
    /// Target sample spacing as a multiple of the circle's nearest gap.
    pub spacing_per_gap: f64,
    /// Most samples in total; more is a [`MeshError::Sampling`].
    pub max_total: usize,
    /// Most resampling rounds after the first triangulation.
    pub max_rounds: usize,
}

impl Default for SamplingOptions {
    fn default() -> Self {
        SamplingOptions {
            min_per_circle: 32,
            max_per_circle: 1 << 14,
            spacing_per_gap: 1.0,
            max_total: 8_000_000,
            max_rounds: 4,
        }
    }
}

/// Where the samples of one circle live in [`Samples`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircleSamples {
    pub circle: CircleId,
    /// Index of its sample 0 in [`Samples::points`].
    pub first: u32,
    /// Number of samples (a multiple of 8).
    pub count: u32,
    /// The gap to its nearest neighbour that drove the density.
    pub gap: f64,
}

/// The boundary samples of all circles: the bounding circle's first, then the holes in order.
/// Sample `s` is the `index_of[s]`-th (counter-clockwise from angle 0) of circle
/// `circle_of[s]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    pub points: Vec<Point>,
    pub circle_of: Vec<CircleId>,
    pub index_of: Vec<u32>,
    /// Per circle, in slot order: slot 0 the bounding circle, slot `i + 1` hole `i`.
    pub circles: Vec<CircleSamples>,
}

/// Accessors taking a sample index or circle id panic when it is out of range, like slice
/// indexing.
impl Samples {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.points.len()
    }
    /// True when there is no sample.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
    /// The sampling of circle `id` (`-1` the bounding circle).
    pub fn of_circle(&self, id: CircleId) -> &CircleSamples {
        &self.circles[(id + 1) as usize]
    }
    /// The number of samples on the circle of sample `s`.
    pub fn count_of(&self, s: u32) -> u32 {
        self.of_circle(self.circle_of[s as usize]).count
    }
    /// The global index of sample `k` (taken mod the count) of circle `id`.
    pub fn sample(&self, id: CircleId, k: u32) -> u32 {
        let c = self.of_circle(id);
        c.first + k % c.count
    }
    /// The next sample counter-clockwise on the same circle.
    pub fn next(&self, s: u32) -> u32 {
        let c = self.of_circle(self.circle_of[s as usize]);
        c.first + (self.index_of[s as usize] + 1) % c.count
    }
    /// The previous sample (clockwise) on the same circle.
    pub fn prev(&self, s: u32) -> u32 {
        let c = self.of_circle(self.circle_of[s as usize]);
        c.first + (self.index_of[s as usize] + c.count - 1) % c.count
    }
    /// True when `a` and `b` are consecutive samples of one circle: the edge `ab` is a
    /// boundary edge (paper section 2).
    pub fn is_boundary_edge(&self, a: u32, b: u32) -> bool {
        self.circle_of[a as usize] == self.circle_of[b as usize]
            && a != b
            && (self.next(a) == b || self.next(b) == a)
    }
    /// The nominal angle `2 pi k / n` of sample `s` about its circle's centre.
    pub fn angle(&self, s: u32) -> f64 {
        TAU * self.index_of[s as usize] as f64 / self.count_of(s) as f64
    }
}

/// The `n` unit vectors at angles `2 pi k / n`, `k = 0..n`, for `n` a positive multiple of 8.
///
/// Only the first octant (`0 <= k <= n/8`) calls `cos`/`sin`; `u_{n/8}` is set to
/// `(1/sqrt 2, 1/sqrt 2)` exactly; the second octant swaps coordinates
/// (`u_{n/4 - k} = (y_k, x_k)`) and the other three quadrants rotate by exact quarter turns.
/// Hence `u_{n/2 - k} = (-x_k, y_k)`, `u_{n - k} = (x_k, -y_k)` and `u_{n/4 - k} = (y_k, x_k)`
/// hold bitwise. Returns an empty vector when `n` is not a positive multiple of 8.
pub fn unit_offsets(n: usize) -> Vec<Point> {
    if n == 0 || n % 8 != 0 {
        return Vec::new();
    }
    let m = n / 8;
    let mut u = vec![[0.0; 2]; n];
    for (k, uk) in u.iter_mut().enumerate().take(m + 1) {
        if k == m {
            *uk = [FRAC_1_SQRT_2, FRAC_1_SQRT_2];
        } else {
            let t = FRAC_PI_4 * (k as f64 / m as f64);
            *uk = [t.cos(), t.sin()];
        }
    }
    for k in m + 1..=2 * m {
        let [x, y] = u[2 * m - k];
        u[k] = [y, x];
    }
    for k in 2 * m + 1..n {
        let [x, y] = u[k - 2 * m];
        u[k] = [-y, x];
    }
    u
}

/// Each circle's gap to its nearest neighbour, in slot order (slot 0 the bounding circle,
/// slot `i + 1` hole `i`). Hole-hole gaps come from the k-d tree, so this is `O(h log h)`.
/// With no hole the bounding circle's "gap" is its radius.
pub fn nearest_gaps(domain: &Domain) -> Vec<f64> {
    let holes = domain.holes();
    let b = domain.bounding();
    let index = HoleIndex::new(holes);
    let mut gaps = Vec::with_capacity(holes.len() + 1);
    gaps.push(b.radius);
    let mut bmin = f64::INFINITY;
    for (i, h) in holes.iter().enumerate() {
        let to_bounding = b.radius - dist(h.center, b.center) - h.radius;
        bmin = bmin.min(to_bounding);
        let g = match index.nearest_gap(i) {
            Some((_, g)) => g.min(to_bounding),
            None => to_bounding,
        };
        gaps.push(g);
    }
    if !holes.is_empty() {
        gaps[0] = bmin;
    }
    gaps
}

/// Round `n` up to a multiple of 8 (at least 8), saturating.
fn round8(n: usize) -> usize {
    n.max(8).saturating_add(7) / 8 * 8
}

/// The initial sample count of each circle (slot order), from its radius and gap.
pub fn initial_counts(domain: &Domain, gaps: &[f64], opts: &SamplingOptions) -> Vec<usize> {
    let lo = round8(opts.min_per_circle);
    let hi = (opts.max_per_circle / 8 * 8).max(lo);
    domain
        .circle_ids()
        .zip(gaps)
        .map(|(id, &g)| {
            let r = domain.circle(id).radius;
            let spacing = opts.spacing_per_gap * g;
            let want = TAU * r / spacing;
            let n = if want.is_finite() && want > 0.0 {
                // `as` saturates; the clamp keeps it sane.
                want.ceil().min(hi as f64) as usize
            } else {
                hi
            };
            round8(n).clamp(lo, hi)
        })
        .collect()
}

/// Sample every circle with the given counts (slot order; each rounded up to a multiple of 8).
/// `gaps` (slot order, e.g. from [`nearest_gaps`]) is recorded in [`CircleSamples::gap`];
/// missing entries are recorded as NaN.
pub fn sample(domain: &Domain, counts: &[usize], gaps: &[f64]) -> Samples {
    let total: usize = counts.iter().map(|&n| round8(n)).sum();
    let mut s = Samples {
        points: Vec::with_capacity(total),
        circle_of: Vec::with_capacity(total),
        index_of: Vec::with_capacity(total),
        circles: Vec::with_capacity(counts.len()),
    };
    for (slot, (id, &n)) in domain.circle_ids().zip(counts).enumerate() {
        let n = round8(n);
        let g = gaps.get(slot).copied().unwrap_or(f64::NAN);
        let c = domain.circle(id);
        s.circles.push(CircleSamples {
            circle: id,
            first: s.points.len() as u32,
            count: n as u32,
            gap: g,
        });
        for (k, u) in unit_offsets(n).into_iter().enumerate() {
            s.points
                .push([c.center[0] + c.radius * u[0], c.center[1] + c.radius * u[1]]);
            s.circle_of.push(id);
            s.index_of.push(k as u32);
        }
    }
    s
}

/// What broke one of the sampling invariants.
#[derive(Debug, Clone, PartialEq)]
pub enum ViolationKind {
    /// (a) consecutive samples `from` and its successor are not joined by a Delaunay edge.
    MissingBoundaryEdge { from: u32 },
    /// (b) an in-domain triangle with two or three boundary edges.
    TwoBoundaryEdges { triangle: u32 },
    /// (c) an interior triangle with two vertices on one circle.
    InteriorRepeatsCircle { triangle: u32 },
    /// A triangle with all three vertices on the bounding circle (neither in a hole nor in
    /// the domain).
    Outside { triangle: u32 },
    /// Two samples coincide exactly (the circle is too small for its coordinates).
    Duplicate { first: u32, duplicate: u32 },
    /// Soft invariant (d): medial arc `arc` has a single sample on this circle's side, so
    /// one of its blocks has a zero-length wall.
    SingleSampleWall { arc: u32 },
}

/// One invariant violation, blamed on one circle.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    pub circle: CircleId,
    pub kind: ViolationKind,
}

impl Violation {
    /// A sentence for error messages.
    pub fn describe(&self) -> String {
        let who = circle_name(self.circle);
        match &self.kind {
            ViolationKind::MissingBoundaryEdge { from } => format!(
                "consecutive samples {from} and the next on {who} are not joined by a Delaunay edge"
            ),
            ViolationKind::TwoBoundaryEdges { triangle } => {
                format!("triangle {triangle} has two boundary edges on {who}")
            }
            ViolationKind::InteriorRepeatsCircle { triangle } => {
                format!("interior triangle {triangle} has two vertices on {who}")
            }
            ViolationKind::Outside { triangle } => {
                format!("triangle {triangle} has all three vertices on {who}")
            }
            ViolationKind::SingleSampleWall { arc } => {
                format!("medial arc {arc} has a single sample on {who}")
            }
            ViolationKind::Duplicate { first, duplicate } => format!(
                "samples {first} and {duplicate} of {who} coincide: the circle is too small \
                 for the precision of its coordinates"
            ),
        }
    }
}

/// Check the sampling invariants (a), (b), (c) and the in-hole/in-domain dichotomy on a
/// triangulation of `samples` whose triangles are classified by `kinds`
/// ([`crate::medial::classify`]). Returns every violation found (empty when all hold).
///
/// # Panics
/// When `tri` is not a triangulation of `samples.points` (see [`crate::medial::classify`]).
pub fn check_invariants(
    samples: &Samples,
    tri: &Triangulation,
    kinds: &[TriangleKind],
) -> Vec<Violation> {
    let mut out = Vec::new();
    for &(first, duplicate) in tri.duplicates() {
        out.push(Violation {
            circle: samples.circle_of[duplicate as usize],
            kind: ViolationKind::Duplicate { first, duplicate },
        });
    }
    // (a): mark the boundary edge starting at `a` (the edge a -> next(a)).
    let mut seen = vec![false; samples.len()];
    for t in 0..tri.len() {
        let v = tri.triangle(t);
        for k in 0..3 {
            let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            if samples.is_boundary_edge(a, b) {
                let from = if samples.next(a) == b { a } else { b };
                seen[from as usize] = true;
            }
        }
        let tt = t as u32;
        match kinds.get(t).copied().unwrap_or(TriangleKind::MultiBoundary) {
            TriangleKind::Outside => out.push(Violation {
                circle: BOUNDING,
                kind: ViolationKind::Outside { triangle: tt },
            }),
            TriangleKind::MultiBoundary => {
                // Blame the circle of a vertex shared by two boundary edges.
                let c = (0..3)
                    .find(|&k| {
                        let (p, q, r) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
                        samples.is_boundary_edge(p, q) && samples.is_boundary_edge(p, r)
                    })
                    .map(|k| samples.circle_of[v[k] as usize])
                    .unwrap_or(samples.circle_of[v[0] as usize]);
                out.push(Violation {
                    circle: c,
                    kind: ViolationKind::TwoBoundaryEdges { triangle: tt },
                });
            }
            TriangleKind::Interior => {
                let c = v.map(|s| samples.circle_of[s as usize]);
                let repeated = if c[0] == c[1] || c[0] == c[2] {
                    Some(c[0])
                } else if c[1] == c[2] {
                    Some(c[1])
                } else {
                    None
                };
                if let Some(c) = repeated {
                    out.push(Violation {
                        circle: c,
                        kind: ViolationKind::InteriorRepeatsCircle { triangle: tt },
                    });
                }
            }
            TriangleKind::Hole(_) | TriangleKind::Boundary { .. } => {}
        }
    }
    let duplicated: HashSet<u32> = tri.duplicates().iter().map(|&(_, d)| d).collect();
    for (s, &ok) in seen.iter().enumerate() {
        let s = s as u32;
        if !ok && !duplicated.contains(&s) && !duplicated.contains(&samples.next(s)) {
            out.push(Violation {
                circle: samples.circle_of[s as usize],
                kind: ViolationKind::MissingBoundaryEdge { from: s },
            });
        }
    }
    out
}

/// Soft invariant (d): every medial arc with at least one boundary triangle has a wall of at
/// least one sample step on both sides (`|C1|, |C2| >= 2`), so that every wall corner is shared
/// by exactly two blocks (paper section 3) and no block has a zero-length wall. An arc between
/// two adjacent interior triangles (empty chain) breaks it too, unless the two triangles are
/// exactly co-circular (a true degeneracy of the layout, paper section 4.2, left to arc
/// collapsing: resampling cannot remove it). Returns one violation per offending side.
pub fn thin_walls(tri: &Triangulation, medial: &MedialGraph) -> Vec<Violation> {
    let mut out = Vec::new();
    for (e, arc) in medial.arcs.iter().enumerate() {
        if arc.triangles.is_empty() {
            let Some(v0) = medial.vertices.get(arc.ends[0] as usize) else {
                continue;
            };
            if tri.is_cocircular_edge(v0.triangle as usize, arc.end_slots[0] as usize) {
                continue;
            }
        }
        for (side, chain) in [&arc.c1, &arc.c2].into_iter().enumerate() {
            if chain.len() < 2 {
                out.push(Violation {
                    circle: arc.circles[side],
                    kind: ViolationKind::SingleSampleWall { arc: e as u32 },
                });
            }
        }
    }
    out
}

/// How many doublings (1 to 4, or 0 for "do not refine") circle `circle` with `n` samples needs so that the wall of
/// `arc` on it spans at least two sample steps: the exact normal feet of the arc's two medial
/// vertices on the circle are `delta` radians apart (about the circle's centre), and a spacing
/// of `delta / 2` puts a sample strictly between the spokes. Depends only on the angle, so
/// mirror images ask for the same factor up to rounding at a power-of-two boundary (and the
/// group rule of [`sample_and_triangulate`] then takes the larger one for both).
fn refinement_log2(
    domain: &Domain,
    medial: &MedialGraph,
    arc: u32,
    circle: CircleId,
    n: usize,
) -> u32 {
    let Some(a) = medial.arcs.get(arc as usize) else {
        return 1;
    };
    let c = domain.circle(circle).center;
    let angle = |v: u32| {
        medial
            .vertices
            .get(v as usize)
            .map(|m| (m.position[1] - c[1]).atan2(m.position[0] - c[0]))
    };
    let (Some(t0), Some(t1)) = (angle(a.ends[0]), angle(a.ends[1])) else {
        return 1;
    };
    let delta = (t1 - t0).rem_euclid(TAU);
    let delta = delta.min(TAU - delta);
    let need = 2.0 * TAU / delta;
    if need.is_nan() || need > SOFT_MAX_SAMPLES {
        // A very short arc (nearly co-circular interior triangles): leave it to arc
        // collapsing rather than flood the circle with samples.
        return 0;
    }
    let mut k = 1;
    while k < 4 && (n as f64) * f64::from(1u32 << k) < need {
        k += 1;
    }
    k
}

/// The soft invariant (d) never asks for more samples than this on one circle: arcs whose
/// normal feet are less than `4 pi / SOFT_MAX_SAMPLES` (about 1.4 degrees) apart are left
/// with a single-sample wall (they are short arcs, for arc collapsing).
const SOFT_MAX_SAMPLES: f64 = 512.0;

/// The result of [`sample_and_triangulate`]: samples meeting the invariants, their Delaunay
/// triangulation, its classification and the medial graph (paper Algorithm 1).
#[derive(Debug, Clone)]
pub struct SampledDomain {
    pub samples: Samples,
    pub triangulation: Triangulation,
    pub kinds: Vec<TriangleKind>,
    pub medial: MedialGraph,
    /// Resampling rounds used (0 when the first sampling was good).
    pub rounds: usize,
    /// Violations of the soft invariant (d) ([`thin_walls`]) left when the rounds or the
    /// per-circle limit ran out; their blocks have a zero-length wall.
    pub thin_walls: Vec<Violation>,
}

/// Sample, triangulate, check the invariants, and resample offending circles until they
/// hold; then build the medial graph.
///
/// Hard invariants ((a)-(c) and the in-hole/in-domain dichotomy, [`check_invariants`]) must
/// hold; the soft invariant (d) ([`thin_walls`]) is pursued with the same resampling while
/// rounds remain, then accepted as is.
///
/// Resampling rule (keeps mirror symmetry): when circle `c` offends, every circle with the
/// same radius and nearest gap (bitwise) as `c` doubles its count. This depends only on
/// geometry, so mirror images are refined together. Errors: [`MeshError::Sampling`] when the
/// hard invariants still fail after [`SamplingOptions::max_rounds`] rounds or an offending
/// circle is already at [`SamplingOptions::max_per_circle`], when the total would exceed
/// [`SamplingOptions::max_total`], or when samples coincide (a circle too small for its
/// coordinates); [`MeshError::Triangulation`] from the engine; [`MeshError::Internal`] from
/// the medial graph (not expected once the invariants hold).
pub fn sample_and_triangulate(
    domain: &Domain,
    opts: &SamplingOptions,
) -> Result<SampledDomain, MeshError> {
    let gaps = nearest_gaps(domain);
    let mut counts = initial_counts(domain, &gaps, opts);
    let cap = (opts.max_per_circle / 8 * 8).max(round8(opts.min_per_circle));
    let radii: Vec<f64> = domain
        .circle_ids()
        .map(|c| domain.circle(c).radius)
        .collect();
    let mut round = 0;
    loop {
        let total: usize = counts.iter().sum();
        if total > opts.max_total {
            let worst = counts
                .iter()
                .enumerate()
                .max_by_key(|&(_, &n)| n)
                .map(|(i, _)| i as CircleId - 1)
                .unwrap_or(BOUNDING);
            return Err(MeshError::Sampling {
                circle: worst,
                message: format!(
                    "{total} samples would be needed in total, more than the limit {}",
                    opts.max_total
                ),
            });
        }
        let samples = sample(domain, &counts, &gaps);
        let triangulation = Triangulation::new(&samples.points)?;
        let kinds = classify(&samples, &triangulation);
        let hard = check_invariants(&samples, &triangulation, &kinds);
        let (violations, soft_result) = if hard.is_empty() {
            let medial = medial_graph(&samples, &triangulation, &kinds)?;
            let soft = thin_walls(&triangulation, &medial);
            let done = SampledDomain {
                samples,
                triangulation,
                kinds,
                medial,
                rounds: round,
                thin_walls: soft.clone(),
            };
            if soft.is_empty() || round >= opts.max_rounds {
                return Ok(done);
            }
            (soft, Some(done))
        } else {
            if let Some(v) = hard
                .iter()
                .find(|v| matches!(v.kind, ViolationKind::Duplicate { .. }))
            {
                return Err(MeshError::Sampling {
                    circle: v.circle,
                    message: v.describe(),
                });
            }
            if round >= opts.max_rounds {
                return Err(MeshError::Sampling {
                    circle: hard[0].circle,
                    message: format!(
                        "{} ({} invariant violations left after {round} resampling rounds)",
                        hard[0].describe(),
                        hard.len()
                    ),
                });
            }
            (hard, None)
        };
        // Refinement factor 2^k per (radius, gap) group, the largest any member needs.
        let mut keys: HashMap<(u64, u64), u32> = HashMap::new();
        for v in &violations {
            let slot = (v.circle + 1) as usize;
            let k = match (&v.kind, &soft_result) {
                (ViolationKind::SingleSampleWall { arc }, Some(done)) => {
                    refinement_log2(domain, &done.medial, *arc, v.circle, counts[slot])
                }
                _ => 1,
            };
            let e = keys
                .entry((radii[slot].to_bits(), gaps[slot].to_bits()))
                .or_insert(k);
            *e = (*e).max(k);
        }
        let mut refined = false;
        for slot in 0..counts.len() {
            if let Some(&k) = keys.get(&(radii[slot].to_bits(), gaps[slot].to_bits())) {
                if counts[slot] >= cap {
                    if soft_result.is_none() {
                        return Err(MeshError::Sampling {
                            circle: slot as CircleId - 1,
                            message: format!(
                                "{} and the circle already has the most samples allowed ({cap})",
                                violations[0].describe()
                            ),
                        });
                    }
                } else if k > 0 {
                    counts[slot] = counts[slot].saturating_mul(1 << k).min(cap);
                    refined = true;
                }
            }
        }
        if !refined {
            if let Some(done) = soft_result {
                return Ok(done);
            }
        }
        round += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_are_unit_and_symmetric() {
        for n in [8, 16, 24, 32, 64, 200, 1024] {
            let u = unit_offsets(n);
            assert_eq!(u.len(), n);
            assert_eq!(u[0], [1.0, 0.0]);
            for k in 0..n {
                let [x, y] = u[k];
                assert!((x.hypot(y) - 1.0).abs() < 4e-16);
                let t = TAU * k as f64 / n as f64;
                assert!((x - t.cos()).abs() < 1e-15 && (y - t.sin()).abs() < 1e-15);
                assert_eq!(u[(n / 2 + n - k) % n], [-x, y]);
                assert_eq!(u[(n - k) % n], [x, -y]);
                assert_eq!(u[(n / 4 + n - k) % n], [y, x]);
            }
        }
        assert!(unit_offsets(12).is_empty());
        assert!(unit_offsets(0).is_empty());
    }

    #[test]
    fn counts_are_multiples_of_8() {
        let d = Domain::hexagon_example();
        let gaps = nearest_gaps(&d);
        assert_eq!(gaps.len(), 8);
        // The bounding circle (radius sqrt(3) - 0.3) to the outer holes, and hole to hole.
        assert!((gaps[0] - (3f64.sqrt() - 1.6)).abs() < 1e-12);
        assert!((gaps[1] - 0.4).abs() < 1e-12);
        let counts = initial_counts(&d, &gaps, &SamplingOptions::default());
        assert!(counts.iter().all(|&n| n % 8 == 0 && n >= 32));
        let s = sample(&d, &counts, &gaps);
        assert_eq!(s.len(), counts.iter().sum::<usize>());
        for (i, c) in s.circles.iter().enumerate() {
            assert_eq!(c.circle, i as CircleId - 1);
            let f = c.first;
            assert_eq!(s.next(f + c.count - 1), f);
            assert_eq!(s.prev(f), f + c.count - 1);
            assert!(s.is_boundary_edge(f, f + 1));
            assert!(!s.is_boundary_edge(f, f + 2));
        }
    }
}
