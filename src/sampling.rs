//! Boundary sampling (paper section 2; DESIGN section 4).
//!
//! Every circle is sampled on a uniform grid of `N` angles (`N` a multiple of 8): grid point
//! `k` is `center + r * u_k` with `u_k` the unit vector at angle `2 pi k / N`. The unit
//! offsets are computed with `cos`/`sin` only in the first octant; the other octants are
//! exact reflections and swaps (see [`unit_offsets`], [`unit_offset`]), so a layout
//! mirror-symmetric about `x = 0`, `y = 0` or a diagonal `y = +-x` gets bitwise
//! mirror-symmetric sample coordinates, and symmetric packings produce exact Delaunay ties
//! (which the engine breaks and reports).
//!
//! Density (issue 8, [`sample_adaptive`]): only a subset of the grid is used. Every circle gets
//! [`SamplingOptions::min_per_circle`] coarse samples; intervals facing a close circle are
//! bisected until their arc length is at most [`SamplingOptions::spacing_per_gap`] times the
//! local gap, so points are spent only where circles are close. Close circles come from the
//! k-d tree [`HoleIndex`] (no quadratic loop). The uniform [`sample`] (one count per circle,
//! from its nearest gap, [`initial_counts`]) is kept for periodic boxes and tests.
//!
//! After triangulation, [`check_invariants`] verifies the three conditions of DESIGN section 4:
//! (a) consecutive samples of a circle are joined by a Delaunay edge; (b) no in-domain triangle
//! has two boundary edges; (c) every interior triangle has its three vertices on three
//! different circles; and also that every triangle lies either inside one hole (three vertices
//! on it) or in the domain. [`sample_and_triangulate`] resamples offending circles (doubling
//! their density) until these hold, within bounded rounds and total samples.

use crate::domain::{circle_name, dist, Circle, CircleId, Domain, HoleIndex, BOUNDING};
use crate::geometry::{Point, Triangulation};
use crate::medial::{medial_graph, reuse, MedialGraph, TriangleKind};

mod fused;
use crate::mesher::MeshError;
pub use fused::classify_and_check;
#[doc(hidden)]
pub use fused::classify_and_check_in;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_4, TAU};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Tuning of the boundary sampling.
#[derive(Debug, Clone, PartialEq)]
pub struct SamplingOptions {
    /// Fewest samples on a circle (rounded up to a multiple of 8, at least 8).
    pub min_per_circle: usize,
    /// Most samples on a circle (rounded down to a multiple of 8). Adaptive sampling spends
    /// them only near close circles (about `pi sqrt(2 rho / g)` for a gap `g` between circles
    /// of reduced radius `rho`), so the default is large; [`SamplingOptions::max_total`] is
    /// the resource limit.
    pub max_per_circle: usize,
    /// Target sample spacing as a multiple of the circle's nearest gap.
    pub spacing_per_gap: f64,
    /// Most samples in total; more is a [`MeshError::Sampling`]. Checked circle by circle
    /// while sampling, before the samples and the triangulation are allocated.
    ///
    /// Default 32 M: random bubbles need about 85-100 samples per circle, so the default
    /// meshes about 300 000 of them (issue 8: 100 000 particles need about 9 M; the old 8 M
    /// stopped near 94 000). The front end holds a few hundred bytes per sample at peak
    /// (points, indices, triangulation, medial graph), so an absurd input is refused before
    /// it needs more than roughly 10 GB. The limit is a plain count: [`Default`] cannot see
    /// the circle count, so it cannot be a per-circle budget.
    pub max_total: usize,
    /// Most resampling rounds after the first triangulation.
    pub max_rounds: usize,
    /// Extra density doublings per circle from the start, in slot order (slot 0 the bounding
    /// circle, slot `i + 1` hole `i`; missing entries are 0). Exact mode uses it to refine
    /// only the circles around an arc whose exact geometry disagreed with the sampling. A
    /// boost is shared by every circle of the same radius and gap (bitwise), so mirror images
    /// stay sampled alike.
    pub boost: Vec<u32>,
    /// Pursue the soft invariant (d) ([`thin_walls`]) with resampling rounds (default `true`).
    /// `false`: stop as soon as the hard invariants hold (one triangulation when the first
    /// sampling is good); [`SampledDomain::thin_walls`] still lists the violations left. Exact
    /// mode uses `false`: it computes exact walls, so a single-sample wall costs it nothing,
    /// while the paper pipeline (whose walls follow the samples) needs the rounds.
    pub soft_rounds: bool,
}

impl Default for SamplingOptions {
    fn default() -> Self {
        SamplingOptions {
            min_per_circle: 32,
            max_per_circle: 1 << 20,
            spacing_per_gap: 1.0,
            max_total: 32_000_000,
            max_rounds: 4,
            boost: Vec::new(),
            soft_rounds: true,
        }
    }
}

/// Where the samples of one circle live in [`Samples`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircleSamples {
    pub circle: CircleId,
    /// Index of its sample 0 in [`Samples::points`].
    pub first: u32,
    /// Number of samples (a multiple of 8 for uniform sampling; any number `>= 8` for
    /// adaptive sampling).
    pub count: u32,
    /// The gap to its nearest neighbour that drove the density.
    pub gap: f64,
}

/// The boundary samples of all circles: the bounding circle's first, then the holes in order.
/// Sample `s` is the `index_of[s]`-th (counter-clockwise from angle 0) of circle
/// `circle_of[s]`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Samples {
    pub points: Vec<Point>,
    pub circle_of: Vec<CircleId>,
    pub index_of: Vec<u32>,
    /// Per circle, in slot order: slot 0 the bounding circle, slot `i + 1` hole `i`.
    pub circles: Vec<CircleSamples>,
    /// Per sample, its index on its circle's uniform grid of `grid_counts[slot]` angles
    /// (adaptive sampling, [`sample_adaptive`]): sample `s` lies at the grid angle
    /// `2 pi grid[s] / grid_counts[slot]`. Empty when every circle is sampled uniformly (the
    /// grid index is then `index_of[s]` and the grid size the circle's count).
    pub grid: Vec<u64>,
    /// Per circle (slot order), the size of its uniform grid (a multiple of 8); empty when
    /// uniform.
    pub grid_counts: Vec<u64>,
}

