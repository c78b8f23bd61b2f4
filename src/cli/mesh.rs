//! `medial-blocks mesh [INPUT] [-o DIR] [--mode paper] [--cells N] [--format LIST]`.

use super::{Failure, Global};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use medial_blocks::domain::{Circle, Domain};
use medial_blocks::output::{report, write_files_with_progress, Format};
use medial_blocks::{mesh, Mode, Options};
use std::path::PathBuf;
use std::time::Duration;

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
  medial-blocks --threads 2 --quiet mesh layout.json --format vtu,plot3d

Input JSON: {\"bounding\": {\"center\": [x, y], \"radius\": R},
             \"holes\": [{\"center\": [x, y], \"radius\": r}, ...]}
Input CSV (file name ending in .csv): x,y,r per line (an optional header line is skipped),
  with the bounding circle given by --bounding X,Y,R.
Files in DIR: mesh.vtm + mesh/*.vts (vtk), mesh.vtu (vtu), mesh.xyz + mesh.p3d (plot3d),
  mesh.msh + mesh.geo (gmsh), mesh.svg (svg), mesh.png (png), report.json +
  connectivity.json (json), mesh.cgns (cgns: builds with --features cgns only).
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
    /// Writers, comma separated: vtk, vtu, plot3d, gmsh, svg, png, json, cgns (with the
    /// cgns feature), or all.
    #[arg(long, default_value = DEFAULT_FORMATS)]
    pub format: String,
    /// The bounding circle `X,Y,R` for a CSV input.
    #[arg(long, allow_hyphen_values = true)]
    pub bounding: Option<String>,
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
        let b = parse_numbers(b, "--bounding", 3).map_err(Failure::input)?;
        let holes = parse_holes_csv(&text).map_err(bad)?;
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
        Domain::from_json_str(&text).map_err(|e| bad(e.to_string()))
    }
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

pub fn run(args: Args, global: Global) -> Result<(), Failure> {
    let formats =
        Format::parse_list(&args.format).map_err(|e| Failure::input(format!("--format: {e}")))?;
    let domain = read_domain(&args)?;
    let options = Options {
        mode: match args.mode {
            ModeArg::Paper => Mode::Paper,
        },
        cells: args.cells,
    };
    let bar = progress(global);
    bar.set_message(format!("meshing {} holes", domain.hole_count()));
    let mesh = mesh(&domain, &options).map_err(|e| {
        bar.finish_and_clear();
        match e {
            medial_blocks::MeshError::Internal(_) => Failure::output(e.to_string()),
            _ => Failure::input(e.to_string()),
        }
    })?;
    let written = write_files_with_progress(&mesh, &args.output, &formats, |f| {
        bar.set_message(format!("writing {}", f.name()));
    });
    bar.finish_and_clear();
    written.map_err(|e| {
        Failure::output(format!("cannot write into {}: {e}", args.output.display()))
    })?;
    if !global.quiet {
        let r = report::Report::from_mesh(&mesh);
        print!("{}", summary(&r));
        println!("written to {}/", args.output.display());
    }
    Ok(())
}
