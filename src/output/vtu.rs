//! VTK XML unstructured grid (`DIR/mesh.vtu`): the whole mesh as one conforming grid of
//! quadrilaterals (VTK cell type 9), nodes shared by blocks merged through
//! [`crate::numbering`].
//!
//! Points are the global nodes in [`crate::numbering::number_nodes`] order (z = 0). Cells come block by block,
//! in each block in the order `i + j * ni` with corners `(i, j), (i + 1, j), (i + 1, j + 1),
//! (i, j + 1)` (counter-clockwise). Cell data: `block_id` (Int32) and the quality figures of
//! [`crate::quality::CellFields`] (Float64), the same arrays as the `.vts` files. ASCII,
//! floats in Rust's shortest round-trip formatting, so the file is deterministic; or, with
//! [`Encoding::Binary`], the same values as raw appended data, streamed in parallel chunks.
//!
//! Memory (issue 8): nothing of the size of the mesh is held beside it. The merged nodes come
//! block by block from a [`Numbering`] (the points each block adds, the ids of its cells'
//! corners), and the cell figures are computed a chunk of blocks at a time: in the binary file
//! once, each array's part of a chunk written at its place in the appended data (every size is
//! known in advance); in the ASCII file once per array, for the cells of each chunk of lines.

use super::binary::{self, Appended, Encoding};
use super::text::{self, write_chunked};
use super::{check_mesh, write_atomic};
use crate::mesh::Mesh;
use crate::numbering::Numbering;
use crate::quality::cell_fields;
use std::io::{self, Seek, SeekFrom, Write};
use std::path::Path;

/// Write `mesh` as one VTK XML UnstructuredGrid at `path` (atomically).
///
/// Errors: I/O failures, or a mesh whose grids do not match its blocks (`InvalidInput`).
pub fn write_vtu(mesh: &Mesh, path: &Path) -> io::Result<()> {
    write_vtu_encoded(mesh, path, Encoding::Ascii)
}

/// [`write_vtu`] in `encoding`.
pub fn write_vtu_encoded(mesh: &Mesh, path: &Path, encoding: Encoding) -> io::Result<()> {
    check_mesh(mesh)?;
    write_atomic(path, |w| match encoding {
        Encoding::Ascii => write_to(w, mesh),
        Encoding::Binary => write_binary(w, mesh),
    })
}

/// The numbering of the merged nodes and the first cell of every block (and the total at the
/// end).
fn prepare(mesh: &Mesh) -> (Numbering, Vec<usize>) {
    let nodes = Numbering::new(&mesh.layout, &mesh.grids);
    let mut first_cell = Vec::with_capacity(mesh.grids.len() + 1);
    first_cell.push(0);
    for g in &mesh.grids {
        first_cell.push(first_cell.last().copied().unwrap_or(0) + g.cells());
    }
    (nodes, first_cell)
}

/// The values of cell array `k` ([`super::vtk::CELL_ARRAYS`]) of the cells `cells` (global
/// cell numbers) into `out`: the figures of every block the range meets, computed here.
fn cell_values(
    mesh: &Mesh,
    first_cell: &[usize],
    k: usize,
    cells: std::ops::Range<usize>,
    out: &mut Vec<f64>,
) {
    if cells.is_empty() {
        return;
    }
    for b in block_of(first_cell, cells.start)..=block_of(first_cell, cells.end - 1) {
        let f = cell_fields(&mesh.grids[b]);
        let from = cells.start.max(first_cell[b]) - first_cell[b];
        let to = cells.end.min(first_cell[b + 1]) - first_cell[b];
        out.extend_from_slice(&super::vtk::cell_array(&f, k)[from..to]);
    }
}

/// The XML up to the `<Points>` opening: the file header and the piece's counts.
fn piece_open<W: Write>(w: &mut W, points: usize, cells: usize) -> io::Result<()> {
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{points}\" NumberOfCells=\"{cells}\">"
    )?;
    writeln!(w, "      <Points>")
}

