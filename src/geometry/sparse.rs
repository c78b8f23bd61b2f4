//! [`Triangulation::extended`](super::triangulation::Triangulation::extended) without
//! rebuilding the whole triangulation (issue 8: at 1e5 particles refinement inserts a few
//! hundred samples into 6 M triangles, and the builder's half-edge arrays cost a second or so
//! to rebuild and compact).
//!
//! [`extend`] replays what the resumed builder ([`super::build::Builder::resume`] then
//! [`super::build::Builder::insert`], then the compaction of `Triangulation::finish`) does, on
//! copies of the finished arrays: the same walks (the same random edge order, the same step
//! caps), the same cavity search in the same order, the same slots reused and appended. In the
//! builder's layout the kept triangles come first, then one infinite triangle per hull edge,
//! then the appended ones; the compaction drops the infinite ones, so a builder slot
//! `F + H + j` becomes `F + j`, which is where this appends. It gives up (`None`, the caller
//! runs the builder) wherever the replay would need the infinite triangles themselves: a walk
//! crossing the hull, a point outside the hull or on it, an exact duplicate, a failed location
//! or a broken cavity. So the result is the builder's whenever it is given.

use super::build::{incircle_with, next, orient_fast, orient_with, prev, walk_caps, WalkRng};
use super::triangulation::NONE;
use super::Point;
use std::cmp::Ordering;
use std::collections::HashMap;

/// The finished arrays of a triangulation, as `Triangulation` holds them.
pub(super) struct Arrays {
    pub(super) tris: Vec<[u32; 3]>,
    pub(super) adj: Vec<[u32; 3]>,
    pub(super) vertex_tri: Vec<u32>,
}

/// The replay gave up: the builder must run.
struct GiveUp;

/// What [`extend`] wrote over the arrays it was given: enough to give back the earlier
/// arrays ([`Log::undo`]) and the earlier triangle and neighbours of every changed slot.
pub(super) struct Log {
    /// Triangle count of the earlier arrays.
    pub(super) base: usize,
    /// Point count of the earlier arrays (`vertex_tri` length).
    pub(super) points: usize,
    /// `(slot, triangle, neighbours)` before each write to an earlier slot, in write order.
    pub(super) slots: Vec<(u32, [u32; 3], [u32; 3])>,
    /// `(vertex, triangle)` before each write to an earlier vertex's triangle.
    pub(super) vertices: Vec<(u32, u32)>,
    /// The slots whose triangle was written (cavity slots and appended ones), increasing.
    pub(super) changed: Vec<u32>,
}

impl Log {
    /// The arrays given to [`extend`], from the ones it returned with this log.
    pub(super) fn undo(&self, mut a: Arrays) -> Arrays {
        for &(s, t, n) in self.slots.iter().rev() {
            a.tris[s as usize] = t;
            a.adj[s as usize] = n;
        }
        a.tris.truncate(self.base);
        a.adj.truncate(self.base);
        for &(v, t) in self.vertices.iter().rev() {
            a.vertex_tri[v as usize] = t;
        }
        a.vertex_tri.truncate(self.points);
        a
    }
}

struct Sparse<'a> {
    log: Log,
    pts: &'a [Point],
    all_safe: bool,
    a: Arrays,
    /// Number of hull edges: the builder holds that many infinite triangles besides these.
    hull: usize,
    last: u32,
    rng: WalkRng,
    seen: Vec<(u32, bool)>,
    stack: Vec<u32>,
    cavity: Vec<u32>,
    /// `(u, w, outside triangle or NONE, its edge slot)` per cavity boundary edge `u -> w`.
    boundary: Vec<(u32, u32, u32, u8)>,
    /// A current triangle of each vertex whose star changed.
    touched: HashMap<u32, u32>,
}

/// The triangulation arrays after inserting the points `insert` (indices into `pts`, in that
/// order) into the finished arrays `a` of the triangulation of the other points, with
/// `vertices` distinct points: for `insert = n0..pts.len()` (the earlier points a prefix) as
/// the resumed builder gives them after compaction; `None` where the builder must run
/// (module docs). `pts` are the points as the predicates see them (scaled), `all_safe` as for
/// the builder. Works in place: on success the arrays come back with the [`Log`] of what was
/// written over them; where it gives up, `Err` gives back `a` as it was.
pub(super) fn extend(
    pts: &[Point],
    all_safe: bool,
    a: Arrays,
    vertices: usize,
    insert: impl IntoIterator<Item = u32>,
    duplicates: &[(u32, u32)],
) -> Result<(Arrays, Log), Arrays> {
    // Euler: a triangulation of V points with H hull vertices has 2V - 2 - H triangles.
    let Some(hull) = (2 * vertices).checked_sub(2 + a.tris.len()) else {
        return Err(a);
    };
    if a.tris.is_empty() || a.adj.len() != a.tris.len() {
        return Err(a);
    }
    let log = Log {
        base: a.tris.len(),
        points: a.vertex_tri.len(),
        slots: Vec::new(),
        vertices: Vec::new(),
        changed: Vec::new(),
    };
    let mut s = Sparse {
        log,
        pts,
        all_safe,
        a,
        hull,
        last: 0,
        rng: WalkRng::new(),
        seen: Vec::new(),
        stack: Vec::new(),
        cavity: Vec::new(),
        boundary: Vec::new(),
        touched: HashMap::new(),
    };
    for pi in insert {
        if s.insert(pi).is_err() {
            return Err(s.log.undo(s.a));
        }
    }
    s.finish(duplicates)
}

