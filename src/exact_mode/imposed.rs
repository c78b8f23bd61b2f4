//! Node counts imposed by block key (tracker issue 6, sequences): a solver maps its fields
//! from one frame to the next when consecutive frames with the same medial combinatorics
//! have the same blocks with the same `ni x nj` ([`crate::sequence`]).
//!
//! A block's key depends on the combinatorics only: its wall circle and, at its two medial
//! corners (corner 3 and corner 2), the circles around that medial vertex in
//! counter-clockwise order of their touching points, rotated to start at the smallest (so the
//! two vertices of three circles, mirror images, have different keys). Circles are
//! [`CircleTag`]s `(id, a, b)`: a bounded domain's circle id with `a = b = 0`, or a periodic
//! domain's hole `id` counted from its copy nearest to the canonical copy of the block's wall
//! ([`nearest_copy`]): `(a, b)` names the copy `(a Lx, b Ly)` away from that one. Counted so,
//! a tag does not depend on which copy of a hole lies in the box, so a hole that crosses the
//! box's edge between two frames (its centre wrapped to the other side) keeps the tags of
//! its blocks and of the blocks around it, and a sequence keeps its run (issue 6's "the same
//! circle triples"); counted from the canonical copies, every crossing ended the run.

use crate::geometry::Point;
use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// A circle: `(id, a, b)` (see the module documentation).
pub type CircleTag = (i64, i64, i64);

/// The copy `(i, j)` (centre `to + (i Lx, j Ly)`) of a periodic hole centred at `to` that is
/// nearest to the point `from`, per axis `floor((from - to) / L + 1/2)` (a copy exactly half a
/// period away on either side: the one below), in a box of `size`; `0` on an axis where that
/// is not a finite number (clamped to `i32`). The same for every copy of `from` and `to` that
/// a box holds up to the difference of their wraps: moving `to` by `-L` adds one, moving
/// `from` by `-L` takes one away (halves rounded up on both sides of zero, so that this holds
/// at exact ties too; up to the rounding of the quotient within an ulp of a tie).
pub fn nearest_copy(size: [f64; 2], from: Point, to: Point) -> (i32, i32) {
    let axis = |a: usize| {
        let q = ((from[a] - to[a]) / size[a] + 0.5).floor();
        if q.is_finite() {
            q.clamp(i32::MIN as f64, i32::MAX as f64) as i32
        } else {
            0
        }
    };
    (axis(0), axis(1))
}

/// [`nearest_copy`] of hole `to` from hole `from` of `holes` (canonical centres, a box of
/// `size`); `(0, 0)` when either id is not a hole.
pub fn nearest_copy_of(
    holes: &[crate::domain::Circle],
    size: [f64; 2],
    from: u32,
    to: u32,
) -> (i32, i32) {
    match (holes.get(from as usize), holes.get(to as usize)) {
        (Some(f), Some(t)) => nearest_copy(size, f.center, t.center),
        _ => (0, 0),
    }
}

/// `(wall, circles around corner 3, circles around corner 2)`.
pub type BlockKey = (CircleTag, Vec<CircleTag>, Vec<CircleTag>);

/// Counts imposed on blocks by key: `[ni, nj]` (cells along the wall, cells along the spokes),
/// and whether a build has applied them.
///
/// A build applies them only through [`ImposedCounts::counts_for`]; when it never did, the
/// options' imposed counts changed nothing, and the mesh is the one made without them
/// (`Options::imposed_counts` is read nowhere else): a sequence then keeps that mesh as the
/// frame's own instead of meshing it again ([`crate::sequence`], issue 8).
#[derive(Debug, Default)]
pub struct ImposedCounts {
    pub counts: BTreeMap<BlockKey, [usize; 2]>,
    /// Set by [`ImposedCounts::counts_for`] when it gives counts (shared through the options'
    /// `Arc`: every build of one meshing with these options sees the same flag).
    applied: AtomicBool,
    /// The keys of every build offered these counts ([`Offer`]), in the order offered.
    offers: Mutex<Vec<Offer>>,
}