/// `(i + 1) % count`, without a division when `i < count` (every index on its circle): the
/// classification and the invariant checks take a next sample per boundary edge of every
/// triangle (issue 8).
fn wrap_next(i: u32, count: u32) -> u32 {
    if i < count {
        if i + 1 == count {
            0
        } else {
            i + 1
        }
    } else {
        (i + 1) % count
    }
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
        c.first + wrap_next(self.index_of[s as usize], c.count)
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
    /// The index of sample `s` on its circle's uniform grid ([`Samples::grid`]).
    pub fn grid_index(&self, s: u32) -> u64 {
        match self.grid.get(s as usize) {
            Some(&g) => g,
            None => u64::from(self.index_of[s as usize]),
        }
    }
    /// The size of the uniform grid of circle `id` ([`Samples::grid_counts`]).
    pub fn grid_count(&self, id: CircleId) -> u64 {
        match self.grid_counts.get((id + 1) as usize) {
            Some(&n) if !self.grid.is_empty() => n,
            _ => u64::from(self.of_circle(id).count),
        }
    }
    /// The nominal angle `2 pi k / N` of sample `s` about its circle's centre (`k` its grid
    /// index, `N` the grid size; `k = index_of[s]`, `N` the count for uniform sampling).
    pub fn angle(&self, s: u32) -> f64 {
        let n = self.grid_count(self.circle_of[s as usize]);
        TAU * self.grid_index(s) as f64 / n as f64
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
    if n == 0 || !n.is_multiple_of(8) {
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
/// slot `i + 1` hole `i`). Hole-hole gaps come from the k-d tree, so this is `O(h log h)`
/// (once per domain: [`Domain::nearest_hole_gaps`]). With no hole the bounding circle's "gap" is
/// its radius.
pub fn nearest_gaps(domain: &Domain) -> Vec<f64> {
    let holes = domain.holes();
    let b = domain.bounding();
    let mut gaps = Vec::with_capacity(holes.len() + 1);
    gaps.push(b.radius);
    let mut bmin = f64::INFINITY;
    for (h, nearest) in holes.iter().zip(domain.nearest_hole_gaps()) {
        let to_bounding = b.radius - dist(h.center, b.center) - h.radius;
        bmin = bmin.min(to_bounding);
        let g = match nearest {
            Some(g) => g.min(to_bounding),
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
        grid: Vec::new(),
        grid_counts: Vec::new(),
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

/// The unit vector at angle `2 pi k / n` for `n` a positive multiple of 8, bitwise equal to
/// `unit_offsets(n)[k % n]` but computed alone (so `n` may be far beyond what a table holds).
/// `[NaN, NaN]` when `n` is not a positive multiple of 8.
pub fn unit_offset(k: u64, n: u64) -> Point {
    if n == 0 || !n.is_multiple_of(8) {
        return [f64::NAN; 2];
    }
    let k = k % n;
    let m = n / 8;
    let first = |j: u64| -> Point {
        if j == m {
            [FRAC_1_SQRT_2, FRAC_1_SQRT_2]
        } else {
            let t = FRAC_PI_4 * (j as f64 / m as f64);
            [t.cos(), t.sin()]
        }
    };
    // The table fills `0..=2m` directly and then `u[k] = rot(u[k - 2m])`: so `k > 2m` is
    // `rot^q(u[r])` with `r` in `1..=2m`.
    let (r, q) = if k <= 2 * m {
        (k, 0)
    } else {
        let r = (k - 1) % (2 * m) + 1;
        (r, (k - r) / (2 * m))
    };
    let mut u = if r <= m {
        first(r)
    } else {
        let [x, y] = first(2 * m - r);
        [y, x]
    };
    for _ in 0..q {
        u = [-u[1], u[0]];
    }
    u
}

/// The unit vectors of one grid of `n` angles ([`unit_offsets`]), serving [`unit_offset`] on
/// every grid that refines or coarsens it by a power of two. `unit_offset(k, n)` depends only
/// on the angle `k / n`: its first-octant argument is the correctly rounded quotient `j / m` of
/// integers that stay exact in `f64` when both are scaled by a power of two, and the octant
/// folding is integer arithmetic that scales with them; so `unit_offset(k 2^s, n 2^s)` is
/// bitwise `unit_offset(k, n)` (tested against it). Adaptive sampling takes its coarse samples
/// and their first bisections from the table instead of calling `cos`/`sin` for each (issue 8).
struct UnitTable {
    u: Vec<Point>,
}

/// [`UnitTable`] on one grid of `n` angles: `k` of that grid is entry `(k << down) >> up` of the
/// table when the low `up` bits of `k` are zero.
struct GridUnits<'a> {
    n: u64,
    table: &'a [Point],
    up: u32,
    down: u32,
}

impl UnitTable {
    /// The table of the grid of `n` angles; empty (every lookup computed) when `n` is not a
    /// positive multiple of 8 or above `2^12`.
    fn new(n: u64) -> Self {
        UnitTable {
            u: if n <= 1 << 12 {
                unit_offsets(n as usize)
            } else {
                Vec::new()
            },
        }
    }

    /// Lookups on the grid of `n` angles.
    fn grid(&self, n: u64) -> GridUnits<'_> {
        let size = self.u.len() as u64;
        let scale = |a: u64, b: u64| {
            (b > 0 && a.is_multiple_of(b) && (a / b).is_power_of_two())
                .then(|| (a / b).trailing_zeros())
        };
        let (table, up, down): (&[Point], _, _) = if n == 0 || !n.is_multiple_of(8) {
            (&[], 0, 0)
        } else if let Some(up) = scale(n, size) {
            (&self.u, up, 0)
        } else if let Some(down) = scale(size, n) {
            (&self.u, 0, down)
        } else {
            (&[], 0, 0)
        };
        GridUnits { n, table, up, down }
    }
}

impl GridUnits<'_> {
    /// Bitwise `unit_offset(k, n)`.
    fn at(&self, k: u64) -> Point {
        if self.table.is_empty() {
            return unit_offset(k, self.n);
        }
        let k = if k < self.n { k } else { k % self.n };
        if k.trailing_zeros() >= self.up {
            self.table[((k >> self.up) << self.down) as usize]
        } else {
            unit_offset(k, self.n)
        }
    }
}

/// A circle near the one being sampled, as seen from a point `p`: its surface distance is
/// `|p - center| - radius` (a hole) or `radius - |p - center|` (the bounding circle).
#[derive(Debug, Clone, Copy)]
struct Near {
    center: Point,
    radius: f64,
    outer: bool,
}

impl Near {
    /// The distance from `p` to this circle (mirror-exact: only `dx * dx + dy * dy`).
    fn gap(&self, p: Point) -> f64 {
        let d = dist(p, self.center);
        if self.outer {
            self.radius - d
        } else {
            d - self.radius
        }
    }
}

/// Most levels of the uniform grid of one circle: its size is at most `8 * 2^MAX_LEVELS`
/// (grid angles stay exact rationals of `f64`).
const MAX_LEVELS: u32 = 36;

/// The coarse count actually used for circle `c` asked for `n` coarse samples (`n0 2^k`:
/// the options' count `n0`, a multiple of 8, doubled `k` times by resampling): `n` halved,
/// never below `n0`, while the coarse chords would bulge off their arcs (the sagitta
/// `(2 pi / n)^2 r / 8`) by less than `unit / 2`, `unit = eps (r + max |centre coordinate|)`.
/// Rounding moves a sample by at most `0.71 unit`, and three consecutive samples bulge by four
/// sagittas, so above that bound resampling keeps a circle's samples convex; below it,
/// doubling only makes them coincide or fold. The first sampling (`n = n0`) is never
/// changed, and the count is `n` whenever `r >= 0.1 n^2 unit`: layouts away from the limits
/// of precision are sampled exactly as before.
fn coarse_count(c: Circle, n: u64, n0: u64) -> u64 {
    let reach = c.radius + c.center[0].abs().max(c.center[1].abs());
    let min_sagitta = 0.5 * f64::EPSILON * reach;
    let mut n = n;
    while n.is_multiple_of(16) && n / 2 >= n0 {
        let s = TAU * c.radius / n as f64;
        if s * s / (8.0 * c.radius) >= min_sagitta {
            break;
        }
        n /= 2;
    }
    n
}

/// One circle's adaptive samples: `n0` coarse samples (a multiple of 8), then recursive bisection of every interval
/// whose arc length `L` is too long for the local gap (`L (1 + f / 2) > f g(mid)`, with `g`
/// 1-Lipschitz this bounds `L <= f g` on the whole interval), never below a precision floor
/// (see the comments in the body). `outer` is true for the bounding circle. Returns the grid size and the
/// grid indices in increasing order; `Err(())` when more than `cap` samples would be needed.
/// Unit vectors come from `units` ([`UnitTable`], the same values as [`unit_offset`]).
#[allow(clippy::too_many_arguments)]
fn adaptive_circle(
    c: Circle,
    outer: bool,
    n0: u64,
    f: f64,
    g_nearest: f64,
    near: &[Near],
    cap: usize,
    units: &UnitTable,
) -> Result<(u64, Vec<u64>), ()> {
    if n0 > cap as u64 || n0 == 0 || !n0.is_multiple_of(8) {
        return Err(());
    }
    let coarse = TAU * c.radius / n0 as f64;
    // Finest level: where even the nearest gap asks for no more.
    let mut levels = 0;
    // Precision floor: consecutive samples must bulge off their chord (`s^2 / 8r`) by at
    // least 32 ulps of the coordinates (`eps (r + max |centre coordinate|)`), so that rounded
    // samples keep the circle's convex position: `s >= sqrt(256 eps r (r + |c|))`, about
    // `r / 2^22` for a circle at the origin. Closer holes get a spacing above their gap there:
    // the Delaunay edges between consecutive samples survive, as the other hole's samples lie
    // outside the circle.
    let reach = c.radius + c.center[0].abs().max(c.center[1].abs());
    let floor = (256.0 * f64::EPSILON * c.radius * reach).sqrt();
    // The bounding circle is the other way round: every hole sample must lie strictly inside
    // the bounding polygon, so each chord's sagitta must stay below the gap to the nearest
    // hole minus rounding. The floor may stop the bisection with a spacing of up to twice
    // itself (a sagitta of up to 128 ulps); where that is more than half the nearest gap `g`,
    // the bounding circle is bisected further, to a spacing `s <= sqrt(4 R g)` (sagitta at
    // most `g / 2`, at least `g / 8`). A hole sample, at least `g` from the circle, then stays
    // `g / 2 - 1.5 unit > 0` inside every chord (`unit = eps (R + |C|)`, rounding moves a
    // sample by at most `0.71 unit`), and three consecutive samples bulge by at least
    // `4 g / 8 > 1.5 unit` (convex after rounding) when `g > 2.84 unit`; [`Domain`]
    // validation refuses gaps below [`Domain::MIN_GAP_ULPS`] `= 3` units. For every other circle, and whenever
    // the floor is not what stops the bisection, `sag_limit` changes nothing.
    let sag_limit = if outer {
        (4.0 * c.radius * g_nearest).sqrt()
    } else {
        f64::INFINITY
    };
    while levels < MAX_LEVELS
        && coarse / 2f64.powi(levels as i32) * (1.0 + 0.5 * f) > f * g_nearest
        && (coarse / 2f64.powi(levels as i32 + 1) >= floor
            || coarse / 2f64.powi(levels as i32) > sag_limit)
    {
        levels += 1;
    }
    let n = n0.checked_mul(1u64 << levels).ok_or(())?;
    let step0 = 1u64 << levels;
    let unit = TAU * c.radius / n as f64;
    let grid = units.grid(n);
    let point = |k: u64| {
        let u = grid.at(k);
        [c.center[0] + c.radius * u[0], c.center[1] + c.radius * u[1]]
    };
    let mut out: Vec<u64> = Vec::with_capacity(n0.min(1 << 16) as usize);
    struct Ctx<'a> {
        f: f64,
        unit: f64,
        cap: usize,
        point: &'a dyn Fn(u64) -> Point,
    }
    fn bisect(ctx: &Ctx, a: u64, step: u64, near: &[Near], out: &mut Vec<u64>) -> Result<(), ()> {
        if step < 2 || near.is_empty() {
            return Ok(());
        }
        let len = step as f64 * ctx.unit;
        let x = len * (1.0 + 0.5 * ctx.f) / ctx.f;
        let mid = a + step / 2;
        let p = (ctx.point)(mid);
        let mut g = f64::INFINITY;
        let mut keep: Vec<Near> = Vec::new();
        for nb in near {
            let d = nb.gap(p);
            g = g.min(d);
            // Sub-interval midpoints lie within `len / 2` of `p`, and their thresholds are
            // below `x`: a circle farther than `x + len` never decides there.
            if d.is_nan() || d < x + len {
                keep.push(*nb);
            }
        }
        if g.is_nan() || g >= x {
            return Ok(());
        }
        bisect(ctx, a, step / 2, &keep, out)?;
        out.push(mid);
        if out.len() > ctx.cap {
            return Err(());
        }
        bisect(ctx, mid, step / 2, &keep, out)
    }
    let ctx = Ctx {
        f,
        unit,
        cap,
        point: &point,
    };
    for k in 0..n0 {
        out.push(k * step0);
        bisect(&ctx, k * step0, step0, near, &mut out)?;
        if out.len() > cap {
            return Err(());
        }
    }
    Ok((n, out))
}

/// The result of [`sample_adaptive`] when a circle would need more samples than allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct TooManySamples {
    /// The circle being sampled when a limit was passed.
    pub circle: CircleId,
    /// The limit passed.
    pub limit: usize,
    /// True when the limit is [`SamplingOptions::max_total`] (all circles together), false
    /// for [`SamplingOptions::max_per_circle`].
    pub total: bool,
}

/// Adaptive sampling (issue 8): every circle gets `round8(min_per_circle)` coarse samples at
/// angles `2 pi k / n0`, and intervals facing a close circle are bisected until their arc
/// length is at most `spacing_per_gap / 2^density[slot]` times the local gap (the distance from
/// the interval to the nearest other circle, 1-Lipschitz along the circle). Samples are points
/// of a uniform grid of `n0 2^L` angles ([`unit_offset`]), so the mirror symmetry of
/// [`unit_offsets`] holds: every decision depends only on mirror-exact distances and integer
/// grid indices. Close circles come from the k-d tree ([`HoleIndex::within_gap`]) for holes
/// and one linear scan for the bounding circle: no quadratic step. The samples of a circle
/// are in counter-clockwise (grid) order. `gaps` (slot order) are recorded as
/// [`CircleSamples::gap`] and bound the finest level.
pub fn sample_adaptive(
    domain: &Domain,
    opts: &SamplingOptions,
    gaps: &[f64],
    density: &[u32],
) -> Result<Samples, TooManySamples> {
    sample_adaptive_after(domain, opts, gaps, density, None).map(|(s, _)| s)
}

/// [`sample_adaptive`], taking from `previous` (a sampling of an earlier domain) the samples
/// of every circle whose sampling cannot differ: the same circle in the same slot, sampled with
/// the same options and density, with the same nearest gap (bitwise), and no circle of
/// `domain` beyond the earlier ones within its reach (its set of close circles is then the
/// earlier one: [`HoleIndex::within_gap`] is a pairwise predicate). Every earlier slot before
/// it then has the same samples, so the same budget is left, and [`adaptive_circle`] is
/// deterministic. Returns the samples and how many circles were taken over (the same samples
/// as [`sample_adaptive`]; tested in `tests/perf_resample.rs`).
///
/// The circles are sampled on the thread pool when it has more than one thread and there are
/// at least [`PARALLEL_MIN_CIRCLES`] of them; the result (samples, count taken over, error) is
/// that of the serial loop whatever the thread count ([`sample_adaptive_on`]).
#[doc(hidden)]
pub fn sample_adaptive_after(
    domain: &Domain,
    opts: &SamplingOptions,
    gaps: &[f64],
    density: &[u32],
    previous: Option<&SampledDomain>,
) -> Result<(Samples, usize), TooManySamples> {
    let index = domain.hole_index();
    let ctx = SlotContext::new(domain, &index, opts, gaps, density, previous);
    sample_adaptive_with(&ctx, ctx.parallel())
}

/// [`sample_adaptive_after`], on the thread pool when `parallel` (whatever the number of
/// circles or threads) and by the serial loop alone otherwise: the same result either way
/// (tested in `tests/perf_sampling_parallel.rs`, the serial loop being the reference).
///
/// The serial loop samples the circles in slot order, each within what the ones before it left
/// of [`SamplingOptions::max_total`] (and within [`SamplingOptions::max_per_circle`]); the first
/// circle that does not fit is the error. A sampling within a budget is the same under any
/// budget it fits (a budget only turns a longer sampling into an error, and decides whether an
/// earlier circle's samples may be taken over by the same comparison). So the parallel path
/// samples every circle within the per-circle budget alone, in any order, and checks the total
/// afterwards: when every circle fits and the total does too, each circle fitted what the serial
/// loop would have left it, and the samples are the serial ones; otherwise the serial loop runs
/// and returns its error. A running count of the samples made stops the parallel path once the
/// total is passed, so memory stays bounded by the total limit as in the serial loop.
#[doc(hidden)]
pub fn sample_adaptive_on(
    domain: &Domain,
    opts: &SamplingOptions,
    gaps: &[f64],
    density: &[u32],
    previous: Option<&SampledDomain>,
    parallel: bool,
) -> Result<(Samples, usize), TooManySamples> {
    let index = domain.hole_index();
    let ctx = SlotContext::new(domain, &index, opts, gaps, density, previous);
    sample_adaptive_with(&ctx, parallel)
}

/// [`sample_adaptive_on`] with the circles' inputs gathered.
fn sample_adaptive_with(
    ctx: &SlotContext,
    parallel: bool,
) -> Result<(Samples, usize), TooManySamples> {
    let plans = match parallel.then(|| ctx.plan_parallel()).flatten() {
        Some(plans) => plans,
        None => ctx.plan_serial()?,
    };
    Ok(ctx.assemble(&plans, parallel))
}

/// The adaptive samples of the circles `slots` of `domain` (slot 0 the bounding circle,
/// slot `i + 1` hole `i`), each on its own: its grid size and increasing grid indices, as
/// [`sample_adaptive`] makes them with `gaps` and `density` (slot order), each within
/// [`SamplingOptions::max_per_circle`] (`Err(())` for a circle that needs more). One hole
/// index for all of them; the circles on the thread pool, results in the order of `slots`.
/// For samplers that copy one circle's samples onto others (the orbits of a periodic tiling,
/// [`crate::periodic`]).
pub(crate) fn adaptive_grids(
    domain: &Domain,
    opts: &SamplingOptions,
    gaps: &[f64],
    density: &[u32],
    slots: &[usize],
) -> Vec<Result<(u64, Vec<u64>), ()>> {
    let index = domain.hole_index();
    let ctx = SlotContext::new(domain, &index, opts, gaps, density, None);
    slots
        .par_iter()
        .map(|&slot| match ctx.plan(slot, ctx.cap) {
            Ok(SlotSamples::Made { n, ks }) => Ok((n, ks)),
            // No earlier sampling is given, so none is taken over.
            Ok(SlotSamples::Taken { .. }) | Err(()) => Err(()),
        })
        .collect()
}

/// Fewest circles sampled on the thread pool (below, waking the pool costs more than it saves).
const PARALLEL_MIN_CIRCLES: usize = 128;

/// Fewest circles per task of the parallel sampling (a circle takes a few microseconds).
const CIRCLES_PER_TASK: usize = 16;

/// Fewest samples per task of the parallel assembly.
const SAMPLES_PER_TASK: usize = 1 << 14;

/// One circle's samples, before they are laid out in [`Samples`]: on a grid of `n` angles.
enum SlotSamples<'a> {
    /// The earlier sampling's samples of the same slot ([`sample_adaptive_after`]): their
    /// points and grid indices.
    Taken {
        n: u64,
        points: &'a [Point],
        grid: &'a [u64],
    },
    /// Grid indices `ks` (increasing), from [`adaptive_circle`].
    Made { n: u64, ks: Vec<u64> },
}

