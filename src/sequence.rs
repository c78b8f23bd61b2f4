//! Mesh sequences (tracker issue 6): one domain per frame (the same domain, holes moving),
//! meshed in parallel into `DIR/frame_NNNNN/`, with a ParaView time series `DIR/mesh.pvd`
//! and `DIR/summary.json`.
//!
//! # Determinism and reuse
//! Every frame's output is a pure function of that frame and the options: frames are meshed
//! independently (in parallel on a [`rayon`] pool of the requested size) and the summary is
//! assembled in frame order afterwards, so the files are byte-identical for any thread count
//! and identical to meshing each frame alone.
//!
//! # Same combinatorics
//! The medial combinatorics of a frame is the sorted list of circle triples of its medial
//! vertices (for a periodic frame: the orbits of the triples, each circle as `(hole, tile)`
//! normalised up to a period shift). When a frame's list equals the previous frame's, the
//! summary says so (`same_combinatorics_as_previous`). To let a solver map its fields, the
//! blocks of every frame are numbered canonically, by a key that depends on the combinatorics
//! only: `(wall circle, circles around corner 3, circles around corner 2)` (the circles
//! around a corner are the wall circles of the blocks meeting there). Two frames with the
//! same combinatorics therefore list the same blocks in the same order; whether their node
//! counts also agree (the counts only depend on the combinatorics except where a long wall
//! arc raises a count, see [`crate::grid::choose_counts`]) is reported as
//! `same_block_structure_as_previous` (same keys, same `ni x nj` per block). No information
//! flows from one frame to the next, so this reuse can never change a result.

use crate::domain::{AnyDomain, CircleId};
use crate::layout::BlockLayout;
use crate::mesh::Mesh;
use crate::mesher::{mesh, MeshError, Options};
use crate::output::{write_atomic, write_files, Format};
use crate::quality::measure;
use rayon::prelude::*;
use serde::Serialize;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// A circle in a combinatorial key: `(hole or -1, tile a, tile b)` (tiles `0` when bounded).
pub type CircleTag = (i64, i64, i64);

/// A meshed frame and its medial combinatorics.
#[derive(Debug, Clone)]
pub struct FrameMesh {
    pub mesh: Mesh,
    /// Sorted circle triples of the medial vertices.
    pub combinatorics: Vec<[CircleTag; 3]>,
}

/// Mesh one frame (bounded or periodic), with canonically numbered blocks (see the module
/// documentation).
pub fn mesh_frame(domain: &AnyDomain, options: &Options) -> Result<FrameMesh, MeshError> {
    let (mut m, combinatorics) = match domain {
        AnyDomain::Bounded(d) => {
            let m = mesh(d, options)?;
            let c = bounded_triples(&m.layout);
            (m, c)
        }
        AnyDomain::Periodic(p) => {
            if options.cells == 0 {
                return Err(MeshError::Options(
                    "--cells must be at least 1 (cells along a block side)".into(),
                ));
            }
            let pl = crate::periodic::periodic_layout(p, options)?;
            let grids = crate::grid::build_grids(&pl.layout, options.cells)?;
            let c = pl
                .triples
                .iter()
                .map(|t| t.map(|(k, a, b)| (k as i64, a as i64, b as i64)))
                .collect();
            (
                Mesh {
                    layout: pl.layout,
                    grids,
                    medial_vertices: pl.medial_vertices,
                    medial_arcs: pl.medial_arcs,
                    holes: p.hole_count(),
                    ..Mesh::default()
                },
                c,
            )
        }
    };
    canonical_order(&mut m);
    Ok(FrameMesh {
        mesh: m,
        combinatorics,
    })
}

/// The wall circles of the blocks meeting at each layout vertex, sorted and deduplicated.
fn vertex_circles(layout: &BlockLayout) -> Vec<Vec<CircleId>> {
    let mut out = vec![Vec::new(); layout.vertices.len()];
    for b in &layout.blocks {
        if let Some(w) = b.wall {
            for &c in &b.corners {
                if let Some(v) = out.get_mut(c as usize) {
                    v.push(w);
                }
            }
        }
    }
    for v in &mut out {
        v.sort_unstable();
        v.dedup();
    }
    out
}

/// Circle triples of the vertices where three or more cells meet (the medial vertices).
fn bounded_triples(layout: &BlockLayout) -> Vec<[CircleTag; 3]> {
    let mut out: Vec<[CircleTag; 3]> = vertex_circles(layout)
        .into_iter()
        .filter(|v| v.len() == 3)
        .map(|v| [0, 1, 2].map(|i| (v[i] as i64, 0, 0)))
        .collect();
    out.sort_unstable();
    out
}

/// The combinatorial key of each block.
fn block_keys(layout: &BlockLayout) -> Vec<(Option<CircleId>, Vec<CircleId>, Vec<CircleId>)> {
    let vc = vertex_circles(layout);
    layout
        .blocks
        .iter()
        .map(|b| {
            let at = |k: usize| vc.get(b.corners[k] as usize).cloned().unwrap_or_default();
            (b.wall, at(3), at(2))
        })
        .collect()
}

/// Renumber the blocks (and their grids) by their combinatorial key (stable).
fn canonical_order(m: &mut Mesh) {
    let keys = block_keys(&m.layout);
    let mut order: Vec<usize> = (0..keys.len()).collect();
    order.sort_by(|&a, &b| keys[a].cmp(&keys[b]));
    if order.len() != m.grids.len() {
        return;
    }
    let blocks = order.iter().map(|&i| m.layout.blocks[i].clone()).collect();
    let grids = order.iter().map(|&i| m.grids[i].clone()).collect();
    m.layout.blocks = blocks;
    m.grids = grids;
}

