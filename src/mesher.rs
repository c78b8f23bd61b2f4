//! The one call: a validated [`Domain`] and [`Options`] in, a [`Mesh`] or a typed error out.

use crate::domain::{CircleId, Domain, DomainError};
use crate::geometry::TriangulationError;
use crate::grid::{build_grids, GridError};
use crate::mesh::Mesh;
use crate::{blocking, templates};

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
    #[error("grid generation failed: {0}")]
    Grid(#[from] GridError),
    #[error("invalid options: {0}")]
    Options(String),
    #[error("internal invariant broken (please report this layout): {0}")]
    Internal(String),
}

/// Mesh `domain` with `options`.
///
/// Two or more holes: sampling, exact Delaunay triangulation, medial graph and Blocking2D
/// ([`crate::blocking`]); no hole (a disk) or one hole (an annulus): the standard templates of
/// [`crate::templates`]. Then node counts and transfinite interpolation ([`crate::grid`]).
///
/// ```
/// use medial_blocks::{mesh, Domain, Options};
/// let domain = Domain::hexagon_example();
/// let mesh = mesh(&domain, &Options::default()).unwrap();
/// assert_eq!(mesh.layout.blocks.len(), 36); // 6 (h - 1) blocks for h = 7 holes
/// ```
pub fn mesh(domain: &Domain, options: &Options) -> Result<Mesh, MeshError> {
    if options.cells == 0 {
        return Err(MeshError::Options(
            "--cells must be at least 1 (cells along a block side)".into(),
        ));
    }
    let holes = domain.hole_count();
    let (layout, medial_vertices, medial_arcs) = match holes {
        0 => (templates::disk(domain.bounding()), 0, 0),
        1 => (
            templates::annulus(domain.bounding(), domain.holes()[0]),
            0,
            0,
        ),
        _ => {
            let b = blocking::build_layout(domain, options)?;
            let (v, e) = (b.medial.vertex_count(), b.medial.arc_count());
            (b.layout, v, e)
        }
    };
    let grids = build_grids(&layout, options.cells)?;
    Ok(Mesh {
        layout,
        grids,
        medial_vertices,
        medial_arcs,
        holes,
    })
}

/// Mesh either kind of domain: [`mesh`] for a bounded one, [`crate::periodic::mesh_periodic`]
/// (one period that tiles the plane) for a periodic one.
pub fn mesh_any(domain: &crate::domain::AnyDomain, options: &Options) -> Result<Mesh, MeshError> {
    match domain {
        crate::domain::AnyDomain::Bounded(d) => mesh(d, options),
        crate::domain::AnyDomain::Periodic(p) => crate::periodic::mesh_periodic(p, options),
    }
}
