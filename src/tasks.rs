//! Leaf sizes of the parallel loops (issue 8).
//!
//! rayon cuts an indexed parallel loop into a few leaves per thread up front, and cuts a
//! leaf further only when another thread steals it; once a leaf has started, it runs to its
//! end on its thread. The last leaf of a loop can then be a large part of the loop, and on a
//! two-core machine the other core waits for it: at 1e5 bubbles the quality pass's last leaf
//! kept one CPU alone for about 40 ms (a system-wide profile, the other CPU idle). Each heavy
//! loop therefore caps its leaves with `with_max_len`, at about a millisecond of work, which
//! still leaves it a dozen leaves or more at 1e3 particles. The cut changes which thread
//! computes what, never a result: every loop it applies to collects in index order.

/// Blocks per leaf of loops that cost some microseconds per block (the quality pass, whose
/// items are chunks of blocks, takes this many blocks' worth of chunks).
pub(crate) const BLOCKS: usize = 256;

/// Medial pieces (two blocks each) per leaf of exact mode's per-piece loops.
pub(crate) const PIECES: usize = 128;

/// Circles per leaf of the sampling's per-circle plans.
pub(crate) const CIRCLES: usize = 256;
