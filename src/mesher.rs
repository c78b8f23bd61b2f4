//! The one call: a validated [`Domain`] and [`Options`] in, a [`Mesh`] or a typed error out.

use crate::domain::{CircleId, Domain, DomainError};
use crate::exact_mode::Clustering;
use crate::geometry::TriangulationError;
use crate::grid::{build_grids, GridError};
use crate::mesh::{Geometry, Mesh};
use crate::sampling::SamplingOptions;
use crate::{blocking, exact_mode, templates, timings};

/// Which geometry the blocks are built on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Exact medial axis (Apollonius vertices, conic arcs) and spoke-aligned grids: every
    /// wall-normal grid line exactly normal to its wall, no folding ([`crate::exact_mode`]).
    #[default]
    Exact,
    /// The paper exactly as written: circumcenter polylines, equally spaced TFI.
    Paper,
}

/// Exact mode: how many times sampling is refined (4x each) when the sampled medial graph
/// disagrees with the exact geometry ([`exact_mode::ExactMesh::inconsistent_arcs`]).
pub const EXACT_RESAMPLING: usize = 2;

/// Exact mode: the fewest samples on a circle of its first sampling (the paper pipeline's
/// default is 32, [`SamplingOptions::min_per_circle`]). The sampling only has to find which
/// circles meet at each medial vertex (exact mode computes the vertices, arcs and short-arc
/// lengths from the circles, [`crate::collapse::ArcLength::Chord`]), and intervals facing a
/// close circle are bisected to the local gap either way, so the floor matters only where
/// circles are far apart. Issue 8: at 24 the triangulation of 1 000 to 100 000 bubbles takes
/// a quarter less time, with the same blocks; over 240 layouts of
/// `examples/adversarial_sweep.rs` (near-touching, rings, lattices, dense packs) one block
/// count changed and none failed. Where 24 is not enough the disagreement checks refine the
/// sampling as before.
pub const EXACT_MIN_PER_CIRCLE: usize = 24;

/// The sampling exact mode starts from (in bounded domains and periodic boxes):
/// [`EXACT_MIN_PER_CIRCLE`] samples per circle at least, and no soft resampling rounds (its
/// walls are exact, so a single-sample wall costs it nothing, [`SamplingOptions::soft_rounds`]).
pub fn exact_sampling() -> SamplingOptions {
    SamplingOptions {
        soft_rounds: false,
        min_per_circle: EXACT_MIN_PER_CIRCLE,
        ..SamplingOptions::default()
    }
}

