//! VTK XML writer: a `vtkMultiBlockDataSet` (`DIR/mesh.vtm`) referencing one ASCII
//! `StructuredGrid` per block (`DIR/mesh/block_NNNN.vts`), which ParaView opens directly.
//!
//! Each `.vts` has `WholeExtent = Extent = "0 ni 0 nj 0 0"`, points in VTK order (i fastest,
//! matching [`BlockGrid`]'s node order) with z = 0, and cell data `block_id` (Int32),
//! `min_angle_deg`, `max_angle_deg` and `min_jacobian` (Float64, see [`crate::quality`]).
//! Floats are written with Rust's shortest round-trip formatting.
//!
//! The block files are written first and `mesh.vtm` last, each atomically (see
//! [`crate::output`]). Block files left over from an earlier run with more blocks are not
//! removed (the `.vtm` does not reference them).

use super::{check_mesh, num, write_atomic};
use crate::mesh::{BlockGrid, Mesh};
use crate::quality::cell_fields;
use std::io::{self, Write};
use std::path::Path;

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
    for (b, grid) in mesh.grids.iter().enumerate() {
        write_atomic(&dir.join(block_file_name(b)), |w| write_vts(w, b, grid))?;
    }
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
    for (name, values) in [
        ("min_angle_deg", &fields.min_angle_deg),
        ("max_angle_deg", &fields.max_angle_deg),
        ("min_jacobian", &fields.min_jacobian),
    ] {
        writeln!(
            w,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        )?;
        for (k, &x) in values.iter().enumerate() {
            if k % 6 == 0 {
                write!(w, "         ")?;
            }
            write!(w, " ")?;
            num(w, x)?;
            if k % 6 == 5 || k + 1 == values.len() {
                writeln!(w)?;
            }
        }
        writeln!(w, "        </DataArray>")?;
    }
    writeln!(w, "      </CellData>")?;
    writeln!(w, "      <Points>")?;
    writeln!(
        w,
        "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for p in &grid.nodes {
        write!(w, "          ")?;
        num(w, p[0])?;
        write!(w, " ")?;
        num(w, p[1])?;
        writeln!(w, " 0.0")?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </StructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}
