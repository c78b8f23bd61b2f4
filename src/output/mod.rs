//! Writers: VTK XML multiblock ([`vtk`]), SVG picture ([`svg`]), JSON report ([`report`]),
//! Plot3D ([`plot3d`]), Gmsh `.msh` ([`gmsh`]) and `.geo` ([`geo`]), block connectivity
//! ([`connectivity`]), VTK unstructured ([`vtu`]), and CGNS (`cgns`, with the cargo feature
//! `cgns`).
//!
//! Every writer is deterministic (same mesh, byte-identical files: floats are written with
//! Rust's shortest round-trip formatting or a fixed precision, and nothing depends on hash
//! order or on the number of threads) and atomic per file: it writes `.NAME.tmp` in the
//! target directory and renames it onto `NAME` only after a successful flush, so a failed run
//! never leaves a complete-looking half file (the temporary file is removed on error).
//! [`write_files`] goes further: it writes every file into a staging directory and moves them
//! into place at the end, `report.json` last, so a `report.json` marks a complete mesh.
//!
//! The text formats put their numbers through [`text`] (the bytes `std::fmt` writes, without
//! its machinery) and format their large arrays in parallel chunks that are written in order
//! ([`text::write_chunked`]); the `.vts` files are formatted one block per task.

pub mod binary;
pub mod connectivity;
pub mod geo;
pub mod gmsh;
pub mod plot3d;
pub mod png;
pub mod report;
pub mod svg;
#[doc(hidden)]
pub mod text;
pub mod vtk;
pub mod vtu;

#[cfg(feature = "cgns")]
pub mod cgns;

use crate::connectivity::Connectivity;
use crate::mesh::Mesh;
use crate::numbering::Numbering;
use crate::quality::well_formed;
pub use binary::Encoding;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Write `path` atomically: `body` writes into a buffered temporary file next to `path`,
/// which is renamed onto `path` only when everything succeeded ([`replace_file`]).
///
/// Guarantee: a file under its final name is always complete; a failed or interrupted run
/// leaves at most a hidden `.NAME.tmp` (removed on a reported error), never a truncated
/// `NAME`. The rename is atomic and comes after the whole body was written and flushed, which
/// is all that guarantee needs. There is deliberately no `fsync` (issue 8: it cost ~3 s for
/// 594 VTK block files): durability against a power loss or kernel crash right after the
/// run is left to the file system, as for any ordinary tool output.
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
        drop(file);
        replace_file(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Give the file `from` (just written) the name `to`, atomically: at every moment `to` names
/// the old file or the new one, complete.
///
/// A plain `rename` onto an existing file does that, but ext4 (`auto_da_alloc`, its default)
/// then starts writing the new file's data to the disk inside the call: ~3 ms for the 4 MB
/// `connectivity.json` of 1e3 bubbles, once per `.vts` block file, on every run into the same
/// directory (a solver remeshing each time step). On Linux, when `to` is an existing regular
/// file the two names are exchanged instead (`renameat2` with `RENAME_EXCHANGE`, one atomic
/// step that starts no write-back) and the old file, now named `from`, is removed. Where the
/// exchange fails (a file system or kernel without it, a filter refusing the call), and for
/// anything that is not an existing regular file, it is a plain `rename`. Either way no data
/// is forced to the disk ([`write_atomic`] has no `fsync` either).
pub fn replace_file(from: &Path, to: &Path) -> io::Result<()> {
    #[cfg(target_os = "linux")]
    if std::fs::symlink_metadata(to).is_ok_and(|m| m.file_type().is_file()) {
        // An exchange happens whole or not at all. When it fails (not supported by this
        // file system or this kernel, `to` gone meanwhile, anything else) the plain rename
        // below does what it always did, and reports its own error if there is one.
        if exchange(from, to).is_ok() {
            return std::fs::remove_file(from);
        }
    }
    std::fs::rename(from, to)
}

/// `renameat2(from, to, RENAME_EXCHANGE)`: swap two existing names atomically.
#[cfg(target_os = "linux")]
fn exchange(from: &Path, to: &Path) -> io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let c = |p: &Path| {
        std::ffi::CString::new(p.as_os_str().as_bytes())
            .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "path with a NUL byte"))
    };
    let (a, b) = (c(from)?, c(to)?);
    // SAFETY: two NUL-terminated paths that outlive the call, relative to the working
    // directory as `std::fs::rename`'s are; renameat2 reads them and returns a status.
    let status = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            a.as_ptr(),
            libc::AT_FDCWD,
            b.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if status == 0 {
        Ok(())
    } else {
        Err(io::Error::last_os_error())
    }
}

