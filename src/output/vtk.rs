//! VTK XML writer: a `vtkMultiBlockDataSet` (`DIR/mesh.vtm`) referencing one ASCII
//! `StructuredGrid` per block (`DIR/mesh/block_NNNN.vts`), which ParaView opens directly.
//!
//! Each `.vts` has `WholeExtent = Extent = "0 ni 0 nj 0 0"`, points in VTK order (i fastest,
//! matching [`BlockGrid`]'s node order) with z = 0, and cell data `block_id` (Int32) and the
//! quality figures of [`CELL_ARRAYS`] (Float64, see [`crate::quality::CellFields`]), so
//! ParaView can colour by block or by quality.
//! Floats are written with Rust's shortest round-trip formatting.
//!
//! The block files are written first and `mesh.vtm` last, each atomically (see
//! [`crate::output`]). Block files left over from an earlier run with more blocks are not
//! removed (the `.vtm` does not reference them).

use super::vtu::{float_lines, int_lines, point_lines, POINTS_HEADER};
use super::{check_mesh, write_atomic};
use crate::mesh::{BlockGrid, Mesh};
use crate::quality::{cell_fields, CellFields};
use rayon::prelude::*;
use std::io::{self, Write};
use std::path::Path;

/// Names of the Float64 cell-data arrays of the `.vts` (and `.vtu`) files, in file order.
pub const CELL_ARRAYS: [&str; 7] = [
    "min_angle_deg",
    "max_angle_deg",
    "min_jacobian",
    "equiangle_skewness",
    "edge_ratio",
    "scaled_jacobian",
    "aspect_ratio",
];

/// The values of cell array `CELL_ARRAYS[k]`.
pub(crate) fn cell_array(f: &CellFields, k: usize) -> &[f64] {
    match k {
        0 => &f.min_angle_deg,
        1 => &f.max_angle_deg,
        2 => &f.min_jacobian,
        3 => &f.equiangle_skewness,
        4 => &f.edge_ratio,
        5 => &f.scaled_jacobian,
        _ => &f.aspect_ratio,
    }
}

/// File name (relative to the output directory) of block `b`'s structured grid.
pub fn block_file_name(b: usize) -> String {
    format!("mesh/block_{b:04}.vts")
}

/// Write `DIR/mesh.vtm` and `DIR/mesh/block_NNNN.vts`, creating the directories as needed.
///
/// Errors: I/O failures, or a mesh whose grids do not match its blocks (`InvalidInput`).
pub fn write_multiblock(mesh: &Mesh, dir: &Path) -> io::Result<()> {
    write_multiblock_with(mesh, dir, true)
}

/// [`write_multiblock`]; with `atomic` false the block files are written under their final
/// names directly (no temporary file and rename each: for [`super::write_files`], whose
/// staging directory already makes the whole set appear at once; a rename per block file
/// is a measurable share of writing 60 000 of them).
pub(crate) fn write_multiblock_with(mesh: &Mesh, dir: &Path, atomic: bool) -> io::Result<()> {
    check_mesh(mesh)?;
    std::fs::create_dir_all(dir.join("mesh"))?;
    // Block files in parallel (on the current rayon pool); the first error in block order
    // is reported, so the outcome does not depend on the number of threads.
    let results: Vec<io::Result<()>> = mesh
        .grids
        .par_iter()
        .enumerate()
        .map(|(b, grid)| {
            let path = dir.join(block_file_name(b));
            if atomic {
                write_atomic(&path, |w| write_vts(w, b, grid))
            } else {
                write_vts(&mut std::fs::File::create(path)?, b, grid)
            }
        })
        .collect();
    results.into_iter().collect::<io::Result<Vec<()>>>()?;
    write_atomic(&dir.join("mesh.vtm"), |w| {
        writeln!(w, "<?xml version=\"1.0\"?>")?;
        writeln!(
            w,
            "<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
        )?;
        writeln!(w, "  <vtkMultiBlockDataSet>")?;
        for b in 0..mesh.grids.len() {
            writeln!(
                w,
                "    <DataSet index=\"{b}\" name=\"block_{b:04}\" file=\"{}\"/>",
                block_file_name(b)
            )?;
        }
        writeln!(w, "  </vtkMultiBlockDataSet>")?;
        writeln!(w, "</VTKFile>")
    })
}

/// Write one block as a VTK XML StructuredGrid (ASCII). The file's text is made in memory
/// (numbers through [`super::text`]) and written in one call.
pub fn write_vts<W: Write>(w: &mut W, block_id: usize, grid: &BlockGrid) -> io::Result<()> {
    let (ni, nj) = (grid.ni, grid.nj);
    let fields = cell_fields(grid);
    // About 24 bytes per point and 6 x 22 + 3 per cell.
    let mut out = Vec::with_capacity(1024 + 24 * grid.nodes.len() + 140 * grid.cells());
    writeln!(out, "<?xml version=\"1.0\"?>")?;
    writeln!(
        out,
        "<VTKFile type=\"StructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(out, "  <StructuredGrid WholeExtent=\"0 {ni} 0 {nj} 0 0\">")?;
    writeln!(out, "    <Piece Extent=\"0 {ni} 0 {nj} 0 0\">")?;
    writeln!(out, "      <CellData Scalars=\"min_angle_deg\">")?;
    writeln!(
        out,
        "        <DataArray type=\"Int32\" Name=\"block_id\" format=\"ascii\">"
    )?;
    int_lines(&mut out, std::iter::repeat_n(block_id, grid.cells()));
    writeln!(out, "        </DataArray>")?;
    for (k, name) in CELL_ARRAYS.iter().enumerate() {
        writeln!(
            out,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        )?;
        float_lines(&mut out, cell_array(&fields, k));
        writeln!(out, "        </DataArray>")?;
    }
    writeln!(out, "      </CellData>")?;
    writeln!(out, "      <Points>")?;
    writeln!(out, "{POINTS_HEADER}")?;
    point_lines(&mut out, &grid.nodes);
    writeln!(out, "        </DataArray>")?;
    writeln!(out, "      </Points>")?;
    writeln!(out, "    </Piece>")?;
    writeln!(out, "  </StructuredGrid>")?;
    writeln!(out, "</VTKFile>")?;
    w.write_all(&out)
}
