//! `medial-blocks mesh [INPUT] [-o DIR] [--mode exact|paper] [--cells N] [--cell-size H]
//! [--first-height H | --first-height-rel F] [--growth G] [--circle-clustering ID:FIRST[:G]]
//! [--wall-cells ID:N] [--smooth N] [--compare-modes] [--refine-ratio R] [--no-refine]
//! [--collapse-fraction F] [--format LIST] [--binary] [--block-cells N] [--timings]`.

use super::{Failure, Global};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use medial_blocks::domain::{AnyDomain, Circle, Domain};
use medial_blocks::exact_mode::{Clustering, FirstCell};
use medial_blocks::input::{parse_holes_csv, parse_triple};
use medial_blocks::output::{report, write_files_prepared, Encoding, Format};
use medial_blocks::periodic::PeriodicDomain;
use medial_blocks::{mesh_any, timings, Mode, Options};
use std::path::PathBuf;
use std::time::Duration;

const DEFAULT_FORMATS: &str = "vtk,svg,json";

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeArg {
    /// Exact medial axis and spoke-aligned grids (walls exactly orthogonal, no folding).
    Exact,
    /// The paper as written: circumcenter polylines, equally spaced TFI.
    Paper,
}

#[derive(clap::Args, Debug)]
#[command(after_help = "Examples:
  medial-blocks mesh                         # the built-in 7-hole hexagon example into out/
  medial-blocks mesh layout.json -o run1 --cells 24
  medial-blocks mesh holes.csv --bounding 0,0,10 --format all
  medial-blocks --threads 2 --quiet mesh layout.json --format vtu,plot3d
  medial-blocks mesh bubbles.csv --periodic 1,1   # one period of a periodic layout
  medial-blocks mesh layout.json --transition 0.25  # join a Cartesian grid of spacing 0.25
  medial-blocks mesh bubbles.json --block-cells 16 --timings  # 16x16 per block, stage times
  medial-blocks mesh --transition 0.2 --transition-rect=-6,-3,6,3  # ... out to a rectangle

