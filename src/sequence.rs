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
//! # Same combinatorics, same blocks, same node counts
//! The medial combinatorics of a frame is the sorted list of circle triples of its medial
//! vertices (for a periodic frame: the orbits of the triples, each circle as `(hole, tile)`
//! normalised up to a period shift). When a frame's list equals the previous frame's, the
//! summary says so (`same_combinatorics_as_previous`). The blocks of every frame are numbered
//! canonically by a key that depends on the combinatorics only
//! ([`crate::exact_mode::imposed::BlockKey`]: the wall circle and the counter-clockwise cycles
//! of circles at the two medial corners), so frames with the same combinatorics list the same
//! blocks in the same order (`same_block_structure_as_previous`).
//!
//! Exact mode sizes cells from the geometry, so two such frames need not have the same node
//! counts on their own. [`run_sequence`] therefore meshes in two passes: every frame with its
//! own counts, then every later frame of a run of equal combinatorics again with the counts
//! of the run's first frame imposed by key; the result is kept when it has those counts and
//! no inverted cell (`same_node_counts_as_previous`, `node_counts_from_frame`), else the
//! frame keeps its own counts (`node_counts_not_kept` says why). Every decision depends on the
//! frames only, never on scheduling: the files are byte-identical for any thread count.
//!
//! Each frame's files are written once (issue 8): pass 1 meshes a wave of frames (as many
//! as threads) at a time, decides in frame order which are later frames of a run to be meshed
//! again, and writes only the others; pass 2 writes the frames it meshes again (or, when the
//! run's counts are not kept, the frame's own mesh, meshed once more). Runs are decided on the
//! meshes: a frame whose files cannot be written is reported failed but does not end its run.

use crate::domain::{AnyDomain, CircleId};
use crate::exact_mode::imposed::{vertex_cycle, BlockKey, ImposedCounts};
use crate::layout::BlockLayout;
use crate::mesh::Mesh;
use crate::mesher::{mesh, MeshError, Options};
use crate::output::{write_atomic, write_files_encoded, Encoding, Format};
use crate::quality::measure;
use rayon::prelude::*;
use serde::Serialize;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// A circle in a combinatorial key: `(hole or -1, tile a, tile b)` (tiles `0` when bounded).
pub use crate::exact_mode::imposed::CircleTag;

/// A meshed frame and its medial combinatorics.
#[derive(Debug, Clone)]
pub struct FrameMesh {
    pub mesh: Mesh,
    /// Sorted circle triples of the medial vertices.
    pub combinatorics: Vec<[CircleTag; 3]>,
    /// The key of each block, in block order ([`crate::exact_mode::imposed`]); `None` for a
    /// periodic mesh in paper mode (its keys would not tell the tiles apart).
    pub keys: Option<Vec<BlockKey>>,
}

impl FrameMesh {
    /// `(key, [ni, nj])` per block, in block order, when the keys are known and unique
    /// (then node counts can be imposed by key).
    pub fn structure(&self) -> Option<Vec<(BlockKey, [usize; 2])>> {
        let keys = self.keys.as_ref()?;
        if keys.len() != self.mesh.grids.len() || keys.windows(2).any(|w| w[0] >= w[1]) {
            return None;
        }
        Some(
            keys.iter()
                .cloned()
                .zip(self.mesh.grids.iter().map(|g| [g.ni, g.nj]))
                .collect(),
        )
    }
}

/// Mesh one frame (bounded or periodic), with canonically numbered blocks (see the module
/// documentation).
pub fn mesh_frame(domain: &AnyDomain, options: &Options) -> Result<FrameMesh, MeshError> {
    let (mut m, combinatorics, keys) = match domain {
        AnyDomain::Bounded(d) => {
            let m = mesh(d, options)?;
            let c = bounded_triples(&m.layout);
            let k = layout_keys(&m.layout);
            (m, c, Some(k))
        }
        AnyDomain::Periodic(p) => {
            let f = crate::periodic::mesh_periodic_frame(p, options)?;
            let c = f
                .triples
                .iter()
                .map(|t| t.map(|(k, a, b)| (k as i64, a as i64, b as i64)))
                .collect();
            (f.mesh, c, f.keys)
        }
    };
    let keys = canonical_order(&mut m, keys);
    Ok(FrameMesh {
        mesh: m,
        combinatorics,
        keys,
    })
}

