//! Memo of per-piece work across the rebuilds of exact mode on one layout (issue #8).
//!
//! [`crate::mesher`] builds the exact layout several times when local fixes (given-up
//! collapses, degree-4 merges) or a local resampling are needed, and each rebuild changes only
//! the pieces around what was fixed. A piece's sub-step densities
//! ([`super::ArcGeometry::densities`]: 257 points of the conic, most of exact mode's cost) are
//! a function of its [`super::ArcGeometry`] alone, and the arc-node parameters drawn from them
//! of that geometry, `nbar` and the arc count. So a build records, per piece, the geometry's
//! bit patterns ([`GeomKey`]: every field) with the lower bound, the target and the
//! parameters it computed, and the next build takes them instead of recomputing: the same
//! values bit for bit, so the mesh does not change.
//!
//! Only the latest build's entries are kept (tens of bytes per piece besides the key, not the
//! densities). Entries are written in piece order and read by key, so nothing depends on the
//! thread count.

use super::counts::Known;
use super::ArcGeometry;
use std::collections::HashMap;

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

/// What one build computed for one piece geometry.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Entry {
    /// The densities' lower bound and (size-driven counts only) the target for one `nbar`.
    pub(crate) known: Known,
    /// `(nbar, n, parameters)`: the `n + 1` arc-node parameters for that `nbar` and count.
    pub(crate) params: Option<(f64, usize, Vec<f64>)>,
}

/// The memo (see the module docs). `PieceCache::default()` is empty: a build with it computes
/// everything, as without a memo.
#[derive(Debug, Default)]
pub struct PieceCache {
    entries: HashMap<GeomKey, Entry>,
    /// Pieces of the latest build whose densities were not computed.
    reused: usize,
}

impl PieceCache {
    /// What an earlier build knew of geometry `key`'s densities.
    pub(crate) fn known(&self, key: &GeomKey) -> Option<Known> {
        self.entries.get(key).map(|e| e.known)
    }

    /// The arc-node parameters an earlier build drew for geometry `key`, `nbar` and count `n`.
    pub(crate) fn params(&self, key: &GeomKey, nbar: f64, n: usize) -> Option<&[f64]> {
        match self.entries.get(key)?.params.as_ref()? {
            (nb, m, p) if nb.to_bits() == nbar.to_bits() && *m == n => Some(p),
            _ => None,
        }
    }

    /// Replace the entries by those of the build that just finished (`reused` of its pieces
    /// computed no densities). A key met twice keeps its last entry.
    pub(crate) fn replace(&mut self, entries: Vec<(GeomKey, Entry)>, reused: usize) {
        self.entries.clear();
        self.entries.extend(entries);
        self.reused = reused;
    }

    /// How many pieces the latest build took from the memo without computing their densities
    /// (for tests: a rebuild that should reuse work does).
    pub fn reused(&self) -> usize {
        self.reused
    }

    /// Number of piece geometries held.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when nothing is held.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}
