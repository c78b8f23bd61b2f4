//! `medial-blocks mesh [INPUT] [-o DIR] [--mode paper] [--cells N] [--format LIST]`.

use super::Failure;
use medial_blocks::domain::{Circle, Domain};
use medial_blocks::input::{parse_holes_csv, parse_triple};
use medial_blocks::output::{report, write_files, Format};
use medial_blocks::{mesh, Mode, Options};
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

Input JSON: {\"bounding\": {\"center\": [x, y], \"radius\": R},
             \"holes\": [{\"center\": [x, y], \"radius\": r}, ...]}
Input CSV (file name ending in .csv): x,y,r per line (an optional header line is skipped),
  with the bounding circle given by --bounding X,Y,R.
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
    #[arg(long, default_value_t = 16, allow_negative_numbers = true)]
    pub cells: usize,
    /// Writers, comma separated: vtk, plot3d, gmsh, svg, png, json, or all.
    #[arg(long, default_value = DEFAULT_FORMATS)]
    pub format: String,
    /// The bounding circle `X,Y,R` for a CSV input.
    #[arg(long, allow_hyphen_values = true)]
    pub bounding: Option<String>,
    /// Print nothing on success.
    #[arg(short, long)]
    pub quiet: bool,
}

fn read_domain(args: &Args) -> Result<Domain, Failure> {
    let Some(path) = &args.input else {
        if args.bounding.is_some() {
            return Err(Failure::input("--bounding needs a CSV input file"));
        }
        return Ok(Domain::hexagon_example());
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::input(format!("cannot read {}: {e}", path.display())))?;
    let bad = |m: String| Failure::input(format!("{}: {m}", path.display()));
    let is_csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_csv {
        let b = args.bounding.as_deref().ok_or_else(|| {
            bad("a CSV of holes needs the bounding circle: --bounding X,Y,R".into())
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
        .map_err(|e| bad(e.to_string()))
    } else {
        if args.bounding.is_some() {
            return Err(bad(
                "--bounding is for CSV input; a JSON domain has its own \"bounding\"".into(),
            ));
        }
        if text.trim().is_empty() {
            return Err(bad("the file is empty".into()));
        }
        Domain::from_json_str(&text).map_err(|e| {
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
    let mesh = mesh(&domain, &options).map_err(|e| match e {
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
