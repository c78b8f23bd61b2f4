//! # medial-blocks
//!
//! Automatic multiblock structured meshes for 2D flow around circular particles, bubbles and
//! droplets, after Guoy & Erickson, *Automatic blocking scheme for structured meshing in 2D
//! multiphase flow simulation* (2004).
//!
//! The public API is small: a [`Domain`] (a bounding circle and holes), [`Options`], one call
//! [`mesh()`], the resulting [`Mesh`] (its [`BlockLayout`] and one [`BlockGrid`] per block),
//! the block [`connectivity`], the quality figures ([`quality`], [`output::report`]) and the
//! writers ([`output`]), all reachable through [`output::write_files`].
//!
//! ```
//! use medial_blocks::output::{report::Report, write_files, Format};
//! use medial_blocks::{mesh, Circle, Domain, Options};
//!
//! // A bounding circle of radius 3 and three holes.
//! let domain = Domain::bounded(
//!     Circle::new(0.0, 0.0, 3.0),
//!     vec![
//!         Circle::new(-1.0, 0.0, 0.4),
//!         Circle::new(1.0, 0.0, 0.4),
//!         Circle::new(0.0, 1.5, 0.5),
//!     ],
//! )?;
//! let mesh = mesh(&domain, &Options { cells: 8, ..Options::default() })?;
//! assert_eq!(mesh.layout.blocks.len(), 12); // 6 (h - 1) blocks for h = 3 holes
//!
//! let report = Report::from_mesh(&mesh);
//! assert_eq!(report.inverted_cells, 0);
//! assert!(report.quality.scaled_jacobian.min.unwrap() > 0.3);
//!
//! let dir = std::env::temp_dir().join("medial-blocks-doctest");
//! write_files(&mesh, &dir, &[Format::Vtk, Format::Vtu, Format::Json])?;
//! assert!(dir.join("mesh.vtu").exists() && dir.join("report.json").exists());
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Ready-made domains (the paper's *Hexagon* and *Lattice*, random bubbles, a square
//! lattice) are in [`layouts`]. Writers: VTK multiblock (`.vtm` + `.vts`) and unstructured
//! (`.vtu`), Plot3D, Gmsh `.msh` and `.geo`, SVG and PNG pictures, JSON connectivity and
//! report, and CGNS with the cargo feature `cgns`.
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
//!
//! Per-block work (quality figures, `.vts` files) runs on rayon's global pool; results are
//! gathered in block order, so output does not depend on the number of threads.

pub mod geometry;

pub mod apollonius;
pub mod blocking;
mod buckets;
pub mod cocircular;
pub mod collapse;
pub mod connectivity;
pub mod domain;
pub mod exact_mode;
#[doc(hidden)]
pub mod fuzzing;
pub mod grid;
pub mod input;
mod lanes;
pub mod layout;
pub mod layouts;
pub mod medial;
pub mod mesh;
pub mod mesher;
pub mod numbering;
pub mod numfmt;
pub mod output;
pub mod periodic;
mod prefetch;
pub mod quality;
pub mod ranges;
pub mod refine;
pub mod sampling;
pub mod sequence;
pub mod spatial_order;
mod tasks;
pub mod templates;
pub mod timings;
pub mod transition;

pub use domain::{AnyDomain, Circle, Domain, DomainError};
pub use layout::BlockLayout;
pub use mesh::{BlockGrid, Mesh};
pub use mesher::{mesh, mesh_any, MeshError, Mode, Options};
pub use periodic::{mesh_periodic, PeriodicDomain};