/// Options of the pipeline.
///
/// Paper mode reads `mode`, `cells` (and `block_cells`, as `cells`) and the degeneracy
/// options (`refine_ratio`, `collapse_fraction`, `max_inserted_holes`). Exact mode reads all
/// fields; for the disk (no hole) both modes use the same template and equal spacing, and for
/// one hole exact mode grids the annulus on its medial loop ([`exact_mode::annulus`]) with
/// all of its options.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    pub mode: Mode,
    /// Paper mode: the number of cells along every block side (raised on long wall arcs).
    /// Exact mode, without `cell_size`: the target size is the median Apollonius radius over
    /// `cells`, so a typical spoke gets about `cells` cells.
    pub cells: usize,
    /// Macro Delaunay refinement (paper Algorithm 3, [`crate::refine`]): insert a hole while an
    /// interior triangle has circumradius / shortest edge above this ratio. Default
    /// `Some(2.0)` (the paper's; smallest angle below about 14.48 degrees); `None` disables it.
    pub refine_ratio: Option<f64>,
    /// Collapse medial arcs shorter than this fraction of the local empty-circle radius
    /// ([`crate::collapse`]; paper mode measures an arc by its sampled polyline, exact mode
    /// by the chord between its ends' Apollonius centres, [`crate::collapse::ArcLength`]).
    /// Default [`DEFAULT_COLLAPSE_FRACTION`]; `0` collapses only zero-length arcs (which are
    /// always collapsed) and, in exact mode, arcs whose exact geometry runs backwards (nearly
    /// co-circular circles whose sampled Delaunay diagonal is not the exact one; see
    /// [`mesh`]).
    pub collapse_fraction: f64,
    /// The most holes refinement may insert before [`MeshError::Refinement`]. Default
    /// [`DEFAULT_MAX_INSERTED_HOLES`].
    pub max_inserted_holes: usize,
    /// Exact mode: the target cell size (overrides `cells`).
    pub cell_size: Option<f64>,
    /// Exact mode: wall clustering of every circle without an override.
    pub clustering: Clustering,
    /// Exact mode: per-circle clustering overrides (`-1` the bounding circle).
    pub circle_clustering: Vec<(CircleId, Clustering)>,
    /// Exact mode: per-circle wall-normal cell counts fixed by the user.
    pub wall_cells: Vec<(CircleId, usize)>,
    /// Exact mode: Winslow smoothing sweeps per block (0: none; at most
    /// [`crate::exact_mode::MAX_SMOOTH_SWEEPS`]).
    pub smooth: usize,
    /// Exact mode: a fixed `N x N` grid per block (issue #8's "16x16 grid per block"): every
    /// circle's wall-normal count is `N` (so every block has `nj = N`) and every medial arc's
    /// count is `N` (`ni = N`), raised only on an arc whose walls need more than `N` cells of
    /// at most 15 degrees ([`exact_mode::MAX_WALL_ANGLE`], as [`crate::grid::MAX_ARC_PER_CELL`]
    /// in paper mode); shared sides match by construction (one count per conformity class,
    /// [`exact_mode::counts::CountProblem::solve_uniform`]). Replaces the size-driven counts
    /// of `cells` / `cell_size`; refused together with `cell_size` or `wall_cells`.
    ///
    /// The paper pipeline (paper mode, exact mode's fallback, the disk and paper mode's annulus
    /// templates)
    /// reads it as `cells`: `N` cells along every block side, raised on long wall arcs, which
    /// is what `cells` already means there. Periodic and transition meshes read `cells` only.
    /// `N` must be in `1..=`[`crate::grid::MAX_CELLS_PER_SIDE`].
    pub block_cells: Option<usize>,
    /// Exact mode: node counts imposed by block key (sequences keep the counts of the first
    /// frame of a run with the same combinatorics, [`crate::sequence`]); used only when every
    /// block's key is known and the counts are consistent. Default `None`.
    pub imposed_counts: Option<std::sync::Arc<exact_mode::imposed::ImposedCounts>>,
    /// Keep every block's nodes (default `true`). `false` is for a caller that needs only
    /// the report and the block connectivity (the CLI with `--format json`, issue 8): exact
    /// mode's medial blocks are then measured as their grids are made and their nodes
    /// dropped, so that the grids never take memory all at once ([`Mesh::measured`] holds
    /// the figures; each grid keeps its `ni` and `nj`). Only [`mesh`] of a domain of two or
    /// more holes and [`crate::mesh_periodic`], in exact mode without smoothing, drop nodes
    /// (inserted holes' template blocks too, measured once made); every other mesh keeps
    /// them (and has no [`Mesh::measured`]): one hole, paper mode, transitions, sequences.
    /// The writers of grids refuse a mesh without nodes.
    pub keep_nodes: bool,
    /// The caller's process exits once this mesh is written (default `false`): exact mode
    /// then leaves the working memory of the attempt that gave the mesh (the sampling,
    /// triangulation, medial graph and blocking it was built from, and its per-piece cache;
    /// millions of small vectors) to the operating system instead of freeing it, as the
    /// CLI's `mesh` does with the mesh itself (issue 8: at 1e5 particles those frees took
    /// 0.16 s of CPU while the report and the connectivity were made). The mesh is the same.
    /// A caller that meshes more than once in a process must leave it `false`, or it keeps
    /// every mesh's working memory until it exits.
    pub exits_after_mesh: bool,
}

/// Default of [`Options::collapse_fraction`].
pub const DEFAULT_COLLAPSE_FRACTION: f64 = 0.05;
/// Default of [`Options::refine_ratio`] (the paper's).
pub const DEFAULT_REFINE_RATIO: f64 = 2.0;
/// Default of [`Options::max_inserted_holes`].
pub const DEFAULT_MAX_INSERTED_HOLES: usize = 10_000;

impl Default for Options {
    fn default() -> Self {
        Options {
            mode: Mode::Exact,
            cells: 16,
            refine_ratio: Some(DEFAULT_REFINE_RATIO),
            collapse_fraction: DEFAULT_COLLAPSE_FRACTION,
            max_inserted_holes: DEFAULT_MAX_INSERTED_HOLES,
            cell_size: None,
            clustering: Clustering::default(),
            circle_clustering: Vec::new(),
            wall_cells: Vec::new(),
            smooth: 0,
            block_cells: None,
            imposed_counts: None,
            keep_nodes: true,
            exits_after_mesh: false,
        }
    }
}

impl Options {
    /// These options with [`Options::keep_nodes`] set: for the meshes that keep every node
    /// whatever the caller asked (a lone hole, transition rings, sequences).
    pub(crate) fn keeping_nodes(&self) -> std::borrow::Cow<'_, Options> {
        if self.keep_nodes {
            std::borrow::Cow::Borrowed(self)
        } else {
            std::borrow::Cow::Owned(Options {
                keep_nodes: true,
                ..self.clone()
            })
        }
    }

    /// The default options in paper mode.
    pub fn paper() -> Options {
        Options {
            mode: Mode::Paper,
            ..Options::default()
        }
    }
}