/// The key of each block of a bounded layout, read from its geometry: at a medial corner,
/// the wall circles of the blocks meeting there, ordered by the angle of their wall corner
/// ([`vertex_cycle`]); blocks without a wall (templates) get the tag `(-2, 0, 0)`; the pieces of
/// one hole's medial loop are numbered ([`crate::exact_mode::imposed::number_loop_pieces`]).
pub fn layout_keys(layout: &BlockLayout) -> Vec<BlockKey> {
    let pos = |v: u32| layout.vertices.get(v as usize).copied().unwrap_or([0.0; 2]);
    let mut touching: Vec<Vec<(CircleTag, crate::geometry::Point)>> =
        vec![Vec::new(); layout.vertices.len()];
    for b in &layout.blocks {
        if let Some(w) = b.wall {
            let tag = (w as i64, 0, 0);
            for (corner, wall_corner) in [(3, 0), (2, 1)] {
                if let Some(t) = touching.get_mut(b.corners[corner] as usize) {
                    t.push((tag, pos(b.corners[wall_corner])));
                }
            }
        }
    }
    let cycles: Vec<Vec<CircleTag>> = touching
        .iter()
        .enumerate()
        .map(|(v, t)| vertex_cycle(pos(v as u32), t))
        .collect();
    let cycle = |v: u32| cycles.get(v as usize).cloned().unwrap_or_default();
    let mut keys: Vec<BlockKey> = layout
        .blocks
        .iter()
        .map(|b| {
            let wall = b.wall.map_or((-2, 0, 0), |w| (w as i64, 0, 0));
            (wall, cycle(b.corners[3]), cycle(b.corners[2]))
        })
        .collect();
    crate::exact_mode::imposed::number_loop_pieces(&mut keys);
    keys
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

/// Renumber the blocks (and their grids) by their key (stable): the [`BlockKey`]s when
/// known, else the coarser [`block_keys`]. Returns the keys in the new order.
fn canonical_order(m: &mut Mesh, keys: Option<Vec<BlockKey>>) -> Option<Vec<BlockKey>> {
    let n = m.layout.blocks.len();
    if m.grids.len() != n || keys.as_ref().is_some_and(|k| k.len() != n) {
        return keys;
    }
    let mut order: Vec<usize> = (0..n).collect();
    match &keys {
        Some(k) => order.sort_by(|&a, &b| k[a].cmp(&k[b])),
        None => {
            let k = block_keys(&m.layout);
            order.sort_by(|&a, &b| k[a].cmp(&k[b]));
        }
    }
    m.layout.blocks = order.iter().map(|&i| m.layout.blocks[i].clone()).collect();
    m.grids = order.iter().map(|&i| m.grids[i].clone()).collect();
    keys.map(|k| order.iter().map(|&i| k[i].clone()).collect())
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
    /// The same blocks (the same canonical block keys, in the same order) as the previous
    /// frame.
    pub same_block_structure_as_previous: bool,
    /// The same blocks with the same `ni x nj` each as the previous frame: a solver can map
    /// its fields node for node.
    pub same_node_counts_as_previous: bool,
    /// The frame whose node counts this frame uses: the first frame of its run of frames with
    /// the same combinatorics (absent when the frame uses its own counts).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node_counts_from_frame: Option<usize>,
    /// Why the run's node counts could not be kept (the frame then uses its own).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node_counts_not_kept: Option<String>,
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

/// `(key, [ni, nj])` per block in block order.
type Structure = Vec<(BlockKey, [usize; 2])>;

struct Done {
    summary: FrameSummary,
    combinatorics: Option<Vec<[CircleTag; 3]>>,
    /// Keys and counts (unique keys only).
    structure: Option<Structure>,
    /// Block keys in order (also when not unique), to compare structures.
    keys: Option<Vec<String>>,
    /// `[ni, nj]` of each block in block order (empty for a failed frame), to compare node
    /// counts also when the keys are not unique.
    counts: Vec<[usize; 2]>,
}

fn failed(index: usize, error: String) -> Done {
    Done {
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
            same_node_counts_as_previous: false,
            node_counts_from_frame: None,
            node_counts_not_kept: None,
        },
        combinatorics: None,
        structure: None,
        counts: Vec::new(),
        keys: None,
    }
}

/// Mesh frame `index` (with `options`, which may impose counts) and write it.
fn run_frame(
    index: usize,
    frame: &Result<AnyDomain, String>,
    options: &Options,
    out: Out,
    dir: &Path,
) -> Done {
    let domain = match frame {
        Ok(d) => d,
        Err(e) => return failed(index, e.clone()),
    };
    let fm = match mesh_frame(domain, options) {
        Ok(fm) => fm,
        Err(e) => return failed(index, e.to_string()),
    };
    finish(index, fm, out, dir)
}

/// What every frame writes: the formats, and the encoding of those with a binary form.
#[derive(Clone, Copy)]
struct Out<'a> {
    formats: &'a [Format],
    encoding: Encoding,
}

