//! The Delaunay triangulation of a large point set built as two halves on two threads, then
//! stitched along a seam (issue 8: the triangulation was the longest stage on one core).
//!
//! Split the points by the vertical line `x = xs` (`xs` their median abscissa): `L` the points
//! with `x < xs`, `R` the others. Triangulate `L` and `R` apart ([`Builder`], in parallel).
//! A triangle of `DT(L)` whose closed circumdisk lies strictly left of the line is
//! *certified*: its disk holds no point of `L` (Delaunay in `DT(L)`) and none of `R` (they are
//! right of the line), so it is a triangle of `DT(L ∪ R)`; the same on the right. Every other
//! triangle of the full triangulation has all its vertices in the *seam set* `S`: the vertices
//! of the triangles of `DT(L)` and `DT(R)` that are not certified (infinite ones included).
//!
//! Why (for a vertex `v ∈ L` of a full triangle `T` with a vertex in `R`): the centre `c` of
//! `T`'s empty circle lies in `v`'s Voronoi cell of `L`, and the disk about `c` through `v`
//! reaches the line. `g(x) = |x - v| + x.x - xs` is convex and `g(c) >= 0`, so `g >= 0` at a
//! vertex of that cell (or the cell is unbounded and `v` is on the hull of `L`): the
//! circumdisk of a triangle of `DT(L)` at `v` reaches the line, and that triangle is not
//! certified. A full triangle with all vertices in `L` is a triangle of `DT(L)`, certified or
//! not.
//!
//! The region `Q` not covered by certified triangles is bounded by *barrier* edges (an edge of
//! a certified triangle whose neighbour in its half is not certified); barriers have both
//! ends in `S` and are full Delaunay edges, so they are edges of `DT(S)`. Inside `Q` the full
//! triangulation uses only `S`'s points and empty circles, so it is `DT(S)` restricted to `Q`:
//! the triangles of `DT(S)` reached from the barriers' outer sides without crossing a barrier.
//!
//! The result is the unique Delaunay triangulation under the lexicographic simulation of
//! simplicity (ties inside a half are broken as in the whole set: SoS compares the points
//! themselves), in the builder's layout; its numbering differs from the one-thread insertion
//! (certified left triangles, certified right ones, then the seam's), and depends on nothing
//! but the points: not on the thread count. The certificate is a floating-point test with a
//! generous error margin, so a doubtful triangle goes to the seam (never the other way).

use super::build::{first_triangle, next, prev, Broken, Builder, Parts};
use super::Point;
use std::collections::HashMap;
use std::mem::MaybeUninit;

/// Fewest points split in halves (below, one builder; a pipeline's 1e3 particles give some
/// 33 000 sample points, 250 particles some 8 300). 2^13 rather than the 2^15 it was: the
/// fifteenth session measured 500 bubbles 39.1 -> 36.5 ms in all (triangulation 8.0 -> 6.4 ms)
/// and 300 bubbles 21.8 -> 20.6 ms, interleaved medians of 15 CLI runs; the other numbering
/// moves the mesh's nodes by rounding only (4e-15 at 500 bubbles, see
/// `tests/reliability_numbering.rs` for why that holds).
pub(super) const SPLIT_MIN: usize = 1 << 13;

/// Triangles per leaf, at least, of a half's parallel certification.
const CERTIFY_SLOTS: usize = 16_384;

/// One half: its triangulation in its own ids, the global id of each of its points, and which
/// of its triangles are certified.
struct Half {
    tv: Vec<[u32; 3]>,
    adj: Vec<[u32; 3]>,
    dups: Vec<(u32, u32)>,
    ids: Vec<u32>,
    certified: Vec<bool>,
    /// Global ids of the vertices of its triangles that are not certified (the half's part of
    /// the seam set; a vertex may come more than once).
    seam: Vec<u32>,
    /// Its barriers: `(u, w, t, k)` for the directed edge `(u, w)` (global ids) of certified
    /// triangle `t` (side `k`) whose neighbour across it is not certified, in triangle order.
    barriers: Vec<(u32, u32, u32, u8)>,
}

