//! Periodic domains (tracker issue 6): mesh one period of a rectangle `Lx x Ly` repeated
//! over the plane, so that copies of the mesh tile the plane (paper section 5, Bubble data).
//!
//! # Method
//! 1. Tiling: the canonical copies of the holes (centres in `[0, Lx) x [0, Ly)`) are
//!    repeated over an `Nx x Ny` array of tiles, `N = 2m + 1` per axis (`m = [1, 1]` first:
//!    the paper's three-by-three tiling), inside an auxiliary bounding circle centred on the
//!    box and enclosing the whole array. Circle `(k, a, b)` is hole `k` moved by
//!    `(a Lx, b Ly)`. A box with many holes takes only a *band* of that array: the copies
//!    whose centres are within a reach of the box (`initial_reach`: three radii and four
//!    radii of the mean empty area per hole, per axis; the whole array from a period on).
//!    Issue 8: 1 000 holes had 9 000 circles to sample, triangulate and block; the band has
//!    about 1 400. Step 4 below checks the band like the array and grows it (`next_extent`).
//! 2. Exactly periodic sampling: the canonical copy of hole `k` is sampled adaptively (as in
//!    bounded domains, [`crate::sampling::sample_adaptive`]: densely only where a circle is
//!    close), every copy gets the same samples (densities and resampling act on whole orbits
//!    `{(k, a, b)}`), and the samples of copy
//!    `(a, b)` are the canonical samples plus `(a Lx', b Ly')`, where the canonical samples
//!    and `Lx', Ly'` are rounded to a common dyadic quantum (about `2^-50` of the array's
//!    extent) so that these sums are exact. The exact Delaunay triangulation with its
//!    translation-invariant symbolic perturbation (lexicographic rank) then triangulates
//!    every copy of a configuration identically, ties included.
//! 3. Blocking2D on the tiling, then keep exactly the blocks whose wall is a canonical copy:
//!    each hole's *cell*. On the torus `V = 2h` medial vertices, `E = 3h` arcs, so the kept
//!    blocks number `2E = 6h`. Their union is one period with a zig-zag boundary.
//! 4. Safety check: every Delaunay triangle the kept blocks use (medial vertices and the
//!    triangles along their arcs) must have its circumcircle inside the array (or band)
//!    shrunk by the largest radius, so that no sample missing from the finite tiling (or of
//!    the auxiliary bounding circle) could lie in it: then it is a triangle of the infinite
//!    periodic triangulation. A band too narrow for them grows first (by at least half, into
//!    the whole array once it would reach a period). Otherwise the array grows per axis to
//!    the half-widths that hold every offending circle (`next_tiling`; a kept arc on the
//!    auxiliary circle grows both axes by half), at most [`MAX_ARRAY_SIDE`] long periods a
//!    side: an elongated box with few holes has empty circles spanning many short periods,
//!    and gets many copies along its short side only. Beyond that, or beyond the sample
//!    limit, the domain is refused with [`MeshError::Tiling`].
//! 5. Geometry by orbits: medial vertices and arcs are identified up to translation by their
//!    sample triples (`(hole, sample index, tile)`, normalised). Every instance's geometry
//!    is its orbit representative's plus the period shift (in the true `Lx`, `Ly`), so both
//!    copies of a zig-zag side are translates by construction. A kept medial side whose other
//!    circle is not canonical becomes an [`EdgeKind::Periodic`] edge naming its partner (the
//!    same arc seen from the other circle's canonical cell) and the translation; the grid
//!    stage gives partners equal cell counts and copies the nodes.
//!
//! # Refinement (exact mode)
//! Macro Delaunay refinement runs on the torus too (`refine_periodic`): poor vertex orbits
//! get fluid holes at their empty circles' centres, appended to the domain's holes and
//! filled by templates ([`exact_mode::periodic::build_with_inserted`]); when the refined
//! layout gives no valid exact mesh, the unrefined one is meshed. A round asks the sampled
//! medial graph first (`poor::medial_poor`, as bounded refinement does) and extracts the
//! layout only when the graph has no poor vertex orbit; every round's first tiling is the
//! first round's band of copies, so that a round's triangulation extends the round before's
//! (`extended_or_new`).
//!
//! Wall corners are placed on the true circles; only the medial geometry comes from the
//! quantised samples (an error of the order of `1e-14` of the period). That is paper mode
//! (`--mode paper`). In exact mode (the default) the same orbits are handed to
//! [`crate::exact_mode::periodic`] as a [`PeriodicBlocking`]: exact geometry per orbit,
//! computed once and translated; see [`mesh_periodic`] for the fallback rule.
//!
//! # Degeneracy (issue 4 on the torus)
//! Co-circular hole groups are the rule here (one hole in a box, square lattices, holes on
//! the box's edges): before Blocking2D the zero-length medial arcs, and arcs shorter than
//! [`Options::collapse_fraction`] of the local radius, are collapsed ([`collapse::contract`])
//! in every copy alike. Arcs are chosen per orbit on the torus (`select_collapse`: exact
//! geometry of the orbit representative decides, clusters are tracked with translations so
//! that no cycle of the torus is contracted), and a contracted vertex is identified up to
//! translation by the samples of its members, so its instances are again the orbit
//! representative plus a period shift; exact mode gets those contracted vertices as vertex
//! orbits of degree `n` (`exact_input_clusters`), so periodic arrays of cylinders and one hole
//! in a box are meshed in exact geometry. Blocks: `6h - 2 collapsed`; [`Mesh::collapsed_arcs`]
//! counts collapsed arc orbits and [`Mesh::cocircular_groups`] lists one group per orbit
//! (canonical hole ids, one entry per tangent image; centre wrapped into the box).

pub mod domain;
mod poor;

pub use domain::{tile_array, tile_offsets, wrap, PeriodicDomain};

use crate::apollonius::{same_circle, Apollonius};
use crate::blocking;
use crate::cocircular::{self, CocircularGroup};
use crate::collapse;
use crate::domain::{Circle, CircleId, Domain};
use crate::exact_mode;
use crate::exact_mode::imposed::BlockKey;
use crate::exact_mode::periodic::{PeriodicArc, PeriodicBlocking, PeriodicVertex};
use crate::geometry::{Point, Triangulation};
use crate::grid::build_grids;
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef, Translation};
use crate::medial::{circumcenter, medial_graph, reuse, MedialGraph, TriangleKind};
use crate::mesh::Mesh;
use crate::mesher::{MeshError, Mode, Options, EXACT_RESAMPLING};
use crate::sampling::{
    initial_counts, thin_walls, unit_offset, unit_offsets, CircleSamples, Samples, SamplingOptions,
    ViolationKind,
};
use crate::timings;
use rayon::prelude::*;
/// Hash maps with a fast hasher (issue 8: SipHash of the orbit keys was 4% of a periodic
/// mesh); nothing reads them in iteration order.
type HashMap<K, V> = std::collections::HashMap<K, V, foldhash::fast::RandomState>;

/// Most samples on the auxiliary bounding circle of the periodic tiling (sampled uniformly;
/// the holes are sampled adaptively within [`SamplingOptions::max_per_circle`]).
pub const PERIODIC_MAX_PER_CIRCLE: usize = 1 << 14;

/// Longest side of the array of copies, in periods of the longer side `max(Lx, Ly)`: a square
/// box gets at most `7 x 7` copies, a box of aspect ratio `A` up to `7 A` copies along its
/// short side (the tiling grows per axis, `next_tiling`).
pub const MAX_ARRAY_SIDE: f64 = 7.0;

/// Most tilings tried before a periodic domain is refused.
const MAX_TILING_ROUNDS: usize = 8;

/// `(hole, sample index, tile a, tile b)`.
type SampleKey = (u32, u32, i32, i32);
/// A medial vertex up to nothing: its Delaunay triangle's samples, sorted.
type VertexKey = [SampleKey; 3];
/// An arc orbit's two ends: `(vertex orbit, shift)`.
type OrbitEnds = [(usize, (i32, i32)); 2];
/// `(hole, tile a, tile b)`.
type CircleKey = (u32, i32, i32);
/// A medial arc: its two circles and two end vertices, each pair sorted.
type ArcKey = ([CircleKey; 2], [VertexKey; 2]);

fn shift_sample(s: SampleKey, d: (i32, i32)) -> SampleKey {
    (s.0, s.1, s.2 + d.0, s.3 + d.1)
}

fn shift_vertex(v: &VertexKey, d: (i32, i32)) -> VertexKey {
    let mut out = v.map(|s| shift_sample(s, d));
    out.sort_unstable();
    out
}

fn shift_arc(a: &ArcKey, d: (i32, i32)) -> ArcKey {
    let mut c = a.0.map(|c| (c.0, c.1 + d.0, c.2 + d.1));
    c.sort_unstable();
    let mut v = [shift_vertex(&a.1[0], d), shift_vertex(&a.1[1], d)];
    v.sort_unstable();
    (c, v)
}

/// The least of `shifted(d)` over the distinct tile shifts `d = shift(item)` of `items`, with
/// its shift; `None` without items. Each shift is tried once (issue 8: the samples of a vertex
/// are mostly in one tile, and a try can build and sort a key); items with the same shift
/// give the same candidate, so the least is that of trying every item (ties keep the first).
fn least_over_shifts<T, K: Ord>(
    items: &[T],
    shift: impl Fn(&T) -> (i32, i32),
    shifted: impl Fn((i32, i32)) -> K,
) -> Option<(K, (i32, i32))> {
    let mut best: Option<(K, (i32, i32))> = None;
    for (i, item) in items.iter().enumerate() {
        let d = shift(item);
        if items[..i].iter().any(|x| shift(x) == d) {
            continue;
        }
        let candidate = (shifted(d), d);
        if best.as_ref().is_none_or(|b| candidate < *b) {
            best = Some(candidate);
        }
    }
    best
}

/// The orbit representative of a vertex key and the shift from it: `key = rep + shift`,
/// the least of the key moved back by each of its samples' tile shifts.
fn normalise_vertex(v: &VertexKey) -> (VertexKey, (i32, i32)) {
    least_over_shifts(v, |s| (s.2, s.3), |d| shift_vertex(v, (-d.0, -d.1))).unwrap_or((*v, (0, 0)))
}

/// The orbit representative of an arc key and the shift from it: the least of the key moved
/// back by the tile shift of either circle.
fn normalise_arc(a: &ArcKey) -> (ArcKey, (i32, i32)) {
    least_over_shifts(&a.0, |c| (c.1, c.2), |d| shift_arc(a, (-d.0, -d.1))).unwrap_or((*a, (0, 0)))
}

/// The auxiliary tiled domain of half-widths `m = [mx, my]`: the copies of the holes in the
/// `(2 mx + 1) x (2 my + 1)` tiles whose centres are within `reach` of the box (issue 8: a box
/// with many holes needs only a band of copies around it, not eight more boxes).
struct Tiling {
    m: [i32; 2],
    n: [i32; 2],
    h: usize,
    size: [f64; 2],
    /// Per axis, the distance beyond the box `[0, L]` within which every copy's centre is in
    /// the tiling: `m L` when the whole array is (a *full* axis), less for a band.
    reach: [f64; 2],
    /// Per axis, whether the tiling is a band along it (not the whole array).
    band: [bool; 2],
    domain: Domain,
    /// Hole id of copy `(a, b)` of hole `k` at `k n0 n1 + (a + m0) n1 + b + m1`, or -1 when
    /// the copy is outside the reach.
    ids: Vec<CircleId>,
    /// `(hole, a, b)` of each hole id, increasing (ids are given in that order).
    keys: Vec<CircleKey>,
    /// Per hole, the number of its copies in the tiling.
    copies: Vec<usize>,
    /// Quantum and quantised periods.
    quantum: f64,
    lq: [f64; 2],
}

impl Tiling {
    /// Every copy of the `(2 mx + 1) x (2 my + 1)` array.
    #[cfg(test)]
    fn new(pd: &PeriodicDomain, m: [i32; 2]) -> Result<Tiling, MeshError> {
        let size = pd.size();
        Tiling::with_reach(pd, m, [0, 1].map(|a| m[a] as f64 * size[a]))
    }

    /// The copies of the array of half-widths `m` whose centres are within `reach` of the
    /// box; an axis with `reach >= m L` takes the whole array (no test on the centres).
    fn with_reach(pd: &PeriodicDomain, m: [i32; 2], reach: [f64; 2]) -> Result<Tiling, MeshError> {
        let size = pd.size();
        let n = [2 * m[0] + 1, 2 * m[1] + 1];
        let h = pd.hole_count();
        let max_l = size[0].max(size[1]);
        let full = [0, 1].map(|a| reach[a] >= m[a] as f64 * size[a]);
        let reach = [0, 1].map(|a| {
            if full[a] {
                m[a] as f64 * size[a]
            } else {
                reach[a]
            }
        });
        let per_hole = (n[0] * n[1]) as usize;
        let mut holes = Vec::with_capacity(h * per_hole);
        let mut ids = vec![-1; h * per_hole];
        let mut keys = Vec::with_capacity(h * per_hole);
        let mut copies = vec![0; h];
        for (k, c) in pd.holes().iter().enumerate() {
            for (j, (a, b)) in tile_array(m).enumerate() {
                let center = [
                    c.center[0] + a as f64 * size[0],
                    c.center[1] + b as f64 * size[1],
                ];
                let within = (0..2).all(|x| {
                    full[x] || (-reach[x] <= center[x] && center[x] <= size[x] + reach[x])
                });
                if within || (a, b) == (0, 0) {
                    ids[k * per_hole + j] = holes.len() as CircleId;
                    keys.push((k as u32, a, b));
                    copies[k] += 1;
                    holes.push(Circle {
                        center,
                        radius: c.radius,
                    });
                }
            }
        }
        let side = |a: usize| {
            if full[a] {
                n[a] as f64 * size[a]
            } else {
                size[a] + 2.0 * reach[a]
            }
        };
        let half = 0.5 * side(0).hypot(side(1));
        let bounding = Circle {
            center: [0.5 * size[0], 0.5 * size[1]],
            radius: half + max_l,
        };
        let domain = Domain::bounded(bounding, holes).map_err(|e| {
            MeshError::Internal(format!("the tiled periodic domain is invalid: {e}"))
        })?;
        // The quantum of the whole array (a band of it is quantised alike).
        let whole = 0.5 * (n[0] as f64 * size[0]).hypot(n[1] as f64 * size[1]) + max_l;
        let extent = (m[0] as f64 * size[0]).max(m[1] as f64 * size[1]) + 2.0 * max_l + whole;
        let e = extent.log2().ceil();
        let quantum = 2f64.powi(e as i32 - 50);
        if !(quantum.is_normal() && e.is_finite()) {
            return Err(MeshError::Options(format!(
                "the period {} is too small or too large to mesh",
                crate::numfmt::NumPair(size)
            )));
        }
        let q = |x: f64| (x / quantum).round() * quantum;
        Ok(Tiling {
            m,
            n,
            h,
            size,
            reach,
            band: full.map(|f| !f),
            domain,
            ids,
            keys,
            copies,
            quantum,
            lq: [q(size[0]), q(size[1])],
        })
    }

    fn q(&self, x: f64) -> f64 {
        (x / self.quantum).round() * self.quantum
    }

    /// Circle id of copy `(a, b)` of hole `k` (-1 when that copy is not in the tiling; the
    /// canonical copy `(0, 0)` always is).
    fn id(&self, k: usize, a: i32, b: i32) -> CircleId {
        if a.abs() > self.m[0] || b.abs() > self.m[1] {
            return -1;
        }
        let j = ((a + self.m[0]) * self.n[1] + (b + self.m[1])) as usize;
        self.ids
            .get(k * (self.n[0] * self.n[1]) as usize + j)
            .copied()
            .unwrap_or(-1)
    }

    /// `(hole, a, b)` of a hole id of the tiling (`None` for the bounding circle).
    fn key(&self, id: CircleId) -> Option<CircleKey> {
        if id < 0 {
            return None;
        }
        self.keys.get(id as usize).copied()
    }

    /// Samples of the tiling: `plans[k]` the grid size and grid indices of hole `k`'s
    /// canonical copy (adaptive, [`crate::sampling::adaptive_grids`]), copied onto every
    /// copy of the orbit (quantised points plus the quantised period shift: exact sums);
    /// `bounding_count` uniform samples on the bounding circle.
    fn samples(&self, plans: &[(u64, Vec<u64>)], bounding_count: usize, gaps: &[f64]) -> Samples {
        let mut s = Samples::default();
        let b = self.domain.bounding();
        let push_circle =
            |s: &mut Samples, id: CircleId, pts: Vec<Point>, grid: &[u64], n: u64, gap: f64| {
                s.circles.push(CircleSamples {
                    circle: id,
                    first: s.points.len() as u32,
                    count: pts.len() as u32,
                    gap,
                });
                s.grid_counts.push(n);
                s.grid.extend_from_slice(grid);
                for (i, p) in pts.into_iter().enumerate() {
                    s.points.push(p);
                    s.circle_of.push(id);
                    s.index_of.push(i as u32);
                }
            };
        let bpts: Vec<Point> = unit_offsets(bounding_count)
            .into_iter()
            .map(|u| [b.center[0] + b.radius * u[0], b.center[1] + b.radius * u[1]])
            .collect();
        let bgrid: Vec<u64> = (0..bpts.len() as u64).collect();
        let bgap = gaps.first().copied().unwrap_or(f64::NAN);
        push_circle(&mut s, -1, bpts, &bgrid, bounding_count as u64, bgap);
        // The canonical copies' samples, then every copy's, in parallel (issue 8: 0.15-0.18 s
        // on one thread at 1e5 holes): each copy's slice of the arrays starts at the sum of
        // the counts before it.
        let canon: Vec<Vec<Point>> = (0..self.h)
            .into_par_iter()
            .map(|k| {
                let c = self.domain.holes()[self.id(k, 0, 0) as usize];
                let (n, ks) = &plans[k];
                ks.iter()
                    .map(|&g| {
                        let u = unit_offset(g, *n);
                        [
                            self.q(c.center[0] + c.radius * u[0]),
                            self.q(c.center[1] + c.radius * u[1]),
                        ]
                    })
                    .collect()
            })
            .collect();
        let base = s.points.len();
        let lens: Vec<usize> = self
            .keys
            .iter()
            .map(|&(k, _, _)| plans[k as usize].1.len())
            .collect();
        let mut total = base;
        for (id, &(k, _, _)) in self.keys.iter().enumerate() {
            let k = k as usize;
            s.circles.push(CircleSamples {
                circle: id as CircleId,
                first: total as u32,
                count: lens[id] as u32,
                gap: gaps.get(k + 1).copied().unwrap_or(f64::NAN),
            });
            s.grid_counts.push(plans[k].0);
            total += lens[id];
        }
        s.points.resize(total, [0.0; 2]);
        s.circle_of.resize(total, 0);
        s.index_of.resize(total, 0);
        s.grid.resize(total, 0);
        // Split the arrays after the bounding circle into one slice per copy.
        fn split<'a, T>(mut rest: &'a mut [T], lens: &[usize]) -> Vec<&'a mut [T]> {
            let mut out = Vec::with_capacity(lens.len());
            for &n in lens {
                let (head, tail) = std::mem::take(&mut rest).split_at_mut(n);
                out.push(head);
                rest = tail;
            }
            out
        }
        let points = split(&mut s.points[base..], &lens);
        let circle_of = split(&mut s.circle_of[base..], &lens);
        let index_of = split(&mut s.index_of[base..], &lens);
        let grid = split(&mut s.grid[base..], &lens);
        points
            .into_par_iter()
            .zip(circle_of)
            .zip(index_of)
            .zip(grid)
            .enumerate()
            .for_each(|(id, (((pts, of), idx), grid))| {
                let (k, a, bb) = self.keys[id];
                let k = k as usize;
                let (dx, dy) = (a as f64 * self.lq[0], bb as f64 * self.lq[1]);
                for (i, p) in canon[k].iter().enumerate() {
                    pts[i] = [p[0] + dx, p[1] + dy];
                    of[i] = id as CircleId;
                    idx[i] = i as u32;
                }
                grid.copy_from_slice(&plans[k].1);
            });
        s
    }
}

