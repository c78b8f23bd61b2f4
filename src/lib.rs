//! # medial-blocks
//!
//! Automatic multiblock structured meshes for 2D flow around circular particles, bubbles and
//! droplets, after Guoy & Erickson, *Automatic blocking scheme for structured meshing in 2D
//! multiphase flow simulation* (2004).
//!
//! The pipeline (see `Architecture.md`):
//!
//! ```text
//! Domain --validate--> boundary samples --exact Delaunay (geometry)--> medial graph
//!   --blocking (Algorithm 2)--> BlockLayout --node counts + TFI--> Mesh --> quality, writers
//! ```
//!
//! The geometry engine ([`geometry`]) knows nothing about meshing: it is a Bowyer–Watson
//! Delaunay triangulation with exact predicates and simulation of simplicity.

pub mod geometry;

pub mod apollonius;
pub mod blocking;
pub mod connectivity;
pub mod domain;
pub mod grid;
pub mod layout;
pub mod medial;
pub mod mesh;
pub mod mesher;
pub mod numbering;
pub mod output;
pub mod periodic;
pub mod quality;
pub mod sampling;
pub mod sequence;
pub mod templates;
pub mod transition;

pub use domain::{AnyDomain, Circle, Domain, DomainError};
pub use layout::BlockLayout;
pub use mesh::{BlockGrid, Mesh};
pub use mesher::{mesh, mesh_any, MeshError, Mode, Options};
pub use periodic::{mesh_periodic, PeriodicDomain};