/// The triangulation of `pts` (in insertion order, every coordinate in the predicates' safe
/// range) by halves, see the module doc, in the builder's layout ([`Parts`], vertex ids the
/// indices of `pts`, infinite vertex `pts.len()`). `Ok(None)` when the split does not apply (a half
/// without three non-collinear points, or every point on one side): the caller builds it in
/// one piece.
pub(super) fn build_split(pts: &[Point]) -> Result<Option<Parts>, Broken> {
    let n = pts.len();
    let mut xs: Vec<f64> = pts.iter().map(|p| p[0]).collect();
    let mid = n / 2;
    let (_, &mut split, _) = xs.select_nth_unstable_by(mid, f64::total_cmp);
    drop(xs);
    let left = |p: &Point| p[0] < split;
    let (l, r) = rayon::join(
        || half(pts, |p| left(p), split, true),
        || half(pts, |p| !left(p), split, false),
    );
    let (Some(l), Some(r)) = (l?, r?) else {
        return Ok(None);
    };
    let mut parts = stitch(pts, &l, &r)?;
    // The scratch arrays `Triangulation::finish` overwrites: the halves' triangle arrays,
    // done with and already in memory, rather than fresh zeroed ones (issue 8: 30 MB of
    // fresh pages faulted in by `finish`'s serial loops at 1e5 particles).
    let (a, b) = if l.tv.len() >= r.tv.len() {
        (l.tv, r.tv)
    } else {
        (r.tv, l.tv)
    };
    parts.mark = scratch_from(a, parts.tv.len());
    parts.start_at = scratch_from(b, n + 1);
    Ok(Some(parts))
}

/// `v`'s memory as `len` entries of scratch (any contents; grown only when shorter).
fn scratch_from(v: Vec<[u32; 3]>, len: usize) -> Vec<u32> {
    let mut v = v.into_flattened();
    v.resize(len, 0);
    v
}

/// Triangulate the points of `pts` with `side(p)` (in their order) and certify its triangles
/// (`on_left`: the half left of `x = split`). `Ok(None)` without three non-collinear points.
fn half(
    pts: &[Point],
    side: impl Fn(&Point) -> bool,
    split: f64,
    on_left: bool,
) -> Result<Option<Half>, Broken> {
    let ids: Vec<u32> = (0..pts.len() as u32)
        .filter(|&i| side(&pts[i as usize]))
        .collect();
    let local: Vec<Point> = ids.iter().map(|&i| pts[i as usize]).collect();
    let Some(b) = build(&local)? else {
        return Ok(None);
    };
    let inf = local.len() as u32;
    // In parallel (collected in slot order): when one half is built first, its thread
    // helps certify the other's (issue 8: at 1e5 particles the later half's certification
    // kept one CPU busy for some 50 ms while the other waited).
    let certified: Vec<bool> = {
        use rayon::prelude::*;
        b.tv.par_iter()
            .with_min_len(CERTIFY_SLOTS)
            .map(|v| !v.contains(&inf) && disk_clear(&local, *v, split, on_left))
            .collect()
    };
    // The half's share of the seam side's scans, here on its own thread.
    let mut seam = Vec::new();
    let mut barriers = Vec::new();
    for (t, v) in b.tv.iter().enumerate() {
        if !certified[t] {
            seam.extend(v.iter().filter(|&&x| x != inf).map(|&x| ids[x as usize]));
            continue;
        }
        for k in 0..3 {
            if !certified[(b.adj[t][k] / 3) as usize] {
                let (u, w) = (ids[v[next(k)] as usize], ids[v[prev(k)] as usize]);
                barriers.push((u, w, t as u32, k as u8));
            }
        }
    }
    Ok(Some(Half {
        tv: b.tv,
        adj: b.adj,
        dups: b.dups,
        ids,
        certified,
        seam,
        barriers,
    }))
}