/// Sampling, triangulation and medial graph of the tiling with orbit-uniform densities.
///
/// Every hole's canonical copy is sampled adaptively (issue 8: samples only where a circle
/// is close, as in bounded domains; uniform sampling put up to 16 384 samples on every copy
/// of a near-touching hole and took seconds to triangulate) and its samples are copied onto
/// the whole orbit, so every copy is sampled alike. A violated sampling invariant doubles
/// the density of the orbits it touches (while they stay within the per-circle limit).
///
/// With `uniform` (paper mode, whose circumcentre polylines follow the samples: adaptive
/// samples made them rougher, with more inverted cells) every orbit is sampled uniformly
/// instead: `2 pi r / gap` samples from its nearest gap, doubled on violations, at most
/// [`PERIODIC_MAX_PER_CIRCLE`].
fn sample_tiling(
    t: &Tiling,
    gaps_canonical: &[f64],
    opts: &SamplingOptions,
    uniform: bool,
    previous: Option<&Sampled>,
) -> Result<(Samples, Triangulation, Vec<TriangleKind>, MedialGraph), MeshError> {
    let b = t.domain.bounding();
    let bgap = t
        .domain
        .holes()
        .iter()
        .map(|h| b.radius - crate::domain::dist(h.center, b.center) - h.radius)
        .fold(f64::INFINITY, f64::min);
    let mut slot_gaps = vec![bgap];
    slot_gaps.extend(
        t.keys
            .iter()
            .map(|&(k, _, _)| gaps_canonical.get(k as usize).copied().unwrap_or(f64::NAN)),
    );
    // The auxiliary bounding circle: uniform, with the cap the uniform sampler had.
    let bounding_opts = SamplingOptions {
        max_per_circle: opts.max_per_circle.min(PERIODIC_MAX_PER_CIRCLE),
        ..opts.clone()
    };
    let mut bcount = initial_counts(&t.domain, &slot_gaps[..1], &bounding_opts)[0];
    let bcap = (bounding_opts.max_per_circle / 8 * 8).max(8);
    let canonical_slot = |k: usize| t.id(k, 0, 0) as usize + 1;
    let uniform_counts: Vec<usize> = if uniform {
        let all = initial_counts(&t.domain, &slot_gaps, &bounding_opts);
        (0..t.h).map(|k| all[canonical_slot(k)]).collect()
    } else {
        Vec::new()
    };
    // The samples of the canonical copies of the orbits `ks` at `density` (per orbit); `Err`
    // for an orbit beyond the per-circle limit (uniform: at the cap already).
    type Plan = Result<(u64, Vec<u64>), ()>;
    let plan = |density: &[u32], ks: &[usize]| -> Vec<Plan> {
        if uniform {
            // `n` samples at the grid angles `2 pi i / n`: doubled per density step, capped;
            // a step that no longer changes the count is refused (the orbit is at the cap).
            return ks
                .iter()
                .map(|&k| {
                    let count = |d: u32| {
                        uniform_counts[k]
                            .saturating_mul(1usize << d.min(40))
                            .min(bcap)
                    };
                    let n = count(density[k]);
                    if density[k] > 0 && n == count(density[k] - 1) {
                        return Err(());
                    }
                    Ok((n as u64, (0..n as u64).collect()))
                })
                .collect();
        }
        let slot_density: Vec<u32> = std::iter::once(0)
            .chain(t.keys.iter().map(|&(k, _, _)| density[k as usize]))
            .collect();
        let slots: Vec<usize> = ks.iter().map(|&k| canonical_slot(k)).collect();
        crate::sampling::adaptive_grids(&t.domain, opts, &slot_gaps, &slot_density, &slots)
    };
    let too_many = |k: usize| MeshError::Sampling {
        circle: k as CircleId,
        message: format!(
            "hole {k} of the periodic tiling would need more than {} samples",
            opts.max_per_circle
        ),
    };
    // Density doublings per orbit, from exact mode's local resampling first
    // ([`SamplingOptions::boost`]: slot `k + 1` is canonical hole `k`, shared by its orbit).
    let mut density: Vec<u32> = (0..t.h)
        .map(|k| opts.boost.get(k + 1).map_or(0, |&b| b.min(16)))
        .collect();
    let all: Vec<usize> = (0..t.h).collect();
    let mut plans: Vec<(u64, Vec<u64>)> = timings::span("sampling", || plan(&density, &all))
        .into_iter()
        .enumerate()
        .map(|(k, p)| p.map_err(|()| too_many(k)))
        .collect::<Result<_, _>>()?;
    let mut gaps = vec![bgap];
    gaps.extend_from_slice(gaps_canonical);
    for round in 0..=opts.max_rounds {
        let total = bcount
            + plans
                .iter()
                .zip(&t.copies)
                .map(|(p, &c)| p.1.len() * c)
                .sum::<usize>();
        if total > opts.max_total {
            return Err(MeshError::Sampling {
                circle: -1,
                message: format!(
                    "the periodic tiling would need {total} samples, more than the limit {}",
                    opts.max_total
                ),
            });
        }
        let samples = timings::span("sampling", || t.samples(&plans, bcount, &gaps));
        let earlier = previous.filter(|_| round == 0);
        let (tri, made) = timings::span("triangulation", || match earlier {
            Some(p) => extended_or_new((&p.samples, &p.tri), &samples),
            None => Triangulation::new(&samples.points).map(|t| (t, Made::Fresh)),
        })?;
        // The round before, when the new triangulation extends its own and every earlier
        // circle is sampled as before: its classes, checks and medial arcs are reused where
        // the insertion kept the triangles (issue 8, as bounded refinement does:
        // [`crate::medial::reuse`]).
        let reuse = earlier
            .filter(|p| {
                made == Made::Extended
                    && p.kinds.len() == p.tri.len()
                    && reuse::same_earlier_circles(&p.samples, &samples)
            })
            .map(|p| (p, reuse::Kept::new(&p.tri, &tri)));
        // The classes and the hard invariants in one parallel pass (the same classes and
        // violations as `classify` then `check_invariants`; issue 8: 0.33 s on one thread
        // per sampling at 1e5 holes).
        let (kinds, hard) = timings::span("sampling", || match &reuse {
            Some((p, kept)) => {
                reuse::classify_and_check_after(&samples, &tri, &p.kinds, p.samples.len(), kept)
            }
            None => crate::sampling::classify_and_check(&samples, &tri),
        });
        let mut grow_b = false;
        let mut grow: Vec<bool> = vec![false; t.h];
        // With only the soft invariant (d) left, the sampling is kept in case no orbit can be
        // refined any more (all at the cap): thin walls are then accepted, as in the bounded
        // sampler (`crate::sampling::sample_and_triangulate`).
        let (violations, soft_done) = if hard.is_empty() {
            let medial = timings::span("medial_graph", || {
                let reused = reuse.as_ref().and_then(|(p, kept)| {
                    reuse::medial_graph_after_graph(&samples, &tri, &kinds, &p.medial, kept)
                });
                match reused {
                    Some(m) => Ok(m),
                    None => medial_graph(&samples, &tri, &kinds),
                }
            })?;
            let soft: Vec<_> = thin_walls(&tri, &medial)
                .into_iter()
                .filter(|v| match v.kind {
                    ViolationKind::SingleSampleWall { arc } => medial
                        .arcs
                        .get(arc as usize)
                        .is_some_and(|a| a.circles.iter().any(|&c| is_canonical(t, c))),
                    _ => false,
                })
                .collect();
            if soft.is_empty() || round == opts.max_rounds || !opts.soft_rounds {
                return Ok((samples, tri, kinds, medial));
            }
            (soft, Some((samples, tri, kinds, medial)))
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
            (hard, None)
        };
        for v in &violations {
            match t.key(v.circle) {
                None => grow_b = true,
                Some((k, _, _)) => grow[k as usize] = true,
            }
        }
        let mut refined = false;
        if grow_b && bcount < bcap {
            bcount = (bcount * 2).min(bcap);
            refined = true;
        }
        let grown: Vec<usize> = (0..t.h).filter(|&k| grow[k] && density[k] < 60).collect();
        for &k in &grown {
            density[k] += 1;
        }
        let made = timings::span("sampling", || plan(&density, &grown));
        for (&k, p) in grown.iter().zip(made) {
            match p {
                Ok(p) => {
                    plans[k] = p;
                    refined = true;
                }
                // At the per-circle limit: this orbit stays as it is.
                Err(()) => density[k] -= 1,
            }
        }
        if !refined {
            if let Some(done) = soft_done {
                return Ok(done);
            }
            break;
        }
    }
    Err(MeshError::Sampling {
        circle: -1,
        message: format!(
            "the periodic tiling's sampling invariants still fail after {} rounds (or with \
             every offending orbit at the limit of {} samples)",
            opts.max_rounds, opts.max_per_circle
        ),
    })
}

/// The triangulation of `samples`, by inserting the new samples into the triangulation of
/// the earlier sampling `previous` when every earlier sample is still there, bit for bit
/// (issue 8: a refinement round's tiling is the earlier one with the inserted holes' copies
/// appended, and only the circles near them may be sampled more densely): as a prefix
/// ([`Triangulation::extended`]), else renumbered ([`Triangulation::extended_renumbered`],
/// through [`crate::sampling::kept_samples`]); otherwise from scratch. The same triangle
/// set either way (the Delaunay triangulation of the points under the simulation of
/// simplicity); only the numbering differs.
fn extended_or_new(
    previous: (&Samples, &Triangulation),
    samples: &Samples,
) -> Result<(Triangulation, Made), crate::geometry::TriangulationError> {
    let (before, tri) = previous;
    if !tri.is_empty() {
        if let Some(t) = tri.extended(&samples.points)? {
            return Ok((t, Made::Extended));
        }
        if let Some(map) = crate::sampling::kept_samples(before, samples) {
            if let Some(t) = tri.extended_renumbered(&samples.points, &map)? {
                return Ok((t, Made::Renumbered));
            }
        }
    }
    Triangulation::new(&samples.points).map(|t| (t, Made::Fresh))
}

/// How [`extended_or_new`] made a triangulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Made {
    /// The earlier samples are a prefix of the new ones: [`Triangulation::extended`].
    Extended,
    /// The earlier samples are all among the new ones: [`Triangulation::extended_renumbered`].
    Renumbered,
    /// From scratch.
    Fresh,
}

fn is_canonical(t: &Tiling, c: CircleId) -> bool {
    matches!(t.key(c), Some((_, 0, 0)))
}

/// The result of the periodic layout stage.
#[derive(Debug, Clone)]
pub struct PeriodicLayout {
    /// One period: `6h` blocks in the non-degenerate case. Walls are [`EdgeKind::Wall`] of
    /// the canonical hole ids; zig-zag sides are [`EdgeKind::Periodic`].
    pub layout: BlockLayout,
    /// Medial vertex and arc orbits (on the torus: `2h` and `3h`).
    pub medial_vertices: usize,
    pub medial_arcs: usize,
    /// The half-widths `[mx, my]` of the tiling used (`(2 mx + 1) x (2 my + 1)` tiles).
    pub tiling: [i32; 2],
    /// The circle triples of the medial vertex orbits, each as `(hole, tile a, tile b)`
    /// normalised up to translation and counted from nearest copies (`normalise_triple`),
    /// sorted: the medial combinatorics of the period.
    pub triples: Vec<[CircleKey; 3]>,
    /// The same blocks as orbits, for exact mode ([`crate::exact_mode::periodic::build`]);
    /// vertex orbits are the contracted vertices (a co-circular group of `n` circles is one
    /// vertex of degree `n`). `None` only when those orbits are not consistent (exact mode
    /// then falls back to this paper layout).
    pub blocking: Option<PeriodicBlocking>,
    /// Zero-length medial arc orbits collapsed (blocks: `6h - 2 collapsed_arcs`).
    pub collapsed_arcs: usize,
    /// The co-circular groups, one per orbit: canonical hole ids (one entry per tangent
    /// image, sorted), the empty circle's centre wrapped into the box, its radius.
    pub cocircular_groups: Vec<CocircularGroup>,
    /// The orbit key of each arc orbit of `blocking`, in its order.
    arc_keys: Vec<ArcKey>,
    /// What the layout was extracted from, for exact mode's local fix (a re-extraction with
    /// arcs running backwards collapsed, on the same sampling, [`reextract`]).
    sampled: Option<std::sync::Arc<Sampled>>,
    /// The refinement ratio for which the extraction found no poor vertex orbit
    /// ([`extract`]'s `poor_limit`), so that the round need not look again.
    no_poor: Option<f64>,
    /// The arc orbits of `blocking` that run backwards, when the extraction looked
    /// ([`extract`]'s `check_backwards`) and found some: the layout was then not numbered
    /// (`layout`, `triples` and the groups are empty), and its exact build is known to stop
    /// there ([`exact_frame`] answers as the stopped build, the local fix re-extracts).
    backwards: Option<Vec<usize>>,
    /// The vertex orbits solved for the layout this one fixes, for its build to take
    /// ([`Sampled::solved_orbits`]; only the local fix's layout has them).
    solved_orbits: Option<std::sync::Arc<exact_mode::periodic::SolvedOrbits>>,
}

/// A sampled, triangulated tiling and its medial graph.
struct Sampled {
    t: Tiling,
    samples: Samples,
    tri: Triangulation,
    /// The classes of `tri`'s triangles, for a refinement round's next sampling
    /// ([`sample_tiling`] reuses them); emptied once the sampling gives a layout.
    kinds: Vec<TriangleKind>,
    medial: MedialGraph,
    /// The exact circles of the arc orbit representatives' ends ([`select_collapse`]): the
    /// ends (sorted) and their circles, solved at the first extraction of this sampling and
    /// reused by the next ones (its collapse attempts and exact mode's local fix,
    /// [`reextract`]), which ask for the same vertices (issue 8).
    end_circles: std::sync::OnceLock<EndCircles>,
    /// The orbit keys of the medial graph and collapse selection's part that depends on the
    /// sampling alone ([`Orbits`]), made at the first extraction and reused by the next ones
    /// of this sampling (its collapse attempts and exact mode's local fix, [`reextract`]).
    /// Dropped once the layout is made when no local fix is expected (the layout has no arc
    /// orbit running backwards), so that the exact build does not hold it.
    orbits: std::sync::OnceLock<Orbits>,
    /// The vertex orbits the extraction that found arc orbits running backwards solved, for
    /// the build of the local fix's layout ([`local_fix`]), which takes them: its vertex
    /// orbits are nearly all those ([`exact_mode::periodic::SolvedOrbits`], issue 8).
    solved_orbits: std::sync::Mutex<Option<exact_mode::periodic::SolvedOrbits>>,
    /// The triangles whose circles an extraction of this sampling measured inside the tiling
    /// ([`extract`]'s step 4), set by the first extraction that found none outside: a later
    /// one (exact mode's local fix, [`reextract`]) measures only the triangles it uses beyond
    /// these (issue 8: 0.15 s at 1e5 holes), with the same outcome.
    measured: std::sync::OnceLock<Vec<bool>>,
    /// A refinement round's solved medial vertices ([`poor::medial_poor`]) with their answers,
    /// for the next round's sampling to reuse.
    solved: std::sync::OnceLock<Vec<(poor::SolveKey, poor::Answer)>>,
    /// How its extractions measure short arcs: by the mode it was sampled for (a sampling is
    /// kept and extracted again in exact mode only), so its [`SelectionBase`] is for this.
    how: collapse::ArcLength,
}

/// What [`Sampled::end_circles`] holds: vertex ids and their exact circles, same order.
type EndCircles = (Vec<u32>, Vec<Option<Apollonius>>);

/// The orbit keys of a sampling's medial graph ([`Sampled::orbits`]; issue 8: at 1e5 holes
/// 0.3 s of every extraction, made again by exact mode's local fix for the same sampling).
struct Orbits {
    /// Per medial vertex, its orbit key (`None` outside the tiling's keyed region).
    vkeys: Vec<Option<VertexKey>>,
    /// Per medial arc, its orbit key.
    akeys: Vec<Option<ArcKey>>,
    /// The medial arc of each key.
    arc_by_key: HashMap<ArcKey, usize>,
    /// Collapse selection's part that depends on the sampling alone, short arcs measured as
    /// [`Sampled::how`] ([`select_collapse`]).
    selection: std::sync::OnceLock<SelectionBase>,
}

/// What [`select_collapse`] finds from the sampling alone, before the collapse fraction, the
/// excluded and the forced arcs come in.
struct SelectionBase {
    /// The orbit representative (a tiling arc) of each tiling arc, when in the tiling.
    rep_of: Vec<Option<usize>>,
    /// The representatives, increasing.
    reps: Vec<usize>,
    /// Per medial arc, the vertex orbits of a representative's two ends with their shifts.
    orbit_ends: Vec<Option<OrbitEnds>>,
    /// The arc representatives at each vertex orbit, increasing.
    incident: Vec<Vec<usize>>,
    /// Per representative (same order as `reps`), its measure.
    measured: Vec<Measure>,
}

impl Orbits {
    /// The orbit keys of the medial graph of a sampling (an error when two arcs of the tiling
    /// have the same key).
    fn new(t: &Tiling, samples: &Samples, medial: &MedialGraph) -> Result<Orbits, MeshError> {
        let vkeys: Vec<Option<VertexKey>> = (0..medial.vertices.len())
            .into_par_iter()
            .map(|v| vertex_key(t, samples, medial, v))
            .collect();
        let arc_key = |e: usize| -> Option<ArcKey> {
            let a = &medial.arcs[e];
            let mut c = [t.key(a.circles[0])?, t.key(a.circles[1])?];
            c.sort_unstable();
            let mut v = [vkeys[a.ends[0] as usize]?, vkeys[a.ends[1] as usize]?];
            v.sort_unstable();
            Some((c, v))
        };
        let akeys: Vec<Option<ArcKey>> = (0..medial.arcs.len())
            .into_par_iter()
            .map(arc_key)
            .collect();
        // Sized once (issue 8: growing it rehashed every key, a millisecond of one thread at 1e3
        // holes).
        let mut arc_by_key: HashMap<ArcKey, usize> =
            HashMap::with_capacity_and_hasher(akeys.len(), Default::default());
        for (e, k) in akeys.iter().enumerate() {
            if let Some(k) = k {
                if arc_by_key.insert(*k, e).is_some() {
                    return Err(MeshError::Internal(
                        "two medial arcs of the periodic tiling have the same key".into(),
                    ));
                }
            }
        }
        Ok(Orbits {
            vkeys,
            akeys,
            arc_by_key,
            selection: std::sync::OnceLock::new(),
        })
    }
}

/// The orbit key of medial vertex `v` of a sampling of the tiling `t`: its samples' keys,
/// sorted; `None` when a sample is outside the keyed tiling.
fn vertex_key(t: &Tiling, samples: &Samples, medial: &MedialGraph, v: usize) -> Option<VertexKey> {
    let sample_key = |s: u32| -> Option<SampleKey> {
        let (k, a, b) = t.key(samples.circle_of[s as usize])?;
        Some((k, samples.index_of[s as usize], a, b))
    };
    let s = medial.vertices[v].samples;
    let mut key = [sample_key(s[0])?, sample_key(s[1])?, sample_key(s[2])?];
    key.sort_unstable();
    Some(key)
}

/// Per axis, what a tiling of the box `size` must hold for the disc of centre `c` and radius
/// `r` widened by `reach` to lie where every copy of every hole is in it (the extraction's
/// step 4): the half-width `m` of a whole array of copies (below, `-m L + reach < c - r`;
/// above, `(m + 1) L - reach > c + r`), and how far beyond the box a band must reach.
fn disc_needs(size: [f64; 2], c: Point, r: f64, reach: f64) -> [(f64, f64); 2] {
    [0, 1].map(|a| {
        let below = (r + reach - c[a]) / size[a];
        let above = (c[a] + r + reach) / size[a] - 1.0;
        let m = below.max(above).floor() + 1.0;
        let beyond = (r + reach - c[a]).max(c[a] + r + reach - size[a]);
        (m, beyond)
    })
}

/// A representative arc as the sampling alone tells ([`SelectionBase::measured`]).
#[derive(Debug, Clone, Copy)]
enum Measure {
    /// An end without a vertex orbit: never collapsed.
    NoEnds,
    /// Zero-length (its ends' exact circles are the same, or it is zero-length in the
    /// triangulation), ends distinct: always collapsed.
    Zero,
    /// Its length relative to the local radius (possibly not finite), and whether it is a
    /// loop (both ends the same vertex: never collapsed as a zero-length arc).
    Length { rel: f64, is_loop: bool },
}

impl std::fmt::Debug for Sampled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sampled")
            .field("medial_vertices", &self.medial.vertices.len())
            .finish()
    }
}

/// The block layout of one period of `pd` (see the module documentation).
pub fn periodic_layout(
    pd: &PeriodicDomain,
    options: &Options,
) -> Result<PeriodicLayout, MeshError> {
    periodic_layout_with(pd, options, &SamplingOptions::default())
}

/// [`periodic_layout`] with explicit sampling options.
pub fn periodic_layout_with(
    pd: &PeriodicDomain,
    options: &Options,
    sampling: &SamplingOptions,
) -> Result<PeriodicLayout, MeshError> {
    // The sampled tiling is for exact mode's local fix only: not held by a caller's layout.
    let mut p = layout_keeping(pd, options, sampling)?;
    p.sampled = None;
    Ok(p)
}

/// [`periodic_layout_with`] that keeps, in exact mode, the sampled tiling for the local fix
/// ([`reextract`]).
fn layout_keeping(
    pd: &PeriodicDomain,
    options: &Options,
    sampling: &SamplingOptions,
) -> Result<PeriodicLayout, MeshError> {
    layout_from(pd, options, sampling, initial_reach(pd), None, false, None)?.layout()
}

/// [`layout_keeping`] for an exact attempt: a layout whose exact build would stop at arc
/// orbits running backwards is not numbered ([`extract`]'s `check_backwards`).
fn layout_for_exact(
    pd: &PeriodicDomain,
    options: &Options,
    sampling: &SamplingOptions,
) -> Result<PeriodicLayout, MeshError> {
    layout_from(pd, options, sampling, initial_reach(pd), None, true, None)?.layout()
}

/// What [`layout_from`] found: the layout, or for a refinement round ([`layout_or_poor`])
/// the poor vertex orbits.
#[allow(clippy::large_enum_variant)]
enum Round {
    /// No poor vertex orbit: the layout ([`layout_keeping`]'s).
    Layout(PeriodicLayout),
    /// The poor vertex orbits ([`poor::medial_poor`] or
    /// [`exact_mode::periodic::poor_vertices`], not empty), and the sampling that has them
    /// (the next round's triangulation extends its own, [`extended_or_new`]).
    Poor(Vec<(f64, Point, f64)>, Box<Sampled>),
}

impl Round {
    /// The layout of a round that asked for no poor vertex orbit (`poor_limit` `None`).
    fn layout(self) -> Result<PeriodicLayout, MeshError> {
        match self {
            Round::Layout(p) => Ok(p),
            Round::Poor(..) => Err(MeshError::Internal(
                "no poor vertices were asked for".into(),
            )),
        }
    }
}

/// [`layout_keeping`] for a refinement round with ratio `limit`: the poor vertex orbits of
/// the layout when there are some, found without numbering the layout (issue 8: the layout
/// of such a round is not used), else the layout. The first tiling is the band within
/// `first_reach` of the box; its triangulation extends that of `previous` (the round
/// before's sampling) where it can ([`extended_or_new`]).
fn layout_or_poor(
    pd: &PeriodicDomain,
    options: &Options,
    sampling: &SamplingOptions,
    limit: f64,
    first_reach: [f64; 2],
    previous: Option<&Sampled>,
) -> Result<Round, MeshError> {
    layout_from(
        pd,
        options,
        sampling,
        first_reach,
        Some(limit),
        true,
        previous,
    )
}

/// [`periodic_layout_with`] from a band of copies within `first_reach` of the box (per axis;
/// from a period on, the whole 3 x 3 array); the first tiling's triangulation extends that of
/// the sampling `previous` (a refinement round's before) where it can ([`extended_or_new`]).
fn layout_from(
    pd: &PeriodicDomain,
    options: &Options,
    sampling: &SamplingOptions,
    first_reach: [f64; 2],
    poor_limit: Option<f64>,
    check_backwards: bool,
    mut previous: Option<&Sampled>,
) -> Result<Round, MeshError> {
    crate::ranges::check_collapse_fraction(options.collapse_fraction)?;
    let gaps = pd.nearest_gaps();
    let opts = sampling.clone();
    let cap = max_half_widths(pd.size());
    let mut m = [1, 1];
    let mut reach = first_reach;
    for _ in 0..MAX_TILING_ROUNDS {
        let copies = (2 * m[0] as usize + 1) * (2 * m[1] as usize + 1) * pd.hole_count();
        let least = copies.saturating_mul(opts.min_per_circle.next_multiple_of(8).max(8));
        if least > opts.max_total {
            return Err(MeshError::Tiling(format!(
                "{} x {} copies of the box are needed ({copies} circles, at least {least} \
                 samples), more than the limit of {} samples: the empty regions are too long \
                 for the period",
                2 * m[0] + 1,
                2 * m[1] + 1,
                opts.max_total
            )));
        }
        let t = Tiling::with_reach(pd, m, reach)?;
        // The round before's sampling serves the first tiling only.
        let earlier = previous.take();
        let (samples, tri, kinds, medial) =
            sample_tiling(&t, &gaps, &opts, options.mode == Mode::Paper, earlier)?;
        let mut sampled = Sampled {
            t,
            samples,
            tri,
            kinds,
            medial,
            end_circles: std::sync::OnceLock::new(),
            measured: std::sync::OnceLock::new(),
            solved_orbits: std::sync::Mutex::new(None),
            orbits: std::sync::OnceLock::new(),
            solved: std::sync::OnceLock::new(),
            // Exact mode builds on the Apollonius centres: it measures short arcs by them.
            how: match options.mode {
                Mode::Exact => collapse::ArcLength::Chord,
                Mode::Paper => collapse::ArcLength::Polyline,
            },
        };
        // A refinement round asks the medial graph first (issue 8: the layout of a round
        // that finds poor vertices is not used, and extracting it took a fifth of a 1e5-hole
        // run); the layout's exact input is asked only when the graph has none.
        let extracted = timings::span("blocking", || {
            if let Some(limit) = poor_limit {
                let poor = poor::medial_poor(pd, &sampled, limit, earlier);
                if !poor.is_empty() {
                    return Ok(Extracted::Poor(poor));
                }
            }
            extract_from(pd, options, &sampled, &[], poor_limit, check_backwards)
        })?;
        match extracted {
            Extracted::Layout(mut p) => {
                // Only a next refinement round reads the classes and the solved vertices
                // (this one ends here).
                let kinds = std::mem::take(&mut sampled.kinds);
                let solved = sampled.solved.take();
                rayon::spawn(move || drop((kinds, solved)));
                // Only a local fix reads the orbits again ([`reextract`]).
                if p.backwards.is_none() {
                    let orbits = sampled.orbits.take();
                    rayon::spawn(move || drop(orbits));
                }
                // Paper mode has no use for it.
                if options.mode == Mode::Exact {
                    p.sampled = Some(std::sync::Arc::new(sampled));
                }
                return Ok(Round::Layout(p));
            }
            Extracted::Poor(poor) => return Ok(Round::Poor(poor, Box::new(sampled))),
            Extracted::TooSmall {
                need,
                need_reach,
                blind,
            } => match next_extent(&sampled.t, need, need_reach, blind, cap) {
                Some(next) => (m, reach) = next,
                None => break,
            },
        }
    }
    Err(MeshError::Tiling(format!(
        "the medial axis of the periodic layout reaches beyond a {} x {} array of copies \
         (empty regions far larger than the period); refused",
        2 * m[0] + 1,
        2 * m[1] + 1
    )))
}

