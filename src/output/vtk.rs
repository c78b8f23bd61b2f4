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
    check_mesh(mesh)?;
    std::fs::create_dir_all(dir.join("mesh"))?;
    // Block files in parallel (on the current rayon pool); the first error in block order
    // is reported, so the outcome does not depend on the number of threads.
    let results: Vec<io::Result<()>> = mesh
        .grids
        .par_iter()
        .enumerate()
        .map(|(b, grid)| write_atomic(&dir.join(block_file_name(b)), |w| write_vts(w, b, grid)))
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

/// Write one block as a VTK XML StructuredGrid (ASCII).
pub fn write_vts<W: Write>(w: &mut W, block_id: usize, grid: &BlockGrid) -> io::Result<()> {
    let (ni, nj) = (grid.ni, grid.nj);
    let fields = cell_fields(grid);
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"StructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "  <StructuredGrid WholeExtent=\"0 {ni} 0 {nj} 0 0\">")?;
    writeln!(w, "    <Piece Extent=\"0 {ni} 0 {nj} 0 0\">")?;
    writeln!(w, "      <CellData Scalars=\"min_angle_deg\">")?;
    writeln!(
        w,
        "        <DataArray type=\"Int32\" Name=\"block_id\" format=\"ascii\">"
    )?;
    for k in 0..grid.cells() {
        if k % 16 == 0 {
            write!(w, "         ")?;
        }
        write!(w, " {block_id}")?;
        if k % 16 == 15 || k + 1 == grid.cells() {
            writeln!(w)?;
        }
    }
    writeln!(w, "        </DataArray>")?;
    for (k, name) in CELL_ARRAYS.iter().enumerate() {
        writeln!(
            w,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        )?;
        super::vtu::floats(w, cell_array(&fields, k).iter().copied())?;
        writeln!(w, "        </DataArray>")?;
    }
    writeln!(w, "      </CellData>")?;
    super::vtu::points(w, &grid.nodes)?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </StructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}
