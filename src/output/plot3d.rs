//! Plot3D multi-block, two-dimensional, whole grid (no iblank), double precision.
//!
//! Layout of both forms: the block count; the node dimensions `(ni + 1, nj + 1)` of every block;
//! then per block all `x` (i fastest) followed by all `y`.
//! - `mesh.xyz`: Fortran unformatted sequential, little-endian: every record framed by its byte
//!   length as a 4-byte integer before and after; records: `[nblocks]`, `[dims...]`, one record
//!   of `x..., y...` per block. This is what VTK's PLOT3D reader (MultiGrid on,
//!   TwoDimensionalGeometry on, BinaryFile on, HasByteCount on, IBlanking off,
//!   DoublePrecision on) and most structured solvers take.
//! - `mesh.p3d`: the same numbers as formatted ASCII.

use super::text::{self, write_chunked};
use super::write_atomic;
use crate::mesh::BlockGrid;
use std::io::{self, Write};
use std::path::Path;

fn record(w: &mut impl Write, bytes: &[u8]) -> io::Result<()> {
    let len = u32::try_from(bytes.len())
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "Plot3D record over 4 GiB"))?;
    w.write_all(&len.to_le_bytes())?;
    w.write_all(bytes)?;
    w.write_all(&len.to_le_bytes())
}

fn dim(n: usize) -> io::Result<i32> {
    i32::try_from(n + 1)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "block too large for Plot3D"))
}

/// Write the Fortran-unformatted binary form.
pub fn write_binary(grids: &[BlockGrid], path: &Path) -> io::Result<()> {
    super::check_grids(grids)?;
    write_atomic(path, |w| {
        let nblocks = i32::try_from(grids.len())
            .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "too many blocks"))?;
        record(w, &nblocks.to_le_bytes())?;
        let mut dims = Vec::with_capacity(grids.len() * 8);
        for g in grids {
            dims.extend_from_slice(&dim(g.ni)?.to_le_bytes());
            dims.extend_from_slice(&dim(g.nj)?.to_le_bytes());
        }
        record(w, &dims)?;
        let mut buf = Vec::new();
        for g in grids {
            buf.clear();
            for axis in 0..2 {
                for p in &g.nodes {
                    buf.extend_from_slice(&p[axis].to_le_bytes());
                }
            }
            record(w, &buf)?;
        }
        Ok(())
    })
}

/// Write the formatted ASCII form (`{:e}` shortest round-trip values, one per line per block
/// and coordinate, wrapped at 4 values per line).
pub fn write_ascii(grids: &[BlockGrid], path: &Path) -> io::Result<()> {
    super::check_grids(grids)?;
    write_atomic(path, |w| {
        writeln!(w, "{}", grids.len())?;
        for g in grids {
            writeln!(w, "{} {}", dim(g.ni)?, dim(g.nj)?)?;
        }
        write_chunked(w, grids.len(), 16, |r, out| {
            for g in &grids[r] {
                for axis in 0..2 {
                    for (k, p) in g.nodes.iter().enumerate() {
                        text::exp(out, p[axis]);
                        let last = k % 4 == 3 || k + 1 == g.nodes.len();
                        out.push(if last { b'\n' } else { b' ' });
                    }
                }
            }
        })
    })
}