impl SlotSamples<'_> {
    /// The number of samples.
    fn len(&self) -> usize {
        match self {
            SlotSamples::Taken { grid, .. } => grid.len(),
            SlotSamples::Made { ks, .. } => ks.len(),
        }
    }
}

/// What every circle of one adaptive sampling reads: the domain, its hole index, the options,
/// the gaps and densities (slot order), and the earlier sampling that may be taken over.
struct SlotContext<'a> {
    domain: &'a Domain,
    index: &'a HoleIndex<'a>,
    opts: &'a SamplingOptions,
    gaps: &'a [f64],
    density: &'a [u32],
    /// The earlier sampling, when it was made with these options; its circles in slot order.
    earlier: Option<(&'a SampledDomain, &'a SamplingInputs)>,
    /// Coarse samples per circle (a multiple of 8).
    n0: u64,
    /// Most samples on one circle ([`SamplingOptions::max_per_circle`], at least `n0`).
    cap: usize,
    /// The unit vectors of the grid of `8 n0` angles: every circle's grid is `n0` times a
    /// power of two ([`coarse_count`], [`adaptive_circle`]).
    units: UnitTable,
}

/// Mutable views of the per-sample arrays of [`Samples`] over one range of samples.
struct SampleSlices<'a> {
    points: &'a mut [Point],
    circle_of: &'a mut [CircleId],
    index_of: &'a mut [u32],
    grid: &'a mut [u64],
}

