//! The public Delaunay triangulation type.

use super::build::{first_triangle, Builder, Parts};
use super::predicates::{incircle, SAFE_MAX, SAFE_MIN};
use super::{exact, Point};
use std::borrow::Cow;
use std::cmp::Ordering;
use std::collections::HashMap;

/// Why a point set could not be triangulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TriangulationError {
    #[error("point {index} has a non-finite coordinate")]
    NonFinite { index: usize },
    #[error("need at least 3 distinct points, got {distinct}")]
    TooFewPoints { distinct: usize },
    #[error("all {distinct} distinct points are collinear")]
    AllCollinear { distinct: usize },
    #[error("too many points: {count} (at most {max})")]
    TooManyPoints { count: usize, max: usize },
    #[error("internal error in the triangulation: {message}")]
    Internal { message: String },
}

/// Largest accepted input size (keeps every internal half-edge id inside `u32`).
pub const MAX_POINTS: usize = 300_000_000;

pub(super) const NONE: u32 = u32::MAX;

/// How [`Triangulation::extended`] inserts the new points.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Extension {
    /// The sparse replay, else the builder.
    Auto,
    /// The resumed builder over the whole triangulation.
    Full,
    /// The sparse replay or nothing.
    Sparse,
}

/// The Delaunay triangulation of a finite planar point set, computed with exact predicates.
///
/// # Guarantees
/// - Every triangle is counter-clockwise (exact `orient2d > 0`) and every interior edge is
///   locally Delaunay (exact `incircle <= 0` for the opposite vertex); the triangles tile the
///   convex hull; every distinct input point is a vertex (points on hull edges included).
/// - In-circle ties (four or more co-circular points) are broken by simulation of simplicity on
///   the lifted coordinate, keyed to the lexicographic `(x, y)` order of the points. The triangle
///   set is therefore a function of the point *set*: permuting the input only renumbers it.
/// - Exact duplicates are removed and reported by [`Self::duplicates`]; triangles always use
///   the first (smallest) input index of a duplicate group.
/// - Co-circular configurations are reported by [`Self::cocircular_groups`] and
///   [`Self::is_cocircular_edge`].
///
/// # Example
/// ```
/// use medial_blocks::geometry::Triangulation;
///
/// // A unit square (4 co-circular points), its centre, and a duplicate of a corner.
/// let pts = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5], [1.0, 0.0]];
/// let dt = Triangulation::new(&pts).unwrap();
/// assert_eq!(dt.len(), 4); // 2n - 2 - h = 2*5 - 2 - 4
/// assert_eq!(dt.duplicates(), &[(1, 5)]);
/// for tri in dt.triangles() {
///     assert!(tri.contains(&4)); // the centre is in every triangle
/// }
/// // The centre breaks the square's circle: no co-circular group remains.
/// assert!(dt.cocircular_groups().is_empty());
///
/// let square = Triangulation::new(&pts[..4]).unwrap();
/// assert_eq!(square.cocircular_groups(), vec![vec![0, 1, 2, 3]]);
/// ```
///
/// `Triangulation::default()` is the empty triangulation (no points, no triangles): what a
/// holder keeps after releasing one nothing reads any more ([`crate::blocking::CollapsedBlocking`]).
#[derive(Debug, Clone, Default)]
pub struct Triangulation {
    points: Vec<Point>,
    tris: Vec<[u32; 3]>,
    adj: Vec<[u32; 3]>,
    duplicates: Vec<(u32, u32)>,
    vertex_tri: Vec<u32>,
}

/// What [`Triangulation::extended_taking`] changed in the triangulation it took.
pub struct Changes {
    log: super::sparse::Log,
    /// Per changed earlier slot (in [`Self::changed`] order), its earlier triangle and
    /// neighbours.
    before: Vec<([u32; 3], [Option<u32>; 3])>,
    before_duplicates: bool,
}

impl Changes {
    /// The triangles of the extension that are not those of the earlier triangulation (same
    /// id, same vertices in the same order), in increasing order: every slot the insertion
    /// wrote (a written triangle has a new point, which no earlier one has).
    pub fn changed(&self) -> &[u32] {
        &self.log.changed
    }
    /// The earlier triangle count.
    pub fn before_len(&self) -> usize {
        self.log.base
    }
    /// The earlier triangle and neighbours of the `i`-th changed slot, for the changed slots
    /// below [`Self::before_len`] (the others are new).
    pub fn before(&self, i: usize) -> ([u32; 3], [Option<u32>; 3]) {
        self.before[i]
    }
    /// True when the earlier triangulation had duplicates.
    pub fn before_had_duplicates(&self) -> bool {
        self.before_duplicates
    }
    /// The earlier triangulation, from `after` (the extension these changes came with).
    pub fn undo(self, after: Triangulation) -> Triangulation {
        let a = self.log.undo(super::sparse::Arrays {
            tris: after.tris,
            adj: after.adj,
            vertex_tri: after.vertex_tri,
        });
        let mut points = after.points;
        points.truncate(self.log.points);
        Triangulation {
            points,
            tris: a.tris,
            adj: a.adj,
            duplicates: after.duplicates,
            vertex_tri: a.vertex_tri,
        }
    }
}

