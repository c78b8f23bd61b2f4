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
//! normalised up to a period shift, tiles counted from nearest copies, so that a hole crossing
//! the box's edge changes nothing: [`crate::exact_mode::imposed::nearest_copy`]). When a
//! frame's list equals the previous frame's, the summary says so
//! (`same_combinatorics_as_previous`). The blocks of every frame are numbered
//! canonically by a key that depends on the combinatorics only
//! ([`crate::exact_mode::imposed::BlockKey`]: the wall circle and the counter-clockwise cycles
//! of circles at the two medial corners), so frames with the same combinatorics list the same
//! blocks in the same order (`same_block_structure_as_previous`).
//!
//! Exact mode sizes cells from the geometry, so two such frames need not have the same node
//! counts on their own. [`run_sequence`] therefore settles the frames in order: a frame that
//! continues a run is meshed with the counts of the run's first frame imposed by key and keeps
//! that mesh when it has those keys and counts, the run's combinatorics and no inverted cell
//! (`same_node_counts_as_previous`, `node_counts_from_frame`); else it is meshed with its own
//! counts, and continues the run with them (`node_counts_not_kept` says why) or starts a new
//! run. Every decision depends on the frames only, never on scheduling: the files are
//! byte-identical for any thread count.
//!
//! Each frame is meshed once when it keeps its run's counts, and written once (issue 8): a
//! wave of frames (as many as threads) is meshed in parallel with the run's counts, the
//! frames not kept are meshed again with their own, and the wave is settled in frame order up
//! to the first frame that starts a new run. A run's first frame is meshed alone (the frames
//! after it need its counts). An attempt whose counts no build applied
//! ([`ImposedCounts::applied`]: its keys never matched, as after a change of combinatorics)
//! made exactly the frame's own mesh, which is kept as such; and the attempts that a change
//! of run leaves unused are kept for the next wave, where they stand for the new run's
//! attempt when its counts could not be given to any of their builds either
//! ([`ImposedCounts::could_take`]). So a layout whose combinatorics change at every frame is
//! meshed once per frame too. Runs are decided on the meshes: a frame whose files cannot be
//! written is reported failed but does not end its run.

use crate::domain::{AnyDomain, CircleId};
use crate::exact_mode::imposed::{vertex_cycle, BlockKey, ImposedCounts, Offer};
use crate::layout::BlockLayout;
use crate::mesh::Mesh;
use crate::mesher::{mesh, MeshError, Options};
use crate::output::report::Report;
use crate::output::{write_atomic, write_files_prepared, Encoding, Format};
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
    // Frames are written with their nodes.
    let options = &*options.keeping_nodes();
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

/// What every frame writes: the formats, and the encoding of those with a binary form.
#[derive(Clone, Copy)]
struct Out<'a> {
    formats: &'a [Format],
    encoding: Encoding,
}

/// A meshed frame to write: its mesh, and its quality report when the formats write one
/// (measured once, for `report.json` and the summary line: issue 8).
struct Meshed {
    fm: FrameMesh,
    report: Option<Report>,
}

impl Meshed {
    /// Frame `index`'s mesh `fm` for a sequence that writes `out`, and what the summary and
    /// the run decisions need of it.
    fn new(index: usize, fm: FrameMesh, out: Out) -> (Done, Meshed) {
        let report = out
            .formats
            .contains(&Format::Json)
            .then(|| Report::from_mesh(&fm.mesh));
        let done = describe(index, &fm, report.as_ref());
        (done, Meshed { fm, report })
    }
}

/// Write frame `index`'s files into `dir/frame_NNNNN/` (`report.json` from `m.report`).
fn write_frame(index: usize, m: &Meshed, out: Out, dir: &Path) -> Result<(), String> {
    crate::timings::on_pool_worker(|| {
        write_files_prepared(
            &m.fm.mesh,
            &frame_dir(dir, index),
            out.formats,
            out.encoding,
            m.report.as_ref(),
            None,
            |_| {},
        )
    })
    .map_err(|e| format!("cannot write frame {index}: {e}"))
}