/// Why no mesh was made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error(transparent)]
    Domain(#[from] DomainError),
    #[error("triangulation failed: {0}")]
    Triangulation(#[from] TriangulationError),
    #[error("boundary sampling of circle {circle} did not converge: {message}")]
    Sampling { circle: CircleId, message: String },
    #[error("grid generation failed: {0}")]
    Grid(#[from] GridError),
    #[error("invalid options: {0}")]
    Options(String),
    #[error(
        "macro Delaunay refinement needs more than {limit} inserted holes ({inserted} inserted \
         so far); raise the limit or the refinement ratio"
    )]
    Refinement { inserted: usize, limit: usize },
    /// A periodic box whose empty regions reach over more copies of the box than the limits
    /// allow (the tiling of [`crate::periodic`]: at most 7 long periods a side, and the
    /// sample limit).
    #[error("periodic tiling: {0}")]
    Tiling(String),
    #[error("internal invariant broken (please report this layout): {0}")]
    Internal(String),
}

/// Mesh `domain` with `options`.
///
/// In exact mode (the default) with two or more holes: the degeneracy handling below, then
/// exact Apollonius vertices (co-circular group circles at collapsed vertices), exact medial
/// arcs and spoke-aligned grids, inserted holes filled by templates ([`crate::exact_mode`],
/// [`Mesh::geometry`] is [`Geometry::Exact`]). Where the exact geometry disagrees with the
/// sampled combinatorics it is fixed on the same triangulation first (short collapses given
/// up around inverted or nearly flat blocks, an arc running backwards collapsed into a
/// degree-4 vertex), then by resampling (see `mesh_exact`); only where it still disagrees is
/// the paper pipeline used instead ([`Geometry::Paper`]), as it is in paper mode:
///
/// Two or more holes: macro Delaunay refinement ([`crate::refine`], paper Algorithm 3: holes
/// are inserted while an interior triangle is poor, the paper's strategy of refining angles
/// below ~15 degrees first), exact Apollonius circles and co-circular groups
/// ([`crate::cocircular`]), collapse of zero-length and short arcs ([`crate::collapse`]),
/// Blocking2D ([`crate::blocking::build_mesh_layout`]) and templates in the inserted holes;
/// no hole (a disk) or one hole (an annulus): the standard templates of
/// [`crate::templates`]. Then node counts and transfinite interpolation ([`crate::grid`]).
/// Exact mode meshes one hole on its closed medial loop ([`exact_mode::annulus`]), with the
/// template as its fallback.
///
/// ```
/// use medial_blocks::{mesh, Domain, Options};
/// let domain = Domain::hexagon_example();
/// let mesh = mesh(&domain, &Options::default()).unwrap();
/// assert_eq!(mesh.layout.blocks.len(), 36); // 6 (h - 1) blocks for h = 7 holes
/// ```
///
/// Called from a thread outside rayon's pool, the work runs on a worker of the pool (the
/// calling thread waits; [`timings::on_pool_worker`]), which is faster than driving the
/// parallel stages from outside; the mesh is the same.
pub fn mesh(domain: &Domain, options: &Options) -> Result<Mesh, MeshError> {
    timings::on_pool_worker(|| mesh_here(domain, options))
}

/// [`mesh`] on this thread: the options checked, then the holes meshed in a spatial order
/// when the layout is large ([`crate::spatial_order`]; the mesh and the errors in the input's
/// hole ids).
fn mesh_here(domain: &Domain, options: &Options) -> Result<Mesh, MeshError> {
    validate_for(options, crate::domain::BOUNDING, domain.hole_count())?;
    crate::spatial_order::mesh_in_spatial_order(
        domain,
        domain.holes(),
        options,
        Domain::reordered,
        mesh_in_order,
    )
}

/// The checks of `options` against a domain whose circles are `first..holes` (see
/// [`validate_circle_ids`]): the ranges, [`Options::block_cells`], the circle ids and exact
/// mode's options. The one set of checks of both entry points, [`mesh`] and
/// [`crate::mesh_periodic`], made before any renaming (their messages name the caller's
/// circle ids).
pub(crate) fn validate_for(
    options: &Options,
    first: CircleId,
    holes: usize,
) -> Result<(), MeshError> {
    crate::ranges::check_ranges(options)?;
    validate_block_cells(options)?;
    validate_circle_ids(options, first, holes)?;
    if options.mode == Mode::Exact {
        exact_mode::validate_options(options)?;
    }
    Ok(())
}

/// [`mesh_here`] with the holes in the order given, the options checked.
fn mesh_in_order(domain: &Domain, options: &Options) -> Result<Mesh, MeshError> {
    let holes = domain.hole_count();
    if options.mode == Mode::Exact {
        if holes >= 2 {
            if let Some(m) = mesh_exact(domain, options)? {
                return Ok(m);
            }
        }
        if holes == 1 {
            // The ring is measured (and may be seeded) below: its nodes are kept.
            let options = &*options.keeping_nodes();
            let built = timings::span("exact_geometry", || {
                exact_mode::annulus::build_annulus(domain, options)
            })?;
            if let Some(m) = built {
                let ring = Mesh {
                    layout: m.layout,
                    grids: m.grids,
                    holes,
                    split_arcs: exact_mode::annulus::ANNULUS_ARCS,
                    geometry: Geometry::Exact,
                    ..Mesh::default()
                };
                return Ok(lone_hole_seeded(domain, options, ring));
            }
        }
    }
    let mut out = Mesh {
        holes,
        ..Mesh::default()
    };
    out.layout = match holes {
        0 => templates::disk(domain.bounding()),
        1 => templates::annulus(domain.bounding(), domain.holes()[0]),
        _ => {
            let b = timings::span("blocking", || blocking::build_mesh_layout(domain, options))?;
            out.medial_vertices = b.medial_vertices;
            out.medial_arcs = b.medial_arcs;
            out.cocircular_groups = b.cocircular_groups;
            out.collapsed_arcs = b.collapsed_arcs;
            out.inserted_holes = b.inserted_holes;
            out.split_arcs = b.split_arcs;
            out.template_blocks = b.template_blocks;
            b.layout
        }
    };
    let side_cells = options.block_cells.unwrap_or(options.cells);
    out.grids = timings::span("grids", || build_grids(&out.layout, side_cells))?;
    Ok(out)
}