/// Smallest and largest non-zero coordinate magnitude (`(inf, 0)` when every coordinate is 0;
/// NaN coordinates are ignored).
///
/// On the bits of `|c|`, which order as the magnitudes do (NaNs above the infinity), so that
/// the two reductions vectorise, and on the pool for large sets (issue 8: the chain of float
/// `min`/`max` took 15 ms on one thread for the 2.5 M samples of 1e5 particles).
fn magnitude_range(points: &[Point]) -> (f64, f64) {
    use rayon::prelude::*;
    const PER_TASK: usize = 1 << 16;
    let (lo, hi) = if points.len() >= 4 * PER_TASK {
        points
            .par_chunks(PER_TASK)
            .map(magnitude_keys)
            .reduce(|| (u64::MAX, 0), |a, b| (a.0.min(b.0), a.1.max(b.1)))
    } else {
        magnitude_keys(points)
    };
    let lo = if lo == u64::MAX {
        f64::INFINITY
    } else {
        f64::from_bits(lo)
    };
    (lo, f64::from_bits(hi))
}

/// [`magnitude_range`] of `points` as the bits of the magnitudes (`u64::MAX` and 0 when none).
fn magnitude_keys(points: &[Point]) -> (u64, u64) {
    const SIGN: u64 = 1 << 63;
    const INF: u64 = 0x7ff0_0000_0000_0000;
    let (mut lo, mut hi) = (u64::MAX, 0u64);
    for p in points {
        for &c in p {
            let b = c.to_bits() & !SIGN;
            let counted = b != 0 && b <= INF;
            lo = lo.min(if counted { b } else { u64::MAX });
            hi = hi.max(if counted { b } else { 0 });
        }
    }
    (lo, hi)
}

/// Power-of-two exponent `s` such that scaling every coordinate by `2^s` keeps all magnitudes in
/// the adaptive predicates' exact range, if one exists (and is not 0), for a point set with
/// [`magnitude_range`] `(lo, hi)`.
fn shift_for((lo, hi): (f64, f64)) -> Option<i32> {
    if hi == 0.0 || (lo >= SAFE_MIN && hi <= SAFE_MAX) {
        return None;
    }
    // Exponents (floor log2) of the extreme magnitudes.
    let e_hi = exact_exponent(hi);
    let e_lo = exact_exponent(lo);
    // Need e_hi + s <= 199 and e_lo + s >= -150.
    let (min_s, max_s) = (-150 - e_lo, 199 - e_hi);
    if min_s > max_s {
        return None;
    }
    Some((min_s + max_s) / 2)
}

/// True when every coordinate lies in the predicates' safe range once scaled by `2^shift`
/// (`shift` from [`shift_for`] on the same range): either a shift was found, or none was needed.
fn all_safe_after((lo, hi): (f64, f64), shift: Option<i32>) -> bool {
    shift.is_some() || hi == 0.0 || (lo >= SAFE_MIN && hi <= SAFE_MAX)
}

/// `floor(log2(|x|))` for finite non-zero `x` (exact, also for subnormals).
fn exact_exponent(x: f64) -> i32 {
    let (m, e) = exact::decompose(x);
    let bits = 64 - m.unsigned_abs().leading_zeros() as i32;
    e + bits - 1
}

/// `x * 2^s`, exact when the result stays normal (`s` may exceed the f64 exponent range).
fn scale(x: f64, s: i32) -> f64 {
    let half = s / 2;
    let pow = |k: i32| f64::from_bits(((1023 + k) as u64) << 52);
    x * pow(half) * pow(s - half)
}

