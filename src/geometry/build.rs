//! Bowyer–Watson construction with a vertex at infinity.
//!
//! Internal representation (flat arrays, `u32` ids):
//! - vertex ids are input indices; the infinite vertex is `n = pts.len()`;
//! - `tv[t]` are the vertices of triangle `t`, counter-clockwise (for an infinite triangle
//!   `(u, v, ∞)` the outside of the hull edge `u → v` is on its left);
//! - `adj[3t + k]` is the half-edge `3m + j` across the edge opposite vertex `k` of `t`, i.e.
//!   triangle `m` sees `t` across its edge opposite vertex `j`.
//!
//! Invariant after each insertion: the finite triangles form the Delaunay triangulation of the
//! inserted points under the SoS-perturbed lifting (see [`super::predicates`]) and the infinite
//! triangles close the hull, every hull edge carrying exactly one infinite triangle.

use super::predicates::{incircle_sos, incircle_sos_safe, lex_cmp, orient2d, orient2d_safe, safe};
use super::Point;
use std::cmp::Ordering;

/// Marks a triangle tested and found not in conflict (ORed with the insertion stamp).
const OUTSIDE: u32 = 1 << 31;

/// Where a point landed.
enum Located {
    /// A triangle in conflict with the point.
    Triangle(u32),
    /// The point equals this existing vertex exactly.
    Duplicate(u32),
}

/// What went wrong inside the construction (an internal invariant broke; should not happen).
#[derive(Debug)]
pub(crate) struct Broken(pub(crate) String);

pub(crate) struct Builder<'a> {
    pts: &'a [Point],
    /// Every coordinate of `pts` is in the predicates' safe range: the unchecked predicates
    /// apply (same signs, no per-call range test).
    all_safe: bool,
    inf: u32,
    pub(crate) tv: Vec<[u32; 3]>,
    /// Per triangle slot `t`, the half-edge across its edge `k` (opposite vertex `k`): `3 m + j`
    /// for edge `j` of triangle `m`. Triples rather than a flat array so that
    /// [`Builder::into_parts`] can hand it on as the finished triangulation's neighbour array
    /// (compacted in place); the walk and the insertion read it flat (`as_flattened`).
    pub(crate) adj: Vec<[u32; 3]>,
    mark: Vec<u32>,
    stamp: u32,
    start_at: Vec<u32>,
    stack: Vec<u32>,
    cavity: Vec<u32>,
    boundary: Vec<(u32, u32, u32)>,
    last: u32,
    rng: WalkRng,
    /// `(existing vertex, duplicate input index)` pairs found during insertion.
    pub(crate) dups: Vec<(u32, u32)>,
}

/// The next edge slot of a triangle (`k + 1 mod 3`).
#[inline(always)]
pub(super) fn next(k: usize) -> usize {
    if k == 2 {
        0
    } else {
        k + 1
    }
}

/// The previous edge slot of a triangle (`k + 2 mod 3`).
#[inline(always)]
pub(super) fn prev(k: usize) -> usize {
    if k == 0 {
        2
    } else {
        k - 1
    }
}

/// The walk's random choice of the first edge to test: xorshift32 from a fixed seed, one draw
/// per walk step. The sparse replay (`sparse.rs`) draws from the same generator so that it
/// takes the builder's steps.
#[derive(Clone, Copy)]
pub(super) struct WalkRng(u32);

impl WalkRng {
    pub(super) fn new() -> WalkRng {
        WalkRng(0x9e37_79b9)
    }

    /// The next edge slot to test first, in `0..3`.
    #[inline(always)]
    pub(super) fn next3(&mut self) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        (self.0 % 3) as usize
    }
}

/// Step caps of point location in a triangulation of `n_tri` triangles (infinite ones
/// included): the floating-point walk, then the exact walk.
#[inline(always)]
pub(super) fn walk_caps(n_tri: usize) -> (usize, usize) {
    (64 + 4 * (n_tri as f64).sqrt() as usize, 4 * n_tri + 16)
}