/// The error of a writer of grids given a mesh made without its nodes.
fn no_nodes() -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        "the mesh was made without its nodes (Options::keep_nodes false): only the json \
         format (report.json, connectivity.json) can be written from it",
    )
}

/// Check that every grid is well formed (its node count matches its `ni`, `nj`).
pub(crate) fn check_grids(grids: &[crate::mesh::BlockGrid]) -> io::Result<()> {
    match grids.iter().position(|g| !well_formed(g)) {
        Some(b) if grids[b].nodes.is_empty() && grids[b].cells() > 0 => Err(no_nodes()),
        Some(b) => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("grid {b}: node count does not match its ni, nj"),
        )),
        None => Ok(()),
    }
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
    if mesh.measured.is_some() {
        return Err(no_nodes());
    }
    check_grids(&mesh.grids)?;
    let (vertices, edges) = (mesh.layout.vertices.len(), mesh.layout.edges.len());
    let dangling = |block: &crate::layout::Block| {
        block.corners.iter().any(|&v| v as usize >= vertices)
            || block.sides.iter().any(|s| s.edge as usize >= edges)
    };
    if let Some(b) = mesh.layout.blocks.iter().position(dangling) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "block {b}: a corner or side names a vertex or edge the layout does not have \
                 ({vertices} vertices, {edges} edges)"
            ),
        ));
    }
    Ok(())
}

/// Blocks per chunk when the points or the cells of a run of blocks are formed in parallel.
const BLOCKS_PER_CHUNK: usize = 16;