impl Triangulation {
    /// Triangulate `points`. Exact duplicates are removed and reported by [`Self::duplicates`].
    ///
    /// Errors: a NaN or infinite coordinate, fewer than 3 distinct points, all distinct points
    /// collinear, or more than [`MAX_POINTS`] points. Never panics.
    pub fn new(points: &[Point]) -> Result<Self, TriangulationError> {
        if let Some(index) = points
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(TriangulationError::NonFinite { index });
        }
        if points.len() > MAX_POINTS {
            return Err(TriangulationError::TooManyPoints {
                count: points.len(),
                max: MAX_POINTS,
            });
        }
        let range = magnitude_range(points);
        let shift = shift_for(range);
        let order = super::order::insertion_order(points);
        // Points in insertion order (vertex ids are positions in it), scaled by 2^shift; on
        // the pool for the sets the split builds (issue 8: 38 ms on one thread at 1e5 particles).
        let at = |&i: &u32| {
            let p = points[i as usize];
            shift.map_or(p, |s| [scale(p[0], s), scale(p[1], s)])
        };
        let work: Vec<Point> = if order.len() >= super::split::SPLIT_MIN {
            use rayon::prelude::*;
            order.par_iter().map(at).collect()
        } else {
            order.iter().map(at).collect()
        };
        debug_assert!(work.iter().all(|p| p.iter().all(|&c| c.is_finite())));
        // First vertex, first point distinct from it, first point not collinear with them.
        let (b, c) = match first_triangle(&work) {
            Ok(bc) => bc,
            Err(distinct @ (0 | 1)) => return Err(TriangulationError::TooFewPoints { distinct }),
            Err(_) => {
                let distinct = count_distinct(points);
                return Err(if distinct < 3 {
                    TriangulationError::TooFewPoints { distinct }
                } else {
                    TriangulationError::AllCollinear { distinct }
                });
            }
        };
        let all_safe = all_safe_after(range, shift);
        if all_safe && work.len() >= super::split::SPLIT_MIN {
            // Two halves on two threads, stitched (the same triangle set, another numbering;
            // see `split`). A failure there is a bug: checked in debug builds, else the
            // one-piece construction below answers.
            match super::split::build_split(&work) {
                Ok(Some(parts)) => return Ok(Self::finish(points, Some(order), parts, work)),
                Ok(None) => {}
                Err(e) => debug_assert!(false, "split triangulation: {}", e.0),
            }
        }
        let mut builder = Builder::new(&work, all_safe, 0, b, c);
        builder
            .insert_rest(b, c)
            .map_err(|e| TriangulationError::Internal { message: e.0 })?;
        let parts = builder.into_parts();
        Ok(Self::finish(points, Some(order), parts, work))
    }

    /// The triangulation of `points`, whose first [`Self::vertex_count`] entries are this
    /// triangulation's points (bit for bit): the new points are inserted into it in input
    /// order instead of triangulating from scratch. `Ok(None)` when `points` does not extend
    /// this triangulation's points, or when the coordinate scaling of the predicates
    /// (`shift_for`) would differ.
    ///
    /// The triangle *set* is the one [`Self::new`] gives (the Delaunay triangulation under the
    /// lexicographic simulation of simplicity is a function of the point set; duplicates keep
    /// their smallest index); the triangle *numbering* differs: kept triangles keep their ids,
    /// new ones follow. Deterministic.
    pub fn extended(&self, points: &[Point]) -> Result<Option<Self>, TriangulationError> {
        self.extended_on(points, Extension::Auto)
    }

    /// [`Self::extended`] always by the resumed builder over the whole triangulation (the
    /// reference for the sparse replay [`Self::extended`] takes when it can; same result).
    #[doc(hidden)]
    pub fn extended_full(&self, points: &[Point]) -> Result<Option<Self>, TriangulationError> {
        self.extended_on(points, Extension::Full)
    }

    /// [`Self::extended`] by the sparse replay only: `Ok(None)` also where it gives up (tests
    /// count how often it applies).
    #[doc(hidden)]
    pub fn extended_sparse(&self, points: &[Point]) -> Result<Option<Self>, TriangulationError> {
        self.extended_on(points, Extension::Sparse)
    }

    /// The checks of [`Self::extended`] on `points`, and the points as the predicates see them
    /// with their `all_safe`; `Ok(None)` where it gives `Ok(None)`.
    #[allow(clippy::type_complexity)]
    fn extension_points<'p>(
        &self,
        points: &'p [Point],
    ) -> Result<Option<(Cow<'p, [Point]>, bool)>, TriangulationError> {
        let n0 = self.points.len();
        let bits = |p: &Point| p.map(f64::to_bits);
        if points.len() < n0
            || points[..n0]
                .iter()
                .zip(&self.points)
                .any(|(a, b)| bits(a) != bits(b))
        {
            return Ok(None);
        }
        if let Some(index) = points[n0..]
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(TriangulationError::NonFinite { index: n0 + index });
        }
        if points.len() > MAX_POINTS {
            return Err(TriangulationError::TooManyPoints {
                count: points.len(),
                max: MAX_POINTS,
            });
        }
        if self.tris.is_empty() {
            return Ok(None);
        }
        Ok(self.extension_work(points, magnitude_range(&points[n0..])))
    }

    /// `points` as the predicates see them when they extend this triangulation, with their
    /// `all_safe`: `new` is the magnitude range of the points not yet in it (the kept ones'
    /// range is this triangulation's). `None` when the coordinate scaling (`shift_for`) of
    /// all of them differs from this triangulation's. Unscaled points are used in place.
    fn extension_work<'p>(
        &self,
        points: &'p [Point],
        new: (f64, f64),
    ) -> Option<(Cow<'p, [Point]>, bool)> {
        let (old_lo, old_hi) = magnitude_range(&self.points);
        let range = (old_lo.min(new.0), old_hi.max(new.1));
        let shift = shift_for(range);
        if shift != shift_for((old_lo, old_hi)) {
            return None;
        }
        let work: Cow<'_, [Point]> = match shift {
            None => Cow::Borrowed(points),
            Some(s) => points
                .iter()
                .map(|&p| [scale(p[0], s), scale(p[1], s)])
                .collect(),
        };
        Some((work, all_safe_after(range, shift)))
    }

    /// [`Self::extended`] by the way `how` says: the sparse replay on copies of this
    /// triangulation's arrays (`sparse::extend`) gives the builder's result or nothing.
    fn extended_on(
        &self,
        points: &[Point],
        how: Extension,
    ) -> Result<Option<Self>, TriangulationError> {
        let n0 = self.points.len();
        let Some((work, all_safe)) = self.extension_points(points)? else {
            return Ok(None);
        };
        if how != Extension::Full {
            let arrays = super::sparse::Arrays {
                tris: self.tris.clone(),
                adj: self.adj.clone(),
                vertex_tri: self.vertex_tri.clone(),
            };
            debug_assert_eq!(
                2 * self.vertex_count() - 2 - self.tris.len(),
                self.adj.iter().flatten().filter(|&&m| m == NONE).count()
            );
            if let Ok((a, _)) = super::sparse::extend(
                &work,
                all_safe,
                arrays,
                self.vertex_count(),
                n0 as u32..points.len() as u32,
                &self.duplicates,
            ) {
                return Ok(Some(Triangulation {
                    points: points.to_vec(),
                    tris: a.tris,
                    adj: a.adj,
                    duplicates: self.duplicates.clone(),
                    vertex_tri: a.vertex_tri,
                }));
            }
            if how == Extension::Sparse {
                return Ok(None);
            }
        }
        let (tv, adj) = self.builder_arrays(points.len() as u32);
        let mut builder = Builder::resume(&work, all_safe, tv, adj, self.duplicates.clone());
        for pos in n0..points.len() {
            builder
                .insert(pos as u32)
                .map_err(|e| TriangulationError::Internal { message: e.0 })?;
        }
        let parts = builder.into_parts();
        let spare = match work {
            Cow::Owned(v) => v,
            Cow::Borrowed(_) => Vec::new(),
        };
        Ok(Some(Self::finish(points, None, parts, spare)))
    }

    /// The triangulation of `points`, which hold this triangulation's points at other places:
    /// `map[v]` is the index in `points` of its point `v` (bit for bit; one entry per point,
    /// distinct). This triangulation is renumbered and the other points are inserted into it
    /// in increasing index order, instead of triangulating from scratch. For a resampling that
    /// only adds points to some circles: their samples stay contiguous, so the earlier points
    /// are no prefix ([`Self::extended`]) but all are still there.
    ///
    /// `Ok(None)` when `map` does not say that (wrong length, an index out of range, a point
    /// that differs, a repeated index), when the coordinate scaling of the predicates
    /// (`shift_for`) would differ, or when either point set has duplicates (whose kept index
    /// the renumbering could change). The triangle *set* is the one [`Self::new`] gives (a
    /// function of the point set under the lexicographic simulation of simplicity); the
    /// *numbering* is that of the extension: the earlier triangles keep their ids, new ones
    /// follow. By the sparse replay of [`Self::extended`] on the renumbered arrays where it
    /// applies (every new point strictly inside the hull), else the resumed builder.
    /// Deterministic.
    pub fn extended_renumbered(
        &self,
        points: &[Point],
        map: &[u32],
    ) -> Result<Option<Self>, TriangulationError> {
        let n0 = self.points.len();
        if map.len() != n0 || !self.duplicates.is_empty() || self.tris.is_empty() {
            return Ok(None);
        }
        if points.len() > MAX_POINTS {
            return Err(TriangulationError::TooManyPoints {
                count: points.len(),
                max: MAX_POINTS,
            });
        }
        if points.len() >= NONE as usize {
            return Ok(None);
        }
        let bits = |p: &Point| p.map(f64::to_bits);
        // Which indices of `points` the earlier points take.
        let mut taken = vec![false; points.len()];
        for (v, &m) in map.iter().enumerate() {
            match taken.get_mut(m as usize) {
                Some(t) if !*t && bits(&points[m as usize]) == bits(&self.points[v]) => *t = true,
                _ => return Ok(None),
            }
        }
        // The earlier points are finite: only the others can fail this.
        if let Some(index) = points
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(TriangulationError::NonFinite { index });
        }
        let Some((work, all_safe)) = self.extension_work(points, magnitude_range(points)) else {
            return Ok(None);
        };
        let new_points = || {
            taken
                .iter()
                .enumerate()
                .filter(|(_, &t)| !t)
                .map(|(pos, _)| pos as u32)
        };
        // The sparse replay on the renumbered arrays: the triangles keep their slots, so only
        // the vertex ids change (issue 8: converting 6 triangles per point into the builder's
        // half-edge layout and compacting it back cost more than the few hundred insertions
        // of a refinement round).
        let mut vertex_tri = vec![NONE; points.len()];
        for (v, &t) in self.vertex_tri.iter().enumerate() {
            vertex_tri[map[v] as usize] = t;
        }
        let arrays = super::sparse::Arrays {
            tris: self
                .tris
                .iter()
                .map(|t| t.map(|x| map[x as usize]))
                .collect(),
            adj: self.adj.clone(),
            vertex_tri,
        };
        if let Ok((a, _)) = super::sparse::extend(
            &work,
            all_safe,
            arrays,
            self.vertex_count(),
            new_points(),
            &[],
        ) {
            return Ok(Some(Triangulation {
                points: points.to_vec(),
                tris: a.tris,
                adj: a.adj,
                duplicates: Vec::new(),
                vertex_tri: a.vertex_tri,
            }));
        }
        let inf = points.len() as u32;
        let (mut tv, adj) = self.builder_arrays(inf);
        for t in &mut tv {
            for x in t.iter_mut() {
                if *x != inf {
                    *x = map[*x as usize];
                }
            }
        }
        let mut builder = Builder::resume(&work, all_safe, tv, adj, Vec::new());
        for pos in new_points() {
            builder
                .insert(pos)
                .map_err(|e| TriangulationError::Internal { message: e.0 })?;
        }
        let parts = builder.into_parts();
        if !parts.dups.is_empty() {
            return Ok(None);
        }
        let spare = match work {
            Cow::Owned(v) => v,
            Cow::Borrowed(_) => Vec::new(),
        };
        Ok(Some(Self::finish(points, None, parts, spare)))
    }

    /// [`Self::extended`] by the sparse replay, moving this triangulation's arrays into the
    /// result instead of copying them (issue 8: at 1e5 particles the copies were some 220 MB
    /// of fresh pages). On `Ok(Some)` this triangulation is left empty, and the [`Changes`]
    /// give it back ([`Changes::undo`]) and tell which triangles changed. On `Ok(None)` (the
    /// replay gave up, or [`Self::extended`] would give `Ok(None)`) and on `Err` it is
    /// unchanged. The result equals [`Self::extended`]'s (`tests/geometry_sparse_extend.rs`).
    pub fn extended_taking(
        &mut self,
        points: &[Point],
    ) -> Result<Option<(Self, Changes)>, TriangulationError> {
        let n0 = self.points.len();
        let Some((work, all_safe)) = self.extension_points(points)? else {
            return Ok(None);
        };
        let vertices = self.vertex_count();
        let arrays = super::sparse::Arrays {
            tris: std::mem::take(&mut self.tris),
            adj: std::mem::take(&mut self.adj),
            vertex_tri: std::mem::take(&mut self.vertex_tri),
        };
        let insert = n0 as u32..points.len() as u32;
        match super::sparse::extend(&work, all_safe, arrays, vertices, insert, &self.duplicates) {
            Ok((a, log)) => {
                let mut pts = std::mem::take(&mut self.points);
                pts.extend_from_slice(&points[n0..]);
                let duplicates = std::mem::take(&mut self.duplicates);
                let before_duplicates = !duplicates.is_empty();
                // The first save of a slot holds its earlier value (every changed earlier
                // slot was saved before its first write).
                let mut first: HashMap<u32, ([u32; 3], [u32; 3])> = HashMap::new();
                for &(t, tri, adj) in &log.slots {
                    first.entry(t).or_insert((tri, adj));
                }
                let before = log
                    .changed
                    .iter()
                    .take_while(|&&t| (t as usize) < log.base)
                    .map(|t| {
                        let (tri, adj) = first[t];
                        (tri, adj.map(|m| (m != NONE).then_some(m)))
                    })
                    .collect();
                Ok(Some((
                    Triangulation {
                        points: pts,
                        tris: a.tris,
                        adj: a.adj,
                        duplicates,
                        vertex_tri: a.vertex_tri,
                    },
                    Changes {
                        log,
                        before,
                        before_duplicates,
                    },
                )))
            }
            Err(a) => {
                self.tris = a.tris;
                self.adj = a.adj;
                self.vertex_tri = a.vertex_tri;
                Ok(None)
            }
        }
    }

    /// This triangulation in the builder's layout (see `build`): the finite triangles, then one
    /// infinite triangle `(u, w, inf)` per hull edge `w -> u` of a finite triangle, in order of
    /// finite triangle and edge; `adj` as half-edge ids.
    fn builder_arrays(&self, inf: u32) -> (Vec<[u32; 3]>, Vec<[u32; 3]>) {
        let next = |k: usize| (k + 1) % 3;
        let prev = |k: usize| (k + 2) % 3;
        // Reserved once for the infinite triangles (at most one per kept point) and the two new
        // triangles per inserted point; pages beyond those used are never touched.
        let cap = self.tris.len() + self.points.len() + 2 * (inf as usize - self.points.len()) + 8;
        let mut tv = Vec::with_capacity(cap);
        tv.extend_from_slice(&self.tris);
        let mut adj: Vec<[u32; 3]> = Vec::with_capacity(cap);
        adj.resize(tv.len(), [NONE; 3]);
        // The infinite triangle whose first vertex is `u`, per vertex.
        let mut hull_from: Vec<u32> = vec![NONE; self.points.len()];
        for (t, nb) in self.adj.iter().enumerate() {
            let v = self.tris[t];
            for k in 0..3 {
                let (a, b) = (v[next(k)], v[prev(k)]);
                if nb[k] != NONE {
                    // Both half-edges of an interior edge are linked from its lower triangle,
                    // which reads the other triangle once instead of twice.
                    let m = nb[k] as usize;
                    if m < t {
                        continue;
                    }
                    let w = self.tris[m];
                    if let Some(j) = (0..3).find(|&j| w[next(j)] == b && w[prev(j)] == a) {
                        adj[t][k] = (3 * m + j) as u32;
                        adj[m][j] = (3 * t + k) as u32;
                    }
                } else {
                    let s = tv.len();
                    tv.push([b, a, inf]);
                    adj.push([NONE; 3]);
                    adj[s][2] = (3 * t + k) as u32;
                    adj[t][k] = (3 * s + 2) as u32;
                    hull_from[b as usize] = s as u32;
                }
            }
        }
        // Infinite triangle s = (u, w, inf): across its edge (w, inf) is the one starting at w.
        for s in self.tris.len()..tv.len() {
            let w = tv[s][1];
            let s2 = hull_from[w as usize] as usize;
            adj[s][0] = (3 * s2 + 1) as u32;
            adj[s2][1] = (3 * s) as u32;
        }
        (tv, adj)
    }

    /// Compact the builder into finite triangles with input-index vertices.
    /// `order[v]` is the input index of builder vertex `v`; `None` for the identity (a resumed
    /// builder, whose vertex ids are input indices).
    ///
    /// The finite triangles keep the builder's order. Every array of the result is one of the
    /// builder's or the caller's, reused in place (issue 8: at 1e5 particles fresh arrays were
    /// some 450 MB of fresh pages): the triangles and their neighbours are compacted inside the
    /// builder's slot arrays (slot `t` moves to `map[t] <= t`, read before any write reaches
    /// it), the slot map is the builder's per-slot scratch, the vertex tables its per-vertex
    /// scratch or the slot map again, the input indices are `order` itself and the points are
    /// copied into `spare` (the working copy of the points, no longer needed; may be empty).
    fn finish(points: &[Point], order: Option<Vec<u32>>, parts: Parts, spare: Vec<Point>) -> Self {
        if let (Some(ranges), true) = (parts.certified, parts.dups.is_empty()) {
            return Self::finish_stitched(points, order, parts, ranges, spare);
        }
        let Parts {
            inf,
            tv: mut tris,
            mut adj,
            mark: mut map,
            start_at: mut scratch,
            dups,
            certified: _,
        } = parts;
        // Input index of each vertex (empty: the identity); for a duplicate group, its smallest
        // input index.
        let mut input: Vec<u32> = order.unwrap_or_default();
        let mut duplicates = Vec::with_capacity(dups.len());
        if !dups.is_empty() {
            let input_of = |input: &[u32], v: u32| {
                if input.is_empty() {
                    v
                } else {
                    input[v as usize]
                }
            };
            let mut groups: HashMap<u32, Vec<u32>> = HashMap::new();
            for &(v, d) in &dups {
                groups.entry(v).or_default().push(input_of(&input, d));
            }
            // Read every input index before the first change (the changes are to group heads,
            // which no other group reads; kept apart all the same).
            let mut firsts = Vec::new();
            for (v, mut members) in groups {
                members.push(input_of(&input, v));
                members.sort_unstable();
                let first = members[0];
                if first != input_of(&input, v) {
                    firsts.push((v, first));
                }
                duplicates.extend(members[1..].iter().map(|&d| (first, d)));
            }
            if !firsts.is_empty() && input.is_empty() {
                input = (0..inf).collect();
            }
            for (v, first) in firsts {
                input[v as usize] = first;
            }
            duplicates.sort_unstable();
        }
        let mut count = 0u32;
        for (t, v) in tris.iter().enumerate() {
            map[t] = if v.contains(&inf) {
                NONE
            } else {
                count += 1;
                count - 1
            };
        }
        // A vertex's triangle is the last (highest) one having it. Recorded per builder vertex
        // (local in the builder's order) and moved to input indices once per vertex: vertices
        // map to distinct input indices (a duplicate's own builder position is no vertex).
        // The per-vertex scratch is the identity's table, or the builder-order one.
        scratch.truncate(points.len());
        scratch.fill(NONE);
        compact_slots(
            0,
            &mut tris,
            &mut adj,
            |s| map[s as usize],
            &input,
            |x, m| scratch[x as usize] = m,
        );
        // The slot map is no longer needed: it becomes the input-order table (as long, but
        // for many duplicates: there are about two slots per vertex).
        let mut vertex_tri = by_input(scratch, &input, map, points.len());
        for &(first, d) in &duplicates {
            vertex_tri[d as usize] = vertex_tri[first as usize];
        }
        Self::assembled(points, spare, tris, adj, count, vertex_tri, duplicates)
    }

    /// [`Self::finish`] of a stitched triangulation without duplicates (`ranges`, see
    /// [`Parts::certified`]), the same arrays (issue 8: the serial loop took 60-80 ms at 1e5
    /// particles while the other thread waited). Its certified slots are all finite and come
    /// first, so the compaction moves only the seam's slots (serial, after); the certified
    /// slots are mapped in place, the two halves' on two threads. Each slot records itself as
    /// its vertices' triangle: a half's certified triangles have only that half's points, so
    /// the two threads write different entries, each in ascending slot order, and the seam's
    /// slots, numbered after every certified one, overwrite them after: every vertex ends with
    /// the last (highest) triangle having it, as in the serial loop.
    fn finish_stitched(
        points: &[Point],
        order: Option<Vec<u32>>,
        parts: Parts,
        ranges: [u32; 2],
        spare: Vec<Point>,
    ) -> Self {
        use rayon::prelude::*;
        use std::sync::atomic::Ordering::Relaxed;
        let Parts {
            inf,
            tv: mut tris,
            mut adj,
            mark: mut map,
            start_at: mut scratch,
            ..
        } = parts;
        let [left, kept] = ranges.map(|x| x as usize);
        let input: Vec<u32> = order.unwrap_or_default();
        // The slot map, needed only on the seam's slots (the certified ones keep theirs).
        let mut count = kept as u32;
        for t in kept..tris.len() {
            map[t] = if tris[t].contains(&inf) {
                NONE
            } else {
                count += 1;
                count - 1
            };
        }
        let slots = &map[..];
        let new_of = |s: u32| {
            if (s as usize) < kept {
                s
            } else {
                slots[s as usize]
            }
        };
        scratch.truncate(points.len());
        scratch.par_chunks_mut(1 << 16).for_each(|c| c.fill(NONE));
        {
            let vt = atomic_view(&mut scratch);
            let record = |x: u32, t: u32| vt[x as usize].store(t, Relaxed);
            let (tl, tr) = tris[..kept].split_at_mut(left);
            let (al, ar) = adj[..kept].split_at_mut(left);
            rayon::join(
                || compact_slots(0, tl, al, new_of, &input, record),
                || compact_slots(left, tr, ar, new_of, &input, record),
            );
        }
        // The seam's slots, compacted as in `finish`.
        compact_slots(
            kept,
            &mut tris[kept..],
            &mut adj[kept..],
            new_of,
            &input,
            |x, m| scratch[x as usize] = m,
        );
        let vertex_tri = by_input(scratch, &input, map, points.len());
        Self::assembled(points, spare, tris, adj, count, vertex_tri, Vec::new())
    }

    /// The triangulation from its compacted arrays (the first `count` slots of `tris` and
    /// `adj`), its vertex table and duplicates, the points copied into `spare`.
    fn assembled(
        points: &[Point],
        spare: Vec<Point>,
        mut tris: Vec<[u32; 3]>,
        mut adj: Vec<[u32; 3]>,
        count: u32,
        mut vertex_tri: Vec<u32>,
        duplicates: Vec<(u32, u32)>,
    ) -> Self {
        use rayon::prelude::*;
        vertex_tri.shrink_to_fit();
        tris.truncate(count as usize);
        tris.shrink_to_fit();
        adj.truncate(count as usize);
        adj.shrink_to_fit();
        let mut pts = spare;
        pts.clear();
        pts.par_extend(points.par_iter().copied());
        Triangulation {
            points: pts,
            tris,
            adj,
            duplicates,
            vertex_tri,
        }
    }

    /// The input points, as given (indices in triangles refer to these).
    pub fn points(&self) -> &[Point] {
        &self.points
    }
    /// Number of finite triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }
    /// True when there is no triangle.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Triangle `t` as three input indices in counter-clockwise order.
    ///
    /// # Panics
    /// When `t >= self.len()`.
    pub fn triangle(&self, t: usize) -> [u32; 3] {
        self.tris[t]
    }
    /// All finite triangles, counter-clockwise, as input indices.
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.tris.iter().copied()
    }
    /// `neighbors(t)[k]` is the triangle across the edge opposite vertex `k` of triangle `t`,
    /// `None` on the convex hull.
    ///
    /// # Panics
    /// When `t >= self.len()`.
    pub fn neighbors(&self, t: usize) -> [Option<u32>; 3] {
        self.adj[t].map(|m| (m != NONE).then_some(m))
    }
    /// Exact duplicates as `(first, duplicate)` input index pairs, sorted.
    pub fn duplicates(&self) -> &[(u32, u32)] {
        &self.duplicates
    }
    /// Number of distinct points (all of them are vertices).
    pub fn vertex_count(&self) -> usize {
        self.points.len() - self.duplicates.len()
    }
    /// A triangle having input point `v` (or the point it duplicates) as a vertex;
    /// `None` when `v` is out of range.
    pub fn vertex_triangle(&self, v: usize) -> Option<usize> {
        self.vertex_tri
            .get(v)
            .and_then(|&t| (t != NONE).then_some(t as usize))
    }
    /// Triangles with at least one edge on the convex hull, in increasing order.
    pub fn hull_triangles(&self) -> Vec<usize> {
        (0..self.len())
            .filter(|&t| self.adj[t].contains(&NONE))
            .collect()
    }
    /// Convex hull vertices (input indices) in counter-clockwise order, starting at the smallest
    /// index; points lying on hull edges are included.
    pub fn hull(&self) -> Vec<u32> {
        let mut next: HashMap<u32, u32> = HashMap::new();
        for (t, v) in self.tris.iter().enumerate() {
            for k in 0..3 {
                if self.adj[t][k] == NONE {
                    next.insert(v[(k + 1) % 3], v[(k + 2) % 3]);
                }
            }
        }
        let Some(&start) = next.keys().min() else {
            return Vec::new();
        };
        let mut hull = vec![start];
        let mut v = start;
        while let Some(&w) = next.get(&v) {
            if w == start || hull.len() > next.len() {
                break;
            }
            hull.push(w);
            v = w;
        }
        hull
    }
    /// The vertex of triangle `m = neighbors(t)[k]` opposite the shared edge, with `m`.
    fn opposite(&self, t: usize, k: usize) -> Option<(usize, u32)> {
        let m = *self.adj.get(t)?.get(k)?;
        if m == NONE {
            return None;
        }
        let m = m as usize;
        let j = self.adj[m].iter().position(|&x| x as usize == t)?;
        Some((m, self.tris[m][j]))
    }
    /// True when the edge of triangle `t` opposite its vertex `k` is interior and the four points
    /// of the two triangles sharing it are exactly co-circular (exact in-circle zero). False on
    /// the hull and for out-of-range arguments.
    pub fn is_cocircular_edge(&self, t: usize, k: usize) -> bool {
        let Some((_, d)) = self.opposite(t, k) else {
            return false;
        };
        let [a, b, c] = self.tris[t].map(|v| self.points[v as usize]);
        incircle(a, b, c, self.points[d as usize]) == Ordering::Equal
    }
    /// Maximal sets of input points whose triangles are joined across edges with exact
    /// incircle zero; each sorted, the list sorted. Computed from the final triangulation.
    pub fn cocircular_groups(&self) -> Vec<Vec<u32>> {
        let n = self.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut x: u32) -> u32 {
            while parent[x as usize] != x {
                let up = parent[parent[x as usize] as usize];
                parent[x as usize] = up;
                x = up;
            }
            x
        }
        let mut joined = false;
        for t in 0..n {
            for k in 0..3 {
                let m = self.adj[t][k];
                if m == NONE || (m as usize) < t || !self.is_cocircular_edge(t, k) {
                    continue;
                }
                let (rt, rm) = (find(&mut parent, t as u32), find(&mut parent, m));
                if rt != rm {
                    parent[rt.max(rm) as usize] = rt.min(rm);
                }
                joined = true;
            }
        }
        if !joined {
            return Vec::new();
        }
        let mut members: HashMap<u32, Vec<u32>> = HashMap::new();
        let mut size: HashMap<u32, usize> = HashMap::new();
        for t in 0..n {
            let r = find(&mut parent, t as u32);
            *size.entry(r).or_default() += 1;
            members.entry(r).or_default().extend(self.tris[t]);
        }
        let mut groups: Vec<Vec<u32>> = members
            .into_iter()
            .filter(|(r, _)| size[r] > 1)
            .map(|(_, mut g)| {
                g.sort_unstable();
                g.dedup();
                g
            })
            .collect();
        groups.sort();
        groups
    }
}

