//! Memo of per-piece work across the rebuilds of exact mode on one layout (issue #8).
//!
//! [`crate::mesher`] builds the exact layout several times when local fixes (given-up
//! collapses, degree-4 merges) or a local resampling are needed, and each rebuild changes only
//! the pieces around what was fixed. A piece's sub-step densities
//! (`super::ArcGeometry::densities`: 257 points of the conic, most of exact mode's cost) are
//! a function of its `super::ArcGeometry` alone. So a build records, per piece, the
//! geometry's bit patterns (`GeomKey`: every field) with what the counts need from the
//! densities (lower bound, target for one `nbar`), and the next build takes them instead of
//! recomputing: the same values bit for bit, so the mesh does not change.
//!
//! A piece's two block grids and medial nodes depend on its geometry, its counts (`n` and the
//! wall-normal count of each side), the clustering of each side and the smoothing sweeps
//! (`GridKey` with the geometry; its corner spokes are its geometry's ends). When the build
//! is rejected (inverted or poor blocks), the mesher hands its mesh back ([`PieceCache::keep`],
//! kept whole: nothing is moved then) and the next build moves the grids and medial nodes of
//! its unchanged pieces out of it into its own mesh: no copy, and the grids not reused are
//! freed before the new ones are made (peak memory unchanged).
//!
//! Only the latest build's entries are kept (about 300 bytes per piece besides the mesh
//! handed back, not the densities nor the node parameters: a piece without its grids
//! computes its densities again). Entries are written in piece order and read by key (the
//! lookups of one build are made once, in parallel, `PieceCache::find_all`), so nothing
//! depends on the thread count.

use super::counts::Known;
use super::{ArcGeometry, ExactMesh};
use crate::geometry::Point;
use crate::layout::{BlockLayout, Curve};
use crate::mesh::BlockGrid;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::OnceLock;

/// Number of `u64` words in a [`GeomKey`].
const KEY_WORDS: usize = 25;

/// The bit patterns of every field of an [`ArcGeometry`]: equal keys, equal geometry (and so
/// equal densities and nodes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct GeomKey([u64; KEY_WORDS]);

impl GeomKey {
    pub(crate) fn of(g: &ArcGeometry) -> GeomKey {
        let mut w = [0u64; KEY_WORDS];
        let mut i = 0;
        let mut put = |x: f64| {
            w[i] = x.to_bits();
            i += 1;
        };
        for wall in &g.walls {
            put(wall.c[0]);
            put(wall.c[1]);
            put(wall.r);
            put(wall.s);
        }
        for k in 0..2 {
            put(g.start[k]);
            put(g.sweep[k]);
        }
        for end in 0..2 {
            put(g.ends_m[end][0]);
            put(g.ends_m[end][1]);
            for side in 0..2 {
                put(g.ends_a[end][side][0]);
                put(g.ends_a[end][side][1]);
            }
        }
        w[KEY_WORDS - 1] = g.param as u64;
        GeomKey(w)
    }
}

/// Besides the geometry, everything a piece's grids depend on: `n`, the wall-normal count, first
/// height (flag and bits) and growth of each side, and the smoothing sweeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct GridKey([u64; 12]);

impl GridKey {
    /// `sides[k] = (nj, first height, growth)` of the block on `circles[k]`; `rho` the end
    /// grading's ratios ([`super::grading`]).
    pub(crate) fn of(
        n: usize,
        sides: [(usize, Option<f64>, f64); 2],
        smooth: usize,
        rho: [f64; 2],
    ) -> GridKey {
        let mut w = [0u64; 12];
        w[0] = n as u64;
        for (k, (nj, first, growth)) in sides.into_iter().enumerate() {
            w[1 + 4 * k] = nj as u64;
            w[2 + 4 * k] = u64::from(first.is_some());
            w[3 + 4 * k] = first.map_or(0, f64::to_bits);
            w[4 + 4 * k] = growth.to_bits();
        }
        w[9] = smooth as u64;
        w[10] = rho[0].to_bits();
        w[11] = rho[1].to_bits();
        GridKey(w)
    }
}

/// `(nbar, n, parameters)`: a piece's `n + 1` arc-node parameters for that `nbar` and count.
pub(crate) type Params = (f64, usize, Vec<f64>);

