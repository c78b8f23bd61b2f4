//! The JSON report: counts and quality figures of a mesh. Other tools read the key names;
//! do not rename them.

use super::write_atomic;
use crate::cocircular::CocircularGroup;
use crate::connectivity::Connectivity;
use crate::domain::Circle;
use crate::mesh::Mesh;
use crate::quality::{measure_all_with, QualityMetrics};
use serde::Serialize;
use std::io::{self, Write};
use std::path::Path;

/// Summary of a mesh, serialised as `report.json`.
///
/// Required keys (exact names): `holes`, `blocks`, `cells`, `min_angle_deg`, `max_angle_deg`,
/// `mean_min_angle_deg`, `mean_max_angle_deg`, `inverted_cells`, `medial_vertices`,
/// `medial_arcs`, `min_scaled_jacobian`, `max_wall_orthogonality_deviation_deg`,
/// `max_aspect_ratio`, `quality` (per metric (`angle_deg`, `equiangle_skewness`,
/// `edge_ratio`, `scaled_jacobian`, `interface_growth_ratio`, `aspect_ratio`) an object
/// `{"min", "max", "histogram": {"edges", "counts"}, "acceptable": [lo, hi], "outside",
/// "samples"}`, see [`crate::quality::MetricSummary`]), `cocircular_groups`
/// (`[{"holes": [...], "center": [x, y], "radius": r}]`, hole ids 0-based as in the input,
/// `-1` the bounding circle, ids from `holes` on the inserted holes), `collapsed_arcs`,
/// `inserted_holes` (`[{"center": [x, y], "radius": r}]`), `geometry` (`"exact"` or
/// `"paper"`), `coarsened_cell_size` (`[default, used]` or `null`). Angle figures are those of
/// [`crate::quality::Quality`] (0 when there are no cells); a non-finite figure is written as
/// `null`.
///
/// New keys are added as named fields (serde writes them in declaration order); keep the
/// existing names.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    pub holes: usize,
    pub blocks: usize,
    pub cells: usize,
    /// Grid nodes, counted once per block (nodes on shared sides count in each block).
    pub nodes: usize,
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    pub mean_min_angle_deg: f64,
    pub mean_max_angle_deg: f64,
    pub inverted_cells: usize,
    pub min_scaled_jacobian: f64,
    pub medial_vertices: usize,
    pub medial_arcs: usize,
    pub cocircular_groups: Vec<CocircularGroup>,
    pub collapsed_arcs: usize,
    pub inserted_holes: Vec<Circle>,
    /// Largest angle (degrees) between a grid line leaving a wall node and the wall's normal
    /// (`null` without curved walls), see [`QualityMetrics`].
    pub max_wall_orthogonality_deviation_deg: Option<f64>,
    /// Largest cell aspect ratio (`null` without cells), see
    /// [`crate::quality::CellMetrics::aspect_ratio`].
    pub max_aspect_ratio: Option<f64>,
    /// The standard metrics with histograms and acceptable ranges.
    pub quality: QualityMetrics,
    /// `"exact"` or `"paper"`: the geometry the blocks were built on ([`crate::mesh::Geometry`];
    /// `"paper"` in exact mode means it fell back).
    pub geometry: &'static str,
    /// Exact mode: `[default, used]` target cell sizes when the default size would have
    /// given more nodes than [`crate::exact_mode::node_budget`] and was coarsened
    /// ([`Mesh::coarsened_cell_size`]); `null` otherwise.
    pub coarsened_cell_size: Option<[f64; 2]>,
}

impl Report {
    /// Counts from the mesh, quality from [`crate::quality::measure`] and
    /// [`crate::quality::quality_metrics`] over its grids (one pass,
    /// [`crate::quality::measure_all`]).
    ///
    /// Called from outside rayon's pool, the work runs on one of its workers
    /// ([`crate::timings::on_pool_worker`], issue 8: fewer wake-ups).
    pub fn from_mesh(mesh: &Mesh) -> Report {
        let _stage = crate::timings::enter("quality");
        crate::timings::on_pool_worker(|| {
            let conn = Connectivity::new(&mesh.layout, &mesh.grids).ok();
            Report::build(mesh, conn.as_ref())
        })
    }

    /// [`Report::from_mesh`] with the block connectivity already computed (`conn` must be
    /// `Connectivity::new(&mesh.layout, &mesh.grids).ok()`), for a caller that also writes it.
    pub fn from_mesh_with(mesh: &Mesh, conn: Option<&Connectivity>) -> Report {
        let _stage = crate::timings::enter("quality");
        crate::timings::on_pool_worker(|| Report::build(mesh, conn))
    }

    fn build(mesh: &Mesh, conn: Option<&Connectivity>) -> Report {
        let (q, quality) = match &mesh.measured {
            // Measured as the grids were made (their nodes not kept).
            Some(m) => crate::quality::measured_all(&mesh.layout, &mesh.grids, conn, m),
            None => measure_all_with(&mesh.layout, &mesh.grids, conn),
        };
        let nodes = match mesh.measured {
            Some(_) => mesh.grids.iter().map(|g| (g.ni + 1) * (g.nj + 1)).sum(),
            None => mesh.grids.iter().map(|g| g.nodes.len()).sum(),
        };
        Report {
            holes: mesh.holes,
            blocks: mesh.layout.blocks.len(),
            cells: q.cells,
            nodes,
            min_angle_deg: q.min_angle_deg,
            max_angle_deg: q.max_angle_deg,
            mean_min_angle_deg: q.mean_min_angle_deg,
            mean_max_angle_deg: q.mean_max_angle_deg,
            inverted_cells: q.inverted_cells,
            min_scaled_jacobian: q.min_scaled_jacobian,
            medial_vertices: mesh.medial_vertices,
            medial_arcs: mesh.medial_arcs,
            cocircular_groups: mesh.cocircular_groups.clone(),
            collapsed_arcs: mesh.collapsed_arcs,
            inserted_holes: mesh.inserted_holes.clone(),
            max_wall_orthogonality_deviation_deg: quality.max_wall_orthogonality_deviation_deg,
            max_aspect_ratio: quality.aspect_ratio.max,
            quality,
            geometry: mesh.geometry.name(),
            coarsened_cell_size: mesh.coarsened_cell_size,
        }
    }
}

/// Write `report` as pretty-printed JSON (with a final newline) to `path`, atomically.
pub fn write_json(report: &Report, path: &Path) -> io::Result<()> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, report).map_err(io::Error::other)?;
        writeln!(w)
    })
}