/// Number of distinct points (error path only).
fn count_distinct(points: &[Point]) -> usize {
    let mut v: Vec<Point> = points.iter().map(|p| [p[0] + 0.0, p[1] + 0.0]).collect();
    v.sort_unstable_by(super::predicates::lex_cmp);
    v.dedup();
    v.len()
}

/// Compact the slots `base..base + tris.len()` of a finished build (`tris` and `adj` are
/// that range of its arrays) in order: slot `t` moves to `new_of(t)`, with `base <= new_of(t)
/// <= t` (`NONE`: an infinite triangle, dropped); each of its vertices `x` is recorded by
/// `record(x, new_of(t))` (builder ids; a later slot records over an earlier one) and becomes
/// its input id (`input`, empty for the identity), its neighbours the triangles `new_of` of
/// the slots across.
fn compact_slots(
    base: usize,
    tris: &mut [[u32; 3]],
    adj: &mut [[u32; 3]],
    new_of: impl Fn(u32) -> u32,
    input: &[u32],
    mut record: impl FnMut(u32, u32),
) {
    for k in 0..tris.len() {
        let m = new_of((base + k) as u32);
        if m == NONE {
            continue;
        }
        let mut v = tris[k];
        for x in &mut v {
            record(*x, m);
            if !input.is_empty() {
                *x = input[*x as usize];
            }
        }
        let half = adj[k];
        tris[m as usize - base] = v;
        adj[m as usize - base] = half.map(|h| new_of(h / 3));
    }
}