/// The Delaunay triangulation of `pts` in insertion order (as `Triangulation::new` starts
/// it), or `None` without three non-collinear points.
fn build(pts: &[Point]) -> Result<Option<Parts>, Broken> {
    let Ok((b, c)) = first_triangle(pts) else {
        return Ok(None);
    };
    let mut builder = Builder::new(pts, true, 0, b, c);
    builder.insert_rest(b, c)?;
    Ok(Some(builder.into_parts()))
}

/// True when the closed circumdisk of the finite triangle `v` lies strictly on its side of
/// the line `x = split` (left when `on_left`), with a margin covering every rounding of the
/// floating-point circumcentre: a false `true` cannot happen, a false `false` only sends the
/// triangle to the seam. Non-finite intermediate values give `false`.
fn disk_clear(pts: &[Point], v: [u32; 3], split: f64, on_left: bool) -> bool {
    let [a, b, c] = v.map(|i| pts[i as usize]);
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let (cx, cy) = (c[0] - a[0], c[1] - a[1]);
    let (bb, cc) = (bx * bx + by * by, cx * cx + cy * cy);
    let (p, q) = (bx * cy, by * cx);
    let d = 2.0 * (p - q);
    let ux = (cy * bb - by * cc) / d;
    let uy = (bx * cc - cx * bb) / d;
    let r = (ux * ux + uy * uy).sqrt();
    // Relative condition of the denominator, and the numerators' magnitudes over it: the
    // centre's error is a few units in the last place of these (the differences `b - a`,
    // `c - a` are rounded too, which the factor 2 |d| / (|p| + |q|) >= 1 amplifies alike).
    let kappa = 2.0 * (p.abs() + q.abs()) / d.abs();
    let num = ((cy.abs() + cx.abs()) * bb + (by.abs() + bx.abs()) * cc) / d.abs();
    let u = f64::EPSILON;
    let margin = 64.0 * u * (num + (ux.abs() + uy.abs()) * kappa + r)
        + 8.0 * u * (a[0].abs() + split.abs() + r);
    let centre = a[0] + ux;
    if on_left {
        centre + r + margin < split
    } else {
        centre - r - margin > split
    }
}

/// New ids for the slots whose flag is set, from `*count` on (`u32::MAX` for the others).
fn number(flags: &[bool], count: &mut u32) -> Vec<u32> {
    flags
        .iter()
        .map(|&f| {
            if f {
                *count += 1;
                *count - 1
            } else {
                u32::MAX
            }
        })
        .collect()
}

/// The global id of vertex `x` of the seam's triangulation (`ids[x]`; its infinite vertex,
/// `ids.len()`, is the global infinite vertex `n`).
#[inline]
fn global_id(ids: &[u32], n: u32, x: u32) -> u32 {
    if x as usize == ids.len() {
        n
    } else {
        ids[x as usize]
    }
}

/// Global half-edge of slot `k` of new triangle `t`.
#[inline]
fn he(t: u32, k: usize) -> u32 {
    3 * t + k as u32
}