/// Exact orientation, unchecked when every point is known to be in the predicates' safe
/// range (`all_safe`).
#[inline(always)]
pub(super) fn orient_with(all_safe: bool, a: &Point, b: &Point, c: &Point) -> Ordering {
    if all_safe {
        orient2d_safe(*a, *b, *c)
    } else {
        orient2d(*a, *b, *c)
    }
}

/// Exact in-circle test under SoS, unchecked when `all_safe` (as [`orient_with`]).
#[inline(always)]
pub(super) fn incircle_with(all_safe: bool, a: Point, b: Point, c: Point, d: Point) -> Ordering {
    if all_safe {
        incircle_sos_safe(&a, &b, &c, &d)
    } else {
        incircle_sos(a, b, c, d)
    }
}

/// True when triangle `v` (vertex ids into `pts`, `inf` the infinite one) is in conflict with
/// point `q`: finite triangle, `q` inside its circumcircle under SoS; infinite triangle, `q`
/// strictly outside its hull edge, or on its open segment. Takes the builder's parts, so that
/// the cavity search can hold them borrowed apart.
#[inline(always)]
fn conflict(pts: &[Point], all_safe: bool, inf: u32, v: [u32; 3], q: &Point) -> bool {
    let (u, w) = if v[0] == inf {
        (v[1], v[2])
    } else if v[1] == inf {
        (v[2], v[0])
    } else if v[2] == inf {
        (v[0], v[1])
    } else {
        let (a, b, c) = (
            &pts[v[0] as usize],
            &pts[v[1] as usize],
            &pts[v[2] as usize],
        );
        return if all_safe {
            incircle_sos_safe(a, b, c, q) == Ordering::Greater
        } else {
            incircle_sos(*a, *b, *c, *q) == Ordering::Greater
        };
    };
    let (pu, pw) = (&pts[u as usize], &pts[w as usize]);
    match orient_with(all_safe, pu, pw, q) {
        Ordering::Greater => true,
        Ordering::Less => false,
        Ordering::Equal => {
            // Collinear with the hull edge: inside the open segment iff lexicographically
            // between its ends.
            let a = lex_cmp(pu, q);
            let b = lex_cmp(q, pw);
            a == b && a != Ordering::Equal
        }
    }
}

/// Plain floating-point orientation, used only to guide the walk.
#[inline(always)]
pub(super) fn orient_fast(a: &Point, b: &Point, c: &Point) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The first triangle of a construction over `pts` in insertion order: point 0, the first
/// point distinct from it (`b`) and the first point after that not collinear with both
/// (`c`). `Err(k)` when there is none: `k` is 0 without points, 1 when every point equals
/// point 0, 2 when the distinct points are all collinear.
pub(crate) fn first_triangle(pts: &[Point]) -> Result<(u32, u32), usize> {
    let Some(&pa) = pts.first() else {
        return Err(0);
    };
    let Some(b) = pts.iter().position(|&p| p != pa) else {
        return Err(1);
    };
    let pb = pts[b];
    let c = pts[b + 1..]
        .iter()
        .position(|&p| orient2d(pa, pb, p) != Ordering::Equal)
        .ok_or(2usize)?;
    Ok((b as u32, (c + b + 1) as u32))
}

