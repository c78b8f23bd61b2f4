//! `medial-blocks mesh [INPUT] [-o DIR] [--mode paper] [--cells N] [--format LIST]`.

use super::Failure;
use medial_blocks::domain::{AnyDomain, Circle, Domain};
use medial_blocks::output::{report, write_files, Format};
use medial_blocks::periodic::PeriodicDomain;
use medial_blocks::{mesh_any, Mode, Options};
use std::path::PathBuf;

const DEFAULT_FORMATS: &str = "vtk,svg,json";

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeArg {
    /// The paper as written: circumcenter polylines, equally spaced TFI.
    Paper,
}

#[derive(clap::Args, Debug)]
#[command(after_help = "Examples:
  medial-blocks mesh                         # the built-in 7-hole hexagon example into out/
  medial-blocks mesh layout.json -o run1 --cells 24
  medial-blocks mesh holes.csv --bounding 0,0,10 --format all
  medial-blocks mesh bubbles.csv --periodic 1,1   # one period of a periodic layout
  medial-blocks mesh layout.json --transition 0.25  # join a Cartesian grid of spacing 0.25

Input JSON: {\"bounding\": {\"center\": [x, y], \"radius\": R},
             \"holes\": [{\"center\": [x, y], \"radius\": r}, ...]}
Periodic JSON: {\"periodic\": {\"size\": [Lx, Ly]}, \"holes\": [...]} (holes may cross the box's
  edges; the mesh is one period whose zig-zag sides match their partners on the opposite side).
Input CSV (file name ending in .csv): x,y,r per line (an optional header line is skipped),
  with the bounding circle given by --bounding X,Y,R, or a period by --periodic LX,LY.
Files in DIR: mesh.vtm + mesh/*.vts (vtk), mesh.xyz + mesh.p3d (plot3d), mesh.msh + mesh.geo
  (gmsh), mesh.svg (svg), mesh.png (png), report.json + connectivity.json (json).
Exit codes: 0 success, 1 output could not be written or internal error, 2 bad input.")]
pub struct Args {
    /// Domain JSON, or a CSV of holes (`x,y,r`); without it, the built-in 7-hole hexagon.
    pub input: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(short, long, default_value = "out")]
    pub output: PathBuf,
    /// Geometry of the blocks.
    #[arg(long, value_enum, default_value_t = ModeArg::Paper)]
    pub mode: ModeArg,
    /// Target number of cells along a block side.
    #[arg(long, default_value_t = 16)]
    pub cells: usize,
    /// Writers, comma separated: vtk, plot3d, gmsh, svg, png, json, or all.
    #[arg(long, default_value = DEFAULT_FORMATS)]
    pub format: String,
    /// The bounding circle `X,Y,R` for a CSV input.
    #[arg(long, allow_hyphen_values = true)]
    pub bounding: Option<String>,
    /// Add a ring of transition blocks out to a square whose boundary nodes are nodes of a
    /// Cartesian background grid of this spacing (origin at 0); bounded domains only.
    #[arg(long)]
    pub transition: Option<f64>,
    /// The period `LX,LY` for a CSV input: mesh one period of a periodic layout.
    #[arg(long, conflicts_with = "bounding")]
    pub periodic: Option<String>,
    /// Print nothing on success.
    #[arg(short, long)]
    pub quiet: bool,
}

fn parse_numbers(text: &str, what: &str, count: usize) -> Result<Vec<f64>, String> {
    let values: Vec<&str> = text.split(',').map(str::trim).collect();
    if values.len() != count {
        return Err(format!(
            "{what}: expected {count} comma-separated numbers, found {}",
            values.len()
        ));
    }
    values
        .iter()
        .map(|v| {
            v.parse::<f64>()
                .map_err(|_| format!("{what}: '{v}' is not a number"))
        })
        .collect()
}

/// Holes from CSV text: `x,y,r` per line; blank lines skipped; a first line that is not
/// numeric is a header.
pub fn parse_holes_csv(text: &str) -> Result<Vec<Circle>, String> {
    let mut holes = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let first_field = line.split(',').next().unwrap_or("").trim();
        if holes.is_empty() && n == 0 && first_field.parse::<f64>().is_err() {
            continue; // header
        }
        let v = parse_numbers(line, &format!("line {}", n + 1), 3)?;
        holes.push(Circle {
            center: [v[0], v[1]],
            radius: v[2],
        });
    }
    if holes.is_empty() && text.trim().is_empty() {
        return Err("the CSV file is empty".into());
    }
    Ok(holes)
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
            let p = parse_numbers(p, "--periodic", 2).map_err(Failure::input)?;
            let holes = parse_holes_csv(&text).map_err(bad)?;
            return PeriodicDomain::new([p[0], p[1]], holes)
                .map(AnyDomain::Periodic)
                .map_err(|e| bad(e.to_string()));
        }
        let b = args.bounding.as_deref().ok_or_else(|| {
            bad("a CSV of holes needs the bounding circle --bounding X,Y,R or a period --periodic LX,LY".into())
        })?;
        let b = parse_numbers(b, "--bounding", 3).map_err(Failure::input)?;
        let holes = parse_holes_csv(&text).map_err(bad)?;
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
        AnyDomain::from_json_str(&text).map_err(|e| bad(e.to_string()))
    }
}

pub fn run(args: Args) -> Result<(), Failure> {
    let formats =
        Format::parse_list(&args.format).map_err(|e| Failure::input(format!("--format: {e}")))?;
    let domain = read_domain(&args)?;
    let options = Options {
        mode: match args.mode {
            ModeArg::Paper => Mode::Paper,
        },
        cells: args.cells,
    };
    let result = match (&domain, args.transition) {
        (AnyDomain::Bounded(d), Some(s)) => {
            medial_blocks::transition::mesh_with_transition(d, &options, s)
        }
        (AnyDomain::Periodic(_), Some(_)) => {
            return Err(Failure::input(
                "--transition is for bounded domains (a periodic mesh has no outer boundary)",
            ))
        }
        _ => mesh_any(&domain, &options),
    };
    let mesh = result.map_err(|e| match e {
        medial_blocks::MeshError::Internal(_) => Failure::output(e.to_string()),
        _ => Failure::input(e.to_string()),
    })?;
    write_files(&mesh, &args.output, &formats).map_err(|e| {
        Failure::output(format!("cannot write into {}: {e}", args.output.display()))
    })?;
    if !args.quiet {
        let r = report::Report::from_mesh(&mesh);
        println!(
            "{} holes -> {} blocks, {} cells ({} medial vertices, {} arcs)",
            r.holes, r.blocks, r.cells, r.medial_vertices, r.medial_arcs
        );
        println!(
            "angles {:.1}..{:.1} deg (mean smallest {:.1}, mean largest {:.1}), inverted cells {}",
            r.min_angle_deg,
            r.max_angle_deg,
            r.mean_min_angle_deg,
            r.mean_max_angle_deg,
            r.inverted_cells
        );
        println!("written to {}/", args.output.display());
    }
    Ok(())
}
