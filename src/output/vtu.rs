//! VTK XML unstructured grid (`DIR/mesh.vtu`): the whole mesh as one conforming grid of
//! quadrilaterals (VTK cell type 9), nodes shared by blocks merged through
//! [`crate::numbering`].
//!
//! Points are the global nodes in [`number_nodes`] order (z = 0). Cells come block by block,
//! in each block in the order `i + j * ni` with corners `(i, j), (i + 1, j), (i + 1, j + 1),
//! (i, j + 1)` (counter-clockwise). Cell data: `block_id` (Int32) and the quality figures of
//! [`crate::quality::CellFields`] (Float64), the same arrays as the `.vts` files. ASCII,
//! floats in Rust's shortest round-trip formatting, so the file is deterministic.

use super::{check_mesh, num, write_atomic};
use crate::mesh::Mesh;
use crate::numbering::number_nodes;
use crate::quality::cell_fields;
use rayon::prelude::*;
use std::io::{self, Write};
use std::path::Path;

/// Write `mesh` as one VTK XML UnstructuredGrid at `path` (atomically).
///
/// Errors: I/O failures, or a mesh whose grids do not match its blocks (`InvalidInput`).
pub fn write_vtu(mesh: &Mesh, path: &Path) -> io::Result<()> {
    check_mesh(mesh)?;
    write_atomic(path, |w| write_to(w, mesh))
}

fn write_to<W: Write>(w: &mut W, mesh: &Mesh) -> io::Result<()> {
    let nodes = number_nodes(&mesh.layout, &mesh.grids);
    let cells: usize = mesh.grids.iter().map(|g| g.cells()).sum();
    let fields: Vec<_> = mesh.grids.par_iter().map(cell_fields).collect();
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{cells}\">",
        nodes.coords.len()
    )?;
    points(w, &nodes.coords)?;
    writeln!(w, "      <Cells>")?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    for (g, ids) in mesh.grids.iter().zip(&nodes.block_nodes) {
        let id = |i: usize, j: usize| ids[i + j * (g.ni + 1)];
        for j in 0..g.nj {
            for i in 0..g.ni {
                writeln!(
                    w,
                    "          {} {} {} {}",
                    id(i, j),
                    id(i + 1, j),
                    id(i + 1, j + 1),
                    id(i, j + 1)
                )?;
            }
        }
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    )?;
    ints(w, (1..=cells).map(|k| 4 * k))?;
    writeln!(w, "        </DataArray>")?;
    writeln!(
        w,
        "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">"
    )?;
    ints(w, (0..cells).map(|_| 9))?;
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Cells>")?;
    writeln!(w, "      <CellData Scalars=\"min_angle_deg\">")?;
    writeln!(
        w,
        "        <DataArray type=\"Int32\" Name=\"block_id\" format=\"ascii\">"
    )?;
    ints(
        w,
        mesh.grids
            .iter()
            .enumerate()
            .flat_map(|(b, g)| std::iter::repeat_n(b, g.cells())),
    )?;
    writeln!(w, "        </DataArray>")?;
    for (k, name) in super::vtk::CELL_ARRAYS.iter().enumerate() {
        writeln!(
            w,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        )?;
        floats(
            w,
            fields
                .iter()
                .flat_map(|f| super::vtk::cell_array(f, k).iter().copied()),
        )?;
        writeln!(w, "        </DataArray>")?;
    }
    writeln!(w, "      </CellData>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

/// Integers, 16 a line.
fn ints<W: Write>(w: &mut W, values: impl Iterator<Item = usize>) -> io::Result<()> {
    let mut k = 0;
    for x in values {
        if k % 16 == 0 {
            if k > 0 {
                writeln!(w)?;
            }
            write!(w, "         ")?;
        }
        write!(w, " {x}")?;
        k += 1;
    }
    if k > 0 {
        writeln!(w)?;
    }
    Ok(())
}

/// The `<Points>` element of a VTK XML piece (z = 0), shared by the `.vts` and `.vtu` writers.
pub(crate) fn points<W: Write>(w: &mut W, coords: &[crate::geometry::Point]) -> io::Result<()> {
    writeln!(w, "      <Points>")?;
    writeln!(
        w,
        "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for p in coords {
        write!(w, "          ")?;
        num(w, p[0])?;
        write!(w, " ")?;
        num(w, p[1])?;
        writeln!(w, " 0.0")?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    Ok(())
}

/// Floats, 6 a line.
pub(crate) fn floats<W: Write>(w: &mut W, values: impl Iterator<Item = f64>) -> io::Result<()> {
    let mut k = 0;
    for x in values {
        if k % 6 == 0 {
            if k > 0 {
                writeln!(w)?;
            }
            write!(w, "         ")?;
        }
        write!(w, " ")?;
        num(w, x)?;
        k += 1;
    }
    if k > 0 {
        writeln!(w)?;
    }
    Ok(())
}
