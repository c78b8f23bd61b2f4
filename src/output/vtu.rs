//! VTK XML unstructured grid (`DIR/mesh.vtu`): the whole mesh as one conforming grid of
//! quadrilaterals (VTK cell type 9), nodes shared by blocks merged through
//! [`crate::numbering`].
//!
//! Points are the global nodes in [`number_nodes`] order (z = 0). Cells come block by block,
//! in each block in the order `i + j * ni` with corners `(i, j), (i + 1, j), (i + 1, j + 1),
//! (i, j + 1)` (counter-clockwise). Cell data: `block_id` (Int32) and the quality figures of
//! [`crate::quality::CellFields`] (Float64), the same arrays as the `.vts` files. ASCII,
//! floats in Rust's shortest round-trip formatting, so the file is deterministic.

use super::text::{self, write_chunked};
use super::{check_mesh, write_atomic};
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
    // First cell of every block (and the total at the end).
    let mut first_cell = Vec::with_capacity(mesh.grids.len() + 1);
    first_cell.push(0);
    for g in &mesh.grids {
        first_cell.push(first_cell.last().copied().unwrap_or(0) + g.cells());
    }
    let cells = first_cell.last().copied().unwrap_or(0);
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
    writeln!(w, "      <Points>")?;
    writeln!(w, "{POINTS_HEADER}")?;
    write_chunked(w, nodes.coords.len(), 4096, |r, out| {
        point_lines(out, &nodes.coords[r])
    })?;
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    writeln!(w, "      <Cells>")?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    write_chunked(w, mesh.grids.len(), 16, |blocks, out| {
        for b in blocks {
            let (g, ids) = (&mesh.grids[b], &nodes.block_nodes[b]);
            let id = |i: usize, j: usize| ids[i + j * (g.ni + 1)];
            for j in 0..g.nj {
                for i in 0..g.ni {
                    out.extend_from_slice(b"         ");
                    for v in [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)] {
                        out.push(b' ');
                        text::int(out, v);
                    }
                    out.push(b'\n');
                }
            }
        }
    })?;
    writeln!(w, "        </DataArray>")?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    )?;
    ints_chunked(w, cells, |k| 4 * (k + 1))?;
    writeln!(w, "        </DataArray>")?;
    writeln!(
        w,
        "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">"
    )?;
    ints_chunked(w, cells, |_| 9)?;
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Cells>")?;
    writeln!(w, "      <CellData Scalars=\"min_angle_deg\">")?;
    writeln!(
        w,
        "        <DataArray type=\"Int32\" Name=\"block_id\" format=\"ascii\">"
    )?;
    // The block of cell `k`: the last block starting at or before it.
    ints_chunked(w, cells, |k| first_cell.partition_point(|&f| f <= k) - 1)?;
    writeln!(w, "        </DataArray>")?;
    for (k, name) in super::vtk::CELL_ARRAYS.iter().enumerate() {
        writeln!(
            w,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        )?;
        let values: Vec<f64> = fields
            .iter()
            .flat_map(|f| super::vtk::cell_array(f, k).iter().copied())
            .collect();
        let lines = values.len().div_ceil(FLOATS_PER_LINE);
        write_chunked(w, lines, 1024, |r, out| {
            let end = (r.end * FLOATS_PER_LINE).min(values.len());
            float_lines(out, &values[r.start * FLOATS_PER_LINE..end])
        })?;
        writeln!(w, "        </DataArray>")?;
    }
    writeln!(w, "      </CellData>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

/// Integers per line in the `.vts` and `.vtu` data arrays.
pub(crate) const INTS_PER_LINE: usize = 16;
/// Floats per line in the `.vts` and `.vtu` data arrays.
pub(crate) const FLOATS_PER_LINE: usize = 6;

/// The integers `value(k)` for `k` in `0..n`, [`INTS_PER_LINE`] a line, formatted in
/// parallel chunks ([`write_chunked`]).
fn ints_chunked<W: Write>(
    w: &mut W,
    n: usize,
    value: impl Fn(usize) -> usize + Sync,
) -> io::Result<()> {
    write_chunked(w, n.div_ceil(INTS_PER_LINE), 1024, |r, out| {
        let end = (r.end * INTS_PER_LINE).min(n);
        int_lines(out, (r.start * INTS_PER_LINE..end).map(&value))
    })
}

/// Integers, [`INTS_PER_LINE`] a line: each line nine spaces, then ` v` per value.
pub(crate) fn int_lines(out: &mut Vec<u8>, values: impl Iterator<Item = usize>) {
    let mut k = 0;
    for x in values {
        if k % INTS_PER_LINE == 0 {
            if k > 0 {
                out.push(b'\n');
            }
            out.extend_from_slice(b"         ");
        }
        out.push(b' ');
        text::int(out, x);
        k += 1;
    }
    if k > 0 {
        out.push(b'\n');
    }
}

/// Floats (`{:?}`), [`FLOATS_PER_LINE`] a line: each line nine spaces, then ` x` per value.
pub(crate) fn float_lines(out: &mut Vec<u8>, values: &[f64]) {
    for line in values.chunks(FLOATS_PER_LINE) {
        out.extend_from_slice(b"         ");
        for &x in line {
            out.push(b' ');
            text::debug(out, x);
        }
        out.push(b'\n');
    }
}

/// The opening of the `<Points>` data array of a VTK XML piece (z = 0), shared by the `.vts`
/// and `.vtu` writers.
pub(crate) const POINTS_HEADER: &str =
    "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">";

/// One line per point: ten spaces, `x y 0.0` (`{:?}` floats).
pub(crate) fn point_lines(out: &mut Vec<u8>, coords: &[crate::geometry::Point]) {
    for p in coords {
        out.extend_from_slice(b"          ");
        text::debug(out, p[0]);
        out.push(b' ');
        text::debug(out, p[1]);
        out.extend_from_slice(b" 0.0\n");
    }
}