/// A piece's medial nodes, its two block grids (smoothed when asked) and which of them has an
/// inverted cell.
pub(crate) type Payload = (Vec<Point>, [BlockGrid; 2], [bool; 2]);

/// The grids of the latest build, handed back by the mesher ([`PieceCache::keep`]).
#[derive(Debug)]
struct Kept {
    /// Per piece: its medial nodes (empty when its medial edge was not a polyline).
    nodes: Vec<Vec<Point>>,
    grids: Vec<BlockGrid>,
    /// Per block: it has an inverted cell.
    inverted: Vec<bool>,
}

/// Vectors of a rejected build, emptied, that the next build fills instead of allocating its
/// own: the layout's vertices, edges and blocks (taken before the grids are made, so they do
/// not add to the peak). Issue 8: a rebuild allocated
/// about as much as the build it replaces freed (at 1e5 particles ~700 MB per rebuild, large
/// vectors the allocator takes from and returns to the kernel), and every such page is
/// faulted in and zeroed again. Only capacity is kept: every vector here is empty, so what a
/// build computes does not depend on it.
#[derive(Debug, Default)]
struct Spare {
    layout: BlockLayout,
}

/// The memo (see the module docs). `PieceCache::default()` is empty: a build with it computes
/// everything, as without a memo.
#[derive(Debug, Default)]
pub struct PieceCache {
    /// The latest build's pieces, in piece order: geometry key, and what the counts need from
    /// the densities (lower bound and, size-driven counts only, the target for one `nbar`).
    keys: Vec<GeomKey>,
    known: Vec<Known>,
    /// Their medial edges in the latest build's layout and their grid inputs, while its grids
    /// may be handed back.
    medial_edges: Vec<u32>,
    grid_keys: Vec<GridKey>,
    /// The latest build's mesh once handed back.
    kept: Option<Kept>,
    /// Emptied vectors of earlier builds, for the next build to fill ([`Spare`]).
    spare: Spare,
    /// Hash of a geometry key -> the last piece with that hash; lookups compare the full key,
    /// so a hash collision is a miss, never a wrong entry. Built from `keys` on the first
    /// lookup after [`PieceCache::replace`]: the last build of a mesh is never looked up, and
    /// its index was a serial loop of ~15 ms at 1e5 particles (issue 8).
    index: OnceLock<Index>,
    /// Pieces of the latest build whose densities were not computed / whose grids were moved
    /// from the memo.
    reused: usize,
    reused_grids: usize,
    /// The reference path for tests ([`PieceCache::reference`]).
    reference: bool,
}

/// [`PieceCache`]'s index: the [`hash_of`] of a geometry key -> a piece.
type Index = HashMap<u64, u32, BuildHasherDefault<PassThrough>>;

/// A hash of a geometry key's words (multiply-rotate per word, then a final mix; issue 8: SipHash
/// of 25 words per piece and build was measurable). Not keyed: the memo is private to one run,
/// and a collision only costs a recomputation (see `PieceCache::index`).
fn hash_of(key: &GeomKey) -> u64 {
    const K: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut h: u64 = 0;
    for &w in &key.0 {
        h = (h.rotate_left(5) ^ w).wrapping_mul(K);
    }
    // Final avalanche (splitmix64's), so every bit of the result depends on every word.
    h ^= h >> 30;
    h = h.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h ^= h >> 27;
    h = h.wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^ (h >> 31)
}

/// The hasher of `PieceCache::index`, whose keys are already [`hash_of`] values: they are used
/// as they are.
#[derive(Debug, Default, Clone, Copy)]
struct PassThrough(u64);

impl Hasher for PassThrough {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 << 8) | u64::from(b);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = x;
    }
}

impl PieceCache {
    /// A memo that is never read and makes the build compute every piece's densities up
    /// front and draw its nodes from them, as exact mode did before the memo and the
    /// summaries: the oracle the fast paths are tested against (same mesh, bit for bit).
    #[doc(hidden)]
    pub fn reference() -> PieceCache {
        PieceCache {
            reference: true,
            ..PieceCache::default()
        }
    }

    /// True for [`PieceCache::reference`].
    pub(crate) fn is_reference(&self) -> bool {
        self.reference
    }