/// Exact mode's ring of one hole ([`exact_mode::annulus`]) is kept when its smallest angle is
/// at least this (degrees); below it, the lone hole is also meshed with a seeded fluid hole
/// ([`lone_hole_seed`]) and the better of the two is kept. Not higher: the seeded mesh has
/// template blocks, and a sequence keeps node counts over a run only without them (a ring
/// of 15.4 degrees kept its counts over three frames; seeded, at 17.6, it did not).
pub const LONE_HOLE_GOOD_ANGLE_DEG: f64 = 15.0;

/// The fluid hole seeded opposite a lone off-centre hole: half the largest empty circle on
/// the far side (tangent to the bounding circle and the hole, centred on the line of the two
/// centres), as macro Delaunay refinement inserts half the empty circle of a poor vertex.
/// `None` for a concentric hole (its ring is polar).
pub fn lone_hole_seed(domain: &Domain) -> Option<crate::domain::Circle> {
    let b = domain.bounding();
    let h = *domain.holes().first()?;
    let (dx, dy) = (h.center[0] - b.center[0], h.center[1] - b.center[1]);
    let d = dx.hypot(dy);
    if d.is_nan() || d <= 0.0 {
        return None;
    }
    // Tangent to both: |p - c_b| + rho = R and |p - c_h| = rho + r, with p = c_b - t u.
    let rho = 0.5 * (b.radius + d - h.radius);
    let t = b.radius - rho;
    let center = [b.center[0] - t * dx / d, b.center[1] - t * dy / d];
    let seed = crate::domain::Circle {
        center,
        radius: 0.5 * rho,
    };
    (seed.radius.is_finite() && seed.radius > 0.0).then_some(seed)
}

/// The ring of a lone hole, or, when its smallest angle is below [`LONE_HOLE_GOOD_ANGLE_DEG`]
/// (a small hole far off-centre: its medial loop is a long thin ellipse and the ring's cells
/// shear, 3.4 degrees and aspect ratios of 8000 for a hole of 1e-3 R by the wall), the
/// medial blocking with a fluid hole seeded opposite it ([`lone_hole_seed`]) when that has a
/// larger smallest angle and no inverted cell. The same rule with counts imposed (the later
/// frames of a sequence run); a run of seeded frames does not keep its node counts (its
/// template blocks' counts cannot be imposed), see [`LONE_HOLE_GOOD_ANGLE_DEG`].
fn lone_hole_seeded(domain: &Domain, options: &Options, ring: Mesh) -> Mesh {
    let ring_min = crate::quality::measure(&ring.grids).min_angle_deg;
    if ring_min >= LONE_HOLE_GOOD_ANGLE_DEG {
        return ring;
    }
    let Some(seed) = lone_hole_seed(domain) else {
        return ring;
    };
    match mesh_exact_seeded(domain, options, &[seed]) {
        Ok(Some(m)) => {
            let q = crate::quality::measure(&m.grids);
            if q.inverted_cells == 0 && q.min_angle_deg > ring_min {
                m
            } else {
                ring
            }
        }
        _ => ring,
    }
}

/// [`mesh`], timed: the mesh and the exclusive wall time of each pipeline stage
/// ([`crate::timings`]; the stage names are [`timings::STAGES`]) with the peak memory. The
/// mesh is exactly [`mesh`]'s; timing never changes it. Meshes timed concurrently on one
/// rayon pool may record some of each other's stages ([`timings::Recording`]).
pub fn mesh_timed(
    domain: &Domain,
    options: &Options,
) -> Result<(Mesh, timings::Timings), MeshError> {
    let recording = timings::Recording::start();
    let result = mesh(domain, options);
    let t = recording.finish();
    result.map(|m| (m, t))
}