impl<'a> SampleSlices<'a> {
    /// The first `k` samples and the rest.
    fn split_at(self, k: usize) -> (Self, Self) {
        let (p0, p1) = self.points.split_at_mut(k);
        let (c0, c1) = self.circle_of.split_at_mut(k);
        let (i0, i1) = self.index_of.split_at_mut(k);
        let (g0, g1) = self.grid.split_at_mut(k);
        (
            SampleSlices {
                points: p0,
                circle_of: c0,
                index_of: i0,
                grid: g0,
            },
            SampleSlices {
                points: p1,
                circle_of: c1,
                index_of: i1,
                grid: g1,
            },
        )
    }
}

impl<'a> SlotContext<'a> {
    fn new(
        domain: &'a Domain,
        index: &'a HoleIndex<'a>,
        opts: &'a SamplingOptions,
        gaps: &'a [f64],
        density: &'a [u32],
        previous: Option<&'a SampledDomain>,
    ) -> Self {
        let earlier = previous.and_then(|p| {
            let inputs = p.inputs.as_ref()?;
            (inputs.options == *opts && inputs.circles.len() == p.samples.circles.len())
                .then_some((p, inputs))
        });
        let n0 = round8(opts.min_per_circle) as u64;
        SlotContext {
            domain,
            index,
            opts,
            gaps,
            density,
            earlier,
            n0,
            cap: (opts.max_per_circle / 8 * 8).max(n0 as usize),
            units: UnitTable::new(n0.saturating_mul(8)),
        }
    }

    /// Number of circles (slots).
    fn slots(&self) -> usize {
        self.domain.hole_count() + 1
    }

    /// True when the circles are worth sampling on the thread pool.
    fn parallel(&self) -> bool {
        self.slots() >= PARALLEL_MIN_CIRCLES && rayon::current_num_threads() > 1
    }

    /// The circle of `slot` (slot 0 the bounding circle, slot `i + 1` hole `i`).
    fn id(slot: usize) -> CircleId {
        slot as CircleId - 1
    }