/// What the summary and the run decisions need of a meshed frame: its figures from
/// `report` when given (which must be [`Report::from_mesh`] of its mesh: the same figures as
/// [`measure`]), else measured.
fn describe(index: usize, fm: &FrameMesh, report: Option<&Report>) -> Done {
    let q = match report {
        Some(r) => (r.cells, r.min_angle_deg, r.max_angle_deg, r.inverted_cells),
        None => {
            let q = measure(&fm.mesh.grids);
            (q.cells, q.min_angle_deg, q.max_angle_deg, q.inverted_cells)
        }
    };
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
            cells: q.0,
            min_angle_deg: q.1,
            max_angle_deg: q.2,
            inverted_cells: q.3,
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

/// A run of frames with the same combinatorics: its first frame, that frame's unique block
/// keys with their counts (imposed on the later frames), and its combinatorics.
struct Run {
    start: usize,
    want: Structure,
    combinatorics: Vec<[CircleTag; 3]>,
}

impl Run {
    /// The run that a frame meshed with its own counts starts (`None` for a failed frame or
    /// one whose block keys are not unique: its counts cannot be imposed by key).
    fn starting_at(index: usize, d: &Done) -> Option<Run> {
        Some(Run {
            start: index,
            want: d.structure.clone()?,
            combinatorics: d.combinatorics.clone()?,
        })
        .filter(|_| d.summary.ok)
    }

    /// A frame meshed with its own counts continues this run: meshed, the same combinatorics
    /// and the same unique block keys as the run's first frame.
    fn continued_by(&self, d: &Done) -> bool {
        let same_keys = d.structure.as_ref().is_some_and(|y| {
            y.len() == self.want.len() && y.iter().zip(&self.want).all(|(p, q)| p.0 == q.0)
        });
        d.summary.ok && d.combinatorics.as_ref() == Some(&self.combinatorics) && same_keys
    }
}

/// Mesh frame `index` with its own counts.
fn own_mesh(index: usize, frame: &Result<AnyDomain, String>, options: &Options, out: Out) -> Own {
    match frame {
        Ok(d) => mesh_frame(d, options)
            .map(|fm| Meshed::new(index, fm, out))
            .map_err(|e| e.to_string()),
        Err(e) => Err(e.clone()),
    }
}

/// A frame meshed with its own counts: its summary line and mesh, or why it failed.
type Own = Result<(Done, Meshed), String>;

/// Why a frame does not keep its run's counts, and its own mesh when the attempt was it: a
/// build that never applied the imposed counts ([`ImposedCounts::applied`]; its keys did
/// not match the run's, as after a change of combinatorics) made exactly the mesh (or the
/// error) of the frame's own counts.
struct Rejected {
    why: String,
    own: Option<Box<Own>>,
    /// The builds the attempt's counts were offered to ([`ImposedCounts::offers`]).
    offers: Vec<Offer>,
}

/// Whether frame `fm` keeps `run`'s counts: `None` when it has exactly the run's keys and
/// counts, the run's combinatorics and no inverted cell, else why not.
fn verdict(fm: &FrameMesh, run: &Run) -> Option<String> {
    if fm.structure().as_ref() != Some(&run.want) {
        return Some("the run's node counts do not fit this frame's blocks".to_string());
    }
    if fm.combinatorics != run.combinatorics {
        return Some("with the run's node counts this frame's combinatorics differ".to_string());
    }
    match crate::quality::inverted_cells(&fm.mesh.grids) {
        0 => None,
        n => Some(format!(
            "the run's node counts give {n} inverted cells in this frame"
        )),
    }
}

/// [`with_run_counts`] for a frame whose own mesh (or error) `own` is known, from an attempt
/// with other counts that were never applied to the builds `offers`, when `run`'s counts could
/// not be given to any of them either ([`ImposedCounts::could_take`]): meshing with them would
/// make the same builds, so the outcome is judged on `own` without meshing again.
fn judged_again(own: Own, offers: Vec<Offer>, run: &Run) -> Result<(Done, Meshed), Rejected> {
    match own {
        Err(e) => Err(Rejected {
            why: format!("meshing with the run's counts failed: {e}"),
            own: Some(Box::new(Err(e))),
            offers,
        }),
        Ok((d, m)) => match verdict(&m.fm, run) {
            None => Ok((d, m)),
            Some(why) => Err(Rejected {
                why,
                own: Some(Box::new(Ok((d, m)))),
                offers,
            }),
        },
    }
}

/// Mesh a later frame of `run` with the run's counts imposed by key: `Ok` when the mesh is
/// kept (it has exactly the run's keys and counts, the run's combinatorics and no inverted
/// cell), else the reason (the frame is then meshed with its own counts, unless the attempt
/// already was that meshing, see [`Rejected`]).
fn with_run_counts(
    index: usize,
    frame: &Result<AnyDomain, String>,
    run: &Run,
    options: &Options,
    out: Out,
) -> Result<(Done, Meshed), Rejected> {
    let domain = frame.as_ref().map_err(|e| Rejected {
        why: e.clone(),
        own: Some(Box::new(Err(e.clone()))),
        offers: Vec::new(),
    })?;
    let imposed = std::sync::Arc::new(ImposedCounts::new(run.want.iter().cloned().collect()));
    let opts = Options {
        imposed_counts: Some(imposed.clone()),
        ..options.clone()
    };
    let meshed = mesh_frame(domain, &opts);
    // Without the counts applied, this was the frame's own meshing.
    let as_own = !imposed.applied();
    let offers = imposed.offers();
    let fm = meshed.map_err(|e| Rejected {
        why: format!("meshing with the run's counts failed: {e}"),
        own: as_own.then(|| Box::new(Err(e.to_string()))),
        offers: offers.clone(),
    })?;
    match verdict(&fm, run) {
        None => Ok(Meshed::new(index, fm, out)),
        Some(why) => Err(Rejected {
            why,
            own: as_own.then(|| Box::new(Ok(Meshed::new(index, fm, out)))),
            offers,
        }),
    }
}

/// Frame `index`'s summary line and decisions, and its mesh to write (none when it failed).
fn settle(index: usize, m: Own) -> (Done, Option<Meshed>) {
    match m {
        Ok((d, m)) => (d, Some(m)),
        Err(e) => (failed(index, e), None),
    }
}

/// Mesh every frame into `dir/frame_NNNNN/` with `formats` (those with a binary form in
/// `encoding`), on `threads` threads (0: rayon's default), calling `progress` once per frame
/// as it is settled; then write `dir/mesh.pvd` (when `formats` has VTK) and
/// `dir/summary.json`. A frame that fails is reported in the summary and does not stop the
/// others. Errors: only failures to create `dir` or write the summary files.
///
/// Node counts (issue 6), frame by frame in order: a frame that does not continue a run is
/// meshed with its own counts and starts a run (when it meshes and its block keys are
/// unique). A frame after a run's frame is meshed with the counts of the run's first frame
/// imposed by key ([`Options::imposed_counts`]) and continues the run when that mesh has
/// exactly the run's keys and counts, the run's combinatorics and no inverted cell. Else it
/// is meshed with its own counts: it continues the run when it has the run's combinatorics
/// and block keys (the summary then says why the run's counts were not kept, unless its own
/// counts are the run's), and starts a new run otherwise. A failed frame ends its run; a
/// frame whose files cannot be written is reported failed without ending its run.
///
/// Each frame is meshed once when it continues a run with the run's counts (issue 8: the
/// earlier two passes meshed every later frame of a run twice). The frames are taken a wave
/// at a time (as many as threads): with a run going on, the wave's frames are meshed in
/// parallel with the run's counts, those not kept again with their own, and the wave is
/// settled in frame order up to the first frame that starts a new run (the frames after it
/// are meshed again in the next wave, with the new run's counts); a frame that continues no
/// run is meshed alone (its mesh uses every thread). Every decision is the sequential rule
/// above, so the output is the same for any thread count and any scheduling.
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
    let wave = pool.install(rayon::current_num_threads).max(1);
    let mut done: Vec<Done> = Vec::with_capacity(frames.len());
    let mut start: Vec<usize> = Vec::with_capacity(frames.len());
    let mut run: Option<Run> = None;
    // Attempts of frames after a change of run, whose counts were never applied: their own
    // meshes, and the builds they were offered (see [`judged_again`]).
    let mut spare: Vec<Option<(Own, Vec<Offer>)>> = (0..frames.len()).map(|_| None).collect();
    let mut i = 0;
    while i < frames.len() {
        // The frames settled by this wave, with the meshes to write.
        let mut to_write: Vec<(usize, Meshed)> = Vec::new();
        let settled_before = done.len();
        match run.take() {
            None => {
                // An unused attempt whose counts were never applied is the own mesh.
                let own = match spare[i].take() {
                    Some((own, _)) => own,
                    None => pool.install(|| own_mesh(i, &frames[i], options, out)),
                };
                let (d, m) = settle(i, own);
                run = Run::starting_at(i, &d);
                start.push(i);
                done.push(d);
                to_write.extend(m.map(|m| (i, m)));
                i += 1;
            }
            Some(r) => {
                let last = (i + wave).min(frames.len());
                let want = ImposedCounts::new(r.want.iter().cloned().collect());
                let known: Vec<Option<(Own, Vec<Offer>)>> = (i..last)
                    .map(|k| spare[k].take().filter(|(_, o)| !want.could_take(o)))
                    .collect();
                let mut tries: Vec<Option<Result<(Done, Meshed), Rejected>>> = pool.install(|| {
                    (i..last)
                        .into_par_iter()
                        .zip(known)
                        .map(|(k, known)| {
                            Some(match known {
                                Some((own, offers)) => judged_again(own, offers, &r),
                                None => with_run_counts(k, &frames[k], &r, options, out),
                            })
                        })
                        .collect()
                });
                // The frames not kept whose own mesh is still to be made.
                let rejected: Vec<usize> = (i..last)
                    .filter(|&k| matches!(&tries[k - i], Some(Err(r)) if r.own.is_none()))
                    .collect();
                let mut owns: Vec<Option<Own>> = pool.install(|| {
                    rejected
                        .par_iter()
                        .map(|&k| Some(own_mesh(k, &frames[k], options, out)))
                        .collect()
                });
                let mut next = last;
                let mut continuing = Some(r);
                for k in i..last {
                    let (Some(r), Some(tried)) = (continuing.take(), tries[k - i].take()) else {
                        break;
                    };
                    let Rejected { why, own, .. } = match tried {
                        Ok((d, m)) => {
                            start.push(r.start);
                            done.push(d);
                            to_write.push((k, m));
                            continuing = Some(r);
                            continue;
                        }
                        Err(rejected) => rejected,
                    };
                    let own = own
                        .map(|own| *own)
                        .or_else(|| {
                            let slot = rejected.binary_search(&k).ok()?;
                            owns[slot].take()
                        })
                        .unwrap_or_else(|| Err("internal: frame not meshed".into()));
                    let (mut d, m) = settle(k, own);
                    to_write.extend(m.map(|m| (k, m)));
                    if r.continued_by(&d) {
                        if d.structure.as_ref() != Some(&r.want) {
                            d.summary.node_counts_not_kept = Some(why);
                        }
                        start.push(r.start);
                        done.push(d);
                        continuing = Some(r);
                    } else {
                        start.push(k);
                        continuing = Run::starting_at(k, &d);
                        done.push(d);
                        // The wave's later frames were meshed for the run that ended.
                        next = k + 1;
                        break;
                    }
                }
                // Keep the own meshes among the attempts the change of run left unused.
                for k in next..last {
                    if let Some(Err(Rejected {
                        own: Some(own),
                        offers,
                        ..
                    })) = tries[k - i].take()
                    {
                        spare[k] = Some((*own, offers));
                    }
                }
                run = continuing;
                i = next;
            }
        }
        // Once per frame settled (failed ones too).
        for _ in settled_before..done.len() {
            progress();
        }
        let written: Vec<(usize, Result<(), String>)> = pool.install(|| {
            to_write
                .par_iter()
                .map(|(k, m)| (*k, write_frame(*k, m, out, dir)))
                .collect()
        });
        for (k, r) in written {
            if let Err(e) = r {
                done[k] = failed(k, e);
            }
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