impl Sparse<'_> {
    #[inline(always)]
    fn p(&self, v: u32) -> &Point {
        &self.pts[v as usize]
    }

    #[inline(always)]
    fn orient(&self, a: &Point, b: &Point, c: &Point) -> Ordering {
        orient_with(self.all_safe, a, b, c)
    }

    /// Log slot `s` before a write, when it is an earlier one.
    #[inline(always)]
    fn save(&mut self, s: u32) {
        if (s as usize) < self.log.base {
            let i = s as usize;
            self.log.slots.push((s, self.a.tris[i], self.a.adj[i]));
        }
    }

    /// The builder's triangle count (its infinite triangles included).
    fn builder_len(&self) -> usize {
        self.a.tris.len() + self.hull
    }

    /// The builder's visibility walk from finite `start`; crossing the hull gives up.
    fn walk(&mut self, start: u32, q: &Point, exact: bool, cap: usize) -> Result<u32, GiveUp> {
        let mut t = start;
        let mut came_from = u32::MAX;
        'step: for _ in 0..cap {
            let v = self.a.tris[t as usize];
            let r = self.rng.next3();
            for i in 0..3 {
                let k = (r + i) % 3;
                let m = self.a.adj[t as usize][k];
                // An infinite neighbour is never the finite triangle the walk came from.
                if m != NONE && m == came_from {
                    continue;
                }
                let (a, b) = (self.p(v[next(k)]), self.p(v[prev(k)]));
                let behind = if exact {
                    self.orient(a, b, q) == Ordering::Less
                } else {
                    orient_fast(a, b, q) < 0.0
                };
                if behind {
                    if m == NONE {
                        return Err(GiveUp);
                    }
                    came_from = t;
                    t = m;
                    continue 'step;
                }
            }
            return Ok(t);
        }
        Err(GiveUp)
    }

    fn contains_exact(&self, t: u32, q: &Point) -> bool {
        let v = self.a.tris[t as usize];
        (0..3).all(|k| self.orient(self.p(v[next(k)]), self.p(v[prev(k)]), q) != Ordering::Less)
    }

    /// The builder's `locate`: the fast walk, then the exact one, both from the last triangle.
    /// (The builder's fast walk hitting its cap falls through to the exact walk; here that
    /// gives up, as does every case the builder would finish by a scan.)
    fn locate(&mut self, q: &Point) -> Result<u32, GiveUp> {
        let (fast_cap, exact_cap) = walk_caps(self.builder_len());
        let t = self.walk(self.last, q, false, fast_cap)?;
        let t = if self.contains_exact(t, q) {
            t
        } else {
            let t = self.walk(self.last, q, true, exact_cap)?;
            if !self.contains_exact(t, q) {
                return Err(GiveUp);
            }
            t
        };
        if self.a.tris[t as usize].iter().any(|&v| self.p(v) == q) {
            return Err(GiveUp);
        }
        Ok(t)
    }

    /// The edge slot of triangle `m` holding the directed edge `b -> a`.
    fn mirror(&self, m: u32, a: u32, b: u32) -> Result<u8, GiveUp> {
        let w = self.a.tris[m as usize];
        (0..3)
            .find(|&j| w[next(j)] == b && w[prev(j)] == a)
            .map(|j| j as u8)
            .ok_or(GiveUp)
    }

    /// The builder's `insert` of point `pi`, in this numbering.
    fn insert(&mut self, pi: u32) -> Result<(), GiveUp> {
        let q = *self.p(pi);
        let seed = self.locate(&q)?;
        self.seen.clear();
        self.cavity.clear();
        self.boundary.clear();
        self.seen.push((seed, true));
        self.cavity.push(seed);
        self.stack.push(seed);
        while let Some(t) = self.stack.pop() {
            let v = self.a.tris[t as usize];
            for k in 0..3 {
                let (a, b) = (v[next(k)], v[prev(k)]);
                let m = self.a.adj[t as usize][k];
                if m == NONE {
                    // The infinite triangle (b, a, inf): in conflict when q is outside the
                    // hull edge or on it, where the builder would change the hull.
                    if self.orient(self.p(b), self.p(a), &q) != Ordering::Less {
                        self.stack.clear();
                        return Err(GiveUp);
                    }
                    self.boundary.push((a, b, NONE, 0));
                    continue;
                }
                let conflict = match self.seen.iter().find(|e| e.0 == m) {
                    Some(&(_, true)) => continue,
                    Some(&(_, false)) => false,
                    None => {
                        let w = self.a.tris[m as usize];
                        let (pa, pb, pc) = (*self.p(w[0]), *self.p(w[1]), *self.p(w[2]));
                        incircle_with(self.all_safe, pa, pb, pc, q) == Ordering::Greater
                    }
                };
                if conflict {
                    self.seen.push((m, true));
                    self.cavity.push(m);
                    self.stack.push(m);
                } else {
                    self.seen.push((m, false));
                    let j = self.mirror(m, a, b)?;
                    self.boundary.push((a, b, m, j));
                }
            }
        }
        if self.boundary.len() != self.cavity.len() + 2 {
            return Err(GiveUp);
        }
        // The builder's slots: cavity triangles in order, then appended ones.
        let nc = self.cavity.len();
        let mut slots = Vec::with_capacity(self.boundary.len());
        for i in 0..self.boundary.len() {
            let (u, w, m, j) = self.boundary[i];
            let s = if i < nc {
                self.cavity[i]
            } else {
                self.a.tris.push([0; 3]);
                self.a.adj.push([NONE; 3]);
                (self.a.tris.len() - 1) as u32
            };
            self.save(s);
            self.log.changed.push(s);
            self.a.tris[s as usize] = [u, w, pi];
            self.a.adj[s as usize][2] = m;
            if m != NONE {
                self.save(m);
                self.a.adj[m as usize][j as usize] = s;
            }
            slots.push(s);
            self.last = s;
        }
        // Across (w, pi): the new triangle starting at w (the builder's `start_at[w]`, last
        // written wins).
        for i in 0..self.boundary.len() {
            let s = slots[i];
            let w = self.boundary[i].1;
            let n = (0..self.boundary.len())
                .rev()
                .find(|&i2| self.boundary[i2].0 == w)
                .map(|i2| slots[i2])
                .ok_or(GiveUp)?;
            self.save(s);
            self.a.adj[s as usize][0] = n;
            self.save(n);
            self.a.adj[n as usize][1] = s;
        }
        for (i, &(u, _, _, _)) in self.boundary.iter().enumerate() {
            self.touched.insert(u, slots[i]);
        }
        self.touched.insert(pi, slots[0]);
        Ok(())
    }

    /// The highest triangle having each vertex whose star changed (as the compaction records
    /// it), by a walk around the vertex; then the duplicates take their first's.
    fn finish(mut self, duplicates: &[(u32, u32)]) -> Result<(Arrays, Log), Arrays> {
        let cap = self.a.tris.len();
        // Every vertex's triangle first, written only once all are found (so giving up
        // leaves `vertex_tri` as it was).
        let mut found = Vec::with_capacity(self.touched.len());
        for (&v, &t0) in &self.touched {
            let mut best = t0;
            for dir in [next, prev] {
                let mut t = t0;
                for step in 0.. {
                    if step > cap {
                        return Err(self.log.undo(self.a));
                    }
                    let Some(i) = self.a.tris[t as usize].iter().position(|&x| x == v) else {
                        return Err(self.log.undo(self.a));
                    };
                    t = self.a.adj[t as usize][dir(i)];
                    if t == NONE || t == t0 {
                        break;
                    }
                    best = best.max(t);
                }
                if t == t0 {
                    break;
                }
            }
            found.push((v, best));
        }
        self.a.vertex_tri.resize(self.pts.len(), NONE);
        let points = self.log.points;
        let set = |a: &mut Arrays, log: &mut Log, v: u32, t: u32| {
            if (v as usize) < points {
                log.vertices.push((v, a.vertex_tri[v as usize]));
            }
            a.vertex_tri[v as usize] = t;
        };
        for (v, t) in found {
            set(&mut self.a, &mut self.log, v, t);
        }
        for &(first, d) in duplicates {
            let t = self.a.vertex_tri[first as usize];
            set(&mut self.a, &mut self.log, d, t);
        }
        self.log.changed.sort_unstable();
        self.log.changed.dedup();
        Ok((self.a, self.log))
    }
}
