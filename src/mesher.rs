//! The one call: a validated [`Domain`] and [`Options`] in, a [`Mesh`] or a typed error out.

use crate::domain::{CircleId, Domain, DomainError};
use crate::exact_mode::Clustering;
use crate::geometry::TriangulationError;
use crate::grid::{build_grids, GridError};
use crate::mesh::Mesh;
use crate::sampling::SamplingOptions;
use crate::{blocking, exact_mode, templates};

/// Which geometry the blocks are built on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Exact medial axis (Apollonius vertices, conic arcs) and spoke-aligned grids: every
    /// wall-normal grid line exactly normal to its wall, no folding ([`crate::exact_mode`]).
    #[default]
    Exact,
    /// The paper exactly as written: circumcenter polylines, equally spaced TFI.
    Paper,
}

/// Exact mode: how many times sampling is refined (4x each) when the sampled medial graph
/// disagrees with the exact geometry ([`exact_mode::ExactMesh::inconsistent_arcs`]).
pub const EXACT_RESAMPLING: usize = 2;

/// Options of the pipeline.
///
/// Paper mode reads `mode` and `cells` only. Exact mode reads all fields; for the disk and the
/// annulus (fewer than two holes) both modes use the same templates and equal spacing.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    pub mode: Mode,
    /// Paper mode: the number of cells along every block side (raised on long wall arcs).
    /// Exact mode, without `cell_size`: the target size is the median Apollonius radius over
    /// `cells`, so a typical spoke gets about `cells` cells.
    pub cells: usize,
    /// Exact mode: the target cell size (overrides `cells`).
    pub cell_size: Option<f64>,
    /// Exact mode: wall clustering of every circle without an override.
    pub clustering: Clustering,
    /// Exact mode: per-circle clustering overrides (`-1` the bounding circle).
    pub circle_clustering: Vec<(CircleId, Clustering)>,
    /// Exact mode: per-circle wall-normal cell counts fixed by the user.
    pub wall_cells: Vec<(CircleId, usize)>,
    /// Exact mode: Winslow smoothing sweeps per block (0: none).
    pub smooth: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            mode: Mode::Exact,
            cells: 16,
            cell_size: None,
            clustering: Clustering::default(),
            circle_clustering: Vec::new(),
            wall_cells: Vec::new(),
            smooth: 0,
        }
    }
}

impl Options {
    /// The default options in paper mode.
    pub fn paper() -> Options {
        Options {
            mode: Mode::Paper,
            ..Options::default()
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
/// [`crate::templates`]. Then, in paper mode, node counts and transfinite interpolation
/// ([`crate::grid`]); in exact mode (the default), exact geometry and spoke-aligned grids
/// ([`crate::exact_mode`]).
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
    if options.mode == Mode::Exact {
        exact_mode::validate_options(options)?;
        if holes >= 2 {
            return mesh_exact(domain, options);
        }
    }
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

/// Exact mode for two or more holes. The sampled combinatorics must agree with the exact
/// geometry: where nearly co-circular circles make them disagree (an exact arc running
/// backwards, [`exact_mode::ExactMesh::inconsistent_arcs`], or not existing), the sampling is
/// refined 4x per attempt, up to [`EXACT_RESAMPLING`] times. When refinement cannot help (the
/// circles are exactly co-circular, or the finer sampling fails) the last result stands: the
/// mesh with the inverted blocks that quality reports, or the error.
fn mesh_exact(domain: &Domain, options: &Options) -> Result<Mesh, MeshError> {
    let holes = domain.hole_count();
    let mut sampling = SamplingOptions::default();
    let mut last: Option<Result<Mesh, MeshError>> = None;
    for _attempt in 0..=EXACT_RESAMPLING {
        let b = match blocking::build_layout_with(domain, options, &sampling) {
            Ok(b) => b,
            Err(e) => return last.unwrap_or(Err(e)),
        };
        let (v, e) = (b.medial.vertex_count(), b.medial.arc_count());
        match exact_mode::build(domain, &b, options) {
            Ok(m) => {
                let consistent = m.inconsistent_arcs.is_empty();
                let mesh = Mesh {
                    layout: m.layout,
                    grids: m.grids,
                    medial_vertices: v,
                    medial_arcs: e,
                    holes,
                };
                if consistent {
                    return Ok(mesh);
                }
                last = Some(Ok(mesh));
            }
            Err(err @ MeshError::Internal(_)) => {
                if !matches!(last, Some(Ok(_))) {
                    last = Some(Err(err));
                }
            }
            Err(err) => return Err(err),
        }
        sampling.min_per_circle = sampling.min_per_circle.saturating_mul(4);
        sampling.spacing_per_gap *= 0.25;
    }
    last.unwrap_or_else(|| Err(MeshError::Internal("exact mode made no attempt".into())))
}