/// [`extract`] from `sampled` with the arc orbits `forced` collapsed, measuring short arcs as
/// the mode does (`poor_limit` and `check_backwards`, exact mode only, as there).
fn extract_from(
    pd: &PeriodicDomain,
    options: &Options,
    sampled: &Sampled,
    forced: &[ArcKey],
    poor_limit: Option<f64>,
    check_backwards: bool,
) -> Result<Extracted, MeshError> {
    extract(
        pd,
        sampled,
        options.collapse_fraction,
        forced,
        poor_limit,
        check_backwards && options.mode == Mode::Exact,
    )
}

/// Exact mode's local fix (issue 8, as bounded exact mode's degree-4 collapse): the layout of
/// the same sampling as `sampled` with the arc orbits `force` (orbit keys of arcs running
/// backwards: nearly co-circular circles whose sampled Delaunay diagonal is not the exact
/// one) collapsed in every copy, each into one vertex of its four circles, without
/// sampling, triangulating and finding the medial graph again. `Internal` when the
/// extraction does not hold (the caller resamples instead).
fn reextract(
    pd: &PeriodicDomain,
    options: &Options,
    sampled: &Sampled,
    force: &[ArcKey],
) -> Result<PeriodicLayout, MeshError> {
    let mut forced = force.to_vec();
    forced.sort_unstable();
    forced.dedup();
    match timings::span("blocking", || {
        extract_from(pd, options, sampled, &forced, None, false)
    })? {
        Extracted::Layout(p) => Ok(p),
        Extracted::TooSmall { .. } | Extracted::Poor(_) => Err(MeshError::Internal(
            "the layout with forced collapses needs a wider tiling".into(),
        )),
    }
}

/// The largest half-widths of the array of copies for a period `size`: `(2 m + 1) L <=`
/// [`MAX_ARRAY_SIDE`]` max(Lx, Ly)` per axis (`[3, 3]` for a square box), so that the
/// coordinates stay within [`PeriodicDomain::coordinate_magnitude`].
fn max_half_widths(size: [f64; 2]) -> [i32; 2] {
    let l = size[0].max(size[1]);
    size.map(|s| {
        let m = ((MAX_ARRAY_SIDE * l / s - 1.0) / 2.0).floor();
        if m.is_finite() {
            m.clamp(1.0, (i32::MAX / 4) as f64) as i32
        } else {
            1
        }
    })
}

/// The half-widths of the next tiling after `m` was too small: at least the half-widths
/// `need` that would hold every offending circle, and, when some kept arc could not be
/// judged (`blind`: it reaches the auxiliary bounding circle), every axis grown by half
/// (at least one tile); each axis at most `cap`. `None` when nothing can grow.
fn next_tiling(m: [i32; 2], need: [i32; 2], blind: bool, cap: [i32; 2]) -> Option<[i32; 2]> {
    let next: [i32; 2] = std::array::from_fn(|a| {
        let grown = if blind {
            m[a] + (m[a] / 2).max(1)
        } else {
            m[a]
        };
        need[a].max(grown).min(cap[a]).max(m[a])
    });
    (next != m).then_some(next)
}

/// The first reach of the copies around the box, per axis (a full axis when at least the
/// period): three largest radii (a canonical circle centred on the box's edge, a neighbour
/// within its sampling's reach, which is below a radius, and step 4's widening) and four radii
/// of the mean empty area per hole (a typical empty circle, twice: its triangles' circles
/// reach across it). Step 4 checks it; a box whose empty circles are larger grows it.
fn initial_reach(pd: &PeriodicDomain) -> [f64; 2] {
    let size = pd.size();
    let h = pd.hole_count().max(1) as f64;
    let rmax = pd.holes().iter().map(|c| c.radius).fold(0.0, f64::max);
    let holes_area: f64 = pd
        .holes()
        .iter()
        .map(|c| std::f64::consts::PI * c.radius * c.radius)
        .sum();
    let empty = ((size[0] * size[1] - holes_area) / h).max(0.0);
    let d = 3.0 * rmax + 4.0 * (empty / std::f64::consts::PI).sqrt();
    [d; 2]
}

/// The next extent `(m, reach)` after the tiling `t` was too small (see
/// [`Extracted::TooSmall`]). When a band is too narrow or a kept arc is `blind`, only the
/// bands grow: to a quarter beyond what the circles need, at least by half (twice when
/// `blind`), and into the whole 3-wide array once they would reach a period (the circles measured on a band that is too narrow
/// can be far wider than the true ones, across the missing copies, so they do not size the
/// arrays). When the bands hold the circles, the whole arrays grow as [`next_tiling`] says
/// (a band keeps its reach: `next_tiling` leaves its half-width 1). With whole arrays on both
/// axes, [`next_tiling`]. `None` when nothing can grow.
fn next_extent(
    t: &Tiling,
    need: [i32; 2],
    need_reach: [f64; 2],
    blind: bool,
    cap: [i32; 2],
) -> Option<([i32; 2], [f64; 2])> {
    let size = t.size;
    let band = |a: usize| t.band[a];
    if !(band(0) || band(1)) {
        let m = next_tiling(t.m, need, blind, cap)?;
        return Some((m, [0, 1].map(|a| m[a] as f64 * size[a])));
    }
    let mut m = t.m;
    let mut reach = t.reach;
    let band_short = (0..2).any(|a| band(a) && !below(need_reach[a], t.reach[a]));
    if !(blind || band_short) {
        // The bands hold the circles: the whole arrays grow to what they need.
        let m = next_tiling(t.m, need, false, cap)?;
        for a in (0..2).filter(|&a| !band(a)) {
            reach[a] = m[a] as f64 * size[a];
        }
        return Some((m, reach));
    }
    for a in (0..2).filter(|&a| band(a)) {
        let mut d = t.reach[a];
        if !below(need_reach[a], d) {
            d = (1.25 * need_reach[a]).max(1.5 * d);
        }
        if blind {
            d = d.max(2.0 * t.reach[a]);
        }
        if !below(d, size[a]) {
            m[a] = 1;
            reach[a] = size[a];
        } else {
            reach[a] = d;
        }
    }
    (m != t.m || reach != t.reach).then_some((m, reach))
}

/// `x < limit`, false for NaN (a reach that is not a number is never enough).
fn below(x: f64, limit: f64) -> bool {
    x < limit
}

/// What [`extract`] makes of a tiling.
#[allow(clippy::large_enum_variant)]
enum Extracted {
    /// One period's blocks.
    Layout(PeriodicLayout),
    /// Refinement's question ([`extract`]'s `poor_limit`): the poor vertex orbits of the
    /// layout ([`exact_mode::periodic::poor_vertices`], not empty), without the layout.
    Poor(Vec<(f64, Point, f64)>),
    /// The tiling is too small (step 4): `need` are the half-widths whose array holds every
    /// offending circumcircle (at least the current ones), `need_reach` the distances beyond
    /// the box that the circles (widened as step 4 does) reach, per axis; `blind` is set
    /// when a kept arc reaches the auxiliary bounding circle (no circle to measure).
    TooSmall {
        need: [i32; 2],
        need_reach: [f64; 2],
        blind: bool,
    },
}

/// The orbits of a layout's kept corners and arcs, and its exact input, found before the
/// numbering ([`extract`] with a `poor_limit` or `check_backwards`).
struct Early {
    vertex_orbits: Vec<VertexKey>,
    collapsed_orbits: Vec<ArcKey>,
    cluster_orbits: Vec<usize>,
    arc_orbits: Vec<ArcKey>,
    blocking: Result<Option<PeriodicBlocking>, MeshError>,
    /// [`exact_mode::periodic::backwards_orbits`] of `blocking` with its solved vertex
    /// orbits, when the poor check found it from the same solves
    /// ([`exact_mode::periodic::poor_and_backwards`]).
    backwards: Option<Result<exact_mode::periodic::Backwards, MeshError>>,
}

/// A contracted medial vertex (a cluster of collapsed vertices) up to nothing: the samples of
/// all its members' Delaunay triangles, sorted and deduplicated (three samples for a vertex
/// that was not collapsed).
type ClusterKey = Vec<SampleKey>;

/// The orbit representative of a cluster key and the shift from it: `key = rep + shift`,
/// the least of the key moved back by each of its samples' tile shifts.
fn normalise_cluster(key: &[SampleKey]) -> (ClusterKey, (i32, i32)) {
    least_over_shifts(
        key,
        |s| (s.2, s.3),
        |d| {
            let mut k: ClusterKey = key.iter().map(|x| shift_sample(*x, (-d.0, -d.1))).collect();
            k.sort_unstable();
            k
        },
    )
    .unwrap_or_else(|| (key.to_vec(), (0, 0)))
}

/// The arcs of the tiling chosen for collapse (see [`select_collapse`]).
struct Selection<'a> {
    /// One flag per tiling arc.
    flags: Vec<bool>,
    /// One flag per tiling arc: collapsed as a short (not zero-length) arc.
    short: Vec<bool>,
    /// The orbit representative (a tiling arc) of each tiling arc, when in the tiling.
    rep_of: &'a [Option<usize>],
}

/// Union-find over vertex orbits with translations: the instance of orbit `x` at shift `s`
/// lies in the plane cluster `(root, s + offset)` where `find(x) = (root, offset)`.
struct OrbitForest {
    parent: Vec<usize>,
    link: Vec<(i32, i32)>,
}

impl OrbitForest {
    fn find(&self, mut x: usize) -> (usize, (i32, i32)) {
        let mut off = (0, 0);
        while self.parent[x] != x {
            off = (off.0 + self.link[x].0, off.1 + self.link[x].1);
            x = self.parent[x];
        }
        (x, off)
    }
}

/// The arcs to collapse, chosen on the torus so that the choice is translation-invariant:
/// every decision is made once per arc orbit, on its representative instance, and given to
/// every instance (the copies of a hole are float translates of it, not exact ones, so exact
/// tests on different copies could disagree).
///
/// - Zero-length arcs, always: the exact Apollonius circles of the two ends are the same
///   circle ([`same_circle`]: both ends in one co-circular group), or the sample-level
///   criteria of [`cocircular::is_zero_length`] hold (all sampled points equal, or one exactly
///   co-circular Delaunay edge crossed).
/// - Then arcs shorter than `fraction` times the smaller empty-circle radius of their ends
///   (measured as `how` says, [`collapse::ArcLength`]: exact mode the chord between the two
///   Apollonius centres, paper mode [`cocircular::arc_length`]; [`cocircular::local_radius`]),
///   shortest (relative) first,
///   except the representatives in `exclude`.
///
/// As in [`collapse::select`], an arc orbit is skipped when its ends are already in one
/// cluster or when another remaining arc joins the same two clusters of the plane; clusters
/// are tracked on the torus with translations ([`OrbitForest`]), so that an orbit closing a
/// cycle of the torus (contractible or not) is never taken and every cluster of the plane is
/// a finite tree. Arcs without a representative in the tiling (near its bounding circle) are
/// never collapsed.
///
/// What depends on the sampling alone (the representatives, their end orbits, which are
/// zero-length and the others' relative lengths: [`SelectionBase`]) is made at the first
/// selection and kept in `orbits` for the next ones (issue 8: the collapse attempts and exact
/// mode's local fix select again on the same sampling); `fraction`, `exclude` and `forced`
/// are applied to it at each selection.
#[allow(clippy::too_many_arguments)]
fn select_collapse<'o>(
    domain: &Domain,
    tri: &Triangulation,
    points: &[Point],
    medial: &MedialGraph,
    end_circles: &std::sync::OnceLock<EndCircles>,
    orbits: &'o Orbits,
    fraction: f64,
    how: collapse::ArcLength,
    exclude: &[usize],
    forced: &[ArcKey],
) -> Selection<'o> {
    // The sampling's part, made at its first selection (`how` is the sampling's own).
    let base = orbits
        .selection
        .get_or_init(|| SelectionBase::new(domain, tri, points, medial, end_circles, orbits, how));
    let SelectionBase {
        rep_of,
        reps,
        orbit_ends,
        incident,
        ..
    } = base;
    let akeys = &orbits.akeys;
    // Each representative as the options say: `Some(None)` zero-length, `Some(Some(rel))`
    // short, in representative order.
    let measured: Vec<Option<Option<f64>>> = reps
        .par_iter()
        .zip(&base.measured)
        .map(|(&r, &m)| match m {
            Measure::NoEnds => None,
            Measure::Zero => Some(None),
            Measure::Length { rel, is_loop } => {
                let force =
                    || akeys[r].is_some_and(|k| forced.binary_search(&normalise_arc(&k).0).is_ok());
                if !is_loop && !forced.is_empty() && force() {
                    Some(None)
                } else if fraction > 0.0 && !exclude.contains(&r) {
                    (rel.is_finite() && rel < fraction).then_some(Some(rel))
                } else {
                    None
                }
            }
        })
        .collect();
    let mut zero: Vec<usize> = Vec::new();
    let mut short: Vec<(f64, usize)> = Vec::new();
    for (&r, m) in reps.iter().zip(measured) {
        match m {
            Some(None) => zero.push(r),
            Some(Some(rel)) => short.push((rel, r)),
            None => {}
        }
    }
    short.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let order: Vec<(usize, bool)> = zero
        .into_iter()
        .map(|r| (r, true))
        .chain(short.into_iter().map(|(_, r)| (r, false)))
        .collect();
    let n = incident.len();
    let mut forest = OrbitForest {
        parent: (0..n).collect(),
        link: vec![(0, 0); n],
    };
    // The two plane clusters an arc orbit joins, as (root, shift) pairs.
    let clusters = |forest: &OrbitForest, r: usize| {
        let ends = orbit_ends[r].expect("a representative with both end orbits");
        ends.map(|(x, s)| {
            let (root, off) = forest.find(x);
            (root, (s.0 + off.0, s.1 + off.1))
        })
    };
    let rel = |c: OrbitEnds| (c[1].1 .0 - c[0].1 .0, c[1].1 .1 - c[0].1 .1);
    // The vertex orbits of each root's tree: an arc orbit parallel to `r` has an end in the
    // tree of `r`'s first root, so only the arc orbits at that tree's vertex orbits
    // ([`SelectionBase::incident`]) are looked at (issue 8: every arc orbit was, for each arc
    // orbit collapsed, 1.1 s at 100 000 holes).
    let mut tree: Vec<Vec<usize>> = (0..n).map(|x| vec![x]).collect();
    // Per medial arc: collapsed as a zero-length arc, as a short one, or not (a dense table
    // rather than a map: issue 8).
    let mut taken: Vec<Option<bool>> = vec![None; medial.arcs.len()];
    for &(r, is_zero) in &order {
        let c = clusters(&forest, r);
        if c[0].0 == c[1].0 {
            continue;
        }
        let parallel = tree[c[0].0].iter().flat_map(|&x| &incident[x]).any(|&f| {
            if f == r || taken[f].is_some() {
                return false;
            }
            let g = clusters(&forest, f);
            let (d, e) = (rel(c), rel(g));
            (g[0].0 == c[0].0 && g[1].0 == c[1].0 && d == e)
                || (g[0].0 == c[1].0 && g[1].0 == c[0].0 && d == (-e.0, -e.1))
        });
        if parallel {
            continue;
        }
        // Merge root c[1] into root c[0]: (c1.root, c1.shift) ~ (c0.root, c0.shift).
        let (x, y) = (c[0].0, c[1].0);
        forest.parent[y] = x;
        forest.link[y] = (c[0].1 .0 - c[1].1 .0, c[0].1 .1 - c[1].1 .1);
        let moved = std::mem::take(&mut tree[y]);
        tree[x].extend(moved);
        taken[r] = Some(is_zero);
    }
    let flags: Vec<bool> = rep_of
        .iter()
        .map(|r| r.is_some_and(|r| taken[r].is_some()))
        .collect();
    let short = rep_of
        .iter()
        .map(|r| r.is_some_and(|r| taken[r] == Some(false)))
        .collect();
    Selection {
        flags,
        short,
        rep_of,
    }
}

impl SelectionBase {
    /// [`select_collapse`]'s part that depends on the sampling alone, short arcs measured as
    /// `how`.
    fn new(
        domain: &Domain,
        tri: &Triangulation,
        points: &[Point],
        medial: &MedialGraph,
        end_circles: &std::sync::OnceLock<EndCircles>,
        orbits: &Orbits,
        how: collapse::ArcLength,
    ) -> SelectionBase {
        let (akeys, vkeys, arc_by_key) = (&orbits.akeys, &orbits.vkeys, &orbits.arc_by_key);
        let rep_of: Vec<Option<usize>> = akeys
            .par_iter()
            .map(|k| k.and_then(|k| arc_by_key.get(&normalise_arc(&k).0).copied()))
            .collect();
        let mut reps: Vec<usize> = rep_of.iter().flatten().copied().collect();
        reps.sort_unstable();
        reps.dedup();
        // The same for every extraction of one sampling (`reps` depends on the sampling
        // alone): solved once.
        let (ends, solved) = end_circles.get_or_init(|| {
            let mut ends: Vec<u32> = reps.iter().flat_map(|&r| medial.arcs[r].ends).collect();
            ends.sort_unstable();
            ends.dedup();
            let solved = cocircular::vertex_circles_of(domain, medial, &ends);
            (ends, solved)
        });
        // Vertex `v`'s circle, when `v` is an end of a representative and solved (`ends` is
        // sorted).
        let circle = |v: u32| -> Option<&Apollonius> {
            let at = ends.binary_search(&v).ok()?;
            solved[at].as_ref()
        };
        // Vertex orbits of the representatives' ends, with the ends' shifts.
        // (The ends' normalised keys in parallel, numbered in representative order.)
        type Normalised = Option<(VertexKey, (i32, i32))>;
        let normalised: Vec<[Normalised; 2]> = reps
            .par_iter()
            .map(|&r| {
                medial.arcs[r]
                    .ends
                    .map(|v| vkeys[v as usize].map(|k| normalise_vertex(&k)))
            })
            .collect();
        let mut orbit_index: HashMap<VertexKey, usize> =
            HashMap::with_capacity_and_hasher(2 * reps.len(), Default::default());
        // Per medial arc (a dense table rather than a map keyed by arc id: issue 8), the
        // vertex orbits of a representative's two ends with their shifts.
        let mut orbit_ends: Vec<Option<OrbitEnds>> = vec![None; medial.arcs.len()];
        for (&r, ends) in reps.iter().zip(&normalised) {
            let mut out = [(0, (0, 0)); 2];
            let mut ok = true;
            for (k, end) in ends.iter().enumerate() {
                match *end {
                    Some((rep, d)) => {
                        let n = orbit_index.len();
                        out[k] = (*orbit_index.entry(rep).or_insert(n), d);
                    }
                    None => ok = false,
                }
            }
            if ok {
                orbit_ends[r] = Some(out);
            }
        }
        let radius = |v: u32| match circle(v) {
            Some(c) => c.radius,
            None => cocircular::local_radius(medial, &[], points, v),
        };
        let centre = |v: u32| circle(v).map(|c| c.center);
        // Each representative measured on its own, in parallel, in representative order.
        let measured: Vec<Measure> = reps
            .par_iter()
            .map(|&r| {
                if orbit_ends[r].is_none() {
                    return Measure::NoEnds;
                }
                let arc = &medial.arcs[r];
                let [a, b] = arc.ends;
                let same = match (circle(a), circle(b)) {
                    (Some(x), Some(y)) => same_circle(&x.exact, &y.exact),
                    _ => false,
                };
                if a != b && (same || cocircular::is_zero_length(arc, medial, tri, &[])) {
                    Measure::Zero
                } else {
                    let rel =
                        collapse::measured_length(arc, centre, how) / radius(a).min(radius(b));
                    Measure::Length {
                        rel,
                        is_loop: a == b,
                    }
                }
            })
            .collect();
        // The arc representatives at each vertex orbit, in increasing arc order.
        let mut incident: Vec<Vec<usize>> = vec![Vec::new(); orbit_index.len()];
        for (f, ends) in orbit_ends.iter().enumerate() {
            for &(x, _) in ends.iter().flatten() {
                incident[x].push(f);
            }
        }
        SelectionBase {
            rep_of,
            reps,
            orbit_ends,
            incident,
            measured,
        }
    }
}

/// The error of a tiling whose copies do not agree (`what` names the part).
fn not_translation_consistent(what: &str) -> MeshError {
    MeshError::Internal(format!(
        "the periodic tiling is not translation-consistent ({what})"
    ))
}