/// Write frame `index`'s files and describe it (a failed frame when writing fails).
fn finish(index: usize, fm: FrameMesh, out: Out, dir: &Path) -> Done {
    match write_frame(index, &fm, out, dir) {
        Ok(()) => describe(index, &fm),
        Err(e) => failed(index, e),
    }
}

/// Write frame `index`'s files into `dir/frame_NNNNN/`.
fn write_frame(index: usize, fm: &FrameMesh, out: Out, dir: &Path) -> Result<(), String> {
    write_files_encoded(&fm.mesh, &frame_dir(dir, index), out.formats, out.encoding)
        .map_err(|e| format!("cannot write frame {index}: {e}"))
}

/// What the summary and the run decisions need of a meshed frame.
fn describe(index: usize, fm: &FrameMesh) -> Done {
    let q = measure(&fm.mesh.grids);
    let keys = match &fm.keys {
        Some(k) => k.iter().map(|k| format!("{k:?}")).collect(),
        None => block_keys(&fm.mesh.layout)
            .iter()
            .map(|k| format!("{k:?}"))
            .collect(),
    };
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
            same_node_counts_as_previous: false,
            node_counts_from_frame: None,
            node_counts_not_kept: None,
        },
        structure: fm.structure(),
        counts: fm.mesh.grids.iter().map(|g| [g.ni, g.nj]).collect(),
        combinatorics: Some(fm.combinatorics.clone()),
        keys: Some(keys),
    }
}

/// Frames `i - 1` and `i` are in one run: both meshed, the same combinatorics and the same
/// unique block keys.
fn linked(a: &Done, b: &Done) -> bool {
    let same_keys = match (&a.structure, &b.structure) {
        (Some(x), Some(y)) => x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.0 == q.0),
        _ => false,
    };
    a.summary.ok
        && b.summary.ok
        && a.combinatorics.is_some()
        && a.combinatorics == b.combinatorics
        && same_keys
}