    fn find(&self, key: &GeomKey) -> Option<usize> {
        if self.reference {
            return None;
        }
        let i = *self.index().get(&hash_of(key))? as usize;
        (self.keys.get(i)? == key).then_some(i)
    }

    /// The index of `keys`, built on first use.
    fn index(&self) -> &Index {
        self.index.get_or_init(|| {
            let mut index = Index::default();
            index.reserve(self.keys.len());
            index.extend(
                self.keys
                    .iter()
                    .enumerate()
                    .map(|(i, k)| (hash_of(k), i as u32)),
            );
            index
        })
    }

    /// The latest build's piece with geometry `keys[e]`, for every `e` (in parallel; a key
    /// met twice in that build is found at its last piece).
    pub(crate) fn find_all(&self, keys: &[GeomKey]) -> Vec<Option<u32>> {
        use rayon::prelude::*;
        if !self.reference {
            // Built once here, not by whichever lookup comes first.
            self.index();
        }
        keys.par_iter()
            .map(|k| self.find(k).map(|i| i as u32))
            .collect()
    }

    /// What the latest build knew of the densities of its piece `i` ([`PieceCache::find_all`]).
    pub(crate) fn known(&self, i: Option<u32>) -> Option<Known> {
        self.known.get(i? as usize).copied()
    }

    /// The grids handed back for piece `e` of a new build (the latest build's piece
    /// `found[e]`, [`PieceCache::find_all`]; other inputs `grid_keys[e]`), moved out of the
    /// memo (each piece's at most once, to the first new piece that asks); then the memo is
    /// emptied until [`PieceCache::replace`]. Only the grids of a piece whose grid inputs are
    /// unchanged are taken, and only when the mesh handed back has them (counts as recorded).
    /// `None` when no mesh was handed back (nothing to take): no list of `None`s, which at
    /// 1e5 particles was 30 MB of fresh pages written on one thread (issue 8).
    pub(crate) fn take_grids(
        &mut self,
        found: &[Option<u32>],
        grid_keys: &[GridKey],
    ) -> Option<Vec<Option<Payload>>> {
        let kept = self.kept.take();
        let old_keys = std::mem::take(&mut self.grid_keys);
        let n = self.keys.len();
        // Nothing else is read before `replace`: free the entries before the new grids are
        // made (and, below, every grid not taken).
        self.keys = Vec::new();
        self.known = Vec::new();
        self.index = OnceLock::new();
        self.reused_grids = 0;
        let mut kept = kept?;
        if kept.grids.len() < 2 * n || kept.nodes.len() != n || old_keys.len() != n {
            return None;
        }
        let mut taken = vec![false; n];
        let out: Vec<Option<Payload>> = found
            .iter()
            .zip(grid_keys)
            .map(|(&i, gk)| {
                let i = i? as usize;
                if taken[i] || old_keys[i] != *gk {
                    return None;
                }
                taken[i] = true;
                let w = gk.0;
                let (g0, g1) = (&kept.grids[2 * i], &kept.grids[2 * i + 1]);
                let fits = (g0.ni, g0.nj, g1.ni, g1.nj)
                    == (w[0] as usize, w[1] as usize, w[0] as usize, w[5] as usize);
                // A mesh made without keeping its nodes (`Options::keep_nodes`) has none to give.
                let whole = crate::quality::well_formed(g0) && crate::quality::well_formed(g1);
                if !(fits && whole && kept.nodes[i].len() == g0.ni + 1) {
                    return None;
                }
                let nodes = std::mem::take(&mut kept.nodes[i]);
                let pair = [
                    std::mem::take(&mut kept.grids[2 * i]),
                    std::mem::take(&mut kept.grids[2 * i + 1]),
                ];
                let bad = [kept.inverted[2 * i], kept.inverted[2 * i + 1]];
                Some((nodes, pair, bad))
            })
            .collect();
        // The grids not taken are freed now, before the new grids are made (the list too: kept
        // for the new list, it would be held while the grids are made, the peak).
        drop(kept);
        self.reused_grids = out.iter().filter(|x| x.is_some()).count();
        Some(out)
    }