/// The block keys of one build that was offered imposed counts, in brief: enough to tell that
/// other counts could not have been given to it. [`ImposedCounts::counts_for`] gives counts
/// only when the build has as many keys as the counts and finds each of them: with distinct
/// keys, the same set, hence the same wrapping sum of key hashes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Offer {
    len: usize,
    sum: u64,
    distinct: bool,
}

/// A key's hash (`DefaultHasher::new()` has fixed keys: the same on every run).
fn key_hash(k: &BlockKey) -> u64 {
    let mut h = std::hash::DefaultHasher::new();
    k.hash(&mut h);
    h.finish()
}

impl Offer {
    /// The offer of a build with block keys `keys`.
    fn of(keys: &[BlockKey]) -> Offer {
        let mut hashes: Vec<u64> = keys.iter().map(key_hash).collect();
        let sum = hashes.iter().fold(0u64, |a, &h| a.wrapping_add(h));
        hashes.sort_unstable();
        // Equal hashes count as repeated keys: a collision only makes `could_take` say yes.
        let distinct = hashes.windows(2).all(|w| w[0] != w[1]);
        Offer {
            len: keys.len(),
            sum,
            distinct,
        }
    }
}

impl ImposedCounts {
    /// Impose `counts`, not applied yet.
    pub fn new(counts: BTreeMap<BlockKey, [usize; 2]>) -> ImposedCounts {
        ImposedCounts {
            counts,
            applied: AtomicBool::new(false),
            offers: Mutex::new(Vec::new()),
        }
    }

    /// Whether [`ImposedCounts::counts_for`] has given counts to a build.
    pub fn applied(&self) -> bool {
        self.applied.load(Ordering::Relaxed)
    }

