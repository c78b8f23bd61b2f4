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

pub use triangulation::{Changes, Triangulation, TriangulationError, MAX_POINTS};