/// The full triangulation from the two halves: certified triangles kept, the rest from the
/// seam `DT(S)`, see the module doc.
///
/// Issue 8: the seam side (its set, `DT(S)`, the barriers and the region) and the copy of the
/// certified triangles of each half (nearly every triangle: 150 ms on one thread at 1e5
/// particles) run side by side, each half into its own range of the arrays, which are
/// allocated once at their final size: a triangulation of `V` distinct points with the
/// vertex at infinity has `2 V - 2` triangles (Euler), checked at the end. The arrays and
/// numbering are those of copying one triangle after the other: certified left triangles,
/// certified right ones, then the seam's.
fn stitch(pts: &[Point], l: &Half, r: &Half) -> Result<Parts, Broken> {
    let n = pts.len() as u32;
    let halves = [l, r];
    // Duplicates have equal abscissas: each pair lies in one half (the seam has none).
    let distinct = pts.len() - l.dups.len() - r.dups.len();
    let total = (2 * distinct).saturating_sub(2);
    // New ids: certified left, certified right, then the seam's triangles inside the region.
    let left_kept = l.certified.iter().filter(|&&c| c).count();
    let (new_left, new_right) = rayon::join(
        || number(&l.certified, &mut 0),
        || number(&r.certified, &mut (left_kept as u32)),
    );
    let new_id = [new_left, new_right];
    let kept = left_kept + r.certified.iter().filter(|&&c| c).count();
    if kept > total {
        return Err(Broken(format!(
            "{kept} certified triangles, more than the {total} of {distinct} points"
        )));
    }
    // Not initialised (issue 8: zeroing them first took 0.6 ms of one thread at 1e3
    // particles, their fresh pages; now each half's thread touches its own range): every
    // entry is written exactly once below, the halves' ranges by their threads, the seam's
    // range after them, and only then are the lengths set.
    let mut tv: Vec<[u32; 3]> = Vec::with_capacity(total);
    let mut adj: Vec<[u32; 3]> = Vec::with_capacity(total);
    let (tv_u, adj_u) = (
        &mut tv.spare_capacity_mut()[..total],
        &mut adj.spare_capacity_mut()[..total],
    );
    let (tv_k, tv_s) = tv_u.split_at_mut(kept);
    let (adj_k, adj_s) = adj_u.split_at_mut(kept);
    let seam = {
        let (tv_l, tv_r) = tv_k.split_at_mut(left_kept);
        let (adj_l, adj_r) = adj_k.split_at_mut(left_kept);
        let (seam, (wl, wr)) = rayon::join(
            || seam_side(pts, &halves, &new_id),
            || {
                rayon::join(
                    || copy_certified(n, l, &new_id[0], 0, tv_l, adj_l),
                    || copy_certified(n, r, &new_id[1], left_kept as u32, tv_r, adj_r),
                )
            },
        );
        if wl != left_kept || wr != kept - left_kept {
            return Err(Broken("certified triangles not all copied".into()));
        }
        seam?
    };
    let Seam {
        ids: seam_ids,
        parts: seam,
        across,
        inside,
    } = seam;
    let mut count = kept as u32;
    let seam_new = number(&inside, &mut count);
    if count as usize != total {
        return Err(Broken(format!(
            "stitched triangulation has {count} triangles, not the {total} of {distinct} points"
        )));
    }
    let gs = |x: u32| global_id(&seam_ids, n, x);

    // The seam's triangles inside the region, after the halves' (new ids `kept, kept + 1,
    // ...` in seam order); the barriers' half-edges in the halves' range are set after.
    let mut written = 0;
    let mut barrier_links = Vec::new();
    for (t, v) in seam.tv.iter().enumerate() {
        if !inside[t] {
            continue;
        }
        let me = seam_new[t];
        if me as usize != kept + written {
            return Err(Broken("seam triangles numbered out of order".into()));
        }
        tv_s[written].write(v.map(gs));
        let mut links = [u32::MAX; 3];
        for (k, link) in links.iter_mut().enumerate() {
            let b = across[3 * t + k];
            if b != u32::MAX {
                *link = b;
                // The barrier's half-edge, in a half's range.
                barrier_links.push((b, he(me, k)));
            } else {
                let o = seam.adj[t][k];
                let m = seam_new[(o / 3) as usize];
                if m == u32::MAX {
                    return Err(Broken("seam region leaks past a barrier".into()));
                }
                *link = he(m, (o % 3) as usize);
            }
        }
        adj_s[written].write(links);
        written += 1;
    }
    if written != total - kept {
        return Err(Broken("seam triangles not all placed".into()));
    }
    // SAFETY: entries `0..kept` were written by `copy_certified` (each writes its slice's
    // entries in order, every one of them: checked by its count above) and `kept..total` by
    // the loop above (in order, `total - kept` of them: checked), so all `total` entries of
    // both vectors are initialised; `total` is their capacity.
    unsafe {
        tv.set_len(total);
        adj.set_len(total);
    }
    for (b, h) in barrier_links {
        adj.as_flattened_mut()[b as usize] = h;
    }
    // In parallel (issue 8: one scan of 60 MB at 1e5 particles on one thread).
    let unmatched = {
        use rayon::prelude::*;
        adj.as_flattened()
            .par_chunks(1 << 16)
            .any(|c| c.contains(&u32::MAX))
    };
    if unmatched {
        return Err(Broken(
            "stitched triangulation has an unmatched edge".into(),
        ));
    }
    let mut dups = Vec::with_capacity(l.dups.len() + r.dups.len());
    for h in halves {
        dups.extend(
            h.dups
                .iter()
                .map(|&(v, d)| (h.ids[v as usize], h.ids[d as usize])),
        );
    }
    Ok(Parts {
        inf: n,
        // Scratch, filled by the caller (`build_split`).
        mark: Vec::new(),
        start_at: Vec::new(),
        tv,
        adj,
        dups,
        certified: Some([left_kept as u32, kept as u32]),
    })
}