impl<'a> Builder<'a> {
    /// Start from the triangle `a, b, c` (non-collinear) and its three infinite neighbours.
    /// `all_safe`: every coordinate of `pts` is in the predicates' safe range (the caller knows
    /// it from the coordinate range; checked in debug builds).
    pub(crate) fn new(pts: &'a [Point], all_safe: bool, a: u32, b: u32, c: u32) -> Self {
        debug_assert_eq!(all_safe, pts.iter().all(safe));
        let n = pts.len();
        let inf = n as u32;
        let (b, c) =
            if orient2d(pts[a as usize], pts[b as usize], pts[c as usize]) == Ordering::Greater {
                (b, c)
            } else {
                (c, b)
            };
        // Reserved once: the triangles, infinite ones included, number 2 (vertices + 1) - 4.
        let cap = 2 * n + 8;
        let mut s = Builder {
            pts,
            all_safe,
            inf,
            tv: Vec::with_capacity(cap),
            adj: Vec::with_capacity(cap),
            mark: Vec::with_capacity(cap),
            stamp: 0,
            start_at: vec![0; n + 1],
            stack: Vec::new(),
            cavity: Vec::new(),
            boundary: Vec::new(),
            last: 0,
            rng: WalkRng::new(),
            dups: Vec::new(),
        };
        s.tv.extend_from_slice(&[[a, b, c], [c, b, inf], [a, c, inf], [b, a, inf]]);
        s.adj.extend_from_slice(&[[u32::MAX; 3]; 4]);
        s.mark.extend_from_slice(&[0; 4]);
        // Link the four triangles by matching reversed edges.
        for t in 0..4 {
            for k in 0..3 {
                let (u, v) = (s.tv[t][next(k)], s.tv[t][prev(k)]);
                for m in 0..4 {
                    for j in 0..3 {
                        if s.tv[m][next(j)] == v && s.tv[m][prev(j)] == u {
                            s.adj[t][k] = (3 * m + j) as u32;
                        }
                    }
                }
            }
        }
        s
    }

    /// Resume from a finished triangulation: `tv` / `adj` in this module's layout (infinite
    /// triangles included, vertex ids = indices of `pts`), `dups` its duplicate pairs. Further
    /// [`Builder::insert`] calls then add points as for a builder that made it.
    pub(crate) fn resume(
        pts: &'a [Point],
        all_safe: bool,
        tv: Vec<[u32; 3]>,
        adj: Vec<[u32; 3]>,
        dups: Vec<(u32, u32)>,
    ) -> Self {
        debug_assert_eq!(all_safe, pts.iter().all(safe));
        let n = pts.len();
        let inf = n as u32;
        let last = tv.iter().position(|v| !v.contains(&inf)).unwrap_or(0) as u32;
        Builder {
            pts,
            all_safe,
            inf,
            mark: vec![0; tv.len()],
            tv,
            adj,
            stamp: 0,
            start_at: vec![0; n + 1],
            stack: Vec::new(),
            cavity: Vec::new(),
            boundary: Vec::new(),
            last,
            rng: WalkRng::new(),
            dups,
        }
    }

    #[inline(always)]
    fn p(&self, v: u32) -> &Point {
        &self.pts[v as usize]
    }

    /// Exact orientation of three points of `pts`.
    #[inline(always)]
    fn orient(&self, a: &Point, b: &Point, c: &Point) -> Ordering {
        orient_with(self.all_safe, a, b, c)
    }

    #[inline(always)]
    fn is_infinite(&self, t: u32) -> bool {
        let v = self.tv[t as usize];
        v[0] == self.inf || v[1] == self.inf || v[2] == self.inf
    }

    /// The finite triangle across the hull edge of infinite triangle `t`.
    #[inline]
    fn finite_neighbor(&self, t: u32) -> u32 {
        let v = self.tv[t as usize];
        let k = if v[0] == self.inf {
            0
        } else if v[1] == self.inf {
            1
        } else {
            2
        };
        self.adj[t as usize][k] / 3
    }

    /// Exact check that the walk ended right: `q` in the closed finite triangle `t`, or strictly
    /// outside the hull edge of infinite triangle `t`.
    fn contains_exact(&self, t: u32, q: &Point) -> bool {
        let v = self.tv[t as usize];
        let inf = self.inf;
        if v.contains(&inf) {
            let (u, w) = if v[0] == inf {
                (v[1], v[2])
            } else if v[1] == inf {
                (v[2], v[0])
            } else {
                (v[0], v[1])
            };
            return self.orient(self.p(u), self.p(w), q) == Ordering::Greater;
        }
        (0..3).all(|k| self.orient(self.p(v[next(k)]), self.p(v[prev(k)]), q) != Ordering::Less)
    }