/// `table` as atomics, for writes from several threads that never meet.
fn atomic_view(table: &mut [u32]) -> &[std::sync::atomic::AtomicU32] {
    // SAFETY: `AtomicU32` has the size, alignment and bit validity of `u32`, and the
    // exclusive borrow of `table` is held for the view's whole life.
    unsafe { &*(table as *mut [u32] as *const [std::sync::atomic::AtomicU32]) }
}

/// The vertex table by input index from `by_vertex` (per builder vertex), into `table`'s
/// memory (`n` entries; `by_vertex` itself for the identity, `input` empty). Vertices map to
/// distinct input indices, so the writes on the pool never meet.
fn by_input(by_vertex: Vec<u32>, input: &[u32], mut table: Vec<u32>, n: usize) -> Vec<u32> {
    use rayon::prelude::*;
    use std::sync::atomic::Ordering::Relaxed;
    if input.is_empty() {
        return by_vertex;
    }
    table.clear();
    table.resize(n, NONE);
    let vt = atomic_view(&mut table);
    by_vertex
        .par_iter()
        .zip(input.par_iter())
        .with_min_len(1 << 16)
        .for_each(|(&m, &i)| {
            if m != NONE {
                vt[i as usize].store(m, Relaxed);
            }
        });
    table
}

#[cfg(test)]
mod tests {
    use super::{magnitude_range, Point, Triangulation};

