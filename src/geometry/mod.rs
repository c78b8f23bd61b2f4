//! The exact geometry engine: predicates, exact arithmetic, simulation of simplicity and a
//! Bowyer–Watson Delaunay triangulation. Nothing in here knows about meshing.

pub mod triangulation;

/// A point in the plane, `[x, y]`.
pub type Point = [f64; 2];

pub use triangulation::{Triangulation, TriangulationError};