/// The certified triangles of half `h` (new ids `new_id`, the first of them `base`) into
/// `tv` and `adj` (one entry per certified triangle, in order): global vertex ids, and the
/// half-edge across each side when the neighbour is certified too, else `u32::MAX` (a
/// barrier, linked by the seam). Returns how many it copied: `tv.len()` when it wrote every
/// entry (more than `tv.len()` when there were more certified triangles than entries).
fn copy_certified(
    n: u32,
    h: &Half,
    new_id: &[u32],
    base: u32,
    tv: &mut [MaybeUninit<[u32; 3]>],
    adj: &mut [MaybeUninit<[u32; 3]>],
) -> usize {
    let inf = h.ids.len() as u32;
    let g = |x: u32| if x == inf { n } else { h.ids[x as usize] };
    // The certified triangles' new ids follow their order from `base` on ([`number`]): entry
    // `at` is the `at`-th triangle copied.
    let mut at = 0;
    for (t, v) in h.tv.iter().enumerate() {
        if !h.certified[t] {
            continue;
        }
        debug_assert_eq!(new_id[t] - base, at as u32);
        if at == tv.len() {
            // More certified triangles than ids: the caller sees the count.
            return at + 1;
        }
        tv[at].write(v.map(g));
        let mut links = [u32::MAX; 3];
        for (k, link) in links.iter_mut().enumerate() {
            let o = h.adj[t][k];
            let m = (o / 3) as usize;
            if h.certified[m] {
                *link = he(new_id[m], (o % 3) as usize);
            }
        }
        adj[at].write(links);
        at += 1;
    }
    at
}

/// The seam side of [`stitch`]: the seam set's global ids, `DT(S)`, per seam half-edge the
/// new half-edge of the certified triangle across a barrier (`u32::MAX`: none), and which
/// seam triangles are inside the region.
struct Seam {
    ids: Vec<u32>,
    parts: Parts,
    across: Vec<u32>,
    inside: Vec<bool>,
}