Input JSON: {\"bounding\": {\"center\": [x, y], \"radius\": R},
             \"holes\": [{\"center\": [x, y], \"radius\": r}, ...]}
Periodic JSON: {\"periodic\": {\"size\": [Lx, Ly]}, \"holes\": [...]} (holes may cross the box's
  edges; the mesh is one period whose zig-zag sides match their partners on the opposite side).
Input CSV (file name ending in .csv): x,y,r per line (an optional header line is skipped),
  with the bounding circle given by --bounding X,Y,R, or a period by --periodic LX,LY.
Files in DIR: mesh.vtm + mesh/*.vts (vtk), mesh.vtu (vtu), mesh.xyz + mesh.p3d (plot3d),
  mesh.msh + mesh.geo (gmsh), mesh.svg (svg), mesh.png (png), report.json +
  connectivity.json (json), mesh.cgns (cgns: builds with --features cgns only),
  timings.json (only with --timings: per-stage seconds, CPU seconds, calls, peak memory;
  \"spans\": every entry of every stage in order, e.g. each local-fix round).
Exit codes: 0 success, 1 output could not be written or internal error, 2 bad input.")]
pub struct Args {
    /// Domain JSON, or a CSV of holes (`x,y,r`); without it, the built-in 7-hole hexagon.
    pub input: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(short, long, default_value = "out")]
    pub output: PathBuf,
    /// Geometry of the blocks.
    #[arg(long, value_enum, default_value_t = ModeArg::Exact)]
    pub mode: ModeArg,
    /// Target number of cells along a block side (exact mode: along a typical spoke, and the
    /// cell size this gives is coarsened when the mesh would exceed 64 x blocks x (CELLS + 1)^2
    /// nodes, at least 2^22: see "coarsened_cell_size" in report.json); 1 to 100000.
    #[arg(long, default_value_t = 16, allow_negative_numbers = true)]
    pub cells: usize,
    /// Exact mode: an N x N grid in every block (N cells along the wall and the arc, N along
    /// the spokes), raised along an arc only where a wall would span more than 15 degrees per
    /// cell; shared sides always match. Paper mode: the same as --cells N (N per block side).
    /// N is 1 to 100000.
    #[arg(
        long,
        value_name = "N",
        conflicts_with_all = ["cells", "cell_size", "wall_cells"],
        allow_negative_numbers = true
    )]
    pub block_cells: Option<usize>,
    /// Print per-stage wall time and peak memory on stderr (unless --quiet) and write them to
    /// DIR/timings.json. Nothing else changes: the other files are byte-identical without it.
    #[arg(long)]
    pub timings: bool,
    /// Exact mode: target cell size (overrides --cells); a finite length > 0.
    #[arg(long, allow_negative_numbers = true)]
    pub cell_size: Option<f64>,
    /// Exact mode: first cell height at every wall (absolute length); finite, > 0.
    #[arg(
        long,
        conflicts_with = "first_height_rel",
        allow_negative_numbers = true
    )]
    pub first_height: Option<f64>,
    /// Exact mode: first cell height at every wall, as a fraction of the circle's radius;
    /// finite, > 0.
    #[arg(long, allow_negative_numbers = true)]
    pub first_height_rel: Option<f64>,
    /// Exact mode: growth ratio of the wall clustering (the largest ratio of neighbouring
    /// wall-normal cells); 1 to 10.
    #[arg(long, default_value_t = 1.2, allow_negative_numbers = true)]
    pub growth: f64,
    /// Exact mode: clustering of one circle, `ID:FIRST[:GROWTH]` (ID -1 is the bounding
    /// circle; FIRST ending in `r` is relative to the radius, e.g. `3:0.01r:1.1`; FIRST > 0,
    /// GROWTH 1 to 10). Repeatable.
    #[arg(long, allow_hyphen_values = true)]
    pub circle_clustering: Vec<String>,
    /// Exact mode: wall-normal cell count of one circle, `ID:N` (N 1 to 100000). Repeatable.
    #[arg(long, allow_hyphen_values = true)]
    pub wall_cells: Vec<String>,
    /// Exact mode: Winslow smoothing sweeps per block, 0 to 1000 (never lowers the min
    /// scaled Jacobian).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub smooth: usize,
    /// Also mesh the domain in the other mode and write both modes' quality figures to
    /// DIR/modes.json (`{"exact": {...}, "paper": {...}}`).
    #[arg(long)]
    pub compare_modes: bool,
    /// Writers, comma separated: vtk, vtu, plot3d, gmsh, svg, png, json, cgns (with the
    /// cgns feature), or all. With json alone (report.json, connectivity.json) no node is
    /// held: each block is measured as it is made (less memory, faster; the same files).
    #[arg(long, default_value = DEFAULT_FORMATS)]
    pub format: String,
    /// Write the VTK files (.vts, .vtu) with raw appended binary data and the Gmsh .msh as
    /// 4.1 binary: the same values, about half the size, faster to write and to read.
    /// Plot3D's mesh.xyz is binary either way.
    #[arg(long)]
    pub binary: bool,
    /// The bounding circle `X,Y,R` for a CSV input.
    #[arg(long, allow_hyphen_values = true)]
    pub bounding: Option<String>,
    /// Macro Delaunay refinement: insert holes while an interior triangle has circumradius /
    /// shortest edge above R (paper Algorithm 3; 2.0 means smallest angles above ~14.5 deg).
    /// R is finite and at least 1/sqrt(3) = 0.5773502691896258, the ratio of the equilateral
    /// triangle (no triangle has less).
    #[arg(
        long,
        default_value_t = medial_blocks::mesher::DEFAULT_REFINE_RATIO,
        allow_negative_numbers = true
    )]
    pub refine_ratio: f64,
    /// Add a ring of transition blocks out to a square whose boundary nodes are nodes of a
    /// Cartesian background grid of this spacing (origin at 0; a finite length > 0); bounded
    /// domains only.
    #[arg(long, allow_negative_numbers = true)]
    pub transition: Option<f64>,
    /// With --transition: transition out to this rectangle instead of the square,
    /// `XMIN,YMIN,XMAX,YMAX`, grown outwards to the nearest background grid lines (its corners
    /// are background nodes); it must enclose the bounding circle with one background interval
    /// to spare on every side. Aspect ratios up to about 3 give valid blocks.
    #[arg(
        long,
        requires = "transition",
        value_name = "XMIN,YMIN,XMAX,YMAX",
        allow_hyphen_values = true
    )]
    pub transition_rect: Option<String>,
    /// The period `LX,LY` for a CSV input: mesh one period of a periodic layout.
    #[arg(long, conflicts_with = "bounding", allow_hyphen_values = true)]
    pub periodic: Option<String>,
    /// No macro Delaunay refinement (no inserted holes).
    #[arg(long)]
    pub no_refine: bool,
    /// Collapse medial arcs shorter than F times the local empty-circle radius (0: only
    /// zero-length arcs, which are always collapsed); 0 to 1 (up to 1 the merged vertex stays
    /// well inside both ends' empty circles, in the fluid).
    #[arg(
        long,
        default_value_t = medial_blocks::mesher::DEFAULT_COLLAPSE_FRACTION,
        allow_negative_numbers = true
    )]
    pub collapse_fraction: f64,
}

/// The writers' encoding for `--binary`.
pub fn encoding(binary: bool) -> Encoding {
    if binary {
        Encoding::Binary
    } else {
        Encoding::Ascii
    }
}

fn read_domain(args: &Args) -> Result<AnyDomain, Failure> {
    let Some(path) = &args.input else {
        if args.bounding.is_some() {
            return Err(Failure::input("--bounding needs a CSV input file"));
        }
        if args.periodic.is_some() {
            return Err(Failure::input("--periodic needs a CSV input file"));
        }
        return Ok(AnyDomain::Bounded(Domain::hexagon_example()));
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::input(format!("cannot read {}: {e}", path.display())))?;
    let bad = |m: String| Failure::input(format!("{}: {m}", path.display()));
    let is_csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_csv {
        if let Some(p) = args.periodic.as_deref() {
            let p: Vec<f64> = p
                .split(',')
                .map(|v| v.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .ok()
                .filter(|v: &Vec<f64>| v.len() == 2)
                .ok_or_else(|| {
                    Failure::input(format!(
                        "--periodic: expected LX,LY (two numbers), got '{p}'"
                    ))
                })?;
            let holes = parse_holes_csv(&text).map_err(|e| bad(e.to_string()))?;
            return PeriodicDomain::new([p[0], p[1]], holes)
                .map(AnyDomain::Periodic)
                .map_err(|e| bad(e.to_string()));
        }
        let b = args.bounding.as_deref().ok_or_else(|| {
            bad(
                "a CSV of holes needs the bounding circle --bounding X,Y,R or a period \
                 --periodic LX,LY"
                    .into(),
            )
        })?;
        let b = parse_triple(b).map_err(|e| Failure::input(format!("--bounding: {e}")))?;
        let holes = parse_holes_csv(&text).map_err(|e| bad(e.to_string()))?;
        Domain::bounded(
            Circle {
                center: [b[0], b[1]],
                radius: b[2],
            },
            holes,
        )
        .map(AnyDomain::Bounded)
        .map_err(|e| bad(e.to_string()))
    } else {
        if args.periodic.is_some() {
            return Err(bad(
                "--periodic is for CSV input; a periodic JSON domain has its own \"periodic\""
                    .into(),
            ));
        }
        if args.bounding.is_some() {
            return Err(bad(
                "--bounding is for CSV input; a JSON domain has its own \"bounding\"".into(),
            ));
        }
        if text.trim().is_empty() {
            return Err(bad("the file is empty".into()));
        }
        AnyDomain::from_json_str(&text).map_err(|e| {
            let mut m = e.to_string();
            if m.contains("number out of range") {
                // serde_json's wording for 1e999 and the like.
                m.push_str(
                    " (a number too large for a 64-bit float, such as 1e999, is refused: \
                     every number must be finite)",
                );
            }
            bad(m)
        })
    }
}

fn parse_first(text: &str) -> Result<FirstCell, String> {
    let t = text.trim();
    let (num, rel) = match t.strip_suffix('r') {
        Some(n) => (n, true),
        None => (t, false),
    };
    let v: f64 = num
        .parse()
        .map_err(|_| format!("'{text}' is not a first cell height"))?;
    Ok(if rel {
        FirstCell::Relative(v)
    } else {
        FirstCell::Absolute(v)
    })
}

/// `ID:FIRST[:GROWTH]` for `--circle-clustering`.
pub fn parse_circle_clustering(text: &str, growth: f64) -> Result<(i32, Clustering), String> {
    let parts: Vec<&str> = text.split(':').collect();
    if !(2..=3).contains(&parts.len()) {
        return Err(format!(
            "--circle-clustering: expected ID:FIRST[:GROWTH], got '{text}'"
        ));
    }
    let id: i32 = parts[0]
        .trim()
        .parse()
        .map_err(|_| format!("--circle-clustering: '{}' is not a circle id", parts[0]))?;
    let first = parse_first(parts[1]).map_err(|e| format!("--circle-clustering: {e}"))?;
    let growth = match parts.get(2) {
        Some(g) => g
            .trim()
            .parse()
            .map_err(|_| format!("--circle-clustering: '{g}' is not a growth ratio"))?,
        None => growth,
    };
    Ok((
        id,
        Clustering {
            first: Some(first),
            growth,
        },
    ))
}

/// `ID:N` for `--wall-cells`.
pub fn parse_wall_cells(text: &str) -> Result<(i32, usize), String> {
    let (id, n) = text
        .split_once(':')
        .ok_or_else(|| format!("--wall-cells: expected ID:N, got '{text}'"))?;
    let id = id
        .trim()
        .parse()
        .map_err(|_| format!("--wall-cells: '{id}' is not a circle id"))?;
    let n = n
        .trim()
        .parse()
        .map_err(|_| format!("--wall-cells: '{n}' is not a cell count"))?;
    Ok((id, n))
}

fn exact_options(args: &Args) -> Result<Options, Failure> {
    let first = match (args.first_height, args.first_height_rel) {
        (Some(h), _) => Some(FirstCell::Absolute(h)),
        (None, Some(f)) => Some(FirstCell::Relative(f)),
        (None, None) => None,
    };
    let circle_clustering = args
        .circle_clustering
        .iter()
        .map(|t| parse_circle_clustering(t, args.growth))
        .collect::<Result<Vec<_>, _>>()
        .map_err(Failure::input)?;
    let wall_cells = args
        .wall_cells
        .iter()
        .map(|t| parse_wall_cells(t))
        .collect::<Result<Vec<_>, _>>()
        .map_err(Failure::input)?;
    Ok(Options {
        mode: match args.mode {
            ModeArg::Exact => Mode::Exact,
            ModeArg::Paper => Mode::Paper,
        },
        cells: args.block_cells.unwrap_or(args.cells),
        block_cells: args.block_cells,
        cell_size: args.cell_size,
        clustering: Clustering {
            first,
            growth: args.growth,
        },
        circle_clustering,
        wall_cells,
        smooth: args.smooth,
        refine_ratio: (!args.no_refine).then_some(args.refine_ratio),
        collapse_fraction: args.collapse_fraction,
        ..Options::default()
    })
    .and_then(|o| {
        medial_blocks::mesher::validate_block_cells(&o)
            .map_err(|e| Failure::input(e.to_string()))?;
        Ok(o)
    })
}

/// `--compare-modes`: figures of both modes into `modes.json`.
fn compare_modes(
    domain: &Domain,
    options: &Options,
    done: &medial_blocks::Mesh,
    args: &Args,
    quiet: bool,
) -> Result<(), Failure> {
    use medial_blocks::exact_mode::metrics::Figures;
    let other_mode = match options.mode {
        Mode::Exact => Mode::Paper,
        Mode::Paper => Mode::Exact,
    };
    let other = medial_blocks::mesh(
        domain,
        &Options {
            mode: other_mode,
            ..options.clone()
        },
    )
    .map_err(|e| Failure::output(format!("the other mode failed: {e}")))?;
    let (exact, paper) = match options.mode {
        Mode::Exact => (done, &other),
        Mode::Paper => (&other, done),
    };
    let value = serde_json::json!({
        "exact": Figures::of(domain, exact),
        "paper": Figures::of(domain, paper),
    });
    let path = args.output.join("modes.json");
    let text = serde_json::to_string_pretty(&value)
        .map_err(|e| Failure::output(format!("cannot encode modes.json: {e}")))?;
    std::fs::write(&path, text + "\n")
        .map_err(|e| Failure::output(format!("cannot write {}: {e}", path.display())))?;
    // Both modes were run: report.json (when written) gains the per-mode figures too.
    let report_path = args.output.join("report.json");
    if let Ok(old) = std::fs::read_to_string(&report_path) {
        let mut report: serde_json::Value = serde_json::from_str(&old)
            .map_err(|e| Failure::output(format!("cannot read back report.json: {e}")))?;
        if let Some(obj) = report.as_object_mut() {
            obj.insert("modes".into(), value.clone());
        }
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| Failure::output(format!("cannot encode report.json: {e}")))?;
        medial_blocks::output::write_atomic(&report_path, |w| {
            use std::io::Write;
            w.write_all(text.as_bytes())?;
            w.write_all(b"\n")
        })
        .map_err(|e| Failure::output(format!("cannot write {}: {e}", report_path.display())))?;
    }
    if !quiet {
        for (name, m) in [("exact", exact), ("paper", paper)] {
            let f = Figures::of(domain, m);
            println!(
                "{name}: angles {:.1}..{:.1}, min scaled Jacobian {:.3}, wall orthogonality \
                 {:.1e} deg, max aspect ratio {:.1}, inverted {}",
                f.min_angle_deg,
                f.max_angle_deg,
                f.min_scaled_jacobian,
                f.max_wall_orthogonality_deviation_deg,
                f.max_aspect_ratio,
                f.inverted_cells
            );
        }
    }
    Ok(())
}

/// A spinner on stderr, hidden with `--quiet` or when stderr is not a terminal.
fn progress(global: Global) -> ProgressBar {
    if global.quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(Duration::from_millis(120));
    bar
}

/// Format a figure for the summary table.
fn fig(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() && v.abs() < 1e5 => format!("{:.3}", v + 0.0),
        Some(v) if v.is_finite() => format!("{v:.3e}"),
        _ => "-".into(),
    }
}

/// The note on stderr when exact mode (the default) fell back to the paper pipeline's
/// geometry for a layout with one or more holes (`"geometry": "paper"` in report.json; one
/// hole: the template ring instead of exact mode's annulus), which would otherwise go
/// unnoticed: `None` for a mesh of the geometry asked for, and for the disk template (paper
/// geometry by design).
pub fn fallback_note(options: &Options, mesh: &medial_blocks::Mesh) -> Option<&'static str> {
    (options.mode == Mode::Exact
        && mesh.geometry == medial_blocks::mesh::Geometry::Paper
        && mesh.holes >= 1)
        .then_some(
            "note: exact mode fell back to the paper pipeline's geometry for this layout \
             (\"geometry\": \"paper\" in report.json): the exact construction disagreed with \
             the sampled blocking, or could not be built with these options",
        )
}

/// The note on stderr when exact-mode wall options were given for a domain without holes: the
/// disk is meshed by its five-block template (no medial axis to build spokes on), which does
/// not read them; `None` otherwise.
pub fn disk_note(options: &Options, mesh: &medial_blocks::Mesh) -> Option<&'static str> {
    let asked = options.clustering.first.is_some()
        || !options.circle_clustering.is_empty()
        || !options.wall_cells.is_empty()
        || options.cell_size.is_some()
        || options.smooth > 0;
    (options.mode == Mode::Exact
        && mesh.holes == 0
        && mesh.geometry != medial_blocks::mesh::Geometry::Exact
        && asked)
        .then_some(
            "note: a domain without holes is meshed by the disk template (five blocks, equal \
             spacing): --first-height, --first-height-rel, --circle-clustering, --wall-cells, \
             --cell-size and --smooth do not apply to it",
        )
}

/// A block side with at least this many cells makes [`fine_gap_note`] speak.
pub const FINE_GAP_SIDE_CELLS: usize = 2048;

/// The note on stderr when exact mode's own counts (no `--block-cells`) gave a block side of
/// [`FINE_GAP_SIDE_CELLS`] cells or more: cells about square in a gap far narrower than the
/// cell size need thousands along the walls (a row of 9 circles 1e-4 of their radius apart:
/// 36 million cells, 13 691 along one side). Says why and what caps it; `None` otherwise.
pub fn fine_gap_note(options: &Options, mesh: &medial_blocks::Mesh) -> Option<String> {
    if options.mode != Mode::Exact
        || options.block_cells.is_some()
        || mesh.geometry != medial_blocks::mesh::Geometry::Exact
    {
        return None;
    }
    let longest = mesh.grids.iter().map(|g| g.ni.max(g.nj)).max()?;
    let cells: usize = mesh.grids.iter().map(|g| g.cells()).sum();
    (longest >= FINE_GAP_SIDE_CELLS).then(|| {
        format!(
            concat!(
                "note: {cells} cells, {longest} along one block side: exact mode keeps cells ",
                "about square, so walls much closer than the cell size get thousands of cells ",
                "along them; --block-cells N (N x N per block, more only where a wall turns ",
                "over 15 degrees per cell) or a larger --cell-size gives a coarser mesh"
            ),
            cells = cells,
            longest = longest
        )
    })
}

/// The note for a mesh whose default target cell size was coarsened
/// ([`medial_blocks::Mesh::coarsened_cell_size`]): the two sizes and how to choose one.
pub fn coarsened_note(options: &Options, mesh: &medial_blocks::Mesh) -> Option<String> {
    let [from, to] = mesh.coarsened_cell_size?;
    let cells: usize = mesh.grids.iter().map(|g| g.cells()).sum();
    Some(format!(
        concat!(
            "note: the default cell size {from:.4e} (the median empty-circle radius over ",
            "--cells) would give over {budget} nodes for {blocks} blocks, so it was coarsened ",
            "to {to:.4e} ({cells} cells); --cell-size or --block-cells chooses the size"
        ),
        from = from,
        budget = medial_blocks::exact_mode::node_budget(mesh.layout.blocks.len(), options.cells),
        blocks = mesh.layout.blocks.len(),
        to = to,
        cells = cells
    ))
}

/// The short summary printed after meshing.
pub fn summary(r: &report::Report) -> String {
    let mut s = format!(
        "{} holes -> {} blocks, {} cells ({} medial vertices, {} arcs), inverted cells {}\n",
        r.holes, r.blocks, r.cells, r.medial_vertices, r.medial_arcs, r.inverted_cells
    );
    s.push_str(&format!(
        "mean smallest angle {:.1} deg, mean largest {:.1} deg\n",
        r.mean_min_angle_deg, r.mean_max_angle_deg
    ));
    s.push_str(&format!(
        "{:<24}{:>10}{:>10}   {:<16}{:>8}\n",
        "metric", "min", "max", "acceptable", "outside"
    ));
    for (name, m) in r.quality.named() {
        let unit = if name == "interface_growth_ratio" {
            "faces"
        } else {
            "cells"
        };
        s.push_str(&format!(
            "{:<24}{:>10}{:>10}   {:<16}{:>8} {unit}\n",
            name,
            fig(m.min),
            fig(m.max),
            format!("{} .. {}", m.acceptable[0], m.acceptable[1]),
            m.outside
        ));
    }
    s.push_str(&format!(
        "wall orthogonality: largest deviation {} deg\n",
        fig(r.max_wall_orthogonality_deviation_deg)
    ));
    s
}

/// `--timings`: the table on stderr (unless quiet) and `DIR/timings.json` with the mesh's
/// size, the thread count and [`timings::Timings::to_json`].
fn report_timings(
    t: &timings::Timings,
    mesh: &medial_blocks::Mesh,
    args: &Args,
    quiet: bool,
) -> Result<(), Failure> {
    let mut value = t.to_json();
    if let Some(obj) = value.as_object_mut() {
        obj.insert("holes".into(), mesh.holes.into());
        obj.insert("blocks".into(), mesh.layout.blocks.len().into());
        let cells: usize = mesh.grids.iter().map(|g| g.cells()).sum();
        obj.insert("cells".into(), cells.into());
        obj.insert("threads".into(), rayon::current_num_threads().into());
        obj.insert("formats".into(), args.format.clone().into());
        obj.insert("binary".into(), args.binary.into());
        obj.insert(
            "huge_pages".into(),
            super::allocator::huge_pages_active().into(),
        );
        obj.insert("pinned_threads".into(), super::affinity::pinned().into());
    }
    let text = serde_json::to_string_pretty(&value)
        .map_err(|e| Failure::output(format!("cannot encode timings.json: {e}")))?;
    let path = args.output.join("timings.json");
    medial_blocks::output::write_atomic(&path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })
    .map_err(|e| Failure::output(format!("cannot write {}: {e}", path.display())))?;
    if !quiet {
        eprint!("{}", t.table());
    }
    Ok(())
}

pub fn run(args: Args, global: Global) -> Result<(), Failure> {
    let recording = args.timings.then(timings::Recording::start);
    let formats =
        Format::parse_list(&args.format).map_err(|e| Failure::input(format!("--format: {e}")))?;
    let domain = timings::span("input", || read_domain(&args))?;
    let mut options = exact_options(&args)?;
    // Only report.json and connectivity.json to write: no writer reads a node, so the grids
    // are measured as they are made and their nodes dropped (issue 8: a tenth of a run's CPU
    // time went into the fresh pages of nodes nobody wrote). The same files.
    options.keep_nodes = !(formats.iter().all(|f| *f == Format::Json)
        && args.transition.is_none()
        && !args.compare_modes);
    // One mesh, then the process exits: its working memory is left to the kernel (as the
    // mesh itself is, at the end of this function).
    options.exits_after_mesh = true;
    let bar = progress(global);
    let holes = match &domain {
        AnyDomain::Bounded(d) => d.hole_count(),
        AnyDomain::Periodic(p) => p.holes().len(),
    };
    bar.set_message(format!("meshing {holes} holes"));
    let result = match (&domain, args.transition) {
        (AnyDomain::Bounded(d), Some(s)) => match args.transition_rect.as_deref() {
            None => medial_blocks::transition::mesh_with_transition(d, &options, s),
            Some(text) => {
                let v: Vec<f64> = text
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .ok()
                    .filter(|v: &Vec<f64>| v.len() == 4)
                    .ok_or_else(|| {
                        Failure::input(format!(
                            "--transition-rect: expected XMIN,YMIN,XMAX,YMAX (four numbers), \
                             got '{text}'"
                        ))
                    })?;
                let b = d.bounding();
                medial_blocks::transition::Rect::from_bounds(
                    [v[0], v[1], v[2], v[3]],
                    s,
                    b.center,
                    b.radius,
                )
                .and_then(|r| medial_blocks::transition::mesh_with_transition_rect(d, &options, r))
            }
        },
        (AnyDomain::Periodic(_), Some(_)) => {
            return Err(Failure::input(
                "--transition is for bounded domains (a periodic mesh has no outer boundary)",
            ))
        }
        _ => mesh_any(&domain, &options),
    };
    let mesh = result.map_err(|e| {
        bar.finish_and_clear();
        match e {
            medial_blocks::MeshError::Internal(_) => Failure::output(e.to_string()),
            _ => Failure::input(e.to_string()),
        }
    })?;
    if !global.quiet {
        if let Some(note) = fallback_note(&options, &mesh) {
            bar.suspend(|| eprintln!("{note}"));
        }
        if let Some(note) = disk_note(&options, &mesh) {
            bar.suspend(|| eprintln!("{note}"));
        }
        if let Some(note) = fine_gap_note(&options, &mesh) {
            bar.suspend(|| eprintln!("{note}"));
        }
        if let Some(note) = coarsened_note(&options, &mesh) {
            bar.suspend(|| eprintln!("{note}"));
        }
    }
    // The report (quality figures) and the block connectivity once, for report.json,
    // connectivity.json and the summary.
    let want_report = !global.quiet || formats.contains(&Format::Json);
    let conn = want_report.then(|| {
        timings::span("quality", || {
            medial_blocks::connectivity::Connectivity::new(&mesh.layout, &mesh.grids).ok()
        })
    });
    let conn = conn.flatten();
    let summary_report = want_report.then(|| report::Report::from_mesh_with(&mesh, conn.as_ref()));
    let written = timings::span("write", || {
        write_files_prepared(
            &mesh,
            &args.output,
            &formats,
            encoding(args.binary),
            summary_report.as_ref(),
            conn.as_ref(),
            |f| {
                bar.set_message(format!("writing {}", f.name()));
            },
        )
    });
    bar.finish_and_clear();
    written.map_err(|e| {
        Failure::output(format!("cannot write into {}: {e}", args.output.display()))
    })?;
    if !args.timings {
        // A timings.json left by an earlier run with --timings describes another mesh.
        let stale = args.output.join("timings.json");
        match std::fs::remove_file(&stale) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(Failure::output(format!(
                    "cannot remove the stale {}: {e}",
                    stale.display()
                )))
            }
            _ => {}
        }
    }
    if let Some(r) = summary_report.as_ref().filter(|_| !global.quiet) {
        print!("{}", summary(r));
        println!("written to {}/", args.output.display());
    }
    if args.compare_modes {
        let _stage = timings::enter("compare_modes");
        match &domain {
            AnyDomain::Bounded(d) => compare_modes(d, &options, &mesh, &args, global.quiet)?,
            AnyDomain::Periodic(_) => {
                return Err(Failure::input("--compare-modes is for bounded domains"))
            }
        }
    }
    if let Some(r) = recording {
        report_timings(&r.finish(), &mesh, &args, global.quiet)?;
    }
    // The process exits right after this: returning the grids and the connectivity to the
    // allocator one block at a time (~600 K allocations at 1e5 particles) would only delay
    // the exit, the kernel frees the whole address space at once (issue 8).
    std::mem::forget((conn, summary_report));
    std::mem::forget(mesh);
    Ok(())
}