/// Mesh every frame into `dir/frame_NNNNN/` with `formats` (those with a binary form in
/// `encoding`), on `threads` threads (0: rayon's
/// default), calling `progress` once per frame of the first pass; then write `dir/mesh.pvd`
/// (when `formats` has VTK) and `dir/summary.json`. A frame that fails is reported in the
/// summary and does not stop the others. Errors: only failures to create `dir` or write the
/// summary files.
///
/// Node counts (issue 6): pass 1 meshes every frame with its own counts. Consecutive frames
/// with the same combinatorics and the same unique block keys form a *run*; every later
/// frame of a run is meshed again in pass 2 with the counts of the run's first frame imposed
/// by key ([`Options::imposed_counts`]). The result is kept if it has exactly those keys and
/// counts and no inverted cell, else the frame keeps its own counts and the summary says why
/// (`node_counts_not_kept`). Both passes depend only on the frames, so the output is the
/// same for any thread count and any scheduling.
pub fn run_sequence(
    frames: &[Result<AnyDomain, String>],
    options: &Options,
    formats: &[Format],
    encoding: Encoding,
    dir: &Path,
    threads: usize,
    progress: &(dyn Fn() + Sync),
) -> io::Result<SequenceSummary> {
    std::fs::create_dir_all(dir)?;
    let out = Out { formats, encoding };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(io::Error::other)?;
    // Pass 1, a wave of frames at a time (as many as threads, so as many meshes held as
    // before): mesh them in parallel, then decide in frame order which are runs' later frames
    // to be meshed again with their run's counts, and write only the others. A frame meshed
    // again is written once, by pass 2 (issue 8: a moving layout re-meshes nearly every
    // frame, and the writing, not the meshing, is most of a frame with the VTK files).
    let wave = pool.install(rayon::current_num_threads).max(1);
    let mut done: Vec<Done> = Vec::with_capacity(frames.len());
    let mut start: Vec<usize> = Vec::with_capacity(frames.len());
    let mut redo: Vec<(usize, Structure)> = Vec::new();
    for first in (0..frames.len()).step_by(wave) {
        let last = (first + wave).min(frames.len());
        let meshed: Vec<Result<FrameMesh, String>> = pool.install(|| {
            (first..last)
                .into_par_iter()
                .map(|i| {
                    let m = match &frames[i] {
                        Ok(d) => mesh_frame(d, options).map_err(|e| e.to_string()),
                        Err(e) => Err(e.clone()),
                    };
                    progress();
                    m
                })
                .collect()
        });
        let mut to_write = Vec::new();
        for (i, m) in (first..last).zip(meshed) {
            let d = match &m {
                Ok(fm) => describe(i, fm),
                Err(e) => failed(i, e.clone()),
            };
            let s = match done.last() {
                Some(prev) if linked(prev, &d) => start[i - 1],
                _ => i,
            };
            let want = (s != i)
                .then(|| done[s].structure.clone())
                .flatten()
                .filter(|want| d.structure.as_ref() != Some(want));
            start.push(s);
            done.push(d);
            match (m, want) {
                (Ok(_), Some(want)) => redo.push((i, want)),
                (Ok(fm), None) => to_write.push((i, fm)),
                (Err(_), _) => {}
            }
        }
        let written: Vec<(usize, Result<(), String>)> = pool.install(|| {
            to_write
                .par_iter()
                .map(|(i, fm)| (*i, write_frame(*i, fm, out, dir)))
                .collect()
        });
        for (i, r) in written {
            if let Err(e) = r {
                done[i] = failed(i, e);
            }
        }
    }
    let redone: Vec<(usize, Result<Done, String>)> = pool.install(|| {
        redo.par_iter()
            .map(|(i, want)| (*i, reuse_counts(*i, &frames[*i], want, options, out, dir)))
            .collect()
    });
    for (i, r) in redone {
        match r {
            Ok(d) => done[i] = d,
            Err(why) => done[i].summary.node_counts_not_kept = Some(why),
        }
    }
    // A frame that keeps its own counts was not written in pass 1: mesh it again (the same
    // mesh: a frame's mesh is a function of the frame) and write it.
    let own: Vec<usize> = redo
        .iter()
        .map(|(i, _)| *i)
        .filter(|&i| done[i].summary.node_counts_not_kept.is_some())
        .collect();
    let rewritten: Vec<(usize, Done)> = pool.install(|| {
        own.par_iter()
            .map(|&i| (i, run_frame(i, &frames[i], options, out, dir)))
            .collect()
    });
    for (i, d) in rewritten {
        if !d.summary.ok {
            done[i] = d;
        }
    }
    let mut out = Vec::with_capacity(done.len());
    for i in 0..done.len() {
        let mut s = done[i].summary.clone();
        if s.ok && start[i] != i && s.node_counts_not_kept.is_none() {
            s.node_counts_from_frame = Some(start[i]);
        }
        if i > 0 {
            let (a, b) = (&done[i - 1], &done[i]);
            s.same_combinatorics_as_previous =
                a.combinatorics.is_some() && a.combinatorics == b.combinatorics;
            s.same_block_structure_as_previous =
                s.same_combinatorics_as_previous && a.keys.is_some() && a.keys == b.keys;
            // The same keys in the same order: the same counts in order are the same counts
            // per block, also when the keys are not unique (then no counts were imposed, but
            // identical frames still have identical counts).
            s.same_node_counts_as_previous =
                s.same_block_structure_as_previous && a.counts == b.counts;
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

/// Pass 2 for frame `index`: mesh it with the counts `want` imposed; `Err` (why) when the
/// result does not have exactly those keys and counts or has an inverted cell (nothing is
/// written then).
fn reuse_counts(
    index: usize,
    frame: &Result<AnyDomain, String>,
    want: &Structure,
    options: &Options,
    out: Out,
    dir: &Path,
) -> Result<Done, String> {
    let domain = frame.as_ref().map_err(|e| e.clone())?;
    let imposed = ImposedCounts(want.iter().cloned().collect());
    let opts = Options {
        imposed_counts: Some(std::sync::Arc::new(imposed)),
        ..options.clone()
    };
    let fm = mesh_frame(domain, &opts)
        .map_err(|e| format!("meshing with the run's counts failed: {e}"))?;
    if fm.structure().as_ref() != Some(want) {
        return Err("the run's node counts do not fit this frame's blocks".into());
    }
    let inverted = crate::quality::inverted_cells(&fm.mesh.grids);
    if inverted > 0 {
        return Err(format!(
            "the run's node counts give {inverted} inverted cells in this frame"
        ));
    }
    let d = finish(index, fm, out, dir);
    if d.summary.ok {
        Ok(d)
    } else {
        Err(d.summary.error.unwrap_or_default())
    }
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