/// Check [`Options::block_cells`]: `1..=MAX_CELLS_PER_SIDE`, and not with `cell_size` or
/// `wall_cells` (they choose counts another way).
pub fn validate_block_cells(options: &Options) -> Result<(), MeshError> {
    let Some(n) = options.block_cells else {
        return Ok(());
    };
    if n == 0 {
        return Err(MeshError::Options(
            "--block-cells must be at least 1 (cells along each direction of a block)".into(),
        ));
    }
    if n > crate::grid::MAX_CELLS_PER_SIDE {
        return Err(MeshError::Grid(GridError::TooManyCellsPerSide {
            cells: n,
            limit: crate::grid::MAX_CELLS_PER_SIDE,
        }));
    }
    if options.cell_size.is_some() {
        return Err(MeshError::Options(
            "--block-cells and --cell-size both choose the cell counts; give one of them".into(),
        ));
    }
    if !options.wall_cells.is_empty() {
        return Err(MeshError::Options(
            "--block-cells fixes every wall-normal count; it cannot be combined with \
             --wall-cells"
                .into(),
        ));
    }
    Ok(())
}

/// Check that every circle named by [`Options::circle_clustering`] and
/// [`Options::wall_cells`] is a circle of the domain: `first..holes` (`first` is
/// [`crate::domain::BOUNDING`], -1, for a bounded domain, 0 for a periodic one, which has no
/// bounding circle). An id outside that range (an inserted hole's included: those are not
/// known before meshing) would otherwise be ignored without a word.
pub fn validate_circle_ids(
    options: &Options,
    first: CircleId,
    holes: usize,
) -> Result<(), MeshError> {
    let named = options
        .circle_clustering
        .iter()
        .map(|(c, _)| ("--circle-clustering", *c))
        .chain(options.wall_cells.iter().map(|(c, _)| ("--wall-cells", *c)));
    for (flag, c) in named {
        if c < first || i64::from(c) >= holes as i64 {
            let circles = match (first < 0, holes) {
                (true, 0) => "its only circle is -1, the bounding circle".to_string(),
                (true, h) => format!("its circles are -1 (the bounding circle) to {}", h - 1),
                (false, h) => format!(
                    "its circles are 0 to {} (a periodic domain has no bounding circle)",
                    h as i64 - 1
                ),
            };
            return Err(MeshError::Options(format!(
                "{flag} names circle {c}, which is not a circle of the domain: {circles}"
            )));
        }
    }
    Ok(())
}

/// Exact mode: the most local rebuilds (arc collapse, Blocking2D and exact geometry again on
/// the same sampling and triangulation, see `mesh_exact`) per sampling.
pub const EXACT_LOCAL_FIXES: usize = 8;

/// Exact mode for two or more holes, on the full front end
/// ([`blocking::collapsed_blocking_excluding`]: refinement, co-circular groups, collapse) with
/// exact geometry on collapsed vertices and around inserted holes
/// ([`exact_mode::collapsed::build_collapsed`]).
///
/// The sampled combinatorics must agree with the exact geometry: every mesh returned has
/// consistent arcs and no inverted cell. The sampling is taken once, without the soft
/// resampling rounds of invariant (d) ([`SamplingOptions::soft_rounds`]: exact walls do not
/// follow the samples). Where the exact mesh disagrees, it is first fixed locally, on the same
/// sampling and triangulation (no resampling), at most [`EXACT_LOCAL_FIXES`] times
/// (`exact_on_sampling`):
/// - an inverted block, an arc running backwards
///   ([`exact_mode::ExactMesh::inconsistent_arcs`]), or a cell angle below
///   [`MERGED_MIN_ANGLE_DEG`], at a vertex merged by *short*-arc collapse (whose merged centre
///   is on none of the exact bisectors): the short collapses of only those clusters are given
///   up (zero-length collapses, exact co-circular group circles, stay), and remembered by their
///   circles ([`blocking::arc_key`]) for any later sampling;
/// - an arc running backwards with no short collapse to give up at its ends (nearly
///   co-circular circles whose sampled Delaunay diagonal is not the exact one): the arc is
///   collapsed, once, into a degree-4 vertex at the mean of its two Apollonius centres (if
///   that breaks the construction, the circles around it are resampled);
/// - a failure of the exact construction at an unknown place ([`MeshError::Internal`]: a
///   collapsed vertex with two spokes to one circle, an exact arc not defined, a template that
///   does not fit): every short collapse is given up.
///
/// The exact vertices of the sampled graph are taken from the refinement once per sampling
/// ([`exact_mode::exact_vertices_with`]); a local rebuild redoes only the collapse, Blocking2D
/// ([`blocking::CollapsedBlocking::recollapse`]) and the exact layout and grids.
///
/// Only when that does not suffice is the sampling refined 4x, up to [`EXACT_RESAMPLING`]
/// times: only on the circles around the disagreeing arcs and inverted blocks
/// ([`SamplingOptions::boost`]) when they are known, else everywhere. `Ok(None)` when it never
/// agreed: the caller falls back to the paper pipeline and reports [`Geometry::Paper`].
/// Errors other than [`MeshError::Internal`] are returned at once on the first sampling (a
/// finer sampling failing after a coarser one worked falls back to the paper pipeline).
fn mesh_exact(domain: &Domain, options: &Options) -> Result<Option<Mesh>, MeshError> {
    mesh_exact_seeded(domain, options, &[])
}