    /// Visibility walk towards `q`. `exact` selects exact or plain floating-point orientation.
    /// Returns the final triangle, or `None` when the step cap was hit.
    fn walk(&mut self, start: u32, q: &Point, exact: bool, cap: usize) -> Option<u32> {
        let mut t = start;
        if self.is_infinite(t) {
            t = self.finite_neighbor(t);
        }
        // Borrowed apart from the generator, which every step advances.
        let (pts, tv, adj, all_safe, inf) = (
            self.pts,
            &self.tv[..],
            self.adj.as_flattened(),
            self.all_safe,
            self.inf,
        );
        let mut v = tv[t as usize];
        let mut came_from = u32::MAX;
        'step: for _ in 0..cap {
            // Edges tested in the order r, r + 1, r + 2 (mod 3).
            let mut k = self.rng.next3();
            for _ in 0..3 {
                let h = adj[3 * t as usize + k];
                let m = h / 3;
                if m != came_from {
                    let (a, b) = (&pts[v[next(k)] as usize], &pts[v[prev(k)] as usize]);
                    let behind = if exact {
                        orient_with(all_safe, a, b, q) == Ordering::Less
                    } else {
                        orient_fast(a, b, q) < 0.0
                    };
                    if behind {
                        came_from = t;
                        t = m;
                        v = tv[t as usize];
                        if v[0] == inf || v[1] == inf || v[2] == inf {
                            return Some(t);
                        }
                        continue 'step;
                    }
                }
                k = next(k);
            }
            return Some(t);
        }
        None
    }

    fn locate(&mut self, q: &Point) -> Result<Located, Broken> {
        let n_tri = self.tv.len();
        let (fast_cap, exact_cap) = walk_caps(n_tri);
        let mut found = self
            .walk(self.last, q, false, fast_cap)
            .filter(|&t| self.contains_exact(t, q));
        if found.is_none() {
            let from = self.last;
            found = self
                .walk(from, q, true, exact_cap)
                .filter(|&t| self.contains_exact(t, q));
        }
        if found.is_none() {
            found = (0..n_tri as u32).find(|&t| self.contains_exact(t, q));
        }
        let t = found.ok_or_else(|| Broken("point location failed".into()))?;
        for &v in &self.tv[t as usize] {
            if v != self.inf && self.p(v) == q {
                return Ok(Located::Duplicate(v));
            }
        }
        Ok(Located::Triangle(t))
    }

    /// Insert every point of `pts` after point 0 but the first triangle's `b` and `c`
    /// ([`first_triangle`]), in order.
    pub(crate) fn insert_rest(&mut self, b: u32, c: u32) -> Result<(), Broken> {
        for pos in 1..self.pts.len() as u32 {
            if pos != b && pos != c {
                self.insert(pos)?;
            }
        }
        Ok(())
    }

    /// Insert input point `pi` (or record it as a duplicate).
    pub(crate) fn insert(&mut self, pi: u32) -> Result<(), Broken> {
        let q = *self.p(pi);
        let seed = match self.locate(&q)? {
            Located::Duplicate(v) => {
                self.dups.push((v, pi));
                return Ok(());
            }
            Located::Triangle(t) => t,
        };
        self.stamp += 1;
        if self.stamp >= OUTSIDE {
            self.mark.iter_mut().for_each(|m| *m = 0);
            self.stamp = 1;
        }
        let stamp = self.stamp;
        self.mark[seed as usize] = stamp;
        self.cavity.clear();
        self.boundary.clear();
        self.cavity.push(seed);
        self.stack.push(seed);
        // Borrowed apart: the search reads the triangles and writes only the marks and lists.
        let (pts, all_safe, inf) = (self.pts, self.all_safe, self.inf);
        let (tv, adj, mark) = (&self.tv[..], self.adj.as_flattened(), &mut self.mark[..]);
        while let Some(t) = self.stack.pop() {
            let t = t as usize;
            let ht: [u32; 3] = adj[3 * t..3 * t + 3].try_into().expect("three half-edges");
            for (k, &h) in ht.iter().enumerate() {
                let m = (h / 3) as usize;
                let mk = mark[m];
                if mk == stamp {
                    continue;
                }
                if mk != stamp | OUTSIDE && conflict(pts, all_safe, inf, tv[m], &q) {
                    mark[m] = stamp;
                    self.cavity.push(m as u32);
                    self.stack.push(m as u32);
                    continue;
                }
                mark[m] = stamp | OUTSIDE;
                let v = tv[t];
                self.boundary.push((v[next(k)], v[prev(k)], h));
            }
        }
        if self.boundary.len() != self.cavity.len() + 2 {
            return Err(Broken(format!(
                "cavity of {} triangles has {} boundary edges",
                self.cavity.len(),
                self.boundary.len()
            )));
        }
        // The boundary has two edges more than the cavity has triangles: the first edges take
        // the cavity's slots in order, the last two get two new slots. `cavity` then lists
        // the slot of every boundary edge.
        let first_new = self.tv.len() as u32;
        self.tv.extend_from_slice(&[[0; 3]; 2]);
        self.adj.extend_from_slice(&[[u32::MAX; 3]; 2]);
        self.mark.extend_from_slice(&[0; 2]);
        self.cavity.extend_from_slice(&[first_new, first_new + 1]);
        let inf = self.inf;
        let (tv, adj, start_at) = (
            &mut self.tv[..],
            self.adj.as_flattened_mut(),
            &mut self.start_at[..],
        );
        let mut last = 0;
        for (&(u, w, h), &s) in self.boundary.iter().zip(&self.cavity) {
            tv[s as usize] = [u, w, pi];
            adj[3 * s as usize + 2] = h;
            adj[h as usize] = 3 * s + 2;
            start_at[u as usize] = s;
            if u != inf && w != inf {
                last = s;
            }
        }
        // Across `(w, pi)`: the new triangle starting at `w`.
        for (&(_, w, _), &s) in self.boundary.iter().zip(&self.cavity) {
            let n = start_at[w as usize];
            adj[3 * s as usize] = 3 * n + 1;
            adj[3 * n as usize + 1] = 3 * s;
        }
        self.last = last;
        Ok(())
    }

    /// The builder's arrays, free of its borrow of the points, for `Triangulation::finish` to
    /// reuse as the result's arrays instead of fresh ones (issue 8: fresh pages are what a
    /// large triangulation costs).
    pub(crate) fn into_parts(self) -> Parts {
        debug_assert_eq!(self.mark.len(), self.tv.len());
        debug_assert_eq!(self.adj.len(), self.tv.len());
        debug_assert_eq!(self.start_at.len(), self.inf as usize + 1);
        Parts {
            inf: self.inf,
            tv: self.tv,
            adj: self.adj,
            mark: self.mark,
            start_at: self.start_at,
            dups: self.dups,
            certified: None,
        }
    }
}

/// What [`Builder::into_parts`] hands on: the triangle slots `tv` and their half-edges `adj`,
/// one scratch entry per slot (`mark`) and one per vertex plus the infinite one (`start_at`),
/// both free to overwrite, and the duplicate pairs.
pub(crate) struct Parts {
    pub(crate) inf: u32,
    pub(crate) tv: Vec<[u32; 3]>,
    pub(crate) adj: Vec<[u32; 3]>,
    pub(crate) mark: Vec<u32>,
    pub(crate) start_at: Vec<u32>,
    pub(crate) dups: Vec<(u32, u32)>,
    /// A stitched triangulation's (`super::split`) certified slots `[left, kept]`: slots
    /// `0..left` are the left half's certified triangles and `left..kept` the right half's,
    /// all finite, the two groups without a common vertex (each half's triangles have only
    /// that half's points); the seam's slots follow. `None` for a builder's arrays.
    pub(crate) certified: Option<[u32; 2]>,
}