    /// The density doublings asked for `slot`.
    fn density(&self, slot: usize) -> u32 {
        self.density.get(slot).copied().unwrap_or(0)
    }

    /// The spacing-to-gap factor of `slot`.
    fn factor(&self, slot: usize) -> f64 {
        self.opts.spacing_per_gap / 2f64.powi(self.density(slot).min(60) as i32)
    }

    /// The largest local gap that can ever make circle `slot` (radius `r`) bisect: at the
    /// coarse level, `g < x0 = L0 (1 + f/2) / f`; a margin of 2 covers rounding.
    fn reach(&self, slot: usize, r: f64) -> f64 {
        let f = self.factor(slot);
        let k = self.density(slot).min(MAX_LEVELS);
        2.0 * (TAU * r / (self.n0 << k) as f64) * (1.0 + 0.5 * f) / f
    }

    /// The samples of circle `slot` within `budget` samples: taken over from the earlier
    /// sampling when they cannot differ and fit, else [`adaptive_circle`]; `Err(())` when more
    /// than `budget` would be needed.
    fn plan(&self, slot: usize, budget: usize) -> Result<SlotSamples<'a>, ()> {
        let holes = self.domain.holes();
        let b = self.domain.bounding();
        let id = Self::id(slot);
        let c = self.domain.circle(id);
        let g = self.gaps.get(slot).copied().unwrap_or(f64::NAN);
        let x = self.reach(slot, c.radius);
        let old_slots = self.earlier.map_or(0, |(_, i)| i.circles.len());
        let old_holes = old_slots.saturating_sub(1);
        // The close holes (increasing), for a hole.
        let mut close: Vec<usize> = Vec::new();
        let near: Vec<Near> = if id == BOUNDING {
            holes
                .iter()
                .filter(|h| b.radius - dist(h.center, b.center) - h.radius < x)
                .map(|h| Near {
                    center: h.center,
                    radius: h.radius,
                    outer: false,
                })
                .collect()
        } else {
            close = self.index.within_gap(id as usize, x);
            let mut v: Vec<Near> = close
                .iter()
                .map(|&j| Near {
                    center: holes[j].center,
                    radius: holes[j].radius,
                    outer: false,
                })
                .collect();
            if b.radius - dist(c.center, b.center) - c.radius < x {
                v.push(Near {
                    center: b.center,
                    radius: b.radius,
                    outer: true,
                });
            }
            v
        };
        let bits = |c: &Circle| [c.center[0], c.center[1], c.radius].map(f64::to_bits);
        let same = self.earlier.filter(|(p, inputs)| {
            slot < old_slots
                && bits(&inputs.circles[slot]) == bits(&c)
                && p.samples.circles[slot].count as usize <= budget
                && inputs.density.get(slot).copied().unwrap_or(0) == self.density(slot)
                && p.samples.circles[slot].gap.to_bits() == g.to_bits()
                && p.samples.circles[slot].circle == id
                && !p.samples.grid.is_empty()
        });
        let new_near = if id == BOUNDING {
            holes[old_holes.min(holes.len())..]
                .iter()
                .any(|h| b.radius - dist(h.center, b.center) - h.radius < x)
        } else {
            close.last().is_some_and(|&j| j >= old_holes)
        };
        if let (Some((p, _)), false) = (same, new_near) {
            let cs = p.samples.circles[slot];
            let range = cs.first as usize..(cs.first + cs.count) as usize;
            return Ok(SlotSamples::Taken {
                n: p.samples.grid_counts[slot],
                points: &p.samples.points[range.clone()],
                grid: &p.samples.grid[range],
            });
        }
        // Resampling doubles the density everywhere on the circle: the coarse count too.
        let k = self.density(slot).min(MAX_LEVELS);
        // Coarse count `n0 2^k` (fewer for a circle tiny for its coordinates,
        // [`coarse_count`]); one beyond the budget fails in `adaptive_circle`.
        let coarse = self
            .n0
            .checked_mul(1u64 << k)
            .map(|v| coarse_count(c, v, self.n0))
            .filter(|&v| v <= budget as u64)
            .unwrap_or(u64::MAX);
        let (n, ks) = adaptive_circle(
            c,
            id == BOUNDING,
            coarse,
            self.factor(slot),
            g,
            &near,
            budget,
            &self.units,
        )?;
        Ok(SlotSamples::Made { n, ks })
    }

    /// Every circle's samples in slot order, each within what the ones before it left of the
    /// total limit: the first that does not fit is the error.
    fn plan_serial(&self) -> Result<Vec<SlotSamples<'a>>, TooManySamples> {
        let mut plans = Vec::with_capacity(self.slots());
        let mut used = 0usize;
        for slot in 0..self.slots() {
            // The total budget bounds every circle too, so memory stays within `max_total`.
            let left = self.opts.max_total.saturating_sub(used);
            let plan = self
                .plan(slot, self.cap.min(left))
                .map_err(|()| TooManySamples {
                    circle: Self::id(slot),
                    limit: if left < self.cap {
                        self.opts.max_total
                    } else {
                        self.cap
                    },
                    total: left < self.cap,
                })?;
            used += plan.len();
            plans.push(plan);
        }
        Ok(plans)
    }

    /// Every circle's samples, on the thread pool, each within the per-circle budget (and the
    /// total limit); `None` when a circle does not fit or the total is passed (the serial loop
    /// then finds the error, [`sample_adaptive_on`]). Collected in slot order.
    fn plan_parallel(&self) -> Option<Vec<SlotSamples<'a>>> {
        let budget = self.cap.min(self.opts.max_total);
        let made = AtomicUsize::new(0);
        let over = AtomicBool::new(false);
        let plans: Vec<Option<SlotSamples<'a>>> = (0..self.slots())
            .into_par_iter()
            .with_min_len(CIRCLES_PER_TASK)
            .with_max_len(crate::tasks::CIRCLES)
            .map(|slot| {
                if over.load(Ordering::Relaxed) {
                    return None;
                }
                let plan = self.plan(slot, budget).ok();
                let fits = plan.as_ref().is_some_and(|p| {
                    made.fetch_add(p.len(), Ordering::Relaxed) + p.len() <= self.opts.max_total
                });
                if !fits {
                    over.store(true, Ordering::Relaxed);
                }
                plan
            })
            .collect();
        if over.into_inner() {
            return None;
        }
        plans.into_iter().collect()
    }

    /// The samples of `plans` (one per slot, in slot order) laid out in [`Samples`], and how
    /// many were taken over; the arrays filled by ranges of circles on the thread pool when
    /// `parallel` (the same values either way).
    fn assemble(&self, plans: &[SlotSamples], parallel: bool) -> (Samples, usize) {
        let mut circles = Vec::with_capacity(plans.len());
        let mut grid_counts = Vec::with_capacity(plans.len());
        let mut total = 0usize;
        for (slot, plan) in plans.iter().enumerate() {
            let count = plan.len();
            circles.push(CircleSamples {
                circle: Self::id(slot),
                first: total as u32,
                count: count as u32,
                gap: self.gaps.get(slot).copied().unwrap_or(f64::NAN),
            });
            grid_counts.push(match plan {
                SlotSamples::Taken { n, .. } | SlotSamples::Made { n, .. } => *n,
            });
            total += count;
        }
        let reused = plans
            .iter()
            .filter(|p| matches!(p, SlotSamples::Taken { .. }))
            .count();
        let mut s = Samples {
            points: vec![[0.0; 2]; total],
            circle_of: vec![0; total],
            index_of: vec![0; total],
            grid: vec![0; total],
            circles,
            grid_counts,
        };
        let all = SampleSlices {
            points: &mut s.points,
            circle_of: &mut s.circle_of,
            index_of: &mut s.index_of,
            grid: &mut s.grid,
        };
        if parallel {
            // Ranges of whole circles of about `per_task` samples each.
            let per_task = (total / (8 * rayon::current_num_threads())).max(SAMPLES_PER_TASK);
            let mut tasks = Vec::new();
            let mut rest = all;
            let mut start = 0;
            let mut size = 0;
            for (slot, c) in s.circles.iter().enumerate() {
                size += c.count as usize;
                if size >= per_task || slot + 1 == plans.len() {
                    let (head, tail) = rest.split_at(size);
                    tasks.push((start..slot + 1, head));
                    rest = tail;
                    start = slot + 1;
                    size = 0;
                }
            }
            let circles = &s.circles;
            tasks
                .into_par_iter()
                .for_each(|(slots, out)| self.fill(plans, circles, slots, out));
        } else {
            self.fill(plans, &s.circles, 0..plans.len(), all);
        }
        (s, reused)
    }

    /// The samples of circles `slots` (their plans and places in `plans` and `circles`) into
    /// `out`, which holds exactly their samples.
    fn fill(
        &self,
        plans: &[SlotSamples],
        circles: &[CircleSamples],
        slots: std::ops::Range<usize>,
        out: SampleSlices,
    ) {
        let mut rest = out;
        for slot in slots {
            let cs = circles[slot];
            let (o, tail) = rest.split_at(cs.count as usize);
            rest = tail;
            o.circle_of.fill(cs.circle);
            for (i, x) in o.index_of.iter_mut().enumerate() {
                *x = i as u32;
            }
            match &plans[slot] {
                SlotSamples::Made { n, ks } => {
                    let c = self.domain.circle(cs.circle);
                    let units = self.units.grid(*n);
                    for ((p, g), &k) in o.points.iter_mut().zip(o.grid.iter_mut()).zip(ks) {
                        let u = units.at(k);
                        *p = [c.center[0] + c.radius * u[0], c.center[1] + c.radius * u[1]];
                        *g = k;
                    }
                }
                SlotSamples::Taken { points, grid, .. } => {
                    o.points.copy_from_slice(points);
                    o.grid.copy_from_slice(grid);
                }
            }
        }
    }
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
    let mut out = duplicate_violations(samples, tri);
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
                push_repeated_circle(&mut out, c, tt);
            }
            TriangleKind::Hole(_) | TriangleKind::Boundary { .. } => {}
        }
    }
    push_missing_edges(&mut out, samples, tri, &seen);
    out
}