/// The points of the merged mesh ([`Numbering`]) in id order, as `points(points, out)` formats
/// them:
/// the layout vertices in chunks of 4 096, then the points the blocks add, a chunk of blocks
/// at a time.
pub(crate) fn write_merged_points<W: Write>(
    w: &mut W,
    mesh: &Mesh,
    nodes: &Numbering,
    points: impl Fn(&[crate::geometry::Point], &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    let vertices = &mesh.layout.vertices;
    text::write_chunked(w, vertices.len(), 4096, |r, out| points(&vertices[r], out))?;
    text::write_chunked(w, mesh.grids.len(), BLOCKS_PER_CHUNK, |blocks, out| {
        let mut added = Vec::new();
        for b in blocks {
            added.clear();
            nodes.block_points(&mesh.layout, b, &mesh.grids[b], &mut added);
            points(&added, out);
        }
    })
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

/// The staging directory [`write_files`] uses inside the output directory.
pub fn staging_dir(dir: &Path) -> std::path::PathBuf {
    dir.join(format!(".medial-blocks-staging-{}", std::process::id()))
}

/// Write `mesh` into `dir` (created if missing) in each of `formats`, with the file names of
/// [`Format`]'s variants.
///
/// All or nothing, as far as the file system allows: every file is first written into a
/// staging directory inside `dir` ([`staging_dir`]), then renamed into place (a
/// subdirectory `dir` does not have yet, as `mesh/` on the first run, in one rename), index
/// files last: the VTK `mesh.vtm` after its block files and `report.json` after everything. So the
/// presence of `report.json` marks a complete mesh: when `json` is among the formats an older
/// `report.json` is removed before the first rename, and a run that fails at any point leaves
/// no `report.json` (and no staging directory; earlier files may have been replaced).
///
/// Called from a thread outside rayon's pool, the writing runs on one of its workers (the
/// caller waits; [`crate::timings::on_pool_worker`]).
pub fn write_files(mesh: &Mesh, dir: &Path, formats: &[Format]) -> io::Result<()> {
    write_files_encoded(mesh, dir, formats, Encoding::Ascii)
}

/// [`write_files`] with the formats that have a binary form (VTK `.vts` and `.vtu`, Gmsh
/// `.msh`) in `encoding` ([`binary`]).
pub fn write_files_encoded(
    mesh: &Mesh,
    dir: &Path,
    formats: &[Format],
    encoding: Encoding,
) -> io::Result<()> {
    crate::timings::on_pool_worker(|| {
        write_files_prepared(mesh, dir, formats, encoding, None, None, |_| {})
    })
}

/// [`write_files`], calling `progress(format)` before each format is written (for a
/// progress display).
pub fn write_files_with_progress(
    mesh: &Mesh,
    dir: &Path,
    formats: &[Format],
    progress: impl FnMut(Format),
) -> io::Result<()> {
    write_files_reporting(mesh, dir, formats, None, progress)
}

/// [`write_files_with_progress`] with `report.json` written from `report` (which must be
/// [`report::Report::from_mesh`]`(mesh)`) instead of measuring the mesh again: for a caller
/// that also shows the report (the CLI's summary), so the quality figures are computed once.
pub fn write_files_reporting(
    mesh: &Mesh,
    dir: &Path,
    formats: &[Format],
    report: Option<&report::Report>,
    progress: impl FnMut(Format),
) -> io::Result<()> {
    write_files_prepared(mesh, dir, formats, Encoding::Ascii, report, None, progress)
}

/// [`write_files_reporting`] with the block connectivity already computed: `conn` must be
/// [`Connectivity::new`]`(&mesh.layout, &mesh.grids)` when given (the CLI
/// computes it once for the report and `connectivity.json`), and the formats that have a
/// binary form written in `encoding`.
pub fn write_files_prepared(
    mesh: &Mesh,
    dir: &Path,
    formats: &[Format],
    encoding: Encoding,
    report: Option<&report::Report>,
    conn: Option<&Connectivity>,
    mut progress: impl FnMut(Format),
) -> io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let staging = staging_dir(dir);
    if staging.exists() {
        std::fs::remove_dir_all(&staging)?;
    }
    std::fs::create_dir(&staging)?;
    let prepared = Prepared {
        report,
        conn,
        encoding,
    };
    let result = write_into(mesh, &staging, formats, &prepared, &mut progress).and_then(|()| {
        if formats.contains(&Format::Json) {
            match std::fs::remove_file(dir.join("report.json")) {
                Err(e) if e.kind() != io::ErrorKind::NotFound => return Err(e),
                _ => {}
            }
        }
        publish(&staging, dir)
    });
    let cleanup = std::fs::remove_dir_all(&staging);
    result.and(cleanup)
}

/// Every file under `root`, relative to it, in the order [`write_files`] publishes them:
/// sorted, then `*.vtm`, then `report.json` last.
fn staged_files(root: &Path) -> io::Result<Vec<std::path::PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![std::path::PathBuf::new()];
    while let Some(rel) = stack.pop() {
        for entry in std::fs::read_dir(root.join(&rel))? {
            let entry = entry?;
            let path = rel.join(entry.file_name());
            if entry.file_type()?.is_dir() {
                stack.push(path);
            } else {
                out.push(path);
            }
        }
    }
    let rank = |p: &Path| {
        if p == Path::new("report.json") {
            2
        } else if p.extension().is_some_and(|e| e == "vtm") {
            1
        } else {
            0
        }
    };
    out.sort_by(|a, b| rank(a).cmp(&rank(b)).then_with(|| a.cmp(b)));
    Ok(out)
}