/// Keep the canonical cells; [`Extracted::TooSmall`] when the tiling is too small (step 4).
///
/// Zero-length medial arcs (co-circular hole groups, e.g. every corner of a square lattice)
/// and arcs shorter than `fraction` of the local radius (measured as [`Sampled::how`] says)
/// are collapsed ([`select_collapse`], [`collapse::contract`]) before Blocking2D, the same
/// arcs in every copy. A contracted vertex is identified up to translation by its
/// [`ClusterKey`], so its instances are its orbit representative plus the period shift like
/// any other vertex. A kept block with a non-positive outline area is an
/// [`MeshError::Internal`]. The arc orbits `forced` (orbit keys) are collapsed with the
/// zero-length ones (exact mode's local fix, [`reextract`]). With `poor_limit` (refinement's
/// ratio), [`Extracted::Poor`] when the layout has poor vertex orbits
/// ([`exact_mode::periodic::poor_vertices`] of its exact input, found before the numbering);
/// else the layout, the same as without it. With `check_backwards` (exact mode's first
/// extraction of a sampling, `forced` empty), a layout whose exact input has arc orbits running
/// backwards is returned without its numbering ([`PeriodicLayout`]'s `backwards`).
#[allow(clippy::too_many_arguments)]
fn extract(
    pd: &PeriodicDomain,
    sampled: &Sampled,
    fraction: f64,
    forced: &[ArcKey],
    poor_limit: Option<f64>,
    check_backwards: bool,
) -> Result<Extracted, MeshError> {
    let Sampled {
        t,
        samples,
        tri: triangulation,
        medial,
        end_circles,
        how,
        ..
    } = sampled;
    let how = *how;
    let size = t.size;
    // Orbit keys of the original medial graph, made at this sampling's first extraction.
    let orbits = match sampled.orbits.get() {
        Some(o) => o,
        None => {
            let made = Orbits::new(t, samples, medial)?;
            sampled.orbits.get_or_init(|| made)
        }
    };
    let (vkeys, akeys, arc_by_key) = (&orbits.vkeys, &orbits.akeys, &orbits.arc_by_key);
    let inconsistent = not_translation_consistent;

    // Collapse zero-length (always) and short arcs, identically in every copy. As in the
    // bounded pipeline, short collapses that leave a kept block with a non-positive outline
    // area are given up (at most 8 attempts); zero-length ones never are.
    let mut exclude: Vec<usize> = Vec::new();
    let mut attempt = 0;
    let (selection, contracted, aux, vertex_samples) = loop {
        attempt += 1;
        let sel = select_collapse(
            &t.domain,
            triangulation,
            &samples.points,
            medial,
            end_circles,
            orbits,
            fraction,
            how,
            &exclude,
            forced,
        );
        let contracted = collapse::contract(medial, &sel.flags)?;
        let (aux, vertex_samples) = blocking::blocks(&t.domain, samples, &contracted.graph)?;
        let nv = contracted.graph.vertices.len() as u32;
        // Only a block with a corner at a cluster merging a short collapse can make that
        // collapse given up (below, a short arc is given up when its cluster is a corner of a
        // flat block): the other blocks' areas are not computed, the same outcome (issue 8,
        // as the bounded pipeline does; 0.15 s an extraction at 1e5 holes).
        let mut short_cluster = vec![false; nv as usize];
        for (e, arc) in medial.arcs.iter().enumerate() {
            if sel.short[e] {
                short_cluster[contracted.cluster_of[arc.ends[0] as usize] as usize] = true;
            }
        }
        let at_short = |v: u32| v < nv && short_cluster[v as usize];
        let mut bad: Vec<u32> = aux
            .blocks
            .par_iter()
            .enumerate()
            .filter(|(b, block)| {
                block.wall.is_some_and(|c| is_canonical(t, c))
                    && block.corners.iter().any(|&v| at_short(v))
                    && blocking::block_area(&aux, *b) <= 0.0
            })
            .flat_map_iter(|(_, block)| block.corners.into_iter().filter(|&v| v < nv))
            .collect();
        bad.sort_unstable();
        bad.dedup();
        let mut changed = false;
        for (e, arc) in medial.arcs.iter().enumerate() {
            let c = contracted.cluster_of[arc.ends[0] as usize];
            if sel.short[e] && bad.binary_search(&c).is_ok() {
                if let Some(r) = sel.rep_of[e] {
                    if !exclude.contains(&r) {
                        exclude.push(r);
                        changed = true;
                    }
                }
            }
        }
        if !changed || attempt >= 8 {
            break (sel, contracted, aux, vertex_samples);
        }
    };
    let collapse_flags = selection.flags;
    let graph = &contracted.graph;
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); graph.vertices.len()];
    for (v, &c) in contracted.cluster_of.iter().enumerate() {
        members[c as usize].push(v as u32);
    }
    let mut collapsed_at: Vec<Vec<usize>> = vec![Vec::new(); graph.vertices.len()];
    for (e, &f) in collapse_flags.iter().enumerate() {
        if f {
            let c = contracted.cluster_of[medial.arcs[e].ends[0] as usize];
            collapsed_at[c as usize].push(e);
        }
    }
    let cluster_key = |c: usize| -> Option<ClusterKey> {
        let mut key = Vec::with_capacity(3 * members[c].len());
        for &v in &members[c] {
            key.extend_from_slice(&vkeys[v as usize]?);
        }
        key.sort_unstable();
        key.dedup();
        Some(key)
    };
    let ckeys: Vec<Option<ClusterKey>> = (0..graph.vertices.len())
        .into_par_iter()
        .map(cluster_key)
        .collect();
    // Keyed by the borrowed keys (no copy of every key: issue 8).
    let mut cluster_by_key: HashMap<&[SampleKey], usize> =
        HashMap::with_capacity_and_hasher(ckeys.len(), Default::default());
    for (c, k) in ckeys.iter().enumerate() {
        if let Some(k) = k {
            cluster_by_key.insert(k.as_slice(), c);
        }
    }

    let rmax = pd.holes().iter().map(|c| c.radius).fold(0.0, f64::max);
    let margin = 1e-6 * size[0].max(size[1]);
    // Step 4: every triangle used by a kept block is a triangle of the infinite tiling: its
    // circumcircle, widened by the largest radius, lies inside the region whose copies are
    // all in the tiling (the array, or the band within `t.reach` of the box), so no sample
    // missing from the tiling (or of the auxiliary bounding circle) is in it. Each offending
    // circle gives the half-widths, and the reach, that would hold it. (The orbit
    // representatives the layout reads are kept instances: an arc's has a canonical circle,
    // a vertex's a canonical sample, so it is a corner of a kept block and measured too.)
    let reach = rmax + margin;
    // Raises `need` and `need_reach` to hold the circle of triangle `tri` (in range); false
    // when it has no circle to measure.
    let measure = |tri: u32, need: &mut [i32; 2], need_reach: &mut [f64; 2]| -> bool {
        let p = triangulation
            .triangle(tri as usize)
            .map(|s| samples.points[s as usize]);
        let circle =
            circumcenter(p[0], p[1], p[2]).map(|c| (c, (c[0] - p[0][0]).hypot(c[1] - p[0][1])));
        let Some((c, r)) = circle else {
            return false;
        };
        for (a, (m, beyond)) in disc_needs(size, c, r, reach).into_iter().enumerate() {
            if !m.is_finite() {
                return false;
            }
            if m > need[a] as f64 {
                need[a] = m.min((i32::MAX / 4) as f64) as i32;
            }
            need_reach[a] = need_reach[a].max(beyond);
        }
        true
    };
    let kept: Vec<usize> = (0..aux.blocks.len())
        .filter(|&b| aux.blocks[b].wall.is_some_and(|c| is_canonical(t, c)))
        .collect();
    // Each triangle once (issue 8: the blocks around a vertex share its triangle, the two
    // blocks of an arc its triangles), measured in parallel: `need` and `need_reach` are
    // maxima, `blind` a disjunction, so the result does not depend on the order.
    let mut used = vec![false; triangulation.len()];
    let mut blind = false;
    for &b in &kept {
        let e = contracted.kept[b / 2] as usize;
        let arc = &medial.arcs[e];
        if arc.circles.iter().any(|&c| c < 0) {
            blind = true;
            continue;
        }
        let ends = arc
            .ends
            .iter()
            .flat_map(|&v| &members[contracted.cluster_of[v as usize] as usize])
            .map(|&v| medial.vertices[v as usize].triangle);
        for tri in ends.chain(arc.triangles.iter().copied()) {
            match used.get_mut(tri as usize) {
                Some(u) => *u = true,
                None => blind = true,
            }
        }
    }
    // The circles of the triangles `take` accepts among the used ones: the largest
    // half-widths and reaches they need, and whether one could not be measured.
    let measure_all = |take: &(dyn Fn(usize) -> bool + Sync)| {
        used.par_iter()
            .enumerate()
            .filter(|&(tri, &u)| u && take(tri))
            .fold(
                || (t.m, [0.0f64; 2], false),
                |(mut need, mut need_reach, blind), (tri, _)| {
                    let ok = measure(tri as u32, &mut need, &mut need_reach);
                    (need, need_reach, blind || !ok)
                },
            )
            .reduce(
                || (t.m, [0.0f64; 2], false),
                |a, b| {
                    (
                        [a.0[0].max(b.0[0]), a.0[1].max(b.0[1])],
                        [a.1[0].max(b.1[0]), a.1[1].max(b.1[1])],
                        a.2 || b.2,
                    )
                },
            )
    };
    // A full axis holds the circles when the array does; a band when they end inside it.
    let short_of = |need: [i32; 2], need_reach: [f64; 2]| {
        (0..2).any(|a| {
            if t.band[a] {
                !below(need_reach[a], t.reach[a])
            } else {
                need[a] != t.m[a]
            }
        })
    };
    // Every triangle an earlier extraction of this sampling measured was held by the tiling
    // (its circle needs no more than `t.m` and reaches below `t.reach`, all measurable), and
    // each test is a maximum compared with a bound or a disjunction: the used triangles pass
    // exactly when those not measured before do. Only a failure needs the figures of every
    // used triangle (what `TooSmall` reports).
    let before = sampled.measured.get();
    let (mut need, mut need_reach, mut unmeasured) =
        measure_all(&|tri| before.is_none_or(|m| !m[tri]));
    if before.is_some() && (blind || unmeasured || short_of(need, need_reach)) {
        (need, need_reach, unmeasured) = measure_all(&|_| true);
    }
    let blind = blind || unmeasured;
    let short = short_of(need, need_reach);
    if !(blind || short) && before.is_none() {
        let _ = sampled.measured.set(used);
    } else {
        drop(used);
    }
    if blind || short {
        return Ok(Extracted::TooSmall {
            need,
            need_reach,
            blind,
        });
    }
    let shift_point = |p: Point, d: (i32, i32)| -> Point {
        [p[0] + d.0 as f64 * size[0], p[1] + d.1 as f64 * size[1]]
    };
    // Positions of contracted vertex instances: orbit representative + shift. The orbits of
    // their members and collapsed arcs are recorded for the torus counts.
    // (Dense tables indexed by vertex, cluster and edge ids rather than hash maps: issue 8.)
    let mut vpos: Vec<Option<Point>> = vec![None; graph.vertices.len()];
    let mut cluster_orbits: Vec<usize> = Vec::new();
    let nmv = graph.vertices.len() as u32;
    // The placement of each contracted vertex at a kept block's corner, worked out in
    // parallel (issue 8) and taken by the serial numbering below at its first use (so that
    // the first error met is the one in block order).
    struct Placed {
        p: Point,
        r: usize,
        vorbits: Vec<VertexKey>,
        corbits: Vec<ArcKey>,
    }
    // The kept corners that are medial vertices, increasing, and each one's index there
    // (`NONE` for the others): a table rather than a sort and a binary search per corner
    // (issue 8: the numbering below, serial, looks up every corner of 6 blocks per hole).
    let mut needed_at: Vec<u32> = vec![NONE; nmv as usize];
    for &b in &kept {
        for &v in &aux.blocks[b].corners {
            if v < nmv {
                needed_at[v as usize] = 0;
            }
        }
    }
    let mut needed: Vec<u32> = Vec::new();
    for (v, at) in needed_at.iter_mut().enumerate() {
        if *at != NONE {
            *at = needed.len() as u32;
            needed.push(v as u32);
        }
    }
    let place = |c: usize| -> Result<Placed, MeshError> {
        let key = ckeys[c]
            .as_ref()
            .ok_or_else(|| inconsistent("a kept vertex on the bounding circle"))?;
        let (rep, d) = normalise_cluster(key);
        let r = *cluster_by_key
            .get(rep.as_slice())
            .ok_or_else(|| inconsistent("a medial vertex without its representative"))?;
        if members[r].len() != members[c].len() {
            return Err(inconsistent("a collapsed vertex unlike its representative"));
        }
        let vorbits = members[c]
            .iter()
            .map(|&v| {
                let k = vkeys[v as usize].ok_or_else(|| inconsistent("vertex key"))?;
                Ok(normalise_vertex(&k).0)
            })
            .collect::<Result<Vec<_>, MeshError>>()?;
        let corbits = collapsed_at[c]
            .iter()
            .map(|&e| {
                let k = akeys[e].ok_or_else(|| inconsistent("collapsed arc key"))?;
                Ok(normalise_arc(&k).0)
            })
            .collect::<Result<Vec<_>, MeshError>>()?;
        Ok(Placed {
            p: shift_point(graph.vertices[r].position, d),
            r,
            vorbits,
            corbits,
        })
    };
    let mut placed: Vec<Option<Result<Placed, MeshError>>> = needed
        .par_iter()
        .map(|&c| Some(place(c as usize)))
        .collect();

    let mut layout = BlockLayout::default();
    const NONE: u32 = u32::MAX;
    let mut new_vertex: Vec<u32> = vec![NONE; aux.vertices.len()];
    let mut new_edge: Vec<(u32, bool)> = vec![(NONE, false); aux.edges.len()];
    // (new edge, original arc, offset of the other circle)
    let mut periodic: Vec<(u32, usize, (i32, i32))> = Vec::new();
    let mut arc_orbits: Vec<ArcKey> = Vec::new();
    // The medial side of each kept arc, worked out in parallel (as the corners above) and
    // taken at its first use.
    struct MedialSide {
        rep: ArcKey,
        flip: bool,
        /// The representative's polyline moved to this instance (its ends are replaced by
        /// the numbered end vertices).
        pts: Vec<Point>,
    }
    let medial_side = |k: usize| -> Result<MedialSide, MeshError> {
        let e = contracted.kept[k] as usize;
        let key = akeys[e].ok_or_else(|| inconsistent("arc key"))?;
        let (rep, d) = normalise_arc(&key);
        let r = *arc_by_key
            .get(&rep)
            .ok_or_else(|| inconsistent("a medial arc without its representative"))?;
        // Orient the edge as the representative: its first end is the instance vertex whose
        // key is the representative's first end moved by d.
        let rep_first =
            vkeys[medial.arcs[r].ends[0] as usize].ok_or_else(|| inconsistent("arc end key"))?;
        let first = shift_vertex(&rep_first, d);
        let flip = vkeys[medial.arcs[e].ends[0] as usize] != Some(first);
        let pts = medial.arcs[r]
            .polyline
            .iter()
            .map(|&p| shift_point(p, d))
            .collect();
        Ok(MedialSide { rep, flip, pts })
    };
    let mut kept_arcs: Vec<usize> = kept.iter().map(|&b| b / 2).collect();
    kept_arcs.dedup();
    // Each kept arc's index in `kept_arcs` (`NONE` for the others), as `needed_at`.
    let mut kept_arc_at: Vec<u32> = vec![NONE; aux.blocks.len().div_ceil(2)];
    for (at, &k) in kept_arcs.iter().enumerate() {
        kept_arc_at[k] = at as u32;
    }
    let mut sides_of: Vec<Option<Result<MedialSide, MeshError>>> = kept_arcs
        .par_iter()
        .map(|&k| Some(medial_side(k)))
        .collect();
    // Exact mode's input from the orbits of the kept corners and arcs: `None` when the
    // orbits are not consistent (paper mode does not need it).
    let input_of = |vertex_orbits: &[VertexKey],
                    collapsed_orbits: &[ArcKey],
                    cluster_orbits: &[usize],
                    arc_orbits: &[ArcKey]|
     -> Result<Option<PeriodicBlocking>, MeshError> {
        Ok(
            if collapsed_orbits.is_empty() && contracted.kept.len() == medial.arcs.len() {
                Some(exact_input(
                    pd,
                    t,
                    medial,
                    &aux,
                    vkeys,
                    vertex_orbits,
                    arc_orbits,
                    arc_by_key,
                )?)
            } else if collapsed_orbits.is_empty() {
                None
            } else {
                // Collapsed (nearly) co-circular groups: exact mode collapses zero-length arcs
                // and arcs below `EXACT_COLLAPSE_FRACTION` of the local radius, so every
                // cluster is one empty circle up to that fraction. A failure here only leaves
                // exact mode without its input (paper mode does not need it).
                exact_input_clusters(
                    pd,
                    t,
                    medial,
                    &aux,
                    &contracted,
                    &members,
                    &ckeys,
                    &cluster_by_key,
                    cluster_orbits,
                    arc_orbits,
                    arc_by_key,
                )
                .ok()
            },
        )
    };
    // Refinement asks only for the poor vertex orbits of this layout while there are some
    // (issue 8): the exact input is made from the orbits of the kept corners and arcs, known
    // from the placements above, before the numbering; with poor orbits the numbering (half
    // of the extraction) is skipped. The numbered layout's own input is this one.
    let early_wanted = poor_limit.is_some() || (check_backwards && forced.is_empty());
    let early = early_wanted.then_some(()).and_then(|()| {
        let mut early = Early {
            vertex_orbits: Vec::new(),
            collapsed_orbits: Vec::new(),
            cluster_orbits: Vec::new(),
            arc_orbits: Vec::new(),
            blocking: Ok(None),
            backwards: None,
        };
        // Any error here is met again by the numbering, in block order: no early input.
        for x in &placed {
            let Some(Ok(x)) = x else { return None };
            early.vertex_orbits.extend_from_slice(&x.vorbits);
            early.collapsed_orbits.extend_from_slice(&x.corbits);
            early.cluster_orbits.push(x.r);
        }
        for m in &sides_of {
            let Some(Ok(m)) = m else { return None };
            early.arc_orbits.push(m.rep);
        }
        early.vertex_orbits.par_sort_unstable();
        early.vertex_orbits.dedup();
        for v in [&mut early.collapsed_orbits, &mut early.arc_orbits] {
            v.par_sort_unstable();
            v.dedup();
        }
        early.cluster_orbits.sort_unstable();
        early.cluster_orbits.dedup();
        if early
            .arc_orbits
            .iter()
            .any(|a| early.collapsed_orbits.binary_search(a).is_ok())
        {
            return None;
        }
        early.blocking = input_of(
            &early.vertex_orbits,
            &early.collapsed_orbits,
            &early.cluster_orbits,
            &early.arc_orbits,
        );
        if let (Ok(Some(pb)), Some(limit)) = (&early.blocking, poor_limit) {
            // With the backwards check to follow, both from one solve per vertex orbit.
            let poor = if check_backwards && forced.is_empty() {
                let (poor, backwards) = exact_mode::periodic::poor_and_backwards(pb, limit);
                early.backwards = Some(backwards);
                poor
            } else {
                exact_mode::periodic::poor_vertices(pb, limit)
            };
            if !poor.is_empty() {
                return Some(Err(poor));
            }
        }
        Some(Ok(early))
    });
    let mut early = match early {
        Some(Err(poor)) => return Ok(Extracted::Poor(poor)),
        Some(Ok(early)) => Some(early),
        None => None,
    };
    // Looked for and none found (an input that was not made has no vertex to be poor: the
    // round looks again, as it did before).
    let no_poor = poor_limit.filter(|_| {
        early
            .as_ref()
            .is_some_and(|e| matches!(e.blocking, Ok(Some(_))))
    });
    // Exact mode's first extraction of a sampling (issue 8): arc orbits running backwards
    // stop its exact build before the grids, and the local fix extracts the layout again
    // with them collapsed ([`reextract`]), so this layout is not numbered: the stopped
    // build's answer is found here, from the same exact input (an error there is left to
    // the build).
    let backwards = match &mut early {
        Some(Early {
            blocking: Ok(Some(pb)),
            backwards: known,
            ..
        }) if check_backwards && forced.is_empty() => known
            .take()
            .unwrap_or_else(|| exact_mode::periodic::backwards_orbits(pb))
            .ok()
            .filter(|(arcs, _)| !arcs.is_empty()),
        _ => None,
    };
    let early = match (backwards, early) {
        (Some((arcs, solved)), Some(early)) => {
            if let Ok(mut s) = sampled.solved_orbits.lock() {
                *s = Some(solved);
            }
            let Early {
                vertex_orbits,
                collapsed_orbits,
                arc_orbits,
                blocking,
                ..
            } = early;
            let blocking = blocking.ok().flatten();
            // Freed on the pool, off this thread (issue 8: the contracted graph, the auxiliary
            // layout, the per-cluster vectors and the placements and medial sides, not taken
            // here, are millions of small allocations, 0.25 s of serial frees at 1e5 holes).
            // The index borrows the keys: it goes first.
            drop(cluster_by_key);
            let heavy = (
                contracted,
                aux,
                vertex_samples,
                members,
                ckeys,
                placed,
                sides_of,
            );
            rayon::spawn(move || drop(heavy));
            return Ok(Extracted::Layout(PeriodicLayout {
                layout: BlockLayout::default(),
                medial_vertices: vertex_orbits.len(),
                medial_arcs: arc_orbits.len() + collapsed_orbits.len(),
                tiling: t.m,
                triples: Vec::new(),
                collapsed_arcs: collapsed_orbits.len(),
                cocircular_groups: Vec::new(),
                blocking,
                arc_keys: arc_orbits,
                sampled: None,
                no_poor,
                backwards: Some(arcs),
                solved_orbits: None,
            }));
        }
        (_, early) => early,
    };
    // The placements taken, in the order of their first use: their orbits are gathered after
    // the numbering, in parallel, and their vectors freed off this thread (issue 8: copied and
    // freed here one by one, they were a quarter of the serial numbering at 1e5 holes).
    let mut used: Vec<Placed> = Vec::with_capacity(needed.len());
    let mut position_of = |c: usize| -> Result<Point, MeshError> {
        if let Some(p) = vpos[c] {
            return Ok(p);
        }
        let got = needed_at
            .get(c)
            .filter(|&&at| at != NONE)
            .and_then(|&at| placed[at as usize].take());
        let x = match got {
            Some(x) => x?,
            None => place(c)?,
        };
        cluster_orbits.push(x.r);
        vpos[c] = Some(x.p);
        let p = x.p;
        used.push(x);
        Ok(p)
    };
    for &b in &kept {
        let block = &aux.blocks[b];
        let mut corners = [0u32; 4];
        for (i, &v) in block.corners.iter().enumerate() {
            let nv = *new_vertex
                .get(v as usize)
                .ok_or_else(|| MeshError::Internal("a block corner out of range".into()))?;
            if nv != NONE {
                corners[i] = nv;
                continue;
            }
            let p = if v < nmv {
                position_of(v as usize)?
            } else {
                let s = vertex_samples
                    .get(v as usize)
                    .copied()
                    .flatten()
                    .ok_or_else(|| MeshError::Internal("a corner without a sample".into()))?;
                let id = samples.circle_of[s as usize];
                let c = t.domain.circle(id);
                let uk = unit_offset(samples.grid_index(s), samples.grid_count(id));
                [
                    c.center[0] + c.radius * uk[0],
                    c.center[1] + c.radius * uk[1],
                ]
            };
            layout.vertices.push(p);
            let nv = (layout.vertices.len() - 1) as u32;
            new_vertex[v as usize] = nv;
            corners[i] = nv;
        }
        let mut sides = [SideRef {
            edge: 0,
            reversed: false,
        }; 4];
        for (k, side) in block.sides.iter().enumerate() {
            let (ne, flip) = *new_edge
                .get(side.edge as usize)
                .ok_or_else(|| MeshError::Internal("a block side out of range".into()))?;
            if ne != NONE {
                sides[k] = SideRef {
                    edge: ne,
                    reversed: side.reversed ^ flip,
                };
                continue;
            }
            let edge = &aux.edges[side.edge as usize];
            let end = |v: u32| {
                new_vertex
                    .get(v as usize)
                    .copied()
                    .filter(|&nv| nv != NONE)
                    .ok_or_else(|| inconsistent("an edge end that is not a block corner"))
            };
            let ends = [end(edge.ends[0])?, end(edge.ends[1])?];
            let (curve, kind, flip, ends) = match edge.kind {
                EdgeKind::Wall(c) => {
                    let (k, _, _) = t.key(c).ok_or_else(|| inconsistent("bounding wall"))?;
                    (
                        edge.curve.clone(),
                        EdgeKind::Wall(k as CircleId),
                        false,
                        ends,
                    )
                }
                EdgeKind::Medial => {
                    let e = contracted.kept[b / 2] as usize;
                    let got = kept_arc_at
                        .get(b / 2)
                        .filter(|&&at| at != NONE)
                        .and_then(|&at| sides_of[at as usize].take());
                    let MedialSide { rep, flip, mut pts } = match got {
                        Some(x) => x?,
                        None => medial_side(b / 2)?,
                    };
                    arc_orbits.push(rep);
                    let arc = &medial.arcs[e];
                    let ends = if flip { [ends[1], ends[0]] } else { ends };
                    if let Some(f) = pts.first_mut() {
                        *f = layout.vertices[ends[0] as usize];
                    }
                    if let Some(l) = pts.last_mut() {
                        *l = layout.vertices[ends[1] as usize];
                    }
                    let other = arc
                        .circles
                        .iter()
                        .map(|&c| t.key(c))
                        .find(|c| !matches!(c, Some((_, 0, 0))))
                        .flatten();
                    let curve = Curve::Polyline(pts);
                    match other {
                        Some((_, a, bb)) if (a, bb) != (0, 0) => {
                            periodic.push((layout.edges.len() as u32, e, (a, bb)));
                            (curve, EdgeKind::Medial, flip, ends)
                        }
                        _ => (curve, EdgeKind::Medial, flip, ends),
                    }
                }
                kind => (edge.curve.clone(), kind, false, ends),
            };
            layout.edges.push(Edge { ends, curve, kind });
            let ne = (layout.edges.len() - 1) as u32;
            new_edge[side.edge as usize] = (ne, flip);
            sides[k] = SideRef {
                edge: ne,
                reversed: side.reversed ^ flip,
            };
        }
        let wall = block.wall.and_then(|c| t.key(c)).map(|c| c.0 as CircleId);
        layout.blocks.push(Block {
            corners,
            sides,
            wall,
        });
    }
    // The orbits of the placed corners' members and collapsed arcs, in the order of first use.
    let mut vertex_orbits: Vec<VertexKey> = used
        .par_iter()
        .flat_map_iter(|x| x.vorbits.iter().cloned())
        .collect();
    let mut collapsed_orbits: Vec<ArcKey> = used
        .par_iter()
        .flat_map_iter(|x| x.corbits.iter().cloned())
        .collect();
    rayon::spawn(move || drop(used));
    // Pair the zig-zag sides.
    let by_arc: HashMap<usize, u32> = periodic.iter().map(|&(ne, e, _)| (e, ne)).collect();
    for &(ne, e, o) in &periodic {
        let key = akeys[e].ok_or_else(|| inconsistent("arc key"))?;
        let partner_key = shift_arc(&key, (-o.0, -o.1));
        let pe = *arc_by_key
            .get(&partner_key)
            .ok_or_else(|| inconsistent("a zig-zag side without its opposite side"))?;
        let partner = *by_arc
            .get(&pe)
            .ok_or_else(|| inconsistent("a zig-zag side whose opposite side is not kept"))?;
        let translation = Translation([-(o.0 as f64) * size[0], -(o.1 as f64) * size[1]]);
        layout.edges[ne as usize].kind = EdgeKind::Periodic {
            partner,
            translation,
        };
    }
    // No block with zero or negative area leaves this stage (the first such block, measured
    // in parallel).
    // (Buffers per task: two allocations per block took a tenth of a second at 1e5 holes.)
    let flat = (0..layout.blocks.len())
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(pts, outline), b| (b, blocking::block_area_with(&layout, b, pts, outline)),
        )
        .find_first(|&(_, a)| a.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater));
    if let Some((b, a)) = flat {
        return Err(MeshError::Internal(format!(
            "periodic block {b} has a non-positive area {} (a degenerate medial arc that \
             was not collapsed)",
            crate::numfmt::Num(a)
        )));
    }
    // (Parallel sorts of keys of 48 bytes and more: equal keys are equal, so the order is
    // that of a serial sort.)
    vertex_orbits.par_sort_unstable();
    vertex_orbits.dedup();
    arc_orbits.par_sort_unstable();
    arc_orbits.dedup();
    collapsed_orbits.par_sort_unstable();
    collapsed_orbits.dedup();
    if arc_orbits
        .iter()
        .any(|a| collapsed_orbits.binary_search(a).is_ok())
    {
        return Err(inconsistent("an arc orbit both collapsed and kept"));
    }
    cluster_orbits.sort_unstable();
    cluster_orbits.dedup();
    let groups = periodic_groups(t, medial, &members, &cluster_orbits);
    // The exact input: the one made before the numbering when its orbits are these (always,
    // when the numbering met no error: the same kept corners and arcs).
    let blocking = match early {
        Some(early)
            if early.vertex_orbits == vertex_orbits
                && early.arc_orbits == arc_orbits
                && early.collapsed_orbits == collapsed_orbits
                && early.cluster_orbits == cluster_orbits =>
        {
            early.blocking?
        }
        _ => input_of(
            &vertex_orbits,
            &collapsed_orbits,
            &cluster_orbits,
            &arc_orbits,
        )?,
    };
    // Freed on the pool, off this thread (issue 8: the contracted graph, the auxiliary layout
    // and the per-cluster vectors are millions of small allocations, 0.12-0.15 s of serial
    // frees at 1e5 holes). The index borrows the keys: it goes first.
    drop(cluster_by_key);
    let heavy = (contracted, aux, vertex_samples, members, ckeys);
    rayon::spawn(move || drop(heavy));
    let mut triples: Vec<[CircleKey; 3]> = vertex_orbits
        .iter()
        .map(|v| {
            let mut c = v.map(|s| (s.0, s.2, s.3));
            c.sort_unstable();
            normalise_triple(c, pd.holes(), size)
        })
        .collect();
    triples.sort_unstable();
    Ok(Extracted::Layout(PeriodicLayout {
        layout,
        medial_vertices: vertex_orbits.len(),
        medial_arcs: arc_orbits.len() + collapsed_orbits.len(),
        tiling: t.m,
        triples,
        collapsed_arcs: collapsed_orbits.len(),
        cocircular_groups: groups,
        blocking,
        arc_keys: arc_orbits,
        sampled: None,
        no_poor,
        backwards: None,
        solved_orbits: None,
    }))
}