/// Invariant check, first part: one [`ViolationKind::Duplicate`] per duplicate sample of
/// `tri`, in the triangulation's order.
fn duplicate_violations(samples: &Samples, tri: &Triangulation) -> Vec<Violation> {
    tri.duplicates()
        .iter()
        .map(|&(first, duplicate)| Violation {
            circle: samples.circle_of[duplicate as usize],
            kind: ViolationKind::Duplicate { first, duplicate },
        })
        .collect()
}

/// Invariant (c) at interior triangle `triangle` with vertex circles `c`: a violation blaming
/// the circle that appears twice, if one does.
fn push_repeated_circle(out: &mut Vec<Violation>, c: [CircleId; 3], triangle: u32) {
    let repeated = if c[0] == c[1] || c[0] == c[2] {
        Some(c[0])
    } else if c[1] == c[2] {
        Some(c[1])
    } else {
        None
    };
    if let Some(circle) = repeated {
        out.push(Violation {
            circle,
            kind: ViolationKind::InteriorRepeatsCircle { triangle },
        });
    }
}

/// Invariant (a), last part: every boundary edge `s -> next(s)` not marked in `seen` is
/// missing, unless one of its ends is a duplicate sample (which has no edges of its own).
fn push_missing_edges(
    out: &mut Vec<Violation>,
    samples: &Samples,
    tri: &Triangulation,
    seen: &[bool],
) {
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
}