    /// The builds offered these counts so far ([`Offer`]).
    pub fn offers(&self) -> Vec<Offer> {
        self.offers
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    /// Whether these counts might be given to one of the builds `offers` describe: `false`
    /// only when [`ImposedCounts::counts_for`] would refuse each of them (another number of
    /// keys, or distinct keys that are not these counts' keys). A meshing whose builds were
    /// offered other counts that it never applied made every build as without counts; when
    /// these could not have been given to any of those builds either, meshing with these
    /// makes the same builds again: the same mesh, or the same error.
    pub fn could_take(&self, offers: &[Offer]) -> bool {
        let mine = self
            .counts
            .keys()
            .fold(0u64, |a, k| a.wrapping_add(key_hash(k)));
        offers
            .iter()
            .any(|o| o.len == self.counts.len() && (!o.distinct || o.sum == mine))
    }
}

/// The same counts, flag and offers.
impl Clone for ImposedCounts {
    fn clone(&self) -> ImposedCounts {
        ImposedCounts {
            counts: self.counts.clone(),
            applied: AtomicBool::new(self.applied()),
            offers: Mutex::new(self.offers()),
        }
    }
}

/// The counts compared (the flag is what happened to them, not what they are).
impl PartialEq for ImposedCounts {
    fn eq(&self, other: &ImposedCounts) -> bool {
        self.counts == other.counts
    }
}

impl Eq for ImposedCounts {}

/// The circles around a medial vertex at `center`, each with its touching point, as the
/// rotation-normalised counter-clockwise cycle (duplicates of one tag counted once).
pub fn vertex_cycle(center: Point, touching: &[(CircleTag, Point)]) -> Vec<CircleTag> {
    let mut v: Vec<(f64, CircleTag)> = touching
        .iter()
        .map(|(t, p)| ((p[1] - center[1]).atan2(p[0] - center[0]), *t))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    v.dedup_by(|a, b| a.1 == b.1);
    let tags: Vec<CircleTag> = v.into_iter().map(|x| x.1).collect();
    let n = tags.len();
    // The least rotation, compared in place (issue 8: one vector per rotation was built
    // before; the first least one is the same).
    let tags = &tags;
    let rotation = |r: usize| (0..n).map(move |i| tags[(i + r) % n]);
    let best = (0..n)
        .min_by(|&a, &b| rotation(a).cmp(rotation(b)))
        .unwrap_or(0);
    rotation(best).collect()
}

impl ImposedCounts {
    /// The counts for a build whose block `2e + s` (side `s` of arc `e`) has key
    /// `keys[2e + s]`, arc `e` joins the count indices `arc_circles[e]` and there are
    /// `ncirc` circle counts: `Some((circle, arc))` when every key is known and the imposed
    /// counts are consistent (both blocks of an arc the same `ni`, all blocks on a circle the
    /// same `nj`), else `None` (the build keeps its own counts). Giving counts marks them
    /// [`applied`](ImposedCounts::applied): the caller must use them.
    pub fn counts_for(
        &self,
        keys: &[BlockKey],
        arc_circles: &[[usize; 2]],
        ncirc: usize,
    ) -> Option<(Vec<usize>, Vec<usize>)> {
        self.offers
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(Offer::of(keys));
        if keys.len() != 2 * arc_circles.len() || self.counts.len() != keys.len() {
            return None;
        }
        let mut circle: Vec<Option<usize>> = vec![None; ncirc];
        let mut arc = Vec::with_capacity(arc_circles.len());
        for (e, cs) in arc_circles.iter().enumerate() {
            let a = self.counts.get(&keys[2 * e])?;
            let b = self.counts.get(&keys[2 * e + 1])?;
            if a[0] != b[0] || a[0] == 0 {
                return None;
            }
            arc.push(a[0]);
            for (c, nj) in [(cs[0], a[1]), (cs[1], b[1])] {
                let slot = circle.get_mut(c)?;
                match *slot {
                    Some(m) if m != nj => return None,
                    _ if nj == 0 => return None,
                    _ => *slot = Some(nj),
                }
            }
        }
        let circle = circle.into_iter().map(|c| c.unwrap_or(1)).collect();
        self.applied.store(true, Ordering::Relaxed);
        Some((circle, arc))
    }
}

/// The pseudo-circle id of the tag [`number_loop_pieces`] adds (no circle has it: the
/// bounding circle is `-1`, template blocks are tagged `-2`).
pub const LOOP_PIECE: i64 = -3;

/// Tell apart the blocks on a circle whose key repeats and whose two medial corners each see
/// at most two circles: the pieces of one hole's medial loop ([`super::annulus`]), whose cuts
/// all touch the same two circles (template blocks, tagged `-2`, are left alone). The `k`-th such block of a repeated key (in block order, which is
/// the loop's cut order from a canonical direction) gets the tag `(LOOP_PIECE, k, 0)` appended
/// to its corner-3 cycle, so that a sequence can impose counts on them. Unique keys and
/// blocks at a medial vertex of three or more circles are unchanged.
pub fn number_loop_pieces(keys: &mut [BlockKey]) {
    let mut seen: BTreeMap<BlockKey, usize> = BTreeMap::new();
    for k in keys.iter() {
        *seen.entry(k.clone()).or_insert(0) += 1;
    }
    let mut next: BTreeMap<BlockKey, i64> = BTreeMap::new();
    for k in keys.iter_mut() {
        let repeated = seen.get(k).is_some_and(|&n| n > 1);
        if repeated && k.0 .0 >= -1 && k.1.len() <= 2 && k.2.len() <= 2 {
            let ordinal = next.entry(k.clone()).or_insert(0);
            k.1.push((LOOP_PIECE, *ordinal, 0));
            *ordinal += 1;
        }
    }
}

/// The key of every block of a bounded exact build (block `2e + s`: side `s` of arc `e`);
/// `arcs[e]` is `(end vertices, circles)` of arc (or arc piece) `e`; the pieces of one hole's
/// loop numbered ([`number_loop_pieces`]).
pub(super) fn bounded_keys(
    vertices: &[super::ExactVertex],
    arcs: &[([usize; 2], [crate::domain::CircleId; 2])],
) -> Option<Vec<BlockKey>> {
    let cycle = |v: usize| -> Option<Vec<CircleTag>> {
        let x = vertices.get(v)?;
        let touching: Vec<(CircleTag, Point)> = x
            .circles
            .iter()
            .zip(&x.tangent)
            .map(|(&c, &p)| ((c as i64, 0, 0), p))
            .collect();
        Some(vertex_cycle(x.center, &touching))
    };
    let mut keys = Vec::with_capacity(2 * arcs.len());
    for (ends, circles) in arcs {
        let [c0, c1] = [cycle(ends[0])?, cycle(ends[1])?];
        keys.push(((circles[0] as i64, 0, 0), c0.clone(), c1.clone()));
        keys.push(((circles[1] as i64, 0, 0), c1, c0));
    }
    number_loop_pieces(&mut keys);
    Some(keys)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The nearest copy per axis, and the identities that make tags independent of the box's
    /// copies: moving the target hole by `-L` adds one, moving the origin by `-L` takes one.
    #[test]
    fn nearest_copy_counts_the_wraps() {
        let size = [4.0, 3.0];
        assert_eq!(nearest_copy(size, [3.9, 0.1], [0.1, 2.9]), (1, -1));
        assert_eq!(nearest_copy(size, [2.0, 1.0], [2.5, 1.2]), (0, 0));
        for (from, to) in [([3.9, 0.1], [0.1, 2.9]), ([0.3, 2.2], [3.7, 0.4])] {
            let n = nearest_copy(size, from, to);
            let moved_to = [to[0] - size[0], to[1] - size[1]];
            assert_eq!(nearest_copy(size, from, moved_to), (n.0 + 1, n.1 + 1));
            let moved_from = [from[0] - size[0], from[1]];
            assert_eq!(nearest_copy(size, moved_from, to), (n.0 - 1, n.1));
        }
        // Exactly half a period apart: the copy below, on either side, so a wrap adds one.
        assert_eq!(nearest_copy(size, [3.0, 1.5], [1.0, 0.0]), (1, 1));
        assert_eq!(nearest_copy(size, [3.0, 1.5], [-3.0, -3.0]), (2, 2));
        assert_eq!(nearest_copy(size, [1.0, 0.0], [3.0, 1.5]), (0, 0));
        assert_eq!(nearest_copy(size, [f64::NAN, 0.0], [0.0, 0.0]), (0, 0));
        assert_eq!(nearest_copy([0.0, 3.0], [1.0, 0.0], [0.0, 0.0]), (0, 0));
    }

    proptest::proptest! {
        /// The least rotation found in place is the least of the rotations built as vectors
        /// (the former body), for cycles with repeated tags and symmetric ones.
        #[test]
        fn vertex_cycle_takes_the_least_rotation(
            tags in proptest::collection::vec((0i64..3, -1i64..2, 0i64..2), 0..7),
            repeat in 1usize..3,
        ) {
            // Points on the unit circle in tag order (repeated `repeat` times round it), so
            // the counter-clockwise cycle is the tags in order.
            let n = tags.len() * repeat;
            let touching: Vec<(CircleTag, Point)> = (0..n)
                .map(|k| {
                    let a = -3.0 + 6.0 * k as f64 / n.max(1) as f64;
                    (tags[k % tags.len()], [a.cos(), a.sin()])
                })
                .collect();
            let got = vertex_cycle([0.0, 0.0], &touching);
            let mut v: Vec<(f64, CircleTag)> = touching
                .iter()
                .map(|(t, p)| (p[1].atan2(p[0]), *t))
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            v.dedup_by(|a, b| a.1 == b.1);
            let cyc: Vec<CircleTag> = v.into_iter().map(|x| x.1).collect();
            let want = (0..cyc.len())
                .map(|r| (0..cyc.len()).map(|i| cyc[(i + r) % cyc.len()]).collect::<Vec<_>>())
                .min()
                .unwrap_or_default();
            proptest::prop_assert_eq!(got, want);
        }
    }

    fn key(wall: i64, c3: &[i64], c2: &[i64]) -> BlockKey {
        let tags = |c: &[i64]| c.iter().map(|&x| (x, 0, 0)).collect::<Vec<_>>();
        ((wall, 0, 0), tags(c3), tags(c2))
    }

    #[test]
    fn only_repeated_keys_of_loop_pieces_are_numbered() {
        let loop_piece = key(0, &[-1, 0], &[-1, 0]);
        let template = key(-2, &[3], &[3]);
        let at_vertex = key(1, &[-1, 0, 1], &[-1, 0, 1]);
        let unique = key(2, &[-1, 2], &[-1, 2]);
        let mut keys = vec![
            loop_piece.clone(),
            template.clone(),
            at_vertex.clone(),
            loop_piece.clone(),
            template.clone(),
            at_vertex.clone(),
            unique.clone(),
            loop_piece.clone(),
        ];
        number_loop_pieces(&mut keys);
        // The loop pieces get ordinals 0, 1, 2 in block order; nothing else changes.
        for (at, k) in [(0usize, 0i64), (3, 1), (7, 2)] {
            let mut want = loop_piece.clone();
            want.1.push((LOOP_PIECE, k, 0));
            assert_eq!(keys[at], want);
        }
        assert_eq!(
            [&keys[1], &keys[2], &keys[4], &keys[5], &keys[6]],
            [&template, &at_vertex, &template, &at_vertex, &unique]
        );
        // Numbered keys are unique among themselves.
        let mut numbered = vec![keys[0].clone(), keys[3].clone(), keys[7].clone()];
        numbered.sort();
        numbered.dedup();
        assert_eq!(numbered.len(), 3);
    }

    /// `could_take` says no only where `counts_for` refuses: another number of keys, or other
    /// distinct keys; repeated keys (which `counts_for` may accept with missing ones) and the
    /// same keys in another order say yes. Offers are recorded whether or not counts are given,
    /// and `applied` only when they are.
    #[test]
    fn could_take_only_refuses_what_counts_for_refuses() {
        let keys: Vec<BlockKey> = (0..4)
            .map(|i| key(i / 2, &[10 * i, 10 * i + 1], &[10 * i + 2]))
            .collect();
        let imposed = ImposedCounts::new(keys.iter().map(|k| (k.clone(), [3, 2])).collect());
        // Two arcs on circles 0 and 1, each arc's blocks on both circles.
        let arcs = [[0, 1], [0, 1]];
        let mut other = keys.clone();
        other[3] = key(7, &[70, 71], &[72]);
        let offered = ImposedCounts::new(Default::default());
        assert!(offered.counts_for(&other, &arcs, 2).is_none());
        assert!(!offered.applied());
        let no = offered.offers();
        assert_eq!(no.len(), 1);
        assert!(!imposed.could_take(&no));
        assert!(imposed.counts_for(&other, &arcs, 2).is_none());
        // The same keys, reversed: taken, and `counts_for` gives them.
        let reversed: Vec<BlockKey> = keys.iter().rev().cloned().collect();
        let probe = ImposedCounts::new(Default::default());
        assert!(probe.counts_for(&reversed, &arcs, 2).is_none());
        assert!(imposed.could_take(&probe.offers()));
        assert!(imposed.counts_for(&keys, &arcs, 2).is_some());
        assert!(imposed.applied());
        // A repeated key: `counts_for` finds every key of the build, so it could give counts.
        let mut repeated = keys.clone();
        repeated[1] = repeated[0].clone();
        let probe = ImposedCounts::new(Default::default());
        let _ = probe.counts_for(&repeated, &arcs, 2);
        assert!(imposed.could_take(&probe.offers()));
        // Another number of keys: refused by both.
        let probe = ImposedCounts::new(Default::default());
        let _ = probe.counts_for(&keys[..2], &arcs[..1], 2);
        assert!(!imposed.could_take(&probe.offers()));
        assert!(imposed.counts_for(&keys[..2], &arcs[..1], 2).is_none());
    }
}
