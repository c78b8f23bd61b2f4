//! The exact geometry engine: predicates, exact arithmetic, simulation of simplicity and a
//! Bowyer–Watson Delaunay triangulation. Nothing in here knows about meshing.
//!
//! - [`predicates`]: three-valued `orient2d` / `incircle` (adaptive, exact) and the SoS tie-break;
//! - [`Triangulation`]: the Delaunay triangulation of a point set, a function of the set only;
//!   large sets are built as two halves on two threads and stitched along a seam (`split.rs`);
//! - [`verify`]: an independent exact checker (integer arithmetic) used by tests and fuzzing.

mod build;
pub mod exact;
#[doc(hidden)]
pub mod fuzzing;
mod order;
pub mod predicates;
mod sparse;
mod split;
pub mod triangulation;
pub mod verify;
mod wide;

/// A point in the plane, `[x, y]`.
pub type Point = [f64; 2];

/// Squared lengths inside this range take `sqrt(x² + y²)` in [`length`] (no underflow or
/// overflow in the squares or in the products of two lengths); outside it, and for NaN,
/// `hypot`.
pub(crate) const LENGTH_SQ_MIN: f64 = 1e-280;
pub(crate) const LENGTH_SQ_MAX: f64 = 1e280;

/// The length of the vector `(x, y)`: `sqrt(x² + y²)` (within an ulp or so of the exact
/// length) when the squared length is in `[LENGTH_SQ_MIN, LENGTH_SQ_MAX]`, else `hypot`.
/// About 5x cheaper than libm's `hypot` where it matters (the quality report's edges, exact
/// mode's spokes and arc nodes; issue 8), with `hypot`'s safety at the extremes.
#[inline(always)]
pub(crate) fn length(x: f64, y: f64) -> f64 {
    let sq = x * x + y * y;
    if (LENGTH_SQ_MIN..=LENGTH_SQ_MAX).contains(&sq) {
        sq.sqrt()
    } else {
        x.hypot(y)
    }
}

pub(crate) use order::hilbert_order;
pub use triangulation::{Changes, Triangulation, TriangulationError, MAX_POINTS};
