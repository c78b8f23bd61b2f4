//! The one call: a validated [`Domain`] and [`Options`] in, a [`Mesh`] or a typed error out.

use crate::domain::{CircleId, Domain, DomainError};
use crate::geometry::TriangulationError;
use crate::mesh::Mesh;

/// Which geometry the blocks are built on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// The paper exactly as written: circumcenter polylines, equally spaced TFI.
    #[default]
    Paper,
}

/// Options of the pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    pub mode: Mode,
    /// Target number of cells along a block side (the paper: equal spacing).
    pub cells: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            mode: Mode::Paper,
            cells: 16,
        }
    }
}

/// Why no mesh was made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error(transparent)]
    Domain(#[from] DomainError),
    #[error("triangulation failed: {0}")]
    Triangulation(#[from] TriangulationError),
    #[error("boundary sampling of circle {circle} did not converge: {message}")]
    Sampling { circle: CircleId, message: String },
    #[error("invalid options: {0}")]
    Options(String),
    #[error("internal invariant broken (please report this layout): {0}")]
    Internal(String),
}

/// Mesh `domain` with `options`.
pub fn mesh(domain: &Domain, options: &Options) -> Result<Mesh, MeshError> {
    let _ = (domain, options);
    todo!("pipeline")
}
