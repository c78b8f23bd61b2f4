//! VTK XML writer: a `vtkMultiBlockDataSet` (`DIR/mesh.vtm`) referencing one
//! `StructuredGrid` per block (`DIR/mesh/block_NNNN.vts`), which ParaView opens directly;
//! ASCII arrays, or raw appended binary data with [`Encoding::Binary`].
//!
//! Each `.vts` has `WholeExtent = Extent = "0 ni 0 nj 0 0"`, points in VTK order (i fastest,
//! matching [`BlockGrid`]'s node order) with z = 0, and cell data `block_id` (Int32) and the
//! quality figures of [`CELL_ARRAYS`] (Float64, see [`crate::quality::CellFields`]), so
//! ParaView can colour by block or by quality.
//! ASCII floats are written with Rust's shortest round-trip formatting; binary ones are the
//! same values' little-endian bytes ([`super::binary`]).
//!
//! The block files are written first and `mesh.vtm` last, each atomically (see
//! [`crate::output`]). Block files left over from an earlier run with more blocks are not
//! removed (the `.vtm` does not reference them).

use super::binary::{self, Appended, Encoding};
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
    write_multiblock_with(mesh, dir, Encoding::Ascii, true)
}

/// [`write_multiblock`] with the block files in `encoding`.
pub fn write_multiblock_encoded(mesh: &Mesh, dir: &Path, encoding: Encoding) -> io::Result<()> {
    write_multiblock_with(mesh, dir, encoding, true)
}

/// [`write_multiblock`]; with `atomic` false the block files are written under their final
/// names directly (no temporary file and rename each: for [`super::write_files`], whose
/// staging directory already makes the whole set appear at once; a rename per block file
/// is a measurable share of writing 60 000 of them).
pub(crate) fn write_multiblock_with(
    mesh: &Mesh,
    dir: &Path,
    encoding: Encoding,
    atomic: bool,
) -> io::Result<()> {
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
                write_atomic(&path, |w| write_vts_encoded(w, b, grid, encoding))
            } else {
                write_vts_encoded(&mut std::fs::File::create(path)?, b, grid, encoding)
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
    write_vts_encoded(w, block_id, grid, Encoding::Ascii)
}

/// [`write_vts`] in `encoding`: with [`Encoding::Binary`] every array is `format="appended"`
/// and its values follow in one `<AppendedData encoding="raw">` block (the same values as the
/// ASCII file, in the same order).
pub fn write_vts_encoded<W: Write>(
    w: &mut W,
    block_id: usize,
    grid: &BlockGrid,
    encoding: Encoding,
) -> io::Result<()> {
    super::check_grids(std::slice::from_ref(grid))?;
    let (ni, nj) = (grid.ni, grid.nj);
    let fields = cell_fields(grid);
    let id = i32::try_from(block_id).map_err(|_| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("block id {block_id} does not fit VTK's Int32 block_id array"),
        )
    })?;
    // ASCII: about 24 bytes per point and 6 x 22 + 3 per cell.
    let mut out = Vec::with_capacity(1024 + 24 * grid.nodes.len() + 140 * grid.cells());
    writeln!(out, "<?xml version=\"1.0\"?>")?;
    writeln!(
        out,
        "<VTKFile type=\"StructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(out, "  <StructuredGrid WholeExtent=\"0 {ni} 0 {nj} 0 0\">")?;
    writeln!(out, "    <Piece Extent=\"0 {ni} 0 {nj} 0 0\">")?;
    writeln!(out, "      <CellData Scalars=\"min_angle_deg\">")?;
    if encoding == Encoding::Binary {
        let cells = grid.cells();
        let mut at = Appended::default();
        binary::appended_tag(&mut out, "Int32", "block_id", None, at.reserve(4 * cells));
        for name in CELL_ARRAYS {
            binary::appended_tag(&mut out, "Float64", name, None, at.reserve(8 * cells));
        }
        writeln!(out, "      </CellData>")?;
        writeln!(out, "      <Points>")?;
        let points = at.reserve(24 * grid.nodes.len());
        binary::appended_tag(&mut out, "Float64", "Points", Some(3), points);
        writeln!(out, "      </Points>")?;
        writeln!(out, "    </Piece>")?;
        writeln!(out, "  </StructuredGrid>")?;
        out.extend_from_slice(binary::APPENDED_OPEN);
        out.extend_from_slice(&binary::array_header(4 * cells));
        for _ in 0..cells {
            out.extend_from_slice(&id.to_le_bytes());
        }
        for k in 0..CELL_ARRAYS.len() {
            out.extend_from_slice(&binary::array_header(8 * cells));
            binary::f64s(&mut out, cell_array(&fields, k));
        }
        out.extend_from_slice(&binary::array_header(24 * grid.nodes.len()));
        binary::points_xyz(&mut out, &grid.nodes);
        out.extend_from_slice(binary::APPENDED_CLOSE);
        return w.write_all(&out);
    }
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