/// Soft invariant (d): every medial arc with at least one boundary triangle has a wall of at
/// least one sample step on both sides (`|C1|, |C2| >= 2`), so that every wall corner is shared
/// by exactly two blocks (paper section 3) and no block has a zero-length wall. An arc between
/// two adjacent interior triangles (empty chain) breaks it too, unless the two triangles are
/// exactly co-circular (a true degeneracy of the layout, paper section 4.2, left to arc
/// collapsing: resampling cannot remove it). Returns one violation per offending side.
///
/// The arcs are checked in parallel (issue 8: one pass over the 300 000 arcs of 1e5 bubbles
/// took 11-14 ms on one CPU, twice per run), the violations collected in arc order.
pub fn thin_walls(tri: &Triangulation, medial: &MedialGraph) -> Vec<Violation> {
    medial
        .arcs
        .par_iter()
        .enumerate()
        .with_min_len(crate::tasks::ARCS)
        .fold(Vec::new, |mut out, (e, arc)| {
            if arc.triangles.is_empty() {
                let Some(v0) = medial.vertices.get(arc.ends[0] as usize) else {
                    return out;
                };
                if tri.is_cocircular_edge(v0.triangle as usize, arc.end_slots[0] as usize) {
                    return out;
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
            out
        })
        .reduce(Vec::new, |mut a, mut b| {
            a.append(&mut b);
            a
        })
}

/// How many doublings (1 to 4, or 0 for "do not refine") circle `circle` with `n` samples needs so that the wall of
/// `arc` on it spans at least two sample steps: the exact normal feet of the arc's two medial
/// vertices on the circle are `delta` radians apart (about the circle's centre), and a spacing
/// of `delta / 2` puts a sample strictly between the spokes. Depends only on the angle, so
/// mirror images ask for the same factor up to rounding at a power-of-two boundary (and the
/// group rule of [`sample_and_triangulate`] then takes the larger one for both).
fn refinement_log2(domain: &Domain, done: &SampledDomain, arc: u32, circle: CircleId) -> u32 {
    let medial = &done.medial;
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
    // The local angular step at the wall: the wider of the two intervals beside its sample.
    let chain = if a.circles[0] == circle { &a.c1 } else { &a.c2 };
    let samples = &done.samples;
    let step = chain.first().map_or(TAU, |&s| {
        let t = samples.angle(s);
        let next = (samples.angle(samples.next(s)) - t).rem_euclid(TAU);
        let prev = (t - samples.angle(samples.prev(s))).rem_euclid(TAU);
        let w = next.max(prev);
        if w > 0.0 {
            w
        } else {
            TAU
        }
    });
    let n = TAU / step;
    let need = 2.0 * TAU / delta;
    if need.is_nan() || need > SOFT_MAX_SAMPLES {
        // A very short arc (nearly co-circular interior triangles): leave it to arc
        // collapsing rather than flood the circle with samples.
        return 0;
    }
    let mut k = 1;
    while k < 4 && n * f64::from(1u32 << k) < need {
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
    /// What the samples were made from (for [`sample_adaptive_after`]); `None` for a
    /// sampling made otherwise.
    inputs: Option<SamplingInputs>,
}

/// The inputs of an adaptive sampling besides the gaps it records: the options, the density
/// doublings per slot, and the circles in slot order.
#[derive(Debug, Clone)]
struct SamplingInputs {
    options: SamplingOptions,
    density: Vec<u32>,
    circles: Vec<Circle>,
}

/// Sample, triangulate, check the invariants, and resample offending circles until they
/// hold; then build the medial graph.
///
/// Hard invariants ((a)-(c) and the in-hole/in-domain dichotomy, [`check_invariants`]) must
/// hold; the soft invariant (d) ([`thin_walls`]) is pursued with the same resampling while
/// rounds remain (and [`SamplingOptions::soft_rounds`] asks for it), then accepted as is.
///
/// Sampling is adaptive ([`sample_adaptive`]). Resampling rule (keeps mirror symmetry): when
/// circle `c` offends, every circle with the same radius and nearest gap (bitwise) as `c`
/// doubles its density everywhere (coarse count and the spacing-to-gap factor). This depends only on
/// geometry, so mirror images are refined together. Errors: [`MeshError::Sampling`] when the
/// hard invariants still fail after [`SamplingOptions::max_rounds`] rounds, when a circle would
/// need more than [`SamplingOptions::max_per_circle`] samples, when the total would exceed
/// [`SamplingOptions::max_total`], or when samples coincide (a circle too small for its
/// coordinates); [`MeshError::Triangulation`] from the engine; [`MeshError::Internal`] from
/// the medial graph (not expected once the invariants hold).
pub fn sample_and_triangulate(
    domain: &Domain,
    opts: &SamplingOptions,
) -> Result<SampledDomain, MeshError> {
    sample_and_triangulate_after(domain, opts, None)
}

/// [`sample_and_triangulate`], given the sampling of an earlier domain (`previous`, e.g. the
/// round before macro refinement inserted holes): when its sample points are a prefix of the
/// new ones, bit for bit (no other circle was resampled, the new holes' samples come last), the
/// new points are inserted into its triangulation ([`Triangulation::extended`]) instead of
/// triangulating from scratch; when earlier circles were resampled more densely but kept every
/// earlier sample, its triangulation is renumbered and the new samples inserted
/// ([`Triangulation::extended_renumbered`]). Same triangles, numbered differently;
/// deterministic.
pub fn sample_and_triangulate_after(
    domain: &Domain,
    opts: &SamplingOptions,
    previous: Option<&SampledDomain>,
) -> Result<SampledDomain, MeshError> {
    sample_and_triangulate_impl(domain, opts, previous, None, None)
}

/// [`sample_and_triangulate_after`], moving the medial arcs the new graph keeps out of
/// `previous` instead of cloning them ([`reuse::medial_graph_taking`]), and the earlier
/// triangulation's arrays into the new one ([`Triangulation::extended_taking`]) instead of
/// copying them: `previous.medial.arcs` and `previous.triangulation` are left empty. For macro
/// refinement, which reads only the earlier graph's vertices afterwards. The same result.
pub fn sample_and_triangulate_taking(
    domain: &Domain,
    opts: &SamplingOptions,
    previous: Option<&mut SampledDomain>,
) -> Result<SampledDomain, MeshError> {
    match previous {
        Some(p) => {
            let arcs = std::mem::take(&mut p.medial.arcs);
            let tri = std::mem::take(&mut p.triangulation);
            sample_and_triangulate_impl(domain, opts, Some(p), Some(arcs), Some(tri))
        }
        None => sample_and_triangulate_impl(domain, opts, None, None, None),
    }
}

/// [`sample_and_triangulate_after`], with the earlier graph's arcs apart (`taken`, moved
/// into the new graph where kept) when the caller gave them up, and likewise the earlier
/// triangulation (`owned`, then `previous.triangulation` is not read): its arrays move into an
/// extension, and come back ([`crate::geometry::Changes::undo`]) when a further attempt needs
/// them.
fn sample_and_triangulate_impl(
    domain: &Domain,
    opts: &SamplingOptions,
    previous: Option<&SampledDomain>,
    mut taken: Option<Vec<crate::medial::MedialArc>>,
    mut owned: Option<Triangulation>,
) -> Result<SampledDomain, MeshError> {
    let _stage = crate::timings::enter("sampling");
    let index = domain.hole_index();
    let gaps = nearest_gaps(domain);
    let radii: Vec<f64> = domain
        .circle_ids()
        .map(|c| domain.circle(c).radius)
        .collect();
    // Per slot, the number of density doublings asked for by resampling (and the caller's
    // boost, shared by circles of the same radius and gap).
    let mut density = vec![0u32; gaps.len()];
    if !opts.boost.is_empty() {
        let mut by_key: HashMap<(u64, u64), u32> = HashMap::new();
        for (slot, &b) in opts.boost.iter().enumerate().take(gaps.len()) {
            let e = by_key
                .entry((radii[slot].to_bits(), gaps[slot].to_bits()))
                .or_insert(0);
            *e = (*e).max(b.min(16));
        }
        for slot in 0..density.len() {
            if let Some(&b) = by_key.get(&(radii[slot].to_bits(), gaps[slot].to_bits())) {
                density[slot] = b;
            }
        }
    }
    let mut round = 0;
    loop {
        let ctx = SlotContext::new(domain, &index, opts, &gaps, &density, previous);
        let (samples, _) =
            sample_adaptive_with(&ctx, ctx.parallel()).map_err(|e| MeshError::Sampling {
                circle: e.circle,
                message: if e.total {
                    format!(
                        "more samples would be needed in total than the limit {}",
                        e.limit
                    )
                } else {
                    format!(
                        "the circle would need more than the most samples allowed ({}): its \
                         gap to a neighbour is too small for the sampling",
                        e.limit
                    )
                },
            })?;
        let total = samples.len();
        if total > opts.max_total {
            let worst = samples
                .circles
                .iter()
                .max_by_key(|c| c.count)
                .map(|c| c.circle)
                .unwrap_or(BOUNDING);
            return Err(MeshError::Sampling {
                circle: worst,
                message: format!(
                    "{total} samples would be needed in total, more than the limit {}",
                    opts.max_total
                ),
            });
        }
        // What the arrays taken from `owned` changed, while the new triangulation holds them.
        let mut changes = None;
        let (triangulation, extended) = crate::timings::span("triangulation", || {
            let extended = match (owned.as_mut(), previous) {
                (Some(t), _) => match t.extended_taking(&samples.points)? {
                    Some((t, c)) => {
                        changes = Some(c);
                        Some(t)
                    }
                    None => t.extended(&samples.points)?,
                },
                (None, Some(p)) => p.triangulation.extended(&samples.points)?,
                (None, None) => None,
            };
            match extended {
                Some(t) => Ok((t, true)),
                None => {
                    // Earlier circles resampled more densely keep every earlier sample: the
                    // earlier triangulation renumbered, with the new samples inserted.
                    let source = owned.as_ref().or(previous.map(|p| &p.triangulation));
                    let renumbered = match (source, previous) {
                        (Some(t), Some(p)) if !t.is_empty() => kept_samples(&p.samples, &samples)
                            .map(|map| t.extended_renumbered(&samples.points, &map))
                            .transpose()?
                            .flatten(),
                        _ => None,
                    };
                    match renumbered {
                        Some(t) => Ok((t, false)),
                        None => Triangulation::new(&samples.points).map(|t| (t, false)),
                    }
                }
            }
        })?;
        // The round before, when the new triangulation extends its own and every earlier
        // circle is sampled as before: its classes, checks and medial arcs are reused where
        // the insertion kept the triangles ([`crate::medial::reuse`]).
        let before_len = match (&changes, &owned, previous) {
            (Some(c), _, _) => c.before_len(),
            (None, Some(t), _) => t.len(),
            (None, None, Some(p)) => p.triangulation.len(),
            (None, None, None) => 0,
        };
        let reuse = previous
            .filter(|p| {
                extended
                    && p.kinds.len() == before_len
                    && reuse::same_earlier_circles(&p.samples, &samples)
            })
            .map(|p| {
                let kept = match (&changes, &owned) {
                    (Some(c), _) => reuse::Kept::from_changes(c, &triangulation),
                    (None, Some(t)) => reuse::Kept::new(t, &triangulation),
                    (None, None) => reuse::Kept::new(&p.triangulation, &triangulation),
                };
                (p, kept)
            });
        let (kinds, hard) = match &reuse {
            Some((p, kept)) => reuse::classify_and_check_after(
                &samples,
                &triangulation,
                &p.kinds,
                p.samples.len(),
                kept,
            ),
            None => classify_and_check(&samples, &triangulation),
        };
        let (violations, soft_result, spare) = if hard.is_empty() {
            let (medial, soft) = crate::timings::span("medial_graph", || {
                // Taken arcs serve one attempt (a later round walks every arc again).
                let arcs = taken.take();
                let reused = reuse.as_ref().and_then(|(p, kept)| match arcs {
                    Some(mut arcs) => reuse::medial_graph_taking(
                        &samples,
                        &triangulation,
                        &kinds,
                        &p.medial.vertices,
                        &mut arcs,
                        kept,
                    ),
                    None => reuse::medial_graph_after(&samples, &triangulation, &kinds, p, kept),
                });
                let medial = match reused {
                    Some(m) => m,
                    None => medial_graph(&samples, &triangulation, &kinds)?,
                };
                let soft = thin_walls(&triangulation, &medial);
                Ok::<_, MeshError>((medial, soft))
            })?;
            let done = SampledDomain {
                samples,
                triangulation,
                kinds,
                medial,
                rounds: round,
                thin_walls: soft.clone(),
                inputs: Some(SamplingInputs {
                    options: opts.clone(),
                    density: density.clone(),
                    circles: domain.circle_ids().map(|c| domain.circle(c)).collect(),
                }),
            };
            if soft.is_empty() || round >= opts.max_rounds || !opts.soft_rounds {
                return Ok(done);
            }
            (soft, Some(done), None)
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
            (hard, None, Some(triangulation))
        };
        // Refinement factor 2^k per (radius, gap) group, the largest any member needs.
        let mut keys: HashMap<(u64, u64), u32> = HashMap::new();
        for v in &violations {
            let slot = (v.circle + 1) as usize;
            let k = match (&v.kind, &soft_result) {
                (ViolationKind::SingleSampleWall { arc }, Some(done)) => {
                    refinement_log2(domain, done, *arc, v.circle)
                }
                _ => 1,
            };
            let e = keys
                .entry((radii[slot].to_bits(), gaps[slot].to_bits()))
                .or_insert(k);
            *e = (*e).max(k);
        }
        let mut refined = false;
        for slot in 0..density.len() {
            if let Some(&k) = keys.get(&(radii[slot].to_bits(), gaps[slot].to_bits())) {
                if k > 0 {
                    density[slot] += k;
                    refined = true;
                }
            }
        }
        if !refined {
            if let Some(done) = soft_result {
                return Ok(done);
            }
        }
        // This attempt's triangulation is dropped: the arrays it took go back to `owned`
        // for the next attempt.
        if let Some(c) = changes {
            if let Some(t) = spare.or(soft_result.map(|d| d.triangulation)) {
                owned = Some(c.undo(t));
            }
        }
        round += 1;
    }
}

/// Where the samples `before` of an earlier sampling are among `after`, when every earlier
/// circle kept all its samples (a resampling that only made circles denser, as macro
/// refinement does around an inserted hole; new circles come after the earlier ones):
/// `map[s]` is the index in `after` of earlier sample `s`. `None` when a circle lost a sample
/// or moved, or the circles differ. Samples of a circle run counter-clockwise from angle 0 in
/// both, so one merge per circle finds them (points compared bit for bit).
pub(crate) fn kept_samples(before: &Samples, after: &Samples) -> Option<Vec<u32>> {
    if before.circles.len() > after.circles.len() {
        return None;
    }
    let bits = |p: &Point| p.map(f64::to_bits);
    let mut map = vec![0u32; before.points.len()];
    for (b, a) in before.circles.iter().zip(&after.circles) {
        if b.circle != a.circle || b.count > a.count {
            return None;
        }
        let old = before
            .points
            .get(b.first as usize..(b.first + b.count) as usize)?;
        let new = after
            .points
            .get(a.first as usize..(a.first + a.count) as usize)?;
        let mut k = 0;
        for (j, p) in old.iter().enumerate() {
            let key = bits(p);
            while k < new.len() && bits(&new[k]) != key {
                k += 1;
            }
            if k == new.len() {
                return None;
            }
            map[b.first as usize + j] = a.first + k as u32;
            k += 1;
        }
    }
    Some(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The division-free next index equals `(i + 1) % count`, indices on and off the circle.
    #[test]
    fn wrap_next_equals_the_modulo() {
        for count in 1..40u32 {
            for i in 0..100u32 {
                assert_eq!(wrap_next(i, count), (i + 1) % count, "{i} {count}");
            }
        }
    }

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
    fn unit_offset_is_the_table_entry_bitwise() {
        for n in [8u64, 16, 24, 32, 64, 200, 1024, 4096] {
            let u = unit_offsets(n as usize);
            for k in 0..2 * n {
                let v = unit_offset(k, n);
                let w = u[(k % n) as usize];
                assert_eq!(
                    [v[0].to_bits(), v[1].to_bits()],
                    [w[0].to_bits(), w[1].to_bits()]
                );
            }
        }
        assert!(unit_offset(3, 12)[0].is_nan());
    }

    /// The table's lookups are bitwise [`unit_offset`] on grids that refine or coarsen the
    /// table's by powers of two (up to `2^60` angles, indices past the grid included), and
    /// computed on every other grid.
    #[test]
    fn unit_table_is_unit_offset_bitwise() {
        let bits = |u: Point| [u[0].to_bits(), u[1].to_bits()];
        let mut rng = crate::layouts::SplitMix64(7);
        let mut looked_up = 0;
        for size in [8u64, 16, 24, 40, 96, 256, 4096, 8192] {
            let table = UnitTable::new(size);
            assert_eq!(table.u.is_empty(), size > 1 << 12);
            let mut grids: Vec<u64> = (0..=60)
                .filter_map(|s| size.checked_mul(1 << s))
                .chain((1..=6).filter_map(|s| (size >> s << s == size).then_some(size >> s)))
                .collect();
            grids.extend([
                0,
                4,
                12,
                8,
                48,
                72,
                1000,
                1 << 40,
                3 << 40,
                u64::MAX / 8 * 8,
            ]);
            for n in grids {
                let units = table.grid(n);
                looked_up += usize::from(!units.table.is_empty());
                let mut ks: Vec<u64> = (0..n.min(2048)).collect();
                ks.extend((0..2000).map(|_| rng.next_u64() % n.max(1)));
                ks.extend((0..64).map(|s| n.wrapping_mul(3) >> 1 >> (s % 8) << (s % 8)));
                ks.extend((0..n.trailing_zeros()).map(|s| n >> s));
                ks.extend([n, n.wrapping_add(1), 2 * size, u64::MAX]);
                for k in ks {
                    let (a, b) = (units.at(k), unit_offset(k, n));
                    assert!(
                        bits(a) == bits(b) || (a[0].is_nan() && b[0].is_nan()),
                        "table {size} grid {n} index {k}: {a:?} {b:?}"
                    );
                }
            }
        }
        assert!(looked_up > 200, "{looked_up}");
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