/// One frame's line of the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameSummary {
    pub index: usize,
    pub ok: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub blocks: usize,
    pub cells: usize,
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    pub inverted_cells: usize,
    /// The same circle triples form the medial vertices as in the previous frame (false for
    /// the first frame and next to a failed frame).
    pub same_combinatorics_as_previous: bool,
    /// Same canonical block keys and node counts as the previous frame.
    pub same_block_structure_as_previous: bool,
}

/// The whole run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SequenceSummary {
    pub frames: Vec<FrameSummary>,
    pub failed: usize,
}

/// Parse JSON Lines: one domain (bounded or periodic JSON) per non-blank line; a line that
/// does not parse or validate is kept as its error message (`line N: ...`).
pub fn parse_frames(text: &str) -> Vec<Result<AnyDomain, String>> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(n, l)| AnyDomain::from_json_str(l).map_err(|e| format!("line {}: {e}", n + 1)))
        .collect()
}

/// The directory of frame `index` under `dir`: `dir/frame_NNNNN`.
pub fn frame_dir(dir: &Path, index: usize) -> PathBuf {
    dir.join(format!("frame_{index:05}"))
}

struct Done {
    summary: FrameSummary,
    combinatorics: Option<Vec<[CircleTag; 3]>>,
    structure: Option<Vec<(String, [usize; 2])>>,
}

fn run_frame(
    index: usize,
    frame: &Result<AnyDomain, String>,
    options: &Options,
    formats: &[Format],
    dir: &Path,
) -> Done {
    let fail = |error: String| Done {
        summary: FrameSummary {
            index,
            ok: false,
            error: Some(error),
            blocks: 0,
            cells: 0,
            min_angle_deg: 0.0,
            max_angle_deg: 0.0,
            inverted_cells: 0,
            same_combinatorics_as_previous: false,
            same_block_structure_as_previous: false,
        },
        combinatorics: None,
        structure: None,
    };
    let domain = match frame {
        Ok(d) => d,
        Err(e) => return fail(e.clone()),
    };
    let fm = match mesh_frame(domain, options) {
        Ok(fm) => fm,
        Err(e) => return fail(e.to_string()),
    };
    if let Err(e) = write_files(&fm.mesh, &frame_dir(dir, index), formats) {
        return fail(format!("cannot write frame {index}: {e}"));
    }
    let q = measure(&fm.mesh.grids);
    let structure = block_keys(&fm.mesh.layout)
        .into_iter()
        .zip(&fm.mesh.grids)
        .map(|(k, g)| (format!("{k:?}"), [g.ni, g.nj]))
        .collect();
    Done {
        summary: FrameSummary {
            index,
            ok: true,
            error: None,
            blocks: fm.mesh.layout.blocks.len(),
            cells: q.cells,
            min_angle_deg: q.min_angle_deg,
            max_angle_deg: q.max_angle_deg,
            inverted_cells: q.inverted_cells,
            same_combinatorics_as_previous: false,
            same_block_structure_as_previous: false,
        },
        combinatorics: Some(fm.combinatorics),
        structure: Some(structure),
    }
}

/// Mesh every frame into `dir/frame_NNNNN/` with `formats`, on `threads` threads (0: rayon's
/// default), calling `progress` once per finished frame; then write `dir/mesh.pvd` (when
/// `formats` has VTK) and `dir/summary.json`. A frame that fails is reported in the summary
/// and does not stop the others. Errors: only failures to create `dir` or write the
/// summary files.
pub fn run_sequence(
    frames: &[Result<AnyDomain, String>],
    options: &Options,
    formats: &[Format],
    dir: &Path,
    threads: usize,
    progress: &(dyn Fn() + Sync),
) -> io::Result<SequenceSummary> {
    std::fs::create_dir_all(dir)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(io::Error::other)?;
    let done: Vec<Done> = pool.install(|| {
        frames
            .par_iter()
            .enumerate()
            .map(|(i, f)| {
                let d = run_frame(i, f, options, formats, dir);
                progress();
                d
            })
            .collect()
    });
    let mut out = Vec::with_capacity(done.len());
    for i in 0..done.len() {
        let mut s = done[i].summary.clone();
        if i > 0 {
            let (a, b) = (&done[i - 1], &done[i]);
            s.same_combinatorics_as_previous =
                a.combinatorics.is_some() && a.combinatorics == b.combinatorics;
            s.same_block_structure_as_previous = s.same_combinatorics_as_previous
                && a.structure.is_some()
                && a.structure == b.structure;
        }
        out.push(s);
    }
    let summary = SequenceSummary {
        failed: out.iter().filter(|f| !f.ok).count(),
        frames: out,
    };
    if formats.contains(&Format::Vtk) {
        write_pvd(&summary, &dir.join("mesh.pvd"))?;
    }
    write_atomic(&dir.join("summary.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &summary).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    Ok(summary)
}

/// Write the ParaView collection of the successful frames (`timestep` = frame index).
pub fn write_pvd(summary: &SequenceSummary, path: &Path) -> io::Result<()> {
    write_atomic(path, |w| {
        writeln!(w, "<?xml version=\"1.0\"?>")?;
        writeln!(
            w,
            "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">"
        )?;
        writeln!(w, "  <Collection>")?;
        for f in summary.frames.iter().filter(|f| f.ok) {
            writeln!(
                w,
                "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"frame_{:05}/mesh.vtm\"/>",
                f.index, f.index
            )?;
        }
        writeln!(w, "  </Collection>")?;
        writeln!(w, "</VTKFile>")
    })
}
