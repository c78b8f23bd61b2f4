//! Writers: VTK XML multiblock ([`vtk`]), SVG picture ([`svg`]), JSON report ([`report`]),
//! Plot3D ([`plot3d`]), Gmsh `.msh` ([`gmsh`]) and `.geo` ([`geo`]), block connectivity
//! ([`connectivity`]), VTK unstructured ([`vtu`]), and CGNS (`cgns`, with the cargo feature
//! `cgns`).
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
pub mod vtu;

#[cfg(feature = "cgns")]
pub mod cgns;

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

/// A writer the CLI's `--format` can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Format {
    /// `mesh.vtm` + `mesh/block_NNNN.vts` (VTK XML multiblock).
    Vtk,
    /// `mesh.vtu` (VTK XML unstructured grid, nodes merged across blocks).
    Vtu,
    /// `mesh.xyz` (Plot3D binary) + `mesh.p3d` (Plot3D ASCII).
    Plot3d,
    /// `mesh.msh` (Gmsh 4.1) + `mesh.geo` (Gmsh script of the block layout).
    Gmsh,
    /// `mesh.svg`.
    Svg,
    /// `mesh.png`.
    Png,
    /// `report.json` + `connectivity.json`.
    Json,
    /// `mesh.cgns` (needs the cargo feature `cgns`; without it writing fails with
    /// `Unsupported` and [`Format::parse_list`] refuses the name).
    Cgns,
}

impl Format {
    /// Every format this build can write, in writing order (`cgns` only with the feature).
    pub const ALL: &'static [Format] = &[
        Format::Vtk,
        Format::Vtu,
        Format::Plot3d,
        Format::Gmsh,
        Format::Svg,
        Format::Png,
        Format::Json,
        #[cfg(feature = "cgns")]
        Format::Cgns,
    ];
    /// The files (relative to the output directory) this format writes; `mesh/*.vts` stands
    /// for the block files of the VTK multiblock.
    pub fn file_names(self) -> &'static [&'static str] {
        match self {
            Format::Vtk => &["mesh.vtm", "mesh/*.vts"],
            Format::Vtu => &["mesh.vtu"],
            Format::Plot3d => &["mesh.xyz", "mesh.p3d"],
            Format::Gmsh => &["mesh.msh", "mesh.geo"],
            Format::Svg => &["mesh.svg"],
            Format::Png => &["mesh.png"],
            Format::Json => &["report.json", "connectivity.json"],
            Format::Cgns => &["mesh.cgns"],
        }
    }
    /// The name used by `--format`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Vtk => "vtk",
            Format::Vtu => "vtu",
            Format::Cgns => "cgns",
            Format::Plot3d => "plot3d",
            Format::Gmsh => "gmsh",
            Format::Svg => "svg",
            Format::Png => "png",
            Format::Json => "json",
        }
    }
    /// Parse a comma-separated list (`all` = every format); `Err` names the unknown item.
    pub fn parse_list(list: &str) -> Result<Vec<Format>, String> {
        let mut out = Vec::new();
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            if item == "all" {
                out.extend(Format::ALL);
            } else if let Some(f) = Format::ALL.iter().find(|f| f.name() == item) {
                out.push(*f);
            } else if item == "cgns" {
                return Err("format 'cgns' needs a build with the cgns feature: \
                     apt-get install libcgns-dev, then cargo build --release --features cgns"
                    .into());
            } else {
                let names: Vec<&str> = Format::ALL.iter().map(|f| f.name()).collect();
                return Err(format!(
                    "unknown format '{item}' (choose from {}, or all)",
                    names.join(", ")
                ));
            }
        }
        if out.is_empty() {
            return Err("no format named".into());
        }
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }
}

/// Write `mesh` into `dir` (created if missing) in each of `formats`, with the file names of
/// [`Format`]'s variants.
pub fn write_files(mesh: &Mesh, dir: &Path, formats: &[Format]) -> io::Result<()> {
    write_files_with_progress(mesh, dir, formats, |_| {})
}

/// [`write_files`], calling `progress(format)` before each format is written (for a
/// progress display).
pub fn write_files_with_progress(
    mesh: &Mesh,
    dir: &Path,
    formats: &[Format],
    mut progress: impl FnMut(Format),
) -> io::Result<()> {
    std::fs::create_dir_all(dir)?;
    for f in formats {
        progress(*f);
        match f {
            Format::Vtu => vtu::write_vtu(mesh, &dir.join("mesh.vtu"))?,
            #[cfg(feature = "cgns")]
            Format::Cgns => cgns::write_cgns(mesh, &dir.join("mesh.cgns"))?,
            #[cfg(not(feature = "cgns"))]
            Format::Cgns => {
                return Err(io::Error::new(
                    io::ErrorKind::Unsupported,
                    "CGNS output needs a build with the cgns feature \
                     (apt-get install libcgns-dev; cargo build --release --features cgns)",
                ))
            }
            Format::Vtk => vtk::write_multiblock(mesh, dir)?,
            Format::Plot3d => {
                plot3d::write_binary(&mesh.grids, &dir.join("mesh.xyz"))?;
                plot3d::write_ascii(&mesh.grids, &dir.join("mesh.p3d"))?;
            }
            Format::Gmsh => {
                gmsh::write_msh(mesh, &dir.join("mesh.msh"))?;
                geo::write_geo(mesh, &dir.join("mesh.geo"))?;
            }
            Format::Svg => svg::write(mesh, &dir.join("mesh.svg"))?,
            Format::Png => png::write(mesh, &dir.join("mesh.png"))?,
            Format::Json => {
                let conn = crate::connectivity::connectivity(&mesh.layout, &mesh.grids)
                    .map_err(io::Error::other)?;
                connectivity::write_json(&conn, &dir.join("connectivity.json"))?;
                report::write_json(&report::Report::from_mesh(mesh), &dir.join("report.json"))?;
            }
        }
    }
    Ok(())
}