/// The four corners of every cell of `blocks`, in file order (global node numbers).
fn cell_corners_of(
    mesh: &Mesh,
    nodes: &Numbering,
    blocks: std::ops::Range<usize>,
    mut each: impl FnMut([usize; 4]),
) {
    let mut ids = Vec::new();
    for b in blocks {
        let g = &mesh.grids[b];
        nodes.block_ids(&mesh.layout, b, g, &mut ids);
        let id = |i: usize, j: usize| ids[i + j * (g.ni + 1)];
        for j in 0..g.nj {
            for i in 0..g.ni {
                each([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
}

/// The block of cell `k`: the last block starting at or before it.
fn block_of(first_cell: &[usize], k: usize) -> usize {
    first_cell.partition_point(|&f| f <= k) - 1
}

/// The binary file: every array `format="appended"`, then the raw data, each array's bytes
/// formed in parallel chunks ([`write_chunked`]) and written in order.
fn write_binary<W: Write + Seek>(w: &mut W, mesh: &Mesh) -> io::Result<()> {
    let (nodes, first_cell) = prepare(mesh);
    let cells = first_cell.last().copied().unwrap_or(0);
    let points = nodes.len();
    piece_open(w, points, cells)?;
    let mut at = Appended::default();
    let mut head = Vec::new();
    binary::appended_tag(
        &mut head,
        "Float64",
        "Points",
        Some(3),
        at.reserve(24 * points),
    );
    head.extend_from_slice(b"      </Points>\n      <Cells>\n");
    let conn = at.reserve(32 * cells);
    binary::appended_tag(&mut head, "Int64", "connectivity", None, conn);
    binary::appended_tag(&mut head, "Int64", "offsets", None, at.reserve(8 * cells));
    binary::appended_tag(&mut head, "UInt8", "types", None, at.reserve(cells));
    head.extend_from_slice(b"      </Cells>\n      <CellData Scalars=\"min_angle_deg\">\n");
    binary::appended_tag(&mut head, "Int32", "block_id", None, at.reserve(4 * cells));
    for name in super::vtk::CELL_ARRAYS {
        binary::appended_tag(&mut head, "Float64", name, None, at.reserve(8 * cells));
    }
    head.extend_from_slice(b"      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n");
    head.extend_from_slice(binary::APPENDED_OPEN);
    head.extend_from_slice(&binary::array_header(24 * points));
    w.write_all(&head)?;
    super::write_merged_points(w, mesh, &nodes, |p, out| binary::points_xyz(out, p))?;
    w.write_all(&binary::array_header(32 * cells))?;
    write_chunked(w, mesh.grids.len(), 64, |blocks, out| {
        cell_corners_of(mesh, &nodes, blocks, |c| {
            for v in c {
                out.extend_from_slice(&(v as i64).to_le_bytes());
            }
        })
    })?;
    /// An array of `size` bytes per cell, its chunks of cells formed in parallel by `fill`.
    fn chunked<W: Write>(
        w: &mut W,
        cells: usize,
        size: usize,
        fill: impl Fn(std::ops::Range<usize>, &mut Vec<u8>) + Sync,
    ) -> io::Result<()> {
        w.write_all(&binary::array_header(size * cells))?;
        write_chunked(w, cells, 1 << 16, |r, out| {
            out.reserve(size * r.len());
            fill(r, out);
        })
    }
    chunked(w, cells, 8, |r, out| {
        for k in r {
            out.extend_from_slice(&(4 * (k as i64 + 1)).to_le_bytes());
        }
    })?;
    chunked(w, cells, 1, |r, out| out.resize(out.len() + r.len(), 9))?;
    chunked(w, cells, 4, |r, out| {
        if r.is_empty() {
            return;
        }
        // The blocks the range meets, each for its run of cells.
        let mut b = block_of(&first_cell, r.start);
        let mut k = r.start;
        while k < r.end {
            let to = first_cell[b + 1].min(r.end);
            for _ in k..to {
                out.extend_from_slice(&(b as i32).to_le_bytes());
            }
            (k, b) = (to, b + 1);
        }
    })?;
    fields_binary(w, mesh, &first_cell)?;
    w.write_all(binary::APPENDED_CLOSE)
}

/// The cell arrays of [`super::vtk::CELL_ARRAYS`] in the appended data, from the writer's
/// position on (each its byte count, then 8 bytes a cell), ending there after the last: the
/// figures of a chunk of blocks are computed once (a wave of chunks in parallel) and each
/// array's part is written at its place, so the bytes are those of writing the arrays one
/// after the other, and no array of the mesh's size is held.
fn fields_binary<W: Write + Seek>(w: &mut W, mesh: &Mesh, first_cell: &[usize]) -> io::Result<()> {
    let cells = first_cell.last().copied().unwrap_or(0);
    let arrays = super::vtk::CELL_ARRAYS.len();
    let start = w.stream_position()?;
    let stride = 8 + 8 * cells as u64;
    for k in 0..arrays {
        w.seek(SeekFrom::Start(start + k as u64 * stride))?;
        w.write_all(&binary::array_header(8 * cells))?;
    }
    text::in_waves(
        mesh.grids.len(),
        64,
        |blocks| {
            let mut parts = vec![Vec::new(); arrays];
            for b in blocks {
                let f = cell_fields(&mesh.grids[b]);
                for (k, part) in parts.iter_mut().enumerate() {
                    binary::f64s(part, super::vtk::cell_array(&f, k));
                }
            }
            parts
        },
        |blocks, parts| {
            let at = 8 + 8 * first_cell[blocks.start] as u64;
            for (k, part) in parts.iter().enumerate() {
                w.seek(SeekFrom::Start(start + k as u64 * stride + at))?;
                w.write_all(part)?;
            }
            Ok(())
        },
    )?;
    w.seek(SeekFrom::Start(start + arrays as u64 * stride))?;
    Ok(())
}

fn write_to<W: Write>(w: &mut W, mesh: &Mesh) -> io::Result<()> {
    let (nodes, first_cell) = prepare(mesh);
    let cells = first_cell.last().copied().unwrap_or(0);
    piece_open(w, nodes.len(), cells)?;
    writeln!(w, "{POINTS_HEADER}")?;
    super::write_merged_points(w, mesh, &nodes, |p, out| point_lines(out, p))?;
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    writeln!(w, "      <Cells>")?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    write_chunked(w, mesh.grids.len(), 16, |blocks, out| {
        cell_corners_of(mesh, &nodes, blocks, |c| {
            out.extend_from_slice(b"         ");
            for v in c {
                out.push(b' ');
                text::int(out, v);
            }
            out.push(b'\n');
        })
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
    ints_chunked(w, cells, |k| block_of(&first_cell, k))?;
    writeln!(w, "        </DataArray>")?;
    for (k, name) in super::vtk::CELL_ARRAYS.iter().enumerate() {
        writeln!(
            w,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        )?;
        let lines = cells.div_ceil(FLOATS_PER_LINE);
        write_chunked(w, lines, 1024, |r, out| {
            let end = (r.end * FLOATS_PER_LINE).min(cells);
            let mut values = Vec::with_capacity(end - r.start * FLOATS_PER_LINE);
            cell_values(
                mesh,
                &first_cell,
                k,
                r.start * FLOATS_PER_LINE..end,
                &mut values,
            );
            float_lines(out, &values)
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
