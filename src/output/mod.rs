//! Writers: VTK XML multiblock ([`vtk`]), SVG picture ([`svg`]), JSON report ([`report`]),
//! Plot3D ([`plot3d`]), Gmsh `.msh` ([`gmsh`]) and `.geo` ([`geo`]), block connectivity
//! ([`connectivity`]).
//!
//! Every writer is deterministic (same mesh, byte-identical files: floats are written with
//! Rust's shortest round-trip formatting or a fixed precision, and nothing depends on hash
//! order) and atomic per file: it writes `.NAME.tmp` in the target directory and renames it
//! onto `NAME` only after a successful flush, so a failed run never leaves a complete-looking
//! half file (the temporary file is removed on error).

pub mod connectivity;
pub mod geo;
pub mod gmsh;
pub mod plot3d;
pub mod png;
pub mod report;
pub mod svg;
pub mod vtk;

use crate::mesh::Mesh;
use crate::quality::well_formed;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Write `path` atomically: `body` writes into a buffered temporary file next to `path`,
/// which is renamed onto `path` only when everything succeeded.
pub fn write_atomic<F>(path: &Path, body: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("not a file path: {}", path.display()),
        )
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(".tmp");
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        body(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Check that the mesh has one well-formed grid per block, as every writer needs.
pub(crate) fn check_mesh(mesh: &Mesh) -> io::Result<()> {
    if mesh.grids.len() != mesh.layout.blocks.len() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "mesh has {} grids for {} blocks",
                mesh.grids.len(),
                mesh.layout.blocks.len()
            ),
        ));
    }
    if let Some(b) = mesh.grids.iter().position(|g| !well_formed(g)) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("grid {b}: node count does not match its ni, nj"),
        ));
    }
    Ok(())
}

/// Write `x` with the shortest representation that reads back to the same `f64`.
pub(crate) fn num<W: Write>(w: &mut W, x: f64) -> io::Result<()> {
    write!(w, "{x:?}")
}