/// The sampled sweep of block `b`'s side-0 wall, in the side's direction.
fn wall_sweep(layout: &BlockLayout, b: usize) -> Option<f64> {
    let side = layout.blocks.get(b)?.sides[0];
    match layout.edges.get(side.edge as usize)?.curve {
        Curve::Arc { sweep, .. } => Some(if side.reversed { -sweep } else { sweep }),
        _ => None,
    }
}

/// The orbits of the kept blocks for exact mode ([`crate::exact_mode::periodic`]): vertex
/// orbits `vertex_orbits` and arc orbits `arc_orbits` (sorted representatives), each with
/// its representative's circles and end vertices.
#[allow(clippy::too_many_arguments)]
fn exact_input(
    pd: &PeriodicDomain,
    t: &Tiling,
    medial: &MedialGraph,
    aux: &BlockLayout,
    vkeys: &[Option<VertexKey>],
    vertex_orbits: &[VertexKey],
    arc_orbits: &[ArcKey],
    arc_by_key: &HashMap<ArcKey, usize>,
) -> Result<PeriodicBlocking, MeshError> {
    let bad = not_translation_consistent;
    let tag = |c: CircleId| {
        t.key(c)
            .ok_or_else(|| bad("a kept orbit on the bounding circle"))
    };
    // `vertex_orbits` is sorted: an orbit's index is found by a search (issue 8: a map of
    // every key was built for it).
    let index = |rep: &VertexKey| vertex_orbits.binary_search(rep).ok();
    // The medial vertex of each orbit's key: the vertices whose key is an orbit's, found by a
    // search in parallel, then in vertex order, the last of equal keys (as a map of every
    // vertex's key, filled in vertex order, answered; issue 8: that map held every vertex key
    // of the tiling and was filled on one thread).
    const NONE: usize = usize::MAX;
    let found: Vec<(usize, usize)> = vkeys
        .par_iter()
        .enumerate()
        .filter_map(|(v, k)| k.as_ref().and_then(index).map(|i| (i, v)))
        .collect();
    let mut vertex_of = vec![NONE; vertex_orbits.len()];
    for (i, v) in found {
        vertex_of[i] = v;
    }
    // Vertex and arc orbits each on their own, in parallel; the first error in orbit order is
    // the one returned.
    let vertices = vertex_of
        .par_iter()
        .map(|&v| -> Result<PeriodicVertex, MeshError> {
            let v = medial.vertices.get(v).ok_or_else(|| bad("vertex orbit"))?;
            Ok(PeriodicVertex {
                circles: vec![tag(v.circles[0])?, tag(v.circles[1])?, tag(v.circles[2])?],
                near: v.position,
            })
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    let arcs = arc_orbits
        .par_iter()
        .map(|key| -> Result<PeriodicArc, MeshError> {
            let r = *arc_by_key.get(key).ok_or_else(|| bad("arc orbit"))?;
            let arc = &medial.arcs[r];
            let mut ends = [(0usize, (0i32, 0i32)); 2];
            for (j, &v) in arc.ends.iter().enumerate() {
                let k = vkeys
                    .get(v as usize)
                    .copied()
                    .flatten()
                    .ok_or_else(|| bad("arc end key"))?;
                let (rep, d) = normalise_vertex(&k);
                ends[j] = (index(&rep).ok_or_else(|| bad("arc end orbit"))?, d);
            }
            orbit_arc(t, aux, arc, r, ends)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    Ok(PeriodicBlocking {
        size: pd.size(),
        holes: pd.holes().to_vec(),
        vertices,
        arcs,
    })
}

/// The arc orbit of `arc` for exact mode, its ends `ends` (vertex orbit, shift), its sampled
/// wall sweeps read from its blocks `2k`, `2k + 1` of `aux`.
fn orbit_arc(
    t: &Tiling,
    aux: &BlockLayout,
    arc: &crate::medial::MedialArc,
    k: usize,
    ends: OrbitEnds,
) -> Result<PeriodicArc, MeshError> {
    let bad = not_translation_consistent;
    let tag = |c: CircleId| {
        t.key(c)
            .ok_or_else(|| bad("a kept orbit on the bounding circle"))
    };
    Ok(PeriodicArc {
        circles: [tag(arc.circles[0])?, tag(arc.circles[1])?],
        ends,
        hint: [
            wall_sweep(aux, 2 * k).ok_or_else(|| bad("sampled wall"))?,
            wall_sweep(aux, 2 * k + 1).ok_or_else(|| bad("sampled wall"))?,
        ],
    })
}

/// [`exact_input`] after the collapse of zero-length arcs: the vertex orbits are the orbits of
/// the contracted vertices `cluster_orbits` (representatives, sorted and deduplicated, as
/// [`extract`] records them), each with every circle its members touch (a co-circular group
/// of `n` circles is one vertex of degree `n`), in counter-clockwise order about the
/// cluster's position; the arc orbits `arc_orbits` are kept arcs, their ends the clusters of
/// their end vertices. Errors ([`MeshError::Internal`]) when the orbits are not
/// translation-consistent.
#[allow(clippy::too_many_arguments)]
fn exact_input_clusters(
    pd: &PeriodicDomain,
    t: &Tiling,
    medial: &MedialGraph,
    aux: &BlockLayout,
    contracted: &collapse::Contracted,
    members: &[Vec<u32>],
    ckeys: &[Option<ClusterKey>],
    cluster_by_key: &HashMap<&[SampleKey], usize>,
    cluster_orbits: &[usize],
    arc_orbits: &[ArcKey],
    arc_by_key: &HashMap<ArcKey, usize>,
) -> Result<PeriodicBlocking, MeshError> {
    let bad = not_translation_consistent;
    // The orbits by their representative's key, in key order (the first representative of
    // equal keys kept: the pairs are distinct, so the parallel sort orders them as a serial
    // one; issue 8), found by a search rather than a map of every key.
    let mut orbits: Vec<(&ClusterKey, usize)> = cluster_orbits
        .par_iter()
        .map(|&r| {
            ckeys
                .get(r)
                .and_then(Option::as_ref)
                .map(|k| (k, r))
                .ok_or_else(|| bad("cluster key"))
        })
        .collect::<Result<_, _>>()?;
    orbits.par_sort_unstable();
    // The orbit index of each listed cluster (`NONE` for the others): every cluster of a
    // run of equal keys has the index of the one kept.
    const NONE: usize = usize::MAX;
    let mut orbit_at = vec![NONE; ckeys.len()];
    let mut kept = 0;
    for k in 0..orbits.len() {
        if k > 0 && orbits[k].0 != orbits[k - 1].0 {
            kept += 1;
        }
        orbit_at[orbits[k].1] = kept;
    }
    orbits.dedup_by(|a, b| a.0 == b.0);
    // The index of the orbit whose key is `rep`: through the cluster the key map names (a
    // table; issue 8: a search over the orbits' keys, one pointer to follow per step, was
    // 0.3 s of CPU an extraction at 1e5 holes), else by that search. The map's cluster has
    // the key `rep`, so either way the index is that of `rep` among the orbits' keys.
    let index = |rep: &ClusterKey| {
        cluster_by_key
            .get(rep.as_slice())
            .and_then(|&c| orbit_at.get(c).copied())
            .filter(|&i| i != NONE)
            .or_else(|| {
                orbits
                    .binary_search_by(|(k, _)| k.as_slice().cmp(rep.as_slice()))
                    .ok()
            })
    };
    // Vertex and arc orbits each on their own, in parallel; the first error in orbit order is
    // the one returned (issue 8).
    let vertices = orbits
        .par_iter()
        .map(|(_, r)| -> Result<PeriodicVertex, MeshError> {
            let near = contracted
                .graph
                .vertices
                .get(*r)
                .ok_or_else(|| bad("cluster vertex"))?
                .position;
            let mut circles: Vec<(f64, crate::exact_mode::periodic::Tag)> = Vec::new();
            for &v in members.get(*r).ok_or_else(|| bad("cluster members"))? {
                for &c in &medial.vertices[v as usize].circles {
                    let tag = t
                        .key(c)
                        .ok_or_else(|| bad("a kept vertex on the bounding circle"))?;
                    if circles.iter().all(|x| x.1 != tag) {
                        let o = t.domain.circle(c).center;
                        circles.push(((o[1] - near[1]).atan2(o[0] - near[0]), tag));
                    }
                }
            }
            circles.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            Ok(PeriodicVertex {
                circles: circles.into_iter().map(|x| x.1).collect(),
                near,
            })
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    // Kept arcs: their blocks in `aux` are `2k`, `2k + 1` for kept index `k`.
    let mut kept_index: Vec<Option<usize>> = vec![None; medial.arcs.len()];
    for (k, &e) in contracted.kept.iter().enumerate() {
        if let Some(slot) = kept_index.get_mut(e as usize) {
            *slot = Some(k);
        }
    }
    let cluster_end = |v: u32| -> Result<(usize, (i32, i32)), MeshError> {
        let c = *contracted
            .cluster_of
            .get(v as usize)
            .ok_or_else(|| bad("arc end cluster"))?;
        let key = ckeys
            .get(c as usize)
            .and_then(Option::as_ref)
            .ok_or_else(|| bad("arc end key"))?;
        let (rep, d) = normalise_cluster(key);
        Ok((index(&rep).ok_or_else(|| bad("arc end orbit"))?, d))
    };
    let arcs = arc_orbits
        .par_iter()
        .map(|key| -> Result<PeriodicArc, MeshError> {
            let r = *arc_by_key.get(key).ok_or_else(|| bad("arc orbit"))?;
            let arc = &medial.arcs[r];
            let k = kept_index
                .get(r)
                .copied()
                .flatten()
                .ok_or_else(|| bad("a kept arc orbit"))?;
            let ends = [cluster_end(arc.ends[0])?, cluster_end(arc.ends[1])?];
            orbit_arc(t, aux, arc, k, ends)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    Ok(PeriodicBlocking {
        size: pd.size(),
        holes: pd.holes().to_vec(),
        vertices,
        arcs,
    })
}

/// The co-circular groups of one period: within each orbit of contracted vertices, each set
/// of two or more members whose exact Apollonius circles are the same circle. `clusters` are the orbit
/// representatives (contracted vertex ids). Holes are the canonical ids of the group's
/// circles, one entry per tangent circle (a hole tangent to the empty circle with several
/// images appears that many times), sorted; the centre is wrapped into the box. `vertices`
/// is left empty (tiling vertex ids mean nothing outside this stage).
fn periodic_groups(
    t: &Tiling,
    medial: &MedialGraph,
    members: &[Vec<u32>],
    clusters: &[usize],
) -> Vec<CocircularGroup> {
    let mut out = Vec::new();
    for &c in clusters {
        let ms = &members[c];
        if ms.len() < 2 {
            continue;
        }
        let circles = cocircular::vertex_circles_of(&t.domain, medial, ms);
        // Members with exactly the same empty circle (a cluster that also took short arcs
        // may hold several groups, or none).
        let mut classes: Vec<(&Apollonius, Vec<u32>)> = Vec::new();
        for (&v, x) in ms.iter().zip(&circles) {
            let Some(x) = x else {
                continue;
            };
            match classes
                .iter_mut()
                .find(|(y, _)| same_circle(&y.exact, &x.exact))
            {
                Some((_, vs)) => vs.push(v),
                None => classes.push((x, vec![v])),
            }
        }
        for (first, vs) in classes.into_iter().filter(|(_, vs)| vs.len() >= 2) {
            out.push(group_of_members(t, medial, first, &vs));
        }
    }
    out.sort_by(|a, b| {
        a.holes
            .cmp(&b.holes)
            .then(a.center[0].total_cmp(&b.center[0]))
            .then(a.center[1].total_cmp(&b.center[1]))
    });
    out
}

/// The reported group of the medial vertices `ms` of the tiling sharing the circle `first`.
fn group_of_members(
    t: &Tiling,
    medial: &MedialGraph,
    first: &Apollonius,
    ms: &[u32],
) -> CocircularGroup {
    let mut ids: Vec<CircleId> = ms
        .iter()
        .flat_map(|&v| medial.vertices[v as usize].circles)
        .collect();
    ids.sort_unstable();
    ids.dedup();
    let mut holes: Vec<CircleId> = ids
        .iter()
        .filter_map(|&id| t.key(id).map(|k| k.0 as CircleId))
        .collect();
    holes.sort_unstable();
    CocircularGroup {
        holes,
        center: [
            wrap(first.center[0], t.size[0]),
            wrap(first.center[1], t.size[1]),
        ],
        radius: first.radius,
        vertices: Vec::new(),
    }
}

/// A vertex orbit's circle triple `c` (copies of the holes `holes` of a box of `size`) as
/// [`PeriodicLayout::triples`] lists it: for each circle `x` taken as the origin, the others
/// counted from their copy nearest to `x`'s ([`crate::exact_mode::imposed::nearest_copy`]),
/// sorted; the least of the three. It does not depend on which copy of each hole lies in the
/// box (a hole that crossed the box's edge between two frames of a sequence gives the same
/// triples), nor on the shift of the whole triple.
fn normalise_triple(c: [CircleKey; 3], holes: &[Circle], size: [f64; 2]) -> [CircleKey; 3] {
    c.iter()
        .map(|x| {
            let mut s = c.map(|y| {
                let near = crate::exact_mode::imposed::nearest_copy_of(holes, size, x.0, y.0);
                (
                    y.0,
                    y.1.wrapping_sub(x.1).wrapping_sub(near.0),
                    y.2.wrapping_sub(x.2).wrapping_sub(near.1),
                )
            });
            s.sort_unstable();
            s
        })
        .min()
        .unwrap_or(c)
}

/// The medial combinatorics of a period: the circle triples of its vertex orbits
/// ([`PeriodicLayout::triples`]).
pub type Triples = Vec<[CircleKey; 3]>;

/// Mesh one period of `pd`.
///
/// Exact mode (the default): [`periodic_layout`], then the exact geometry of every orbit
/// computed once and translated ([`crate::exact_mode::periodic::build`]). As for bounded
/// domains ([`crate::mesher::mesh`]), when the exact geometry disagrees with the sampled
/// combinatorics, arcs running backwards are first collapsed on the same sampling (their
/// orbits in every copy, `reextract`, once per sampling); otherwise (or for a missing
/// Apollonius circle or an inverted cell) the sampling is refined 4x around the place per
/// attempt, up to [`EXACT_RESAMPLING`] times, and then paper mode is used. Paper mode: node counts and transfinite interpolation ([`build_grids`];
/// partners of periodic sides get equal counts and translated nodes).
///
/// From [`crate::spatial_order::SPATIAL_ORDER_MIN_HOLES`] holes, the holes are meshed in a
/// spatial order and the mesh is given back in the input's hole ids
/// ([`crate::spatial_order`]).
pub fn mesh_periodic(pd: &PeriodicDomain, options: &Options) -> Result<Mesh, MeshError> {
    timings::on_pool_worker(|| {
        // The options are checked against the caller's hole ids before any renaming.
        crate::mesher::validate_for(options, 0, pd.hole_count())?;
        crate::spatial_order::mesh_in_spatial_order(
            pd,
            pd.holes(),
            options,
            PeriodicDomain::reordered,
            // (The block keys are only for sequences: not made.)
            |d, o| periodic_frame_here(d, o, false).map(|f| f.mesh),
        )
    })
}

/// A periodic mesh with its combinatorics.
#[derive(Debug, Clone)]
pub struct PeriodicFrame {
    pub mesh: Mesh,
    /// The medial combinatorics ([`PeriodicLayout::triples`]).
    pub triples: Triples,
    /// Exact mode: the key of each block ([`crate::exact_mode::imposed`]); `None` in paper
    /// mode.
    pub keys: Option<Vec<BlockKey>>,
}

/// [`mesh_periodic`] and the medial combinatorics of the mesh made.
///
/// Like [`crate::mesher::mesh`], it runs on a worker of rayon's pool when called from outside
/// the pool ([`timings::on_pool_worker`]).
pub fn mesh_periodic_frame(
    pd: &PeriodicDomain,
    options: &Options,
) -> Result<PeriodicFrame, MeshError> {
    timings::on_pool_worker(|| {
        crate::mesher::validate_for(options, 0, pd.hole_count())?;
        periodic_frame_here(pd, options, true)
    })
}

/// [`mesh_periodic_frame`] on this thread, the options checked.
/// With `keys`, exact mode's frame has its block keys ([`PeriodicFrame::keys`]); without, it
/// has none (issue 8: 0.13-0.16 s at 1e5 holes that `mesh_periodic` dropped).
fn periodic_frame_here(
    pd: &PeriodicDomain,
    options: &Options,
    keys: bool,
) -> Result<PeriodicFrame, MeshError> {
    if options.mode == Mode::Exact {
        if let Some(done) = mesh_periodic_exact(pd, options, keys)? {
            return Ok(done);
        }
    }
    // The paper layout (also exact mode's fallback): paper mode's uniform sampling.
    let paper = Options {
        mode: Mode::Paper,
        ..options.clone()
    };
    let p = periodic_layout(pd, &paper)?;
    let grids = timings::span("grids", || build_grids(&p.layout, options.cells))?;
    Ok(PeriodicFrame {
        mesh: Mesh {
            layout: p.layout,
            grids,
            medial_vertices: p.medial_vertices,
            medial_arcs: p.medial_arcs,
            holes: pd.hole_count(),
            collapsed_arcs: p.collapsed_arcs,
            cocircular_groups: p.cocircular_groups,
            ..Mesh::default()
        },
        triples: p.triples,
        keys: None,
    })
}

/// Exact mode with macro Delaunay refinement and resampling; `Ok(None)`: use paper mode.
///
/// With [`Options::refine_ratio`], holes are first inserted where a vertex orbit is poor
/// ([`refine_periodic`]) and the refined domain is meshed with those holes filled by
/// templates; if that does not give a valid exact mesh, the domain is meshed without them
/// (as before refinement existed here), so refinement never makes a layout fail.
fn mesh_periodic_exact(
    pd: &PeriodicDomain,
    options: &Options,
    keys: bool,
) -> Result<Option<PeriodicFrame>, MeshError> {
    // Bounded exact mode's sampling: exact walls do not follow the samples, so a wall with a
    // single sample (the soft invariant (d)) costs nothing, and only the combinatorics come
    // from the samples (24 per circle at least, `mesher::EXACT_MIN_PER_CIRCLE`).
    let sampling = crate::mesher::exact_sampling();
    let mut first = None;
    if options.refine_ratio.is_some() {
        match refine_periodic(pd, options, &sampling) {
            Ok(Refinement::Inserted {
                domain,
                inserted,
                layout,
            }) => {
                let mut fluid = vec![false; domain.hole_count()];
                fluid[domain.hole_count() - inserted.len()..].fill(true);
                if let Ok(Some(f)) = exact_attempts(&domain, options, &fluid, layout, keys) {
                    return Ok(Some(f));
                }
            }
            Ok(Refinement::None(p)) => first = p,
            Err(_) => {}
        }
    }
    exact_attempts(pd, options, &[], first, keys)
}

/// What [`refine_periodic`] did.
#[allow(clippy::large_enum_variant)]
enum Refinement {
    /// No vertex orbit was poor (or no hole could be inserted): the first layout, made with
    /// exact mode's collapse fraction, for reuse.
    None(Option<PeriodicLayout>),
    /// Holes inserted: the domain with them appended (the last `inserted.len()` holes), and
    /// its layout when the last round made it (as [`Refinement::None`]'s).
    Inserted {
        domain: PeriodicDomain,
        inserted: Vec<Circle>,
        layout: Option<PeriodicLayout>,
    },
}

/// Most rounds of periodic macro Delaunay refinement.
const MAX_REFINE_ROUNDS: usize = 16;

/// Macro Delaunay refinement on the torus (paper Algorithm 3, as [`crate::refine`] does in
/// bounded domains): while a vertex orbit is poor (the triangle of its exact empty circle's
/// touching points has circumradius over shortest edge above [`Options::refine_ratio`]),
/// insert a hole at the centre of that empty circle with half its radius, wrapped into the
/// box. Poorest first (ties by centre and radius), several per round when they keep the
/// smallest gap `G` of the current domain to every image of every hole and to each other
/// (Lemma 2: an empty circle's half-radius hole always does, up to rounding; a candidate that
/// does not is skipped). Inserted holes are appended after the domain's own; they are fluid
/// and filled by templates ([`exact_mode::periodic::build_with_inserted`]). Stops after
/// [`MAX_REFINE_ROUNDS`] rounds or at [`Options::max_inserted_holes`] (what was inserted so
/// far is kept).
fn refine_periodic(
    pd: &PeriodicDomain,
    options: &Options,
    sampling: &SamplingOptions,
) -> Result<Refinement, MeshError> {
    let Some(limit) = options.refine_ratio else {
        return Ok(Refinement::None(None));
    };
    crate::ranges::check_refine_ratio(limit)?;
    let nearly_zero = Options {
        collapse_fraction: options.collapse_fraction.min(EXACT_COLLAPSE_FRACTION),
        ..options.clone()
    };
    let size = pd.size();
    let mut current = pd.clone();
    let mut inserted: Vec<Circle> = Vec::new();
    // The layout of `current`, when made.
    let mut last = None;
    // Every round's first tiling is the first round's band (inserted holes change the
    // reach `initial_reach` would give, and with it the copies): the next round's tiling is
    // then this one with the inserted holes' copies appended, and its triangulation extends
    // this round's (issue 8).
    let reach = initial_reach(pd);
    // The sampling of the round before, when it found poor vertex orbits.
    let mut previous: Option<Box<Sampled>> = None;
    for _ in 0..MAX_REFINE_ROUNDS {
        // The layout only when it has no poor vertex orbit (else only those: issue 8).
        let round = layout_or_poor(
            &current,
            &nearly_zero,
            sampling,
            limit,
            reach,
            previous.as_deref(),
        )?;
        // Freed on the pool, off this thread.
        if let Some(before) = previous.take() {
            rayon::spawn(move || drop(before));
        }
        let (p, mut poor) = match round {
            Round::Poor(poor, sampled) => {
                previous = Some(sampled);
                (None, poor)
            }
            Round::Layout(p) => {
                let Some(pb) = &p.blocking else {
                    break;
                };
                let poor = if p.no_poor == Some(limit) {
                    Vec::new()
                } else {
                    exact_mode::periodic::poor_vertices(pb, limit)
                };
                (Some(p), poor)
            }
        };
        if poor.is_empty() {
            if inserted.is_empty() {
                return Ok(Refinement::None(p));
            }
            last = p;
            break;
        }
        poor.sort_by(|a, b| {
            b.0.total_cmp(&a.0)
                .then(a.1[0].total_cmp(&b.1[0]))
                .then(a.1[1].total_cmp(&b.1[1]))
                .then(a.2.total_cmp(&b.2))
        });
        let g = current
            .nearest_gaps()
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        // The holes of `current` near each candidate, found through an index of the holes
        // and their images near the box (no scan of every hole per candidate: issue 8).
        let near = NearImages::new(current.holes(), size, g, &poor);
        let index = near.index();
        let mut batch: Vec<Circle> = Vec::new();
        for &(_, centre, rho) in &poor {
            if inserted.len() + batch.len() >= options.max_inserted_holes {
                break;
            }
            if !(centre[0].is_finite() && centre[1].is_finite()) {
                continue;
            }
            let centre = [wrap(centre[0], size[0]), wrap(centre[1], size[1])];
            // Half the empty circle's radius (Lemma 2), but small enough for the hole to keep
            // the gap `G` to its own images: an elongated box's empty circles can be wider
            // than the short period. A smaller hole at the same centre keeps the gap `G` to
            // every other circle too (`rho - R >= rho / 2 >= G`).
            let fit = 0.5 * (size[0].min(size[1]) - g) * (1.0 - 1e-9);
            let hole = Circle {
                center: centre,
                radius: (0.5 * rho).min(fit),
            };
            let ok = hole.radius.is_finite()
                && hole.radius > 0.0
                && size.iter().all(|&l| l - 2.0 * hole.radius >= g)
                && near.keeps_gap(index.as_ref(), &hole)
                && batch.iter().all(|o| image_gap(size, &hole, o) >= g);
            if ok {
                batch.push(hole);
            }
        }
        // (Without the layout, when only the poor orbits were found, the exact attempts
        // make it again: the same sampling, the same layout.)
        if batch.is_empty() {
            last = p;
            break;
        }
        let mut holes = current.holes().to_vec();
        holes.extend_from_slice(&batch);
        match PeriodicDomain::new(size, holes) {
            Ok(d) => current = d,
            Err(_) => {
                last = p;
                break;
            }
        }
        // This round's layout and sampled tiling are freed on the pool, off this thread.
        rayon::spawn(move || drop(p));
        inserted.extend_from_slice(&batch);
    }
    if let Some(before) = previous {
        rayon::spawn(move || drop(before));
    }
    if inserted.is_empty() {
        return Ok(Refinement::None(last));
    }
    Ok(Refinement::Inserted {
        domain: current,
        inserted,
        layout: last,
    })
}

/// The gap from `c` to the nearest image of `o` (centres in the box of `size`: the images in
/// the neighbouring tiles hold the nearest one), as periodic refinement measures it.
fn image_gap(size: [f64; 2], c: &Circle, o: &Circle) -> f64 {
    let mut d = [c.center[0] - o.center[0], c.center[1] - o.center[1]];
    for k in 0..2 {
        d[k] -= (d[k] / size[k]).round() * size[k];
    }
    d[0].hypot(d[1]) - c.radius - o.radius
}

/// The holes of a periodic domain and their images near its box, indexed to find which holes
/// a candidate of periodic refinement could come closer to than the gap `g`
/// ([`NearImages::keeps_gap`]: exactly the scan `holes.iter().all(|o| image_gap(size, q, o)
/// >= g)`, in O(log n) per candidate rather than O(n) once there are many candidates).
struct NearImages<'a> {
    holes: &'a [Circle],
    size: [f64; 2],
    g: f64,
    /// The holes and the images (of the 3 x 3 tiling) whose centres lie within the reach of
    /// the candidates, and the hole each one is a copy of; empty when scanning.
    tiles: Vec<Circle>,
    of: Vec<usize>,
    scan: bool,
}

/// Below this many candidate-hole pairs [`NearImages`] scans (the index costs more).
const NEAR_IMAGES_SCAN: usize = 1 << 22;

impl<'a> NearImages<'a> {
    /// The index for the candidates of `poor` (radii at most half its empty-circle radii).
    fn new(holes: &'a [Circle], size: [f64; 2], g: f64, poor: &[(f64, Point, f64)]) -> Self {
        let scan = poor.len().saturating_mul(holes.len()) <= NEAR_IMAGES_SCAN;
        Self::with_scan(holes, size, g, poor, scan)
    }

    /// [`NearImages::new`], scanning or not as told.
    fn with_scan(
        holes: &'a [Circle],
        size: [f64; 2],
        g: f64,
        poor: &[(f64, Point, f64)],
        scan: bool,
    ) -> Self {
        let mut tiles = Vec::new();
        let mut of = Vec::new();
        if !scan {
            let rmax = holes.iter().map(|c| c.radius).fold(0.0, f64::max);
            let cmax = poor.iter().map(|p| 0.5 * p.2).fold(0.0, f64::max);
            // A copy `o'` with `|q - o'| - r_q - r_o < g` is within `g + r_q + r_o` of `q` (in
            // the box).
            let (t, index_of) = domain::images_near(size, holes, g + cmax + rmax);
            tiles = t;
            of = index_of.into_iter().map(|k| k % holes.len()).collect();
        }
        NearImages {
            holes,
            size,
            g,
            tiles,
            of,
            scan,
        }
    }

    /// The k-d tree of the copies (`None` when scanning).
    fn index(&self) -> Option<crate::domain::HoleIndex<'_>> {
        (!self.scan).then(|| crate::domain::HoleIndex::new(&self.tiles))
    }

    /// `holes.iter().all(|o| image_gap(size, q, o) >= g)` for a candidate `q` (centre in the
    /// box, radius at most the largest half radius of `poor`), `index` from
    /// [`NearImages::index`]: the holes with a copy within a slightly wider gap are measured
    /// with [`image_gap`] itself.
    fn keeps_gap(&self, index: Option<&crate::domain::HoleIndex>, q: &Circle) -> bool {
        let finite = q.center.iter().all(|x| x.is_finite()) && q.radius.is_finite();
        match index {
            Some(index) if finite && self.g.is_finite() => {
                let slack = 1e-9 * (self.g.abs() + q.radius.abs() + self.size[0].max(self.size[1]));
                index
                    .within_gap_of(q, self.g + slack)
                    .into_iter()
                    .all(|k| image_gap(self.size, q, &self.holes[self.of[k]]) >= self.g)
            }
            _ => self
                .holes
                .iter()
                .all(|o| image_gap(self.size, q, o) >= self.g),
        }
    }
}

/// Exact mode with resampling on `pd` (`fluid[k]`: hole `k` was inserted by refinement);
/// `first`, a layout already made with exact mode's collapse fraction on the default
/// sampling, is used for the first attempt. `Ok(None)`: use paper mode.
fn exact_attempts(
    pd: &PeriodicDomain,
    options: &Options,
    fluid: &[bool],
    mut first: Option<PeriodicLayout>,
    keys: bool,
) -> Result<Option<PeriodicFrame>, MeshError> {
    let mut sampling = crate::mesher::exact_sampling();
    // The fallback layout: only zero-length arcs collapsed (exact co-circular groups, one
    // empty circle per collapsed vertex).
    let zero_only = Options {
        collapse_fraction: 0.0,
        ..options.clone()
    };
    let nearly_zero = Options {
        collapse_fraction: options.collapse_fraction.min(EXACT_COLLAPSE_FRACTION),
        ..options.clone()
    };
    for attempt in 0..=EXACT_RESAMPLING {
        // 1. Nearly zero-length arcs collapsed too ([`EXACT_COLLAPSE_FRACTION`]): a nearly
        //    co-circular group (a lattice moved by 1e-6) would otherwise leave arcs of 1e-6
        //    whose blocks are slivers (aspect ratios of 1e11 were measured), or no block area
        //    at all (1e-9). The merged vertex is the empty circle of three of its circles,
        //    its spokes go to the radial projections of its centre; the mesh is kept only
        //    without a corner below `MERGED_MIN_ANGLE_DEG` (as bounded exact mode gives up
        //    such collapses).
        let made = match first.take() {
            Some(p) => Ok(p),
            None => layout_for_exact(pd, &nearly_zero, &sampling),
        };
        let short = match made {
            Ok(p) => Some(p),
            Err(MeshError::Internal(_)) => None,
            Err(_) if attempt > 0 => return Ok(None),
            Err(e) => return Err(e),
        };
        let mut same_as_zero_only = None;
        if let Some(p) = short {
            if p.collapsed_arcs == 0 || nearly_zero.collapse_fraction == 0.0 {
                // Nothing collapsed (or nothing short): the zero-only layout is this one.
                same_as_zero_only = Some(p);
            } else {
                let sampled = p.sampled.clone();
                match exact_frame(pd, p, options, fluid, true, keys)? {
                    Framed::Done(f) => return Ok(Some(f)),
                    // Arcs running backwards come from the sampling, not from the collapse:
                    // the zero-only layout of the same sampling has them too (issue 8: at
                    // 10 000 holes it had the same ones, for a layout and an exact build more
                    // per attempt). Fix them on this sampling, else resample around them at
                    // once; the last attempt still tries the zero-only layout.
                    Framed::Failed { holes, arcs }
                        if !arcs.is_empty() && attempt < EXACT_RESAMPLING =>
                    {
                        let fixed =
                            local_fix(pd, &nearly_zero, options, fluid, sampled, &arcs, keys)?;
                        if let Some(f) = fixed {
                            return Ok(Some(f));
                        }
                        refine_around(&mut sampling, holes);
                        continue;
                    }
                    Framed::Failed { .. } => {}
                }
            }
        }
        // 2. Only zero-length arcs collapsed.
        let p = match same_as_zero_only {
            Some(p) => p,
            None => match layout_for_exact(pd, &zero_only, &sampling) {
                Ok(p) => p,
                Err(MeshError::Internal(_)) => return Ok(None),
                Err(_) if attempt > 0 => return Ok(None),
                Err(e) => return Err(e),
            },
        };
        // No exact input (the orbits of the collapsed vertices were not consistent): paper.
        if p.blocking.is_none() {
            return Ok(None);
        }
        let sampled = p.sampled.clone();
        match exact_frame(pd, p, options, fluid, false, keys)? {
            Framed::Done(f) => return Ok(Some(f)),
            Framed::Failed { holes, arcs, .. } => {
                let fixed = local_fix(pd, &zero_only, options, fluid, sampled, &arcs, keys)?;
                if let Some(f) = fixed {
                    return Ok(Some(f));
                }
                refine_around(&mut sampling, holes)
            }
        }
    }
    Ok(None)
}

/// Exact mode's local fix on one sampling (issue 8, as bounded exact mode's degree-4
/// collapse of a backwards arc): the layout of `sampled` made with `layout_options`, with the
/// arc orbits `arcs` (running backwards) collapsed in every copy besides those of `before`
/// ([`reextract`]), built and kept only when no arc runs backwards, no cell is inverted and
/// no corner is below [`crate::mesher::MERGED_MIN_ANGLE_DEG`]. `Ok(None)` when there is
/// nothing to fix or the fix did not hold (the caller resamples); errors other than
/// [`MeshError::Internal`] are returned.
fn local_fix(
    pd: &PeriodicDomain,
    layout_options: &Options,
    options: &Options,
    fluid: &[bool],
    sampled: Option<std::sync::Arc<Sampled>>,
    arcs: &[ArcKey],
    keys: bool,
) -> Result<Option<PeriodicFrame>, MeshError> {
    let Some(sampled) = sampled.filter(|_| !arcs.is_empty()) else {
        return Ok(None);
    };
    // One fix per sampling: the sampled tiling is dropped before the build, which takes the
    // vertex orbits solved for the layout being fixed.
    let made = reextract(pd, layout_options, &sampled, arcs);
    let solved = sampled.solved_orbits.lock().ok().and_then(|mut s| s.take());
    // (Freed on the pool while the build starts: 0.08 s of frees at 1e5 holes.)
    rayon::spawn(move || drop(sampled));
    let mut p = match made {
        Ok(p) => p,
        Err(MeshError::Internal(_)) => return Ok(None),
        Err(e) => return Err(e),
    };
    if p.blocking.is_none() {
        return Ok(None);
    }
    p.solved_orbits = solved.map(std::sync::Arc::new);
    match exact_frame(pd, p, options, fluid, true, keys)? {
        Framed::Done(f) => Ok(Some(f)),
        Framed::Failed { .. } => Ok(None),
    }
}

/// Refine `sampling` 4x on the orbits of `holes` (issue 8: as bounded exact mode does; a
/// global resampling quadrupled the samples of every copy of every hole, seconds for a
/// thousand holes), everywhere when `holes` is empty (the place is not known).
fn refine_around(sampling: &mut SamplingOptions, holes: Vec<u32>) {
    if holes.is_empty() {
        sampling.min_per_circle = sampling.min_per_circle.saturating_mul(4);
        sampling.spacing_per_gap *= 0.25;
    }
    for k in holes {
        let slot = k as usize + 1;
        if sampling.boost.len() <= slot {
            sampling.boost.resize(slot + 1, 0);
        }
        sampling.boost[slot] += 2;
    }
}

/// What [`exact_frame`] made of a layout.
#[allow(clippy::large_enum_variant)]
enum Framed {
    Done(PeriodicFrame),
    /// No valid exact mesh: the canonical holes (indices into the domain's holes, sorted,
    /// distinct) of the arc orbits that disagreed and of their end vertex orbits, or none
    /// when the place is not known (the exact construction failed, a template block);
    /// `arcs`, the orbit keys of the arcs that ran backwards (the sampled combinatorics were
    /// wrong there), empty when none did.
    Failed {
        holes: Vec<u32>,
        arcs: Vec<ArcKey>,
    },
}

/// The canonical holes around the blocks `bad` of the exact build of `pb` (block `2o + s`
/// is side `s` of arc orbit `o`): those of the arc orbit and of its two end vertex orbits.
/// Empty when a block is not a medial block (a template's), so that the caller refines
/// everywhere.
fn holes_around(pb: &PeriodicBlocking, bad: &[usize]) -> Vec<u32> {
    let mut out = Vec::new();
    for &b in bad {
        let Some(arc) = pb.arcs.get(b / 2) else {
            return Vec::new();
        };
        out.extend(arc.circles.iter().map(|t| t.0));
        for &(v, _) in &arc.ends {
            if let Some(v) = pb.vertices.get(v) {
                out.extend(v.circles.iter().map(|t| t.0));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Periodic exact mode collapses arcs shorter than this fraction of the local empty-circle
/// radius (or `collapse_fraction` when smaller), not paper mode's `collapse_fraction`: enough
/// for nearly co-circular groups (whose arcs would be slivers), while an arc of a few percent
/// of the radius keeps its exact blocks (collapsing it into a merged vertex cost up to 10
/// degrees of smallest angle on random layouts).
pub const EXACT_COLLAPSE_FRACTION: f64 = 1e-3;

/// The exact mesh of `p` (its [`PeriodicLayout::blocking`]), or [`Framed::Failed`] without
/// exact input, when an arc runs backwards, a cell is inverted, or (`strict`) a cell has a
/// corner angle below [`crate::mesher::MERGED_MIN_ANGLE_DEG`]. Errors other than
/// [`MeshError::Internal`] are returned.
fn exact_frame(
    pd: &PeriodicDomain,
    mut p: PeriodicLayout,
    options: &Options,
    fluid: &[bool],
    strict: bool,
    keys: bool,
) -> Result<Framed, MeshError> {
    let framed = frame_of(pd, &mut p, options, fluid, strict, keys);
    // What is left of the layout (its tiling, blocking and arc keys; a rejected mesh's grids)
    // is freed on the pool, off this thread (issue 8: 0.2 s at 1e5 holes), or left to the
    // exit when this frame is the mesh ([`Options::exits_after_mesh`]).
    match framed {
        Ok(Framed::Done(_)) => crate::mesher::let_go(options, p),
        _ => rayon::spawn(move || drop(p)),
    }
    framed
}

/// [`exact_frame`], taking from `p` what the frame keeps.
fn frame_of(
    pd: &PeriodicDomain,
    p: &mut PeriodicLayout,
    options: &Options,
    fluid: &[bool],
    strict: bool,
    keys: bool,
) -> Result<Framed, MeshError> {
    let Some(pb) = &p.blocking else {
        return Ok(Framed::Failed {
            holes: Vec::new(),
            arcs: Vec::new(),
        });
    };
    let failed_at = |arcs: &[usize]| {
        let bad: Vec<usize> = arcs.iter().flat_map(|&o| [2 * o, 2 * o + 1]).collect();
        Framed::Failed {
            holes: holes_around(pb, &bad),
            arcs: arcs
                .iter()
                .filter_map(|&o| p.arc_keys.get(o).copied())
                .collect(),
        }
    };
    // The extraction found the arcs running backwards (the layout is not numbered): the
    // stopped build's answer, after its options check.
    if let Some(arcs) = &p.backwards {
        return match exact_mode::validate_options(options) {
            Ok(()) => Ok(failed_at(arcs)),
            Err(MeshError::Internal(_)) => Ok(Framed::Failed {
                holes: Vec::new(),
                arcs: Vec::new(),
            }),
            Err(e) => Err(e),
        };
    }
    // A build with arcs running backwards stops before its grids (the mesh would not be
    // kept): those arcs are collapsed, or the holes around them resampled, by the caller.
    // It takes the vertex orbits solved for the layout this one fixes, if any.
    let known = p
        .solved_orbits
        .take()
        .and_then(|k| std::sync::Arc::try_unwrap(k).ok());
    // The blocks with an inverted cell, and when `strict` those with a corner below
    // `MERGED_MIN_ANGLE_DEG`, found by the build as it makes each grid (issue 8: a pass over
    // every grid after it took 0.23 s at 1e5 holes). Strict takes one test per cell: a cell
    // with an inverted corner (cross product `<= 0` or NaN) has a corner below any angle by
    // the same products ([`crate::quality::has_corner_below`], tested in `quality`'s
    // `inverted_cells_have_a_corner_below_any_angle`).
    let flag = if strict {
        exact_mode::periodic::Flag::CornerBelow(crate::mesher::MERGED_MIN_ANGLE_DEG)
    } else {
        exact_mode::periodic::Flag::Inverted
    };
    let mut x = match timings::span("exact_geometry", || {
        exact_mode::periodic::build_unless_backwards_with(
            pb,
            options,
            fluid,
            keys,
            known,
            Some(flag),
        )
    }) {
        Ok(exact_mode::periodic::Built::Mesh(x)) => *x,
        Ok(exact_mode::periodic::Built::Backwards(arcs)) => return Ok(failed_at(&arcs)),
        Err(MeshError::Internal(_)) => {
            return Ok(Framed::Failed {
                holes: Vec::new(),
                arcs: Vec::new(),
            })
        }
        Err(e) => return Err(e),
    };
    // (The check's span stays, empty: the rework figures count the checks.)
    let bad: Vec<usize> = timings::span("quality_check", || std::mem::take(&mut x.flagged));
    // (No arc of a whole build runs backwards: `build_unless_backwards`.)
    if !bad.is_empty() {
        let holes = holes_around(pb, &bad);
        rayon::spawn(move || drop(x));
        return Ok(Framed::Failed {
            holes,
            arcs: Vec::new(),
        });
    }
    let real = pd.hole_count() - fluid.iter().filter(|&&f| f).count();
    let mesh = Mesh {
        layout: x.layout,
        grids: x.grids,
        medial_vertices: p.medial_vertices,
        medial_arcs: p.medial_arcs,
        holes: real,
        collapsed_arcs: p.collapsed_arcs,
        cocircular_groups: std::mem::take(&mut p.cocircular_groups),
        inserted_holes: pd.holes()[real..].to_vec(),
        split_arcs: x.split_arcs,
        template_blocks: x.template_blocks,
        geometry: crate::mesh::Geometry::Exact,
        coarsened_cell_size: x.coarsened_from.map(|from| [from, x.cell_size]),
        measured: x.measured,
    };
    // Template blocks have no key: node counts are imposed on layouts without them only.
    let keys = (keys && x.template_blocks == 0).then_some(x.keys);
    Ok(Framed::Done(PeriodicFrame {
        mesh,
        triples: std::mem::take(&mut p.triples),
        keys,
    }))
}

/// The period `[Lx, Ly]` of a periodic layout, read off its translations (the smallest
/// non-zero `|tx|` and `|ty|`); `None` for a layout without periodic sides.
pub fn period_of(layout: &BlockLayout) -> Option<[f64; 2]> {
    let mut out = [f64::INFINITY; 2];
    for e in &layout.edges {
        if let EdgeKind::Periodic { translation, .. } = e.kind {
            for (o, t) in out.iter_mut().zip(translation.0) {
                let v = t.abs();
                if v > 0.0 && v < *o {
                    *o = v;
                }
            }
        }
    }
    (out[0].is_finite() && out[1].is_finite()).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both periodic entry points check `Options::block_cells` as the bounded one does (they
    /// did not: a fixed grid then won over `cell_size` or `wall_cells` without a word, and 0
    /// cells became 1): the same errors, for the paper pipeline too.
    #[test]
    fn periodic_entry_points_check_block_cells_as_the_bounded_one() {
        let pd = crate::layouts::periodic_bubbles(20, 1).expect("layout");
        let bounded = crate::layouts::bubbles(20, 1).expect("layout");
        let fixed = |n: usize| Options {
            block_cells: Some(n),
            ..Options::default()
        };
        let bad = [
            fixed(0),
            fixed(crate::grid::MAX_CELLS_PER_SIDE + 1),
            Options {
                cell_size: Some(0.1),
                ..fixed(4)
            },
            Options {
                wall_cells: vec![(0, 3)],
                ..fixed(4)
            },
            Options {
                wall_cells: vec![(0, 3)],
                ..Options {
                    mode: Mode::Paper,
                    ..fixed(4)
                }
            },
        ];
        for options in bad {
            let want = crate::mesh(&bounded, &options)
                .expect_err("refused")
                .to_string();
            assert!(
                want.contains("block-cells") || want.contains("cells"),
                "{want}"
            );
            let got = mesh_periodic(&pd, &options).expect_err("refused");
            assert_eq!(got.to_string(), want);
            let got = mesh_periodic_frame(&pd, &options).expect_err("refused");
            assert_eq!(got.to_string(), want);
        }
    }

    /// [`normalise_cluster`] as it was: one candidate per sample, the least taken.
    fn normalise_cluster_every_sample(key: &[SampleKey]) -> (ClusterKey, (i32, i32)) {
        key.iter()
            .map(|s| {
                let d = (s.2, s.3);
                let mut k: ClusterKey =
                    key.iter().map(|x| shift_sample(*x, (-d.0, -d.1))).collect();
                k.sort_unstable();
                (k, d)
            })
            .min()
            .unwrap_or_else(|| (key.to_vec(), (0, 0)))
    }

    /// [`normalise_vertex`] and [`normalise_arc`] as they were: one candidate per sample or
    /// circle, the least taken.
    fn normalise_vertex_every_sample(v: &VertexKey) -> (VertexKey, (i32, i32)) {
        v.iter()
            .map(|s| {
                let d = (s.2, s.3);
                (shift_vertex(v, (-d.0, -d.1)), d)
            })
            .min()
            .unwrap_or((*v, (0, 0)))
    }
    fn normalise_arc_every_circle(a: &ArcKey) -> (ArcKey, (i32, i32)) {
        a.0.iter()
            .map(|c| {
                let d = (c.1, c.2);
                (shift_arc(a, (-d.0, -d.1)), d)
            })
            .min()
            .unwrap_or((*a, (0, 0)))
    }

    fn sample_key() -> impl proptest::strategy::Strategy<Value = SampleKey> {
        (0u32..3, 0u32..3, -1i32..2, -1i32..2)
    }

    proptest::proptest! {
        /// The same for vertex and arc keys: each distinct shift tried once gives the
        /// representative of trying every sample's or circle's, in one tile or several.
        #[test]
        fn normalise_vertex_and_arc_try_each_shift_once(
            v in proptest::array::uniform3(sample_key()),
            w in proptest::array::uniform3(sample_key()),
            c in proptest::array::uniform2((0u32..3, -1i32..2, -1i32..2)),
            one_tile in proptest::bool::ANY,
        ) {
            let tile = |k: SampleKey| if one_tile { (k.0, k.1, 0, 1) } else { k };
            let (mut v, mut w) = (v.map(tile), w.map(tile));
            v.sort_unstable();
            w.sort_unstable();
            proptest::prop_assert_eq!(normalise_vertex(&v), normalise_vertex_every_sample(&v));
            let mut c = if one_tile { c.map(|x| (x.0, 0, 1)) } else { c };
            c.sort_unstable();
            let mut ends = [v, w];
            ends.sort_unstable();
            let a: ArcKey = (c, ends);
            proptest::prop_assert_eq!(normalise_arc(&a), normalise_arc_every_circle(&a));
        }

        /// Trying each distinct tile shift once gives the representative and shift of trying
        /// every sample's (issue 8), for sorted keys (as the extraction makes them) and any
        /// other, with samples in one tile, in several and repeated.
        #[test]
        fn normalise_cluster_tries_each_shift_once(
            raw in proptest::collection::vec((0u32..4, 0u32..3, -2i32..3, -2i32..3), 0..12),
            sorted in proptest::bool::ANY,
            one_tile in proptest::bool::ANY,
        ) {
            let mut key: ClusterKey = raw
                .iter()
                .map(|&(c, i, a, b)| if one_tile { (c, i, 1, -1) } else { (c, i, a, b) })
                .collect();
            if sorted {
                key.sort_unstable();
                key.dedup();
            }
            proptest::prop_assert_eq!(
                normalise_cluster(&key),
                normalise_cluster_every_sample(&key)
            );
        }
    }

    /// The array of copies may reach 7 long periods a side: `7 x 7` for a square box, up to
    /// `7 A` copies along the short side of a box of aspect ratio `A` (odd counts, so at most
    /// `2 m + 1 <= 7 A`).
    #[test]
    fn the_array_is_capped_at_seven_long_periods_a_side() {
        assert_eq!(max_half_widths([1.0, 1.0]), [3, 3]);
        assert_eq!(max_half_widths([10.0, 0.5]), [3, 69]);
        assert_eq!(max_half_widths([0.3, 1.0]), [11, 3]);
        for size in [
            [1.0f64, 1.0],
            [10.0, 0.5],
            [0.3, 1.0],
            [1.0, 7.3],
            [1e6, 1.0],
        ] {
            let l = size[0].max(size[1]);
            let m = max_half_widths(size);
            for a in 0..2 {
                let side = (2 * m[a] + 1) as f64 * size[a];
                assert!(side <= 7.0 * l * (1.0 + 1e-12), "{size:?}: {m:?}");
                assert!(
                    side + 2.0 * size[a] > 7.0 * l,
                    "{size:?}: {m:?} not the largest"
                );
            }
        }
    }

    /// The next tiling holds what the offending circles need; a blind step grows both axes
    /// by half (at least one); the cap bounds everything, and nothing to grow ends the search.
    #[test]
    fn the_tiling_grows_to_what_the_circles_need() {
        let cap = [3, 69];
        assert_eq!(next_tiling([1, 1], [1, 11], false, cap), Some([1, 11]));
        assert_eq!(next_tiling([1, 11], [1, 11], true, cap), Some([2, 16]));
        assert_eq!(next_tiling([1, 1], [5, 200], false, cap), Some([3, 69]));
        assert_eq!(next_tiling([3, 69], [5, 200], false, cap), None);
        assert_eq!(next_tiling([3, 69], [3, 69], true, cap), None);
        assert_eq!(next_tiling([2, 4], [1, 1], false, cap), None);
        // Never shrinks.
        assert_eq!(next_tiling([2, 4], [1, 9], false, cap), Some([2, 9]));
    }

    /// The options and sampling of a periodic refinement round (exact mode).
    fn refinement_round() -> (Options, SamplingOptions) {
        let options = Options {
            collapse_fraction: EXACT_COLLAPSE_FRACTION,
            ..Options::default()
        };
        (options, crate::mesher::exact_sampling())
    }

    /// Random boxes with poor vertex orbits at low ratios: `(holes, seed, box)`.
    fn refinement_boxes() -> Vec<(usize, u64, PeriodicDomain)> {
        [(60, 1), (120, 2), (40, 5)]
            .into_iter()
            .map(|(n, seed)| (n, seed, random_box(n, seed)))
            .collect()
    }

    /// The triangle set of a triangulation, as sorted triples of sorted points (bits): what
    /// does not depend on the numbering of points or triangles.
    fn triangle_set(points: &[Point], tri: &Triangulation) -> Vec<[[u64; 2]; 3]> {
        let mut set: Vec<[[u64; 2]; 3]> = tri
            .triangles()
            .map(|t| {
                let mut p = t.map(|v| points[v as usize].map(f64::to_bits));
                p.sort_unstable();
                p
            })
            .collect();
        set.sort_unstable();
        set
    }

    /// A refinement round's tiling is the round before's with the inserted holes' copies
    /// appended (the same reach): its triangulation extends the earlier one (as a prefix, or
    /// renumbered where circles near the new holes were sampled more densely) and is the
    /// triangle set of a triangulation from scratch, and the sampling's classes and medial
    /// graph (reused from the round before) are those of that triangulation; a tiling that
    /// does not hold the earlier samples (a different reach) is triangulated from scratch.
    #[test]
    fn a_refinement_round_extends_the_earlier_triangulation() {
        let (options, sampling) = refinement_round();
        let (mut extended, mut reused) = (0, 0);
        for (n, _, pd) in refinement_boxes() {
            let reach = initial_reach(&pd);
            let Round::Poor(poor, before) =
                layout_or_poor(&pd, &options, &sampling, 0.9, reach, None).unwrap()
            else {
                panic!("{n} holes: no poor vertex orbit at ratio 0.9");
            };
            // The poorest candidate, inserted as refinement would (half the empty radius).
            let (_, c, rho) = poor
                .iter()
                .copied()
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .unwrap();
            let size = pd.size();
            let mut holes = pd.holes().to_vec();
            holes.push(Circle::new(
                wrap(c[0], size[0]),
                wrap(c[1], size[1]),
                0.5 * rho,
            ));
            let next = PeriodicDomain::new(size, holes).unwrap();
            let gaps = next.nearest_gaps();
            for (r, same_reach) in [(reach, true), ([0.75 * reach[0]; 2], false)] {
                let t = Tiling::with_reach(&next, before.t.m, r).unwrap();
                let (samples, fresh, _, _) =
                    sample_tiling(&t, &gaps, &sampling, false, None).unwrap();
                let (tri, made) =
                    extended_or_new((&before.samples, &before.tri), &samples).unwrap();
                assert_eq!(
                    triangle_set(&samples.points, &tri),
                    triangle_set(&samples.points, &fresh),
                    "{n} holes"
                );
                if same_reach {
                    assert_ne!(made, Made::Fresh, "{n} holes");
                    extended += 1;
                    // The sampling itself: its classes and medial graph, reused from the
                    // round before where the triangles were kept, are those of its
                    // triangulation computed afresh.
                    let (samples, tri, kinds, medial) =
                        sample_tiling(&t, &gaps, &sampling, false, Some(&before)).unwrap();
                    assert_eq!(kinds, crate::medial::classify(&samples, &tri), "{n} holes");
                    assert_eq!(
                        medial,
                        medial_graph(&samples, &tri, &kinds).unwrap(),
                        "{n} holes"
                    );
                    reused += usize::from(made == Made::Extended);
                    // The round on that domain answers as one without the round before
                    // (its vertex solves reused, its triangulation extended): the same
                    // candidates, bit for bit (in another vertex order).
                    let sorted = |round: Round| {
                        let Round::Poor(poor, _) = round else {
                            panic!("{n} holes: no poor vertex orbit at ratio 0.9 after one hole");
                        };
                        let mut bits: Vec<[u64; 4]> = poor
                            .iter()
                            .map(|c| [c.0, c.1[0], c.1[1], c.2].map(f64::to_bits))
                            .collect();
                        bits.sort_unstable();
                        bits
                    };
                    let round = |previous| {
                        layout_or_poor(&next, &options, &sampling, 0.9, reach, previous).unwrap()
                    };
                    assert_eq!(
                        sorted(round(Some(&before))),
                        sorted(round(None)),
                        "{n} holes"
                    );
                } else {
                    assert_eq!(made, Made::Fresh, "{n} holes");
                }
            }
        }
        assert_eq!(extended, 3);
        assert!(
            reused > 0,
            "no round extended the earlier samples as a prefix"
        );
    }

    /// A pair of holes 1e-5 of their radius apart across the box's edge: the canonical
    /// copies are sampled adaptively (densely only facing the contact: far fewer samples than
    /// the `2 pi r / gap` a uniform sampling needs, and the samples on the far half of each
    /// circle at the coarse spacing), and every copy of an orbit carries the canonical
    /// samples plus its quantised period shift, bit for bit (what makes the Delaunay
    /// triangulation of every copy alike).
    #[test]
    fn near_touching_orbits_are_sampled_adaptively_and_alike() {
        let (r, g) = (0.2, 2e-6);
        let pd = PeriodicDomain::new(
            [1.0, 0.8],
            vec![
                Circle::new(0.79, 0.4, r),
                Circle::new(0.79 + 2.0 * r + g - 1.0, 0.41, r),
            ],
        )
        .unwrap();
        let t = Tiling::new(&pd, [1, 1]).unwrap();
        let opts = SamplingOptions::default();
        let (samples, ..) = sample_tiling(&t, &pd.nearest_gaps(), &opts, false, None).unwrap();
        let uniform = std::f64::consts::TAU * r / (opts.spacing_per_gap * g);
        for k in 0..2 {
            let canon = samples.of_circle(t.id(k, 0, 0));
            assert!(
                (canon.count as f64) < uniform / 100.0,
                "hole {k}: {} samples, uniform {uniform}",
                canon.count
            );
            let c = pd.holes()[k];
            // The copy whose centre is nearest the other hole faces the contact.
            let pts = |id: CircleId| {
                let cs = samples.of_circle(id);
                &samples.points[cs.first as usize..(cs.first + cs.count) as usize]
            };
            let p0 = pts(t.id(k, 0, 0));
            let far = p0
                .iter()
                .filter(|p| {
                    let other = pd.holes()[1 - k].center;
                    // Points on the half of the circle facing away from every image of
                    // the other hole along x.
                    let dx = (other[0] - c.center[0]).rem_euclid(1.0);
                    let toward = if dx < 0.5 { 1.0 } else { -1.0 };
                    (p[0] - c.center[0]) * toward < -0.5 * r
                })
                .count();
            assert!(
                far <= 2 + canon.count as usize / 4,
                "hole {k}: {far} far samples"
            );
            for (a, b) in tile_array(t.m) {
                let copy = pts(t.id(k, a, b));
                assert_eq!(copy.len(), p0.len());
                let shift = [a as f64 * t.lq[0], b as f64 * t.lq[1]];
                for (q, p) in copy.iter().zip(p0) {
                    assert_eq!(q[0].to_bits(), (p[0] + shift[0]).to_bits());
                    assert_eq!(q[1].to_bits(), (p[1] + shift[1]).to_bits());
                    // ... and the shift is exact: subtracting it gives the canonical point.
                    assert_eq!((q[0] - shift[0]).to_bits(), p[0].to_bits());
                }
            }
            // Grid indices are increasing, on a grid that is a multiple of 8.
            let n = samples.grid_count(t.id(k, 0, 0));
            assert!(n.is_multiple_of(8));
            let first = canon.first as usize;
            let grid = &samples.grid[first..first + canon.count as usize];
            assert!(grid.windows(2).all(|w| w[0] < w[1]) && grid.iter().all(|&x| x < n));
        }
    }

    /// `n` random holes (radii 0.5 to 1, gaps at least 0.05 to every image) in a square box
    /// with about 30% of its area in holes.
    fn random_box(n: usize, seed: u64) -> PeriodicDomain {
        let mut rng = crate::layouts::SplitMix64(seed);
        let l = (n as f64 * std::f64::consts::PI * 0.5625 / 0.3).sqrt();
        let mut holes: Vec<Circle> = Vec::new();
        let mut tries = 0;
        while holes.len() < n && tries < 200 * n {
            tries += 1;
            let r = 0.5 + 0.5 * rng.next_f64();
            let c = [l * rng.next_f64(), l * rng.next_f64()];
            let apart = holes.iter().all(|o| {
                let d = [0, 1].map(|a| {
                    let x = c[a] - o.center[a];
                    x - (x / l).round() * l
                });
                d[0].hypot(d[1]) > r + o.radius + 0.05
            });
            if apart {
                holes.push(Circle::new(c[0], c[1], r));
            }
        }
        PeriodicDomain::new([l, l], holes).unwrap()
    }

    /// A refinement round ([`layout_or_poor`]) first asks the sampled medial graph
    /// ([`poor::medial_poor`]): when it has poor vertex orbits, those are the answer, without
    /// the layout, and they are the poor vertex orbits of the whole layout's exact input
    /// (the same circles up to rounding; the layouts here collapse no arc, so every vertex orbit
    /// of the layout is one medial vertex orbit), each orbit once (no two candidates are
    /// translates of each other by the period). Otherwise the layout's exact input is asked,
    /// and without poor orbits the round gives the whole layout itself, its exact input
    /// included, marked as checked for that ratio (not numbered when it has arcs running
    /// backwards).
    #[test]
    fn a_refinement_round_finds_the_poor_orbits_of_the_whole_layout() {
        let (options, sampling) = refinement_round();
        let (mut poor_rounds, mut layout_rounds, mut compared) = (0, 0, 0);
        for (n, _, pd) in refinement_boxes() {
            let size = pd.size();
            let whole = layout_keeping(&pd, &options, &sampling).unwrap();
            let pb = whole.blocking.as_ref().expect("an exact input");
            let sampled = whole
                .sampled
                .as_ref()
                .expect("exact mode keeps its sampling");
            for limit in [0.9, 1.2, 2.0, 1e3] {
                let expected = exact_mode::periodic::poor_vertices(pb, limit);
                let medial = poor::medial_poor(&pd, sampled, limit, None);
                if whole.collapsed_arcs == 0 {
                    // The same orbits and circles; the solves may round differently (the
                    // circles in another order), so within a relative 1e-12.
                    let by_centre = |mut v: Vec<(f64, Point, f64)>| {
                        v.sort_by(|a, b| a.1[0].total_cmp(&b.1[0]).then(a.1[1].total_cmp(&b.1[1])));
                        v
                    };
                    let (m, e) = (by_centre(medial.clone()), by_centre(expected.clone()));
                    compared += m.len();
                    assert_eq!(m.len(), e.len(), "{n} holes, ratio {limit}");
                    let near = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
                    for (a, b) in m.iter().zip(&e) {
                        assert!(
                            near(a.0, b.0) && near(a.1[0], b.1[0]) && near(a.1[1], b.1[1]),
                            "{n} holes, ratio {limit}: {a:?} {b:?}"
                        );
                        assert!(near(a.2, b.2), "{n} holes, ratio {limit}: {a:?} {b:?}");
                    }
                }
                for (i, a) in medial.iter().enumerate() {
                    for b in &medial[..i] {
                        let d = [0, 1].map(|k| {
                            let x = a.1[k] - b.1[k];
                            x - (x / size[k]).round() * size[k]
                        });
                        assert!(d[0].hypot(d[1]) > 1e-9, "{n} holes: one orbit twice");
                    }
                }
                match layout_or_poor(&pd, &options, &sampling, limit, initial_reach(&pd), None)
                    .unwrap()
                {
                    Round::Poor(poor, _) => {
                        if medial.is_empty() {
                            assert_eq!(poor, expected, "{n} holes, ratio {limit}");
                        } else {
                            assert_eq!(poor, medial, "{n} holes, ratio {limit}");
                        }
                        assert!(!poor.is_empty());
                        poor_rounds += 1;
                    }
                    Round::Layout(p) => {
                        assert!(expected.is_empty(), "{n} holes, ratio {limit}");
                        assert!(medial.is_empty(), "{n} holes, ratio {limit}");
                        assert_eq!(p.blocking, whole.blocking);
                        assert_eq!(p.arc_keys, whole.arc_keys);
                        if p.backwards.is_some() {
                            // Not numbered (see the test after this one).
                            assert!(p.layout.blocks.is_empty());
                            layout_rounds += 1;
                            continue;
                        }
                        assert_eq!(p.layout, whole.layout);
                        assert_eq!(
                            (p.triples, p.arc_keys),
                            (whole.triples.clone(), whole.arc_keys.clone())
                        );
                        assert_eq!(p.no_poor, Some(limit));
                        layout_rounds += 1;
                    }
                }
            }
        }
        assert!(
            poor_rounds > 0 && layout_rounds > 0 && compared > 0,
            "{poor_rounds} {layout_rounds} {compared}"
        );
    }

    /// Periodic refinement's gap check through the index of near images answers as the scan
    /// over every hole, on candidates anywhere in the box (near its edges and corners, where
    /// the nearest copy is an image), of every size up to half the empty radius, with gaps
    /// `g` from far below to far above the domain's, and on the exact boundary `g =`
    /// the candidate's gap to its nearest hole.
    #[test]
    fn the_near_images_gap_check_equals_the_scan() {
        for (n, seed) in [(60, 11), (200, 12), (7, 13)] {
            let pd = random_box(n, seed);
            let size = pd.size();
            let holes = pd.holes();
            let mut rng = crate::layouts::SplitMix64(seed + 100);
            let mut poor = Vec::new();
            for _ in 0..400 {
                let c = [size[0] * rng.next_f64(), size[1] * rng.next_f64()];
                // Near the edges and corners too.
                let c = if rng.next_f64() < 0.3 {
                    [c[0] * 0.02, size[1] - c[1] * 0.02]
                } else {
                    c
                };
                poor.push((3.0, c, 4.0 * rng.next_f64()));
            }
            let (mut kept, mut refused) = (0, 0);
            for g in [0.001, 0.05, 0.3, 1.0, 3.0] {
                let scan = NearImages::with_scan(holes, size, g, &poor, true);
                let tree = NearImages::with_scan(holes, size, g, &poor, false);
                let index = tree.index();
                assert!(index.is_some() && scan.index().is_none());
                for &(_, c, rho) in &poor {
                    let q = Circle {
                        center: c,
                        radius: 0.5 * rho,
                    };
                    let by_scan = holes.iter().all(|o| image_gap(size, &q, o) >= g);
                    assert_eq!(scan.keeps_gap(None, &q), by_scan);
                    assert_eq!(tree.keeps_gap(index.as_ref(), &q), by_scan, "{q:?} g {g}");
                    if by_scan {
                        kept += 1;
                    } else {
                        refused += 1;
                    }
                    // On the boundary: the gap to the nearest hole, exactly.
                    let g0 = holes
                        .iter()
                        .map(|o| image_gap(size, &q, o))
                        .fold(f64::INFINITY, f64::min);
                    if g0.is_finite() && g0 > 0.0 {
                        let edge = NearImages::with_scan(holes, size, g0, &poor, false);
                        let i = edge.index();
                        assert!(edge.keeps_gap(i.as_ref(), &q));
                        let above = NearImages::with_scan(holes, size, g0.next_up(), &poor, false);
                        let i = above.index();
                        assert!(!above.keeps_gap(i.as_ref(), &q));
                    }
                }
            }
            assert!(
                kept > 0 && refused > 0,
                "both outcomes occur ({kept}, {refused})"
            );
        }
    }

    /// A band of copies holds exactly the copies whose centres are within the reach of the
    /// box (brute force over the array), the canonical ones always; ids and keys are inverse;
    /// an axis whose reach is the array's holds every copy along it.
    #[test]
    fn a_band_holds_the_copies_within_its_reach() {
        let pd = random_box(40, 3);
        let l = pd.size();
        for reach in [[0.0, 0.0], [1.5, 4.0], [l[0], 2.5], [l[0], l[1]]] {
            let t = Tiling::with_reach(&pd, [1, 1], reach).unwrap();
            let mut count = 0;
            for (k, c) in pd.holes().iter().enumerate() {
                for (a, b) in tile_array([1, 1]) {
                    let p = [c.center[0] + a as f64 * l[0], c.center[1] + b as f64 * l[1]];
                    let inside = (0..2).all(|x| -reach[x] <= p[x] && p[x] <= l[x] + reach[x]);
                    let id = t.id(k, a, b);
                    assert_eq!(id >= 0, inside || (a, b) == (0, 0), "{reach:?} {k} {a} {b}");
                    if id >= 0 {
                        count += 1;
                        assert_eq!(t.key(id), Some((k as u32, a, b)));
                        let h = t.domain.holes()[id as usize];
                        assert_eq!((h.center, h.radius), (p, c.radius));
                    }
                }
            }
            assert_eq!(t.domain.holes().len(), count);
            assert_eq!(t.copies.iter().sum::<usize>(), count);
            if reach == l {
                assert_eq!(count, 9 * pd.hole_count());
            }
        }
    }

    /// The band gives the layout of the whole 3 x 3 array (the oracle: step 4 makes every
    /// kept triangle one of the infinite tiling, so the band and the array must agree): the
    /// same medial combinatorics, counts and block corners (up to rounding: an orbit's
    /// representative may be another instance), on boxes of 30 to 200 holes, with far fewer
    /// copies.
    #[test]
    fn a_band_of_copies_gives_the_whole_arrays_layout() {
        let exact = crate::mesher::exact_sampling();
        let options = Options {
            collapse_fraction: EXACT_COLLAPSE_FRACTION,
            ..Options::default()
        };
        // The last box has its holes in one corner: its empty circles are far wider than the
        // first band, which has to grow (`next_extent`).
        let clustered = {
            let b = random_box(60, 5);
            let holes = b
                .holes()
                .iter()
                .map(|c| Circle::new(c.center[0], c.center[1], c.radius));
            PeriodicDomain::new([4.0 * b.size()[0], 3.0 * b.size()[1]], holes.collect()).unwrap()
        };
        for (n, seed) in [(30, 1), (60, 2), (120, 3), (200, 4), (60, 0)] {
            let pd = if seed == 0 {
                clustered.clone()
            } else {
                random_box(n, seed)
            };
            let band = periodic_layout_with(&pd, &options, &exact).unwrap();
            let whole = layout_from(&pd, &options, &exact, [f64::INFINITY; 2], None, false, None)
                .and_then(Round::layout)
                .unwrap();
            assert_eq!(band.triples, whole.triples, "{n} holes");
            assert_eq!(
                (band.medial_vertices, band.medial_arcs, band.collapsed_arcs),
                (
                    whole.medial_vertices,
                    whole.medial_arcs,
                    whole.collapsed_arcs
                )
            );
            assert_eq!(band.layout.blocks.len(), whole.layout.blocks.len());
            // Every block of the band has a block of the array with the same corners.
            let corners = |p: &PeriodicLayout, b: &Block| -> Vec<[f64; 2]> {
                b.corners
                    .iter()
                    .map(|&c| p.layout.vertices[c as usize])
                    .collect()
            };
            // Vertices are circumcentres of sample triangles, computed on another instance
            // (another shift) in the band: 1.3e-10 apart for an empty circle of 20 periods'
            // fifth in the clustered box.
            let tol = 1e-9 * pd.size()[0];
            let mut unmatched: Vec<Vec<[f64; 2]>> = whole
                .layout
                .blocks
                .iter()
                .map(|b| corners(&whole, b))
                .collect();
            for b in &band.layout.blocks {
                let x = corners(&band, b);
                let close = |y: &Vec<[f64; 2]>| {
                    x.iter()
                        .zip(y)
                        .all(|(p, q)| (p[0] - q[0]).abs().max((p[1] - q[1]).abs()) <= tol)
                };
                let at = unmatched.iter().position(close);
                assert!(
                    at.is_some(),
                    "{n} holes: a block {x:?} not in the array's layout"
                );
                unmatched.swap_remove(at.unwrap());
            }
            if n >= 120 {
                let first = Tiling::with_reach(&pd, [1, 1], initial_reach(&pd)).unwrap();
                assert!(first.keys.len() * 2 < 9 * n, "{} copies", first.keys.len());
            }
        }
    }

    /// The 100-hole box of `tests/data/periodic_backwards_100.json` (its first layout has
    /// arcs running backwards), with exact mode's options (4 x 4 cells a block) and its
    /// layout options with short collapses.
    fn backwards_box() -> (PeriodicDomain, Options, Options) {
        let pd = match crate::domain::AnyDomain::from_json_str(include_str!(
            "../../tests/data/periodic_backwards_100.json"
        ))
        .unwrap()
        {
            crate::domain::AnyDomain::Periodic(pd) => pd,
            _ => unreachable!("a periodic file"),
        };
        let options = Options {
            block_cells: Some(4),
            ..Options::default()
        };
        let nearly_zero = Options {
            collapse_fraction: options.collapse_fraction.min(EXACT_COLLAPSE_FRACTION),
            ..options.clone()
        };
        (pd, options, nearly_zero)
    }

    /// An exact attempt's layout ([`layout_for_exact`]) with arc orbits running backwards is
    /// not numbered: it names the arc orbits the stopped build of the whole layout names, with
    /// the same exact input and orbit keys, and [`exact_frame`] answers for it as for the
    /// whole layout (the same holes to resample, the same arcs for the local fix). Without
    /// backwards arcs it is the whole layout.
    #[test]
    fn an_exact_attempts_layout_stops_where_the_whole_layouts_build_stops() {
        use crate::exact_mode::periodic::{build_unless_backwards, Built};
        let (pd, options, nearly_zero) = backwards_box();
        let sampling = crate::mesher::exact_sampling();
        let plain = random_box(30, 3);
        let mut seen = [false; 2];
        for (pd, opts) in [(&pd, &nearly_zero), (&plain, &nearly_zero)] {
            let whole = layout_keeping(pd, opts, &sampling).unwrap();
            let pb = whole.blocking.as_ref().expect("exact input");
            let mine = layout_for_exact(pd, opts, &sampling).unwrap();
            assert_eq!(mine.blocking, whole.blocking);
            assert_eq!(mine.arc_keys, whole.arc_keys);
            assert_eq!(mine.collapsed_arcs, whole.collapsed_arcs);
            match build_unless_backwards(pb, &options, &[]).unwrap() {
                Built::Backwards(arcs) => {
                    seen[0] = true;
                    assert_eq!(mine.backwards.as_ref(), Some(&arcs));
                    assert!(mine.layout.blocks.is_empty(), "not numbered");
                    let framed =
                        |p: PeriodicLayout| match exact_frame(pd, p, &options, &[], true, true) {
                            Ok(Framed::Failed { holes, arcs }) => (holes, arcs),
                            _ => panic!("a layout with backwards arcs fails"),
                        };
                    let (h0, a0) = framed(whole);
                    assert!(!a0.is_empty());
                    assert_eq!(framed(mine), (h0, a0));
                }
                Built::Mesh(_) => {
                    seen[1] = true;
                    assert!(mine.backwards.is_none());
                    assert_eq!(mine.layout, whole.layout);
                    assert_eq!(mine.triples, whole.triples);
                }
            }
        }
        assert_eq!(seen, [true, true]);
    }

    /// The exact build that stops at backwards arcs (issue 8) reports exactly the arc orbits
    /// the whole build finds running backwards, and when there are none it is the whole build
    /// (same layout, same nodes to the bit). The oracle is the whole build itself.
    #[test]
    fn a_build_stopped_at_backwards_arcs_names_the_whole_builds_arcs() {
        use crate::exact_mode::periodic::{build_unless_backwards, build_with_inserted, Built};
        let (pd, options, nearly_zero) = backwards_box();
        let zero_only = Options {
            collapse_fraction: 0.0,
            ..options.clone()
        };
        let mut seen = [false; 2];
        let plain = random_box(30, 3);
        let cases = [
            (&pd, &nearly_zero),
            (&pd, &zero_only),
            (&plain, &nearly_zero),
        ];
        for (pd, opts) in cases {
            let p = periodic_layout_with(pd, opts, &crate::mesher::exact_sampling()).unwrap();
            let pb = p.blocking.as_ref().expect("exact input");
            let whole = build_with_inserted(pb, &options, &[]).unwrap();
            match build_unless_backwards(pb, &options, &[]).unwrap() {
                Built::Backwards(arcs) => {
                    seen[0] = true;
                    assert!(!arcs.is_empty());
                    assert_eq!(arcs, whole.inconsistent_arcs);
                }
                Built::Mesh(x) => {
                    seen[1] = true;
                    assert!(whole.inconsistent_arcs.is_empty());
                    assert_eq!(x.layout.blocks.len(), whole.layout.blocks.len());
                    let bits = |g: &[crate::mesh::BlockGrid]| -> Vec<u64> {
                        g.iter()
                            .flat_map(|g| g.nodes.iter().flat_map(|p| p.map(f64::to_bits)))
                            .collect()
                    };
                    assert_eq!(bits(&x.grids), bits(&whole.grids));
                }
            }
        }
        // The file's first layout has arcs running backwards (`tests/perf_periodic.rs`).
        assert_eq!(seen, [true, true]);
    }

    /// The end circles a sampling keeps from its first extraction (issue 8,
    /// [`Sampled::end_circles`]) are those solved afresh for the same vertices, and the local
    /// fix's extraction, which finds them kept, gives the layout of one that solves them
    /// itself (a copy of the sampling with none kept).
    #[test]
    fn kept_end_circles_are_the_fresh_ones_and_give_the_same_layout() {
        use crate::exact_mode::periodic::{build_unless_backwards, Built};
        let (pd, options, nearly_zero) = backwards_box();
        let sampling = crate::mesher::exact_sampling();
        let p = layout_keeping(&pd, &nearly_zero, &sampling).unwrap();
        let sampled = p.sampled.as_deref().unwrap();
        let (ends, kept) = sampled.end_circles.get().expect("kept by the extraction");
        assert!(ends.len() > 10 && ends.windows(2).all(|w| w[0] < w[1]));
        assert!(ends
            .iter()
            .all(|&v| (v as usize) < sampled.medial.vertices.len()));
        let fresh = cocircular::vertex_circles_of(&sampled.t.domain, &sampled.medial, ends);
        assert_eq!(kept, &fresh);
        assert!(kept.iter().filter(|c| c.is_some()).count() > 10);
        let pb = p.blocking.as_ref().expect("exact input");
        let Built::Backwards(arcs) = build_unless_backwards(pb, &options, &[]).unwrap() else {
            panic!("the first layout has arcs running backwards");
        };
        let keys: Vec<ArcKey> = arcs.iter().map(|&o| p.arc_keys[o]).collect();
        let with_kept = reextract(&pd, &nearly_zero, sampled, &keys).unwrap();
        let again = layout_keeping(&pd, &nearly_zero, &sampling).unwrap();
        let mut none_kept = std::sync::Arc::into_inner(again.sampled.unwrap()).unwrap();
        none_kept.end_circles = std::sync::OnceLock::new();
        // A layout without a check for backwards arcs drops its orbit keys.
        assert!(none_kept.orbits.get().is_none());
        let solved = reextract(&pd, &nearly_zero, &none_kept, &keys).unwrap();
        assert!(none_kept.end_circles.get().is_some());
        assert_eq!(with_kept.layout, solved.layout);
        assert_eq!(with_kept.arc_keys, solved.arc_keys);
        assert_eq!(with_kept.collapsed_arcs, solved.collapsed_arcs);
        assert_eq!(with_kept.triples, solved.triples);
        assert!(with_kept.collapsed_arcs > p.collapsed_arcs);
    }

    /// The triangles the first extraction of a sampling measured inside its tiling are kept
    /// ([`Sampled::measured`], issue 8): every one is a triangle of the sampling whose circle
    /// the tiling holds (measured again here, one by one, with the extraction's own test), and
    /// the local fix's extraction that measures only the others gives the layout of one that
    /// measures them all.
    #[test]
    fn kept_measured_triangles_give_the_same_layout() {
        let (pd, _, nearly_zero) = backwards_box();
        let sampling = crate::mesher::exact_sampling();
        let p = layout_for_exact(&pd, &nearly_zero, &sampling).unwrap();
        let arcs = p.backwards.clone().expect("arcs running backwards");
        let keys: Vec<ArcKey> = arcs.iter().map(|&o| p.arc_keys[o]).collect();
        let sampled = p.sampled.as_deref().unwrap();
        let measured = sampled.measured.get().expect("set by the first extraction");
        assert_eq!(measured.len(), sampled.tri.len());
        let t = &sampled.t;
        let rmax = pd.holes().iter().map(|c| c.radius).fold(0.0, f64::max);
        let reach = rmax + 1e-6 * t.size[0].max(t.size[1]);
        let mut count = 0;
        for (tri, _) in measured.iter().enumerate().filter(|(_, &m)| m) {
            count += 1;
            let q = sampled
                .tri
                .triangle(tri)
                .map(|s| sampled.samples.points[s as usize]);
            let c = circumcenter(q[0], q[1], q[2]).expect("a measured triangle has a circle");
            let r = (c[0] - q[0][0]).hypot(c[1] - q[0][1]);
            for (a, (m, beyond)) in disc_needs(t.size, c, r, reach).into_iter().enumerate() {
                if t.band[a] {
                    assert!(below(beyond, t.reach[a]), "triangle {tri} axis {a}");
                } else {
                    assert!(m <= t.m[a] as f64, "triangle {tri} axis {a}");
                }
            }
        }
        assert!(count > 100, "{count}");
        let with_kept = reextract(&pd, &nearly_zero, sampled, &keys).unwrap();
        let again = layout_for_exact(&pd, &nearly_zero, &sampling).unwrap();
        let mut none_kept = std::sync::Arc::into_inner(again.sampled.unwrap()).unwrap();
        none_kept.measured = std::sync::OnceLock::new();
        let made = reextract(&pd, &nearly_zero, &none_kept, &keys).unwrap();
        assert!(
            none_kept.measured.get().is_some(),
            "set by the fix's extraction"
        );
        assert_eq!(with_kept.layout, made.layout);
        assert_eq!(with_kept.arc_keys, made.arc_keys);
        assert_eq!(with_kept.collapsed_arcs, made.collapsed_arcs);
        assert_eq!(with_kept.triples, made.triples);
        assert_eq!(with_kept.tiling, made.tiling);
    }

    /// An exact attempt's layout with arcs running backwards keeps its sampling's orbit keys
    /// and collapse selection's part ([`Sampled::orbits`], issue 8): they are those made
    /// afresh, and the local fix's extraction that finds them kept gives the layout of one
    /// that makes them itself. A layout without such arcs drops them.
    #[test]
    fn kept_orbits_are_the_fresh_ones_and_give_the_same_layout() {
        let (pd, _, nearly_zero) = backwards_box();
        let sampling = crate::mesher::exact_sampling();
        let p = layout_for_exact(&pd, &nearly_zero, &sampling).unwrap();
        let arcs = p
            .backwards
            .clone()
            .expect("the first layout has arcs running backwards");
        let keys: Vec<ArcKey> = arcs.iter().map(|&o| p.arc_keys[o]).collect();
        let sampled = p.sampled.as_deref().unwrap();
        let kept = sampled.orbits.get().expect("kept for the local fix");
        let fresh = Orbits::new(&sampled.t, &sampled.samples, &sampled.medial).unwrap();
        assert_eq!(kept.vkeys, fresh.vkeys);
        assert_eq!(kept.akeys, fresh.akeys);
        assert_eq!(kept.arc_by_key, fresh.arc_by_key);
        let base = kept.selection.get().expect("made by the extraction");
        let again = SelectionBase::new(
            &sampled.t.domain,
            &sampled.tri,
            &sampled.samples.points,
            &sampled.medial,
            &sampled.end_circles,
            &fresh,
            sampled.how,
        );
        assert_eq!(base.rep_of, again.rep_of);
        assert_eq!(base.reps, again.reps);
        assert_eq!(base.orbit_ends, again.orbit_ends);
        assert_eq!(base.incident, again.incident);
        let bits = |m: &[Measure]| -> Vec<(u8, u64)> {
            m.iter()
                .map(|m| match *m {
                    Measure::NoEnds => (0, 0),
                    Measure::Zero => (1, 0),
                    Measure::Length { rel, is_loop } => (2 + u8::from(is_loop), rel.to_bits()),
                })
                .collect()
        };
        assert_eq!(bits(&base.measured), bits(&again.measured));
        assert!(base
            .measured
            .iter()
            .any(|m| matches!(m, Measure::Length { rel, .. } if rel.is_finite())));
        let with_kept = reextract(&pd, &nearly_zero, sampled, &keys).unwrap();
        let again = layout_for_exact(&pd, &nearly_zero, &sampling).unwrap();
        let mut none_kept = std::sync::Arc::into_inner(again.sampled.unwrap()).unwrap();
        none_kept.orbits = std::sync::OnceLock::new();
        let made = reextract(&pd, &nearly_zero, &none_kept, &keys).unwrap();
        assert_eq!(with_kept.layout, made.layout);
        assert_eq!(with_kept.arc_keys, made.arc_keys);
        assert_eq!(with_kept.collapsed_arcs, made.collapsed_arcs);
        assert_eq!(with_kept.triples, made.triples);
        assert!(with_kept.collapsed_arcs > p.collapsed_arcs);
        // Without arcs running backwards (the local fix's layout), nothing is kept.
        let whole = layout_keeping(&pd, &nearly_zero, &sampling).unwrap();
        assert!(whole.sampled.as_deref().unwrap().orbits.get().is_none());
    }

    /// Exact mode's local fix (issue 8): the layout extracted again from the same sampling
    /// with the orbits of the arcs running backwards collapsed keeps none of them (every
    /// other arc orbit of the first layout is kept or collapsed as before), collapses each
    /// (blocks: two fewer per orbit), and its exact build has no arc running backwards and
    /// no inverted cell (orientation recomputed from the nodes).
    #[test]
    fn the_local_fix_collapses_the_backwards_arc_orbits_in_every_copy() {
        use crate::exact_mode::periodic::{build_unless_backwards, Built};
        let (pd, options, nearly_zero) = backwards_box();
        let p = layout_keeping(&pd, &nearly_zero, &crate::mesher::exact_sampling()).unwrap();
        let pb = p.blocking.as_ref().expect("exact input");
        let Built::Backwards(arcs) = build_unless_backwards(pb, &options, &[]).unwrap() else {
            panic!("the first layout has arcs running backwards");
        };
        let keys: Vec<ArcKey> = arcs.iter().map(|&o| p.arc_keys[o]).collect();
        let q = reextract(&pd, &nearly_zero, p.sampled.as_deref().unwrap(), &keys).unwrap();
        assert!(keys.iter().all(|k| !q.arc_keys.contains(k)));
        let kept_before: Vec<&ArcKey> = p.arc_keys.iter().filter(|k| !keys.contains(k)).collect();
        assert!(kept_before.iter().all(|k| q.arc_keys.contains(k)));
        assert_eq!(q.collapsed_arcs, p.collapsed_arcs + keys.len());
        assert_eq!(
            q.layout.blocks.len(),
            p.layout.blocks.len() - 2 * keys.len()
        );
        let qb = q.blocking.as_ref().expect("exact input after the fix");
        let Built::Mesh(x) = build_unless_backwards(qb, &options, &[]).unwrap() else {
            panic!("arcs still run backwards after the fix");
        };
        let inverted = x
            .grids
            .iter()
            .flat_map(|g| {
                (0..g.nj).flat_map(move |j| {
                    (0..g.ni).map(move |i| {
                        let n = |di: usize, dj: usize| g.nodes[(i + di) + (j + dj) * (g.ni + 1)];
                        let (a, b, c, d) = (n(0, 0), n(1, 0), n(1, 1), n(0, 1));
                        // Twice the signed area of the cell (shoelace).
                        (a[0] * b[1] - b[0] * a[1])
                            + (b[0] * c[1] - c[0] * b[1])
                            + (c[0] * d[1] - d[0] * c[1])
                            + (d[0] * a[1] - a[0] * d[1])
                    })
                })
            })
            .filter(|&area| area <= 0.0)
            .count();
        assert_eq!(inverted, 0);
    }

    /// Exact mode's local resampling: a boost on slot `k + 1` refines the whole orbit of hole
    /// `k` (every copy alike) and no other orbit.
    #[test]
    fn a_boost_refines_its_orbit_only() {
        let pd = PeriodicDomain::new(
            [3.0, 2.0],
            vec![
                Circle::new(0.7, 0.6, 0.3),
                Circle::new(2.1, 1.3, 0.25),
                Circle::new(1.5, 0.4, 0.2),
            ],
        )
        .unwrap();
        let t = Tiling::new(&pd, [1, 1]).unwrap();
        let plain = crate::mesher::exact_sampling();
        let boosted = SamplingOptions {
            boost: vec![0, 0, 2],
            ..plain.clone()
        };
        let counts = |opts: &SamplingOptions| -> Vec<Vec<u32>> {
            let (samples, ..) = sample_tiling(&t, &pd.nearest_gaps(), opts, false, None).unwrap();
            (0..3)
                .map(|k| {
                    tile_array(t.m)
                        .map(|(a, b)| samples.of_circle(t.id(k, a, b)).count)
                        .collect()
                })
                .collect()
        };
        let (before, after) = (counts(&plain), counts(&boosted));
        for k in 0..3 {
            // Every copy of an orbit alike.
            assert!(
                after[k].iter().all(|&c| c == after[k][0]),
                "hole {k}: {after:?}"
            );
            if k == 1 {
                assert!(after[k][0] >= 3 * before[k][0], "{before:?} -> {after:?}");
            } else {
                assert_eq!(after[k], before[k]);
            }
        }
    }

    /// The holes around bad blocks: those of the block's arc orbit and of its two end vertex
    /// orbits; none (refine everywhere) for a block that is not a medial block.
    #[test]
    fn the_holes_around_a_bad_block_are_those_of_its_arc_and_ends() {
        let vertex = |c: [u32; 3]| PeriodicVertex {
            circles: c.iter().map(|&k| (k, 0, 0)).collect(),
            near: [0.0, 0.0],
        };
        let arc = |c: [u32; 2], ends: [usize; 2]| PeriodicArc {
            circles: [(c[0], 0, 0), (c[1], 1, 0)],
            ends: [(ends[0], (0, 0)), (ends[1], (0, 1))],
            hint: [0.0, 0.0],
        };
        let pb = PeriodicBlocking {
            size: [1.0, 1.0],
            holes: Vec::new(),
            vertices: vec![vertex([0, 1, 2]), vertex([1, 2, 7]), vertex([3, 4, 5])],
            arcs: vec![arc([1, 2], [0, 1]), arc([3, 4], [2, 2])],
        };
        assert_eq!(holes_around(&pb, &[1]), vec![0, 1, 2, 7]);
        assert_eq!(holes_around(&pb, &[2]), vec![3, 4, 5]);
        assert_eq!(holes_around(&pb, &[0, 3]), vec![0, 1, 2, 3, 4, 5, 7]);
        assert_eq!(holes_around(&pb, &[2, 4]), Vec::<u32>::new());
        assert_eq!(holes_around(&pb, &[]), Vec::<u32>::new());
    }
}