/// [`mesh_exact`] with the fluid holes `seed` inserted from the start
/// ([`crate::refine::refine_seeded`]).
fn mesh_exact_seeded(
    domain: &Domain,
    options: &Options,
    seed: &[crate::domain::Circle],
) -> Result<Option<Mesh>, MeshError> {
    let mut sampling = exact_sampling();
    // Short collapses given up, by their circles: they survive resampling (arc ids do not).
    let mut given_up: Vec<Vec<CircleId>> = Vec::new();
    // Per-piece work of the latest exact build, reused by the next one (rebuilds after local
    // fixes and resamplings change only a few pieces; [`exact_mode::piece_cache`]).
    let mut cache = exact_mode::PieceCache::default();
    for attempt in 0..=EXACT_RESAMPLING {
        let outcome = timings::span("blocking", || {
            blocking::collapsed_blocking_seeded(domain, options, &sampling, false, &given_up, seed)
        })
        .and_then(|mut cb| {
            let outcome = exact_on_sampling(domain, options, &mut cb, &mut given_up, &mut cache);
            // The front end's many small vectors took 0.6 ms to free at 1e3 bubbles and
            // 160 ms at 1e5 (issue 8).
            match outcome {
                Ok(Attempt::Done(_)) => let_go(options, cb),
                _ => rayon::spawn(move || drop(cb)),
            }
            outcome
        });
        let refine = match outcome {
            Ok(Attempt::Done(m)) => {
                let_go(options, cache);
                return Ok(Some(*m));
            }
            Ok(Attempt::Retry(circles)) => circles,
            // A finer sampling failed after a coarser one worked: fall back to paper mode.
            Err(_) if attempt > 0 => return Ok(None),
            Err(e) => return Err(e),
        };
        match refine {
            // Refine 4x only around the arcs that disagreed (issue 8: no global resampling
            // of thousands of circles for one nearly co-circular spot).
            Some(circles) if !circles.is_empty() => {
                for c in circles {
                    let slot = (c + 1) as usize;
                    if sampling.boost.len() <= slot {
                        sampling.boost.resize(slot + 1, 0);
                    }
                    sampling.boost[slot] += 2;
                }
            }
            _ => {
                sampling.min_per_circle = sampling.min_per_circle.saturating_mul(4);
                sampling.spacing_per_gap *= 0.25;
            }
        }
    }
    Ok(None)
}

/// Let go of working memory that the mesh being returned does not need: freed on the pool,
/// off this thread, or never with [`Options::exits_after_mesh`] (the process exits soon and
/// the kernel takes its whole address space back at once).
pub(crate) fn let_go<T: Send + 'static>(options: &Options, x: T) {
    if options.exits_after_mesh {
        std::mem::forget(x);
    } else {
        rayon::spawn(move || drop(x));
    }
}

/// The outcome of exact mode on one sampling.
enum Attempt {
    Done(Box<Mesh>),
    /// The exact geometry disagreed with the sampled combinatorics: the circles around the
    /// disagreement (input circles only) to sample finer, or `None` when unknown (refine all).
    Retry(Option<Vec<CircleId>>),
}