    /// Replace the entries by those of the build that just finished (pieces `keys` with what
    /// the counts need `known`, medial edges `medial_edges`, grid inputs `grid_keys`, `reused`
    /// of them computed no densities). A key met twice is found at its last piece.
    pub(crate) fn replace(
        &mut self,
        keys: Vec<GeomKey>,
        known: Vec<Known>,
        medial_edges: Vec<u32>,
        grid_keys: Vec<GridKey>,
        reused: usize,
    ) {
        self.grid_keys = grid_keys;
        self.index = OnceLock::new();
        self.keys = keys;
        self.known = known;
        self.medial_edges = medial_edges;
        self.reused = reused;
        self.kept = None;
    }

    /// Hand back `mesh`, which must be what the latest build with this memo returned (the
    /// mesher rejected it and builds again): the next build moves the grids and medial nodes
    /// of its unchanged pieces out of it instead of computing them. A mesh whose pieces do not
    /// match the latest build's counts is not used.
    pub fn keep(&mut self, mesh: ExactMesh) {
        let ExactMesh {
            mut layout,
            grids,
            inverted_blocks,
            ..
        } = mesh;
        // The medial nodes of each piece; the rest of the layout is freed now.
        let medial_edges = std::mem::take(&mut self.medial_edges);
        let nodes = medial_edges
            .iter()
            .map(|&edge| match layout.edges.get_mut(edge as usize) {
                Some(e) => match std::mem::replace(&mut e.curve, Curve::Segment) {
                    Curve::Polyline(v) => v,
                    _ => Vec::new(),
                },
                None => Vec::new(),
            })
            .collect();
        // The rest of the layout is freed now; its vectors' allocations serve the next build.
        layout.vertices.clear();
        layout.edges.clear();
        layout.blocks.clear();
        self.spare.layout = layout;
        let mut inverted = vec![false; grids.len()];
        for &b in &inverted_blocks {
            if let Some(x) = inverted.get_mut(b) {
                *x = true;
            }
        }
        self.kept = Some(Kept {
            nodes,
            grids,
            inverted,
        });
    }

    /// How many entries the spare vectors have room for (for tests: a mesh handed back leaves
    /// its layout's vectors here, the next build takes them).
    #[doc(hidden)]
    pub fn spare_capacity(&self) -> usize {
        let l = &self.spare.layout;
        l.vertices.capacity() + l.edges.capacity() + l.blocks.capacity()
    }

    /// An empty layout, holding the allocations of the latest rejected mesh's layout if any.
    pub(crate) fn spare_layout(&mut self) -> BlockLayout {
        std::mem::take(&mut self.spare.layout)
    }

    /// How many pieces the latest build took from the memo without computing their densities
    /// (for tests: a rebuild that should reuse work does).
    pub fn reused(&self) -> usize {
        self.reused
    }

    /// How many pieces the latest build moved their grids from the memo.
    pub fn reused_grids(&self) -> usize {
        self.reused_grids
    }

    /// Number of pieces held.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// True when nothing is held.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`hash_of`] separates keys that differ in one word by one bit (every word, low and high
    /// bits), and the index finds every key of a build of 20 000 distinct keys at its piece.
    #[test]
    fn geometry_hash_separates_keys_and_the_index_finds_them() {
        let mut rng = crate::layouts::SplitMix64(3);
        let base = GeomKey(std::array::from_fn(|_| rng.next_f64().to_bits()));
        let mut seen = std::collections::HashSet::new();
        assert!(seen.insert(hash_of(&base)));
        for w in 0..KEY_WORDS {
            for bit in [0, 1, 31, 52, 63] {
                let mut k = base;
                k.0[w] ^= 1 << bit;
                assert!(seen.insert(hash_of(&k)), "word {w} bit {bit}");
            }
        }
        let keys: Vec<GeomKey> = (0..20_000)
            .map(|_| GeomKey(std::array::from_fn(|_| rng.next_f64().to_bits())))
            .collect();
        let known = Known {
            min_cells: 1,
            target: None,
            ends: None,
        };
        let mut cache = PieceCache::default();
        let n = keys.len();
        cache.replace(keys.clone(), vec![known; n], vec![0; n], vec![], 0);
        for (i, k) in keys.iter().enumerate() {
            assert_eq!(cache.find(k), Some(i));
        }
        assert_eq!(cache.find(&base), None);
    }
}
