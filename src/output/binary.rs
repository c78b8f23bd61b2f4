//! Binary forms of the writers that have one (issue 8: "binary where the format allows"):
//! VTK XML `.vts` / `.vtu` with raw appended data (`Appended`) and Gmsh `.msh` 4.1 binary
//! ([`super::gmsh`]). Plot3D's `mesh.xyz` is always binary; the picture, the JSON files and the
//! Gmsh `.geo` script are text by nature.
//!
//! Every value is written little-endian whatever the machine (the VTK files say
//! `byte_order="LittleEndian"`; a Gmsh binary file starts with the integer 1 so that a reader
//! can tell), so the bytes depend only on the mesh. A binary file holds exactly the `f64`
//! values of the ASCII file (whose shortest round-trip digits read back to the same bits), in
//! the same order; `tests/output_binary.rs` decodes both and compares them bit for bit.

use crate::geometry::Point;

/// How the formats with both an ASCII and a binary form are written (`--binary` on the
/// command line). ASCII is the default; binary files are about half the size and written
/// several times faster (no number formatting).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum Encoding {
    /// Text (the default): VTK `format="ascii"` arrays, Gmsh `4.1 0 8`.
    #[default]
    Ascii,
    /// VTK XML raw appended data (`<AppendedData encoding="raw">`, UInt64 headers), Gmsh
    /// `4.1 1 8` binary.
    Binary,
}

/// Append `values` as little-endian `f64`s.
pub(crate) fn f64s(out: &mut Vec<u8>, values: &[f64]) {
    out.reserve(8 * values.len());
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// Append each point as three little-endian `f64`s `x y 0.0` (VTK points are 3D).
pub(crate) fn points_xyz(out: &mut Vec<u8>, points: &[Point]) {
    out.reserve(24 * points.len());
    for p in points {
        out.extend_from_slice(&p[0].to_le_bytes());
        out.extend_from_slice(&p[1].to_le_bytes());
        out.extend_from_slice(&0f64.to_le_bytes());
    }
}

/// The offsets of the arrays of one VTK XML appended-data block, in file order: each array is
/// its byte count (a little-endian UInt64, the files' `header_type`) followed by its bytes, and
/// its `offset` attribute is where that count starts, counted from the byte after the `_`
/// that opens the block.
#[derive(Default)]
pub(crate) struct Appended {
    next: u64,
}

impl Appended {
    /// The offset of the next array, of `bytes` bytes, and reserve its room.
    pub(crate) fn reserve(&mut self, bytes: usize) -> u64 {
        let at = self.next;
        self.next += 8 + bytes as u64;
        at
    }
}

/// `<DataArray type="TYPE" Name="NAME" [NumberOfComponents="3"] format="appended"
/// offset="OFFSET"/>` on its own line, indented as the ASCII writers indent their arrays.
pub(crate) fn appended_tag(
    out: &mut Vec<u8>,
    ty: &str,
    name: &str,
    components: Option<usize>,
    offset: u64,
) {
    out.extend_from_slice(b"        <DataArray type=\"");
    out.extend_from_slice(ty.as_bytes());
    out.extend_from_slice(b"\" Name=\"");
    out.extend_from_slice(name.as_bytes());
    out.push(b'"');
    if let Some(c) = components {
        out.extend_from_slice(b" NumberOfComponents=\"");
        super::text::int(out, c);
        out.push(b'"');
    }
    out.extend_from_slice(b" format=\"appended\" offset=\"");
    super::text::int(out, offset);
    out.extend_from_slice(b"\"/>\n");
}

/// The opening of the appended-data block, up to and including the `_` after which the
/// offsets count.
pub(crate) const APPENDED_OPEN: &[u8] = b"  <AppendedData encoding=\"raw\">\n   _";

/// The end of the appended-data block and of the file.
pub(crate) const APPENDED_CLOSE: &[u8] = b"\n  </AppendedData>\n</VTKFile>\n";

/// The UInt64 byte count that starts an appended array of `bytes` bytes.
pub(crate) fn array_header(bytes: usize) -> [u8; 8] {
    (bytes as u64).to_le_bytes()
}