/// The input circles around the medial corners of `blocks` (walls of every block sharing a
/// medial corner with one of them), sorted and deduplicated; inserted holes are left out.
fn circles_around(
    layout: &crate::layout::BlockLayout,
    blocks: &[usize],
    holes: usize,
) -> Vec<CircleId> {
    let mut corners: Vec<u32> = blocks
        .iter()
        .filter_map(|&b| layout.blocks.get(b))
        .flat_map(|b| [b.corners[2], b.corners[3]])
        .collect();
    corners.sort_unstable();
    corners.dedup();
    let mut out: Vec<CircleId> = layout
        .blocks
        .iter()
        .filter(|b| b.corners.iter().any(|v| corners.binary_search(v).is_ok()))
        .filter_map(|b| b.wall)
        .filter(|&c| c < holes as CircleId)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// The sampled arcs collapsed as *short* arcs (not zero-length, not forced) in `cb`, in
/// increasing order: all of them (`clusters` `None`), or those merged into one of the
/// contracted vertices `clusters` (sorted).
pub(crate) fn short_collapses(
    cb: &blocking::CollapsedBlocking,
    clusters: Option<&[u32]>,
) -> Vec<u32> {
    let medial = &cb.refined.sampled.medial;
    let mut out: Vec<u32> = cb
        .chosen
        .iter()
        .filter(|c| !c.zero)
        .filter(|c| {
            clusters.is_none_or(|cl| {
                let v = medial.arcs[c.arc as usize].ends[0] as usize;
                cb.contracted
                    .cluster_of
                    .get(v)
                    .is_some_and(|k| cl.binary_search(k).is_ok())
            })
        })
        .map(|c| c.arc)
        .collect();
    out.sort_unstable();
    out
}

/// Exact mode: a cell with a corner angle below this (degrees) in a block at a vertex merged
/// by short-arc collapse has that collapse given up, as an inverted one (the merged centre is
/// an approximation; the collapse must not make a nearly flat cell).
pub const MERGED_MIN_ANGLE_DEG: f64 = 5.0;

/// The blocks (sorted) with a corner at a vertex merged by short-arc collapse and a cell
/// angle below [`MERGED_MIN_ANGLE_DEG`] (found as the grids were made when their nodes were
/// not kept: `measured`).
fn poor_merged_blocks(
    cb: &blocking::CollapsedBlocking,
    layout: &crate::layout::BlockLayout,
    grids: &[crate::mesh::BlockGrid],
    measured: Option<&crate::quality::Measured>,
) -> Vec<usize> {
    let medial = &cb.refined.sampled.medial;
    let merged: Vec<u32> = cb
        .chosen
        .iter()
        .filter(|c| !c.zero)
        .filter_map(|c| {
            let v = medial.arcs.get(c.arc as usize)?.ends[0] as usize;
            cb.contracted.cluster_of.get(v).copied()
        })
        .collect();
    if merged.is_empty() {
        return Vec::new();
    }
    // Merged contracted vertices by id (a lookup per block corner, not a search).
    let nc = cb.contracted.graph.vertices.len();
    let mut is_merged = vec![false; nc];
    for v in merged {
        if let Some(x) = is_merged.get_mut(v as usize) {
            *x = true;
        }
    }
    // In parallel, collected in block order.
    use rayon::prelude::*;
    layout
        .blocks
        .par_iter()
        .enumerate()
        .filter(|(_, b)| {
            b.corners
                .iter()
                .any(|&v| is_merged.get(v as usize).copied().unwrap_or(false))
        })
        .filter(|&(b, _)| match measured {
            Some(m) => m.corner_below(b),
            None => grids
                .get(b)
                .is_some_and(|g| crate::quality::has_corner_below(g, MERGED_MIN_ANGLE_DEG)),
        })
        .map(|(b, _)| b)
        .collect()
}

/// Give up the short collapses `arcs` of `cb` (remembered by [`blocking::arc_key`] in
/// `given_up`, sorted) and redo the collapse on the same sampling.
fn give_up(
    cb: &mut blocking::CollapsedBlocking,
    options: &Options,
    arcs: &[u32],
    given_up: &mut Vec<Vec<CircleId>>,
) -> Result<(), MeshError> {
    for &e in arcs {
        let key = blocking::arc_key(&cb.refined.sampled.medial, e as usize);
        if let Err(at) = given_up.binary_search(&key) {
            given_up.insert(at, key);
        }
    }
    timings::span("blocking", || cb.recollapse(options, arcs, &[]))
}

/// Exact mode on one sampling (see [`mesh_exact`]): build, check, fix locally and rebuild on
/// the same triangulation; [`Attempt::Retry`] when only a resampling can help, `Err` when the
/// exact construction fails other than by [`MeshError::Internal`].
fn exact_on_sampling(
    domain: &Domain,
    options: &Options,
    cb: &mut blocking::CollapsedBlocking,
    given_up: &mut Vec<Vec<CircleId>>,
    cache: &mut exact_mode::PieceCache,
) -> Result<Attempt, MeshError> {
    let holes = domain.hole_count();
    // Inconsistent arcs already collapsed into a degree-4 vertex (sampled arc ids).
    let mut merged: Vec<u32> = Vec::new();
    // The circles around the backwards arcs of the last degree-4 collapse, until a rebuild
    // after it succeeds.
    let mut around_merged: Option<Vec<CircleId>> = None;
    let mut fixes = 0;
    // The exact vertices of the sampled graph do not depend on the collapse: solved once.
    let single = match timings::span("exact_geometry", || {
        exact_mode::exact_vertices_with(
            &cb.refined.domain,
            &cb.refined.sampled.medial,
            &cb.refined.circles,
        )
    }) {
        Ok(v) => v,
        Err(MeshError::Internal(_)) => return Ok(Attempt::Retry(None)),
        Err(err) => return Err(err),
    };
    loop {
        let built = timings::span("exact_geometry", || {
            exact_mode::collapsed::build_collapsed_cached(cb, options, &single, cache)
        });
        let m = match built {
            Ok(m) => m,
            Err(MeshError::Internal(_)) => {
                // A degree-4 collapse of a backwards arc broke the construction: refine the
                // sampling around that arc instead.
                if let Some(circles) = around_merged.take() {
                    return Ok(Attempt::Retry((!circles.is_empty()).then_some(circles)));
                }
                // Somewhere unknown: give up every short collapse (zero-length ones stay).
                let short = short_collapses(cb, None);
                if fixes < EXACT_LOCAL_FIXES && !short.is_empty() {
                    fixes += 1;
                    match give_up(cb, options, &short, given_up) {
                        Ok(()) => continue,
                        Err(MeshError::Internal(_)) => {}
                        Err(err) => return Err(err),
                    }
                }
                return Ok(Attempt::Retry(None));
            }
            Err(err) => return Err(err),
        };
        around_merged = None;
        // Found while the grids were made (`ExactMesh::inverted_blocks`): the same list as
        // `quality::inverted_blocks`, which the debug builds check.
        let inverted = m.inverted_blocks.clone();
        debug_assert!(
            m.measured.is_some() || inverted == crate::quality::inverted_blocks(&m.grids)
        );
        // Nearly flat cells at a vertex merged by short-arc collapse: fixed like inverted ones.
        let poor = timings::span("quality_check", || {
            poor_merged_blocks(cb, &m.layout, &m.grids, m.measured.as_deref())
        });
        if m.inconsistent_arcs.is_empty()
            && inverted.is_empty()
            && (poor.is_empty() || fixes >= EXACT_LOCAL_FIXES)
        {
            return Ok(done(cb, m, holes, options));
        }
        let mut bad: Vec<usize> = inverted;
        for &e in &m.inconsistent_arcs {
            bad.extend([2 * e, 2 * e + 1]);
        }
        bad.sort_unstable();
        bad.dedup();
        if fixes < EXACT_LOCAL_FIXES {
            let mut bad = bad.clone();
            bad.extend_from_slice(&poor);
            bad.sort_unstable();
            bad.dedup();
            // The contracted vertices at the corners of the bad blocks.
            let nc = cb.contracted.graph.vertices.len() as u32;
            let mut clusters: Vec<u32> = bad
                .iter()
                .filter_map(|&b| m.layout.blocks.get(b))
                .flat_map(|b| b.corners)
                .filter(|&v| v < nc)
                .collect();
            clusters.sort_unstable();
            clusters.dedup();
            let short = short_collapses(cb, Some(&clusters));
            // The backwards arcs not collapsed yet (sampled arc ids).
            let mut force: Vec<u32> = m
                .inconsistent_arcs
                .iter()
                .filter_map(|&e| cb.contracted.kept.get(e).copied())
                .filter(|e| merged.binary_search(e).is_err())
                .collect();
            force.sort_unstable();
            force.dedup();
            if !short.is_empty() {
                fixes += 1;
                match give_up(cb, options, &short, given_up) {
                    Ok(()) => {
                        // Rejected: its grids go back to the cache for the rebuild.
                        cache.keep(m);
                        continue;
                    }
                    Err(MeshError::Internal(_)) => {}
                    Err(err) => return Err(err),
                }
            } else if !force.is_empty() {
                // Arcs running backwards with nothing to give up at their ends: collapse them.
                fixes += 1;
                let around = circles_around(&m.layout, &bad, holes);
                merged.extend_from_slice(&force);
                merged.sort_unstable();
                match timings::span("blocking", || cb.recollapse(options, &[], &force)) {
                    Ok(()) => {
                        around_merged = Some(around);
                        cache.keep(m);
                        continue;
                    }
                    Err(MeshError::Internal(_)) => {
                        return Ok(Attempt::Retry((!around.is_empty()).then_some(around)))
                    }
                    Err(err) => return Err(err),
                }
            }
        }
        if bad.is_empty() {
            // Only nearly flat cells, and nothing left to give up for them.
            return Ok(done(cb, m, holes, options));
        }
        let circles = circles_around(&m.layout, &bad, holes);
        cache.keep(m);
        return Ok(Attempt::Retry((!circles.is_empty()).then_some(circles)));
    }
}

/// The exact mesh of `cb` as the mesher's result; what the mesh does not keep of `m` (its
/// exact vertices and counts) is let go ([`let_go`]).
fn done(
    cb: &blocking::CollapsedBlocking,
    m: exact_mode::ExactMesh,
    holes: usize,
    options: &Options,
) -> Attempt {
    let medial = &cb.refined.sampled.medial;
    let exact_mode::ExactMesh {
        layout,
        grids,
        vertices,
        counts,
        cell_size,
        coarsened_from,
        inconsistent_arcs,
        split_arcs,
        template_blocks,
        inverted_blocks,
        measured,
    } = m;
    let_go(
        options,
        (vertices, counts, inconsistent_arcs, inverted_blocks),
    );
    Attempt::Done(Box::new(Mesh {
        layout,
        grids,
        medial_vertices: medial.vertex_count(),
        medial_arcs: medial.arc_count(),
        holes,
        cocircular_groups: cb.groups.clone(),
        collapsed_arcs: cb.collapsed,
        inserted_holes: cb.refined.inserted.clone(),
        split_arcs,
        template_blocks,
        geometry: Geometry::Exact,
        coarsened_cell_size: coarsened_from.map(|from| [from, cell_size]),
        measured,
    }))
}

/// Mesh either kind of domain: [`mesh`] for a bounded one, [`crate::periodic::mesh_periodic`]
/// (one period that tiles the plane) for a periodic one.
pub fn mesh_any(domain: &crate::domain::AnyDomain, options: &Options) -> Result<Mesh, MeshError> {
    match domain {
        crate::domain::AnyDomain::Bounded(d) => mesh(d, options),
        crate::domain::AnyDomain::Periodic(p) => crate::periodic::mesh_periodic(p, options),
    }
}