    /// The stitched triangulation's parallel `finish` gives the serial one's arrays bit for
    /// bit (triangles, neighbours, vertex triangles, points), with the identity order and
    /// with a shuffled one, on sampled circles (the pipeline's points, co-circular groups on
    /// the split line), uniform points, and a thin band (every disk crosses the line: a
    /// large seam).
    #[test]
    fn stitched_finish_equals_the_serial_one() {
        let mut r = crate::layouts::SplitMix64(0x5eed_f1a1_5eed_f1a1);
        let circles = super::super::split::tests::sampled_circles(&mut r, 700, 25, 36);
        let uniform: Vec<Point> = (0..30_000).map(|_| [r.next_f64(), r.next_f64()]).collect();
        let band: Vec<Point> = (0..20_000)
            .map(|_| [1e-6 * r.next_f64(), r.next_f64()])
            .collect();
        for (name, pts) in [("circles", circles), ("uniform", uniform), ("band", band)] {
            let n = pts.len();
            // A permutation (input index of each builder vertex), as the insertion order is.
            let mut order: Vec<u32> = (0..n as u32).collect();
            for i in (1..n).rev() {
                order.swap(i, (r.next_u64() % (i as u64 + 1)) as usize);
            }
            let inputs: Vec<Point> = {
                let mut v = vec![[0.0; 2]; n];
                for (b, &i) in order.iter().enumerate() {
                    v[i as usize] = pts[b];
                }
                v
            };
            for ord in [None, Some(order)] {
                let input = if ord.is_some() { &inputs } else { &pts };
                let finish = |serial: bool| {
                    let mut parts = super::super::split::build_split(&pts)
                        .unwrap()
                        .expect("the split applies");
                    assert!(parts.dups.is_empty() && parts.certified.is_some());
                    if serial {
                        parts.certified = None;
                    }
                    Triangulation::finish(input, ord.clone(), parts, pts.clone())
                };
                let (a, b) = (finish(false), finish(true));
                let what = format!("{name}, order {}", ord.is_some());
                assert_eq!(a.tris, b.tris, "{what}");
                assert_eq!(a.adj, b.adj, "{what}");
                assert_eq!(a.vertex_tri, b.vertex_tri, "{what}");
                assert_eq!(a.duplicates, b.duplicates, "{what}");
                let bits = |t: &Triangulation| -> Vec<[u64; 2]> {
                    t.points.iter().map(|p| p.map(f64::to_bits)).collect()
                };
                assert_eq!(bits(&a), bits(&b), "{what}");
                assert!(a.tris.len() < n * 2 && !a.tris.is_empty(), "{what}");
                super::super::verify::verify_exact(&a).unwrap_or_else(|e| panic!("{what}: {e}"));
            }
        }
    }