/// Rename every staged file into `dir`, creating subdirectories as needed. A staged
/// directory that `dir` does not have yet (the first run into `dir`: `mesh/` of the VTK
/// block files) moves in with one rename instead of one per file (5 896 block files for
/// 1 000 bubbles: 80 ms); one whose counterpart in `dir` holds only regular files that the
/// staged one replaces (an earlier run's block files, no more of them) is exchanged with it
/// in one step (Linux), the old one then removed: the end state of replacing its files one
/// by one, which is what happens otherwise (leaving the counterpart's other files alone).
fn publish(staging: &Path, dir: &Path) -> io::Result<()> {
    for entry in std::fs::read_dir(staging)? {
        let entry = entry?;
        if !entry.file_type()?.is_dir() {
            continue;
        }
        let target = dir.join(entry.file_name());
        match std::fs::symlink_metadata(&target) {
            // Made meanwhile by someone else: the rename fails or finds it empty; either way
            // the files that are still staged go one by one below.
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                let _ = std::fs::rename(entry.path(), &target);
            }
            // Nothing there that the staged files would not replace: the two directories
            // swap in one step, and the old one, now staged, is removed before anything else
            // is published.
            #[cfg(target_os = "linux")]
            Ok(m)
                if m.is_dir()
                    && all_replaced(&target, &entry.path())
                    && exchange(&entry.path(), &target).is_ok() =>
            {
                std::fs::remove_dir_all(entry.path())?;
            }
            _ => {}
        }
    }
    // The files come sorted, so a directory's files are together: each directory is made
    // once, not once per file (60 000 block files at 1e4 particles).
    let mut made: Option<std::path::PathBuf> = None;
    for rel in staged_files(staging)? {
        let target = dir.join(&rel);
        if let Some(parent) = target.parent() {
            if made.as_deref() != Some(parent) {
                std::fs::create_dir_all(parent)?;
                made = Some(parent.to_path_buf());
            }
        }
        replace_file(&staging.join(&rel), &target)?;
    }
    Ok(())
}

/// Whether `old` holds only regular files, each with a regular file of the same name in
/// `new` (so replacing `old`'s files by `new`'s one by one would leave exactly `new`'s;
/// false when either cannot be read).
#[cfg(target_os = "linux")]
fn all_replaced(old: &Path, new: &Path) -> bool {
    let files = |dir: &Path| -> Option<Vec<std::ffi::OsString>> {
        std::fs::read_dir(dir)
            .ok()?
            .map(|e| {
                let e = e.ok()?;
                e.file_type().ok()?.is_file().then(|| e.file_name())
            })
            .collect()
    };
    let (Some(old), Some(mut new)) = (files(old), files(new)) else {
        return false;
    };
    new.sort_unstable();
    old.iter().all(|name| new.binary_search(name).is_ok())
}

/// What the caller of [`write_files_prepared`] already computed.
struct Prepared<'a> {
    report: Option<&'a report::Report>,
    conn: Option<&'a Connectivity<'a>>,
    encoding: Encoding,
}

/// Write every format into `dir`, the staging directory of [`write_files_prepared`].
fn write_into(
    mesh: &Mesh,
    dir: &Path,
    formats: &[Format],
    prepared: &Prepared,
    progress: &mut impl FnMut(Format),
) -> io::Result<()> {
    for f in formats {
        progress(*f);
        let _stage = crate::timings::enter(crate::timings::writer_stage(f.name()));
        match f {
            Format::Vtu => vtu::write_vtu_encoded(mesh, &dir.join("mesh.vtu"), prepared.encoding)?,
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
            // In the staging directory: no temporary file per block.
            Format::Vtk => vtk::write_multiblock_with(mesh, dir, prepared.encoding, false)?,
            Format::Plot3d => {
                plot3d::write_binary(&mesh.grids, &dir.join("mesh.xyz"))?;
                plot3d::write_ascii(&mesh.grids, &dir.join("mesh.p3d"))?;
            }
            Format::Gmsh => {
                gmsh::write_msh_encoded(mesh, &dir.join("mesh.msh"), prepared.encoding)?;
                geo::write_geo(mesh, &dir.join("mesh.geo"))?;
            }
            Format::Svg => svg::write(mesh, &dir.join("mesh.svg"))?,
            Format::Png => png::write(mesh, &dir.join("mesh.png"))?,
            Format::Json => {
                let computed;
                let conn = match prepared.conn {
                    Some(c) => c,
                    None => {
                        computed = Connectivity::new(&mesh.layout, &mesh.grids)
                            .map_err(io::Error::other)?;
                        &computed
                    }
                };
                connectivity::write_json_from(conn, &dir.join("connectivity.json"))?;
                let path = dir.join("report.json");
                match prepared.report {
                    Some(r) => report::write_json(r, &path)?,
                    // The connectivity just written, not checked a second time.
                    None => report::write_json(
                        &report::Report::from_mesh_with(mesh, Some(conn)),
                        &path,
                    )?,
                }
            }
        }
    }
    Ok(())
}