/// [`Seam`] of the halves (new ids of their certified triangles `new_id`).
fn seam_side(pts: &[Point], halves: &[&Half; 2], new_id: &[Vec<u32>; 2]) -> Result<Seam, Broken> {
    let n = pts.len() as u32;
    // Seam set: vertices of the uncertified triangles, in global (insertion) order.
    let mut in_seam = vec![false; pts.len()];
    for h in halves {
        for &x in &h.seam {
            in_seam[x as usize] = true;
        }
    }
    let seam_ids: Vec<u32> = (0..n).filter(|&i| in_seam[i as usize]).collect();
    drop(in_seam);
    let seam_pts: Vec<Point> = seam_ids.iter().map(|&i| pts[i as usize]).collect();
    let seam = build(&seam_pts)?.ok_or_else(|| Broken("seam set is degenerate".into()))?;
    if !seam.dups.is_empty() {
        return Err(Broken("seam set has duplicates".into()));
    }
    let gs = |x: u32| global_id(&seam_ids, n, x);

    // Barriers: directed edge (u, w) of a certified triangle (on its left) whose neighbour in
    // its half is not certified -> that triangle's new half-edge.
    // Looked up, never iterated: a fixed fast hasher (SipHash took a fifth of the seam side).
    let mut barriers: HashMap<(u32, u32), u32, foldhash::fast::FixedState> =
        HashMap::with_capacity_and_hasher(seam.tv.len(), foldhash::fast::FixedState::default());
    for (s, h) in halves.iter().enumerate() {
        for &(u, w, t, k) in &h.barriers {
            barriers.insert((u, w), he(new_id[s][t as usize], k as usize));
        }
    }

    // Seam triangles across a barrier (the one with the reversed edge), then the region
    // reached from them without crossing a barrier.
    let mut across = vec![u32::MAX; 3 * seam.tv.len()];
    let mut inside = vec![false; seam.tv.len()];
    let mut stack = Vec::new();
    let mut matched = 0usize;
    for (t, v) in seam.tv.iter().enumerate() {
        for k in 0..3 {
            let (u, w) = (gs(v[next(k)]), gs(v[prev(k)]));
            if let Some(&h) = barriers.get(&(w, u)) {
                across[3 * t + k] = h;
                matched += 1;
                if !inside[t] {
                    inside[t] = true;
                    stack.push(t);
                }
            }
        }
    }
    if matched != barriers.len() {
        return Err(Broken(format!(
            "{} of {} barrier edges are not seam edges",
            barriers.len() - matched,
            barriers.len()
        )));
    }
    if barriers.is_empty() {
        inside.iter_mut().for_each(|x| *x = true);
    }
    while let Some(t) = stack.pop() {
        for k in 0..3 {
            if across[3 * t + k] == u32::MAX {
                let m = (seam.adj[t][k] / 3) as usize;
                if !inside[m] {
                    inside[m] = true;
                    stack.push(m);
                }
            }
        }
    }
    Ok(Seam {
        ids: seam_ids,
        parts: seam,
        across,
        inside,
    })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::geometry::{verify, Triangulation};

    /// `count` circles of radius 0.5-1.5 in a jittered grid of `columns` columns (spacing 3),
    /// each sampled at `per` equal angles: the pipeline's kind of input.
    pub(in crate::geometry) fn sampled_circles(
        r: &mut crate::layouts::SplitMix64,
        count: usize,
        columns: usize,
        per: usize,
    ) -> Vec<Point> {
        let mut circles = Vec::new();
        for k in 0..count {
            let (cx, cy) = (
                (k % columns) as f64 * 3.0 + r.next_f64(),
                (k / columns) as f64 * 3.0 + r.next_f64(),
            );
            let rad = 0.5 + r.next_f64();
            for m in 0..per {
                let a = m as f64 * std::f64::consts::TAU / per as f64;
                circles.push([cx + rad * a.cos(), cy + rad * a.sin()]);
            }
        }
        circles
    }

    /// Finite triangles as sorted rotations (smallest id first), sorted.
    fn canonical(tv: &[[u32; 3]], inf: u32) -> Vec<[u32; 3]> {
        let mut out: Vec<[u32; 3]> = tv
            .iter()
            .filter(|v| !v.contains(&inf))
            .map(|&v| {
                let k = (0..3).min_by_key(|&k| v[k]).unwrap();
                [v[k], v[(k + 1) % 3], v[(k + 2) % 3]]
            })
            .collect();
        out.sort_unstable();
        out
    }

    /// Point sets that stress the seam: uniform, an integer grid (co-circular quadruples,
    /// points on the split line, collinear hull) with repeated points, sampled circles (the
    /// pipeline's input), and a thin vertical band (every circumdisk crosses the line).
    fn sets() -> Vec<Vec<Point>> {
        let mut r = crate::layouts::SplitMix64(0x1234_5678_9abc_def1);
        let uniform: Vec<Point> = (0..40_000).map(|_| [r.next_f64(), r.next_f64()]).collect();
        let mut grid = Vec::new();
        for i in 0..200 {
            for j in 0..180 {
                grid.push([i as f64, j as f64]);
                if (i * 7 + j) % 5 == 0 {
                    grid.push([i as f64, j as f64]);
                }
            }
        }
        let circles = sampled_circles(&mut r, 900, 30, 40);
        let band: Vec<Point> = (0..36_000)
            .map(|_| [1e-6 * r.next_f64(), r.next_f64()])
            .collect();
        vec![uniform, grid, circles, band]
    }

    #[test]
    fn halves_give_the_one_piece_triangle_set() {
        for pts in sets() {
            assert!(pts.len() >= SPLIT_MIN);
            let parts = build_split(&pts).unwrap().expect("the split applies");
            let one = build(&pts).unwrap().unwrap();
            let inf = pts.len() as u32;
            assert_eq!(canonical(&parts.tv, inf), canonical(&one.tv, inf));
            assert_eq!(parts.tv.len(), one.tv.len(), "infinite triangles too");
            let mut d1 = parts.dups.clone();
            let mut d2 = one.dups.clone();
            d1.sort_unstable();
            d2.sort_unstable();
            assert_eq!(d1, d2);
            // Half-edges: each the reverse of its partner.
            for (t, v) in parts.tv.iter().enumerate() {
                for k in 0..3 {
                    let o = parts.adj[t][k] as usize;
                    assert_eq!(parts.adj.as_flattened()[o] as usize, 3 * t + k);
                    let w = parts.tv[o / 3];
                    let j = o % 3;
                    assert_eq!((w[next(j)], w[prev(j)]), (v[prev(k)], v[next(k)]));
                }
            }
            let dt = Triangulation::new(&pts).unwrap();
            verify::verify_exact(&dt).unwrap();
        }
    }

    /// The numbering is a function of the points: the same arrays on one thread and on two.
    #[test]
    fn numbering_does_not_depend_on_the_thread_count() {
        let pts = sets().swap_remove(2);
        let on = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| Triangulation::new(&pts).unwrap())
        };
        let (a, b) = (on(1), on(2));
        assert!(a.triangles().eq(b.triangles()));
        assert!((0..a.len()).all(|t| a.neighbors(t) == b.neighbors(t)));
    }

    /// Splits that cannot apply or keep nothing: more than half of the points on the median
    /// line (the left half is empty), a collinear left half, points on one circle (every
    /// circumdisk crosses the line: no barrier, the seam is the whole set). Each gives the
    /// one-piece triangle set, or no split; `Triangulation::new` passes the exact re-check.
    #[test]
    fn degenerate_splits_agree_or_fall_back() {
        let mut r = crate::layouts::SplitMix64(7);
        let n = SPLIT_MIN + 100;
        let on_line: Vec<Point> = (0..n)
            .map(|i| {
                if i % 5 < 3 {
                    [0.0, r.next_f64()]
                } else {
                    [r.next_f64(), r.next_f64()]
                }
            })
            .collect();
        let collinear_left: Vec<Point> = (0..n)
            .map(|i| {
                if i % 2 == 0 {
                    [-1.0 - r.next_f64(), 0.5]
                } else {
                    [r.next_f64(), r.next_f64()]
                }
            })
            .collect();
        let circle: Vec<Point> = (0..n)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / n as f64;
                [a.cos(), a.sin()]
            })
            .collect();
        for (name, pts) in [
            ("on the line", on_line),
            ("collinear left", collinear_left),
            ("circle", circle),
        ] {
            let one = build(&pts).unwrap().unwrap();
            let inf = pts.len() as u32;
            if let Some(parts) = build_split(&pts).unwrap() {
                assert_eq!(canonical(&parts.tv, inf), canonical(&one.tv, inf), "{name}");
            }
            let dt = Triangulation::new(&pts).unwrap();
            verify::verify_exact(&dt).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}