    /// The float loop [`magnitude_range`] replaced.
    fn reference(points: &[Point]) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = 0.0f64;
        for p in points {
            for &c in p {
                let a = c.abs();
                if a != 0.0 {
                    lo = lo.min(a);
                    hi = hi.max(a);
                }
            }
        }
        (lo, hi)
    }

    /// Bit for bit the float loop's answer: zeros of both signs, subnormals, infinities and
    /// NaNs among ordinary values, on sets below and above the parallel size.
    #[test]
    fn magnitude_range_is_the_float_loop() {
        let mut r = crate::layouts::SplitMix64(17);
        let specials = [
            0.0,
            -0.0,
            5e-324,
            -5e-324,
            2.2e-308,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            -f64::NAN,
            1.0,
        ];
        for n in [0usize, 1, 2, 7, 100, 300_000] {
            for mix in 0..6 {
                let pts: Vec<Point> = (0..n)
                    .map(|_| {
                        [0, 1].map(|_| {
                            let u = r.next_f64();
                            if mix > 0 && u < 0.02 * mix as f64 {
                                specials[(r.next_f64() * specials.len() as f64) as usize]
                            } else if mix == 5 {
                                0.0
                            } else {
                                (r.next_f64() - 0.5) * (r.next_f64() * 80.0 - 40.0).exp2()
                            }
                        })
                    })
                    .collect();
                let (lo, hi) = magnitude_range(&pts);
                let (wl, wh) = reference(&pts);
                assert_eq!(
                    (lo.to_bits(), hi.to_bits()),
                    (wl.to_bits(), wh.to_bits()),
                    "n = {n}, mix = {mix}"
                );
            }
        }
    }
}
