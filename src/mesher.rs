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
    /// Macro Delaunay refinement (paper Algorithm 3, [`crate::refine`]): insert a hole while an
    /// interior triangle has circumradius / shortest edge above this ratio. Default
    /// `Some(2.0)` (the paper's; smallest angle below about 14.48 degrees); `None` disables it.
    pub refine_ratio: Option<f64>,
    /// Collapse medial arcs shorter than this fraction of the local empty-circle radius
    /// ([`crate::collapse`]). Default [`DEFAULT_COLLAPSE_FRACTION`]; `0` collapses only
    /// zero-length arcs (which are always collapsed).
    pub collapse_fraction: f64,
    /// The most holes refinement may insert before [`MeshError::Refinement`]. Default
    /// [`DEFAULT_MAX_INSERTED_HOLES`].
    pub max_inserted_holes: usize,
}

/// Default of [`Options::collapse_fraction`].
pub const DEFAULT_COLLAPSE_FRACTION: f64 = 0.05;
/// Default of [`Options::refine_ratio`] (the paper's).
pub const DEFAULT_REFINE_RATIO: f64 = 2.0;
/// Default of [`Options::max_inserted_holes`].
pub const DEFAULT_MAX_INSERTED_HOLES: usize = 10_000;

impl Default for Options {
    fn default() -> Self {
        Options {
            mode: Mode::Paper,
            cells: 16,
            refine_ratio: Some(DEFAULT_REFINE_RATIO),
            collapse_fraction: DEFAULT_COLLAPSE_FRACTION,
            max_inserted_holes: DEFAULT_MAX_INSERTED_HOLES,
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
    #[error(
        "macro Delaunay refinement needs more than {limit} inserted holes ({inserted} inserted \
         so far); raise the limit or the refinement ratio"
    )]
    Refinement { inserted: usize, limit: usize },
    #[error("internal invariant broken (please report this layout): {0}")]
    Internal(String),
}

/// Mesh `domain` with `options`.
///
/// Two or more holes: macro Delaunay refinement ([`crate::refine`], paper Algorithm 3: holes
/// are inserted while an interior triangle is poor, the paper's strategy of refining angles
/// below ~15 degrees first), exact Apollonius circles and co-circular groups
/// ([`crate::cocircular`]), collapse of zero-length and short arcs ([`crate::collapse`]),
/// Blocking2D ([`crate::blocking::build_mesh_layout`]) and templates in the inserted holes;
/// no hole (a disk) or one hole (an annulus): the standard templates of
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
    if !(options.collapse_fraction.is_finite() && options.collapse_fraction >= 0.0) {
        return Err(MeshError::Options(format!(
            "the collapse fraction must be a number >= 0, not {}",
            options.collapse_fraction
        )));
    }
    let holes = domain.hole_count();
    let mut out = Mesh {
        holes,
        ..Mesh::default()
    };
    out.layout = match holes {
        0 => templates::disk(domain.bounding()),
        1 => templates::annulus(domain.bounding(), domain.holes()[0]),
        _ => {
            let b = blocking::build_mesh_layout(domain, options)?;
            out.medial_vertices = b.medial_vertices;
            out.medial_arcs = b.medial_arcs;
            out.cocircular_groups = b.cocircular_groups;
            out.collapsed_arcs = b.collapsed_arcs;
            out.inserted_holes = b.inserted_holes;
            out.split_arcs = b.split_arcs;
            out.template_blocks = b.template_blocks;
            b.layout
        }
    };
    out.grids = build_grids(&out.layout, options.cells)?;
    Ok(out)
}
