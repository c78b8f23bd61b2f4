//! `medial-blocks triangulate [POINTS.csv] [-o OUT.json]`: exact Delaunay triangulation of a CSV
//! point list, written as JSON
//! `{"triangles": [[i,j,k],...], "duplicates": [[first,dup],...], "cocircular_groups": [[...],...]}`
//! with 0-based indices of data rows (header and blank lines excluded). Triangles are
//! counter-clockwise, rotated to start at their smallest index, and sorted.

use super::Failure;
use medial_blocks::geometry::{Point, Triangulation, TriangulationError};
use medial_blocks::input::{parse_points_csv, CsvError};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
#[command(after_help = "Examples:
  medial-blocks triangulate                           # the built-in example, JSON on stdout
  medial-blocks triangulate points.csv -o tri.json

Output JSON: {\"triangles\": [[i,j,k],...], \"duplicates\": [[first,dup],...],
              \"cocircular_groups\": [[...],...]} (0-based data-row indices).")]
pub struct Args {
    /// CSV of `x,y` per line (an optional header line is skipped). Without it, a built-in
    /// example (perturbed grid, one exact co-circular group, one duplicate).
    pub points: Option<PathBuf>,
    /// Output JSON file (default: standard output).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

#[derive(serde::Serialize)]
struct Output {
    triangles: Vec<[u32; 3]>,
    duplicates: Vec<[u32; 2]>,
    cocircular_groups: Vec<Vec<u32>>,
}

/// Points of a CSV text and the 1-based line number of each data row
/// ([`medial_blocks::input::parse_points_csv`]), with errors phrased for the command line.
fn parse_csv(text: &str, name: &str) -> Result<(Vec<Point>, Vec<usize>), Failure> {
    parse_points_csv(text).map_err(|e| {
        Failure::input(match e {
            CsvError::WrongColumnCount { line, found, .. } => {
                format!("{name}:{line}: expected 2 columns `x,y`, found {found}")
            }
            CsvError::NotANumber { line, field } => {
                format!("{name}:{line}: `{field}` is not a number")
            }
            CsvError::Empty | CsvError::NoRows { .. } => format!("{name}: no points"),
            CsvError::TooManyRows { line, max } => {
                format!("{name}:{line}: more than {max} points")
            }
        })
    })
}

/// The built-in example: an 8 x 8 grid with small dyadic perturbations, a copy of one of its
/// points, and the 12 lattice points of a radius-5 circle (one exact co-circular group).
pub fn example_points() -> Vec<Point> {
    let mut pts = Vec::new();
    let mut h: u32 = 12345;
    for i in 0..8 {
        for j in 0..8 {
            h = h.wrapping_mul(1_103_515_245).wrapping_add(12345);
            let dx = f64::from((h >> 16) % 17) / 64.0 - 0.125;
            let dy = f64::from((h >> 8) % 17) / 64.0 - 0.125;
            pts.push([f64::from(i) + dx, f64::from(j) + dy]);
        }
    }
    pts.push(pts[9]);
    for (x, y) in [
        (5, 0),
        (4, 3),
        (3, 4),
        (0, 5),
        (-3, 4),
        (-4, 3),
        (-5, 0),
        (-4, -3),
        (-3, -4),
        (0, -5),
        (3, -4),
        (4, -3),
    ] {
        pts.push([14.0 + f64::from(x), 3.5 + f64::from(y)]);
    }
    pts
}

fn error_message(e: &TriangulationError, name: &str, lines: &[usize]) -> Failure {
    match e {
        TriangulationError::NonFinite { index } => Failure::input(format!(
            "{name}:{}: non-finite coordinate",
            lines.get(*index).copied().unwrap_or(0)
        )),
        TriangulationError::Internal { .. } => Failure::output(format!("{name}: {e}")),
        _ => Failure::input(format!("{name}: {e}")),
    }
}

pub fn run(args: Args) -> Result<(), Failure> {
    let (points, lines, name) = match &args.points {
        Some(path) => {
            let name = path.display().to_string();
            let text = std::fs::read_to_string(path)
                .map_err(|e| Failure::input(format!("{name}: cannot read: {e}")))?;
            let (p, l) = parse_csv(&text, &name)?;
            (p, l, name)
        }
        None => {
            let p = example_points();
            let l = (1..=p.len()).collect();
            (p, l, "built-in example".to_string())
        }
    };
    let dt = Triangulation::new(&points).map_err(|e| error_message(&e, &name, &lines))?;
    let mut triangles: Vec<[u32; 3]> = dt
        .triangles()
        .map(|t| {
            let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        })
        .collect();
    triangles.sort_unstable();
    let out = Output {
        triangles,
        duplicates: dt.duplicates().iter().map(|&(a, b)| [a, b]).collect(),
        cocircular_groups: dt.cocircular_groups(),
    };
    let write = |w: &mut dyn Write| -> std::io::Result<()> {
        serde_json::to_writer(&mut *w, &out)?;
        writeln!(w)?;
        w.flush()
    };
    match &args.output {
        Some(path) => {
            let file = std::fs::File::create(path)
                .map_err(|e| Failure::output(format!("cannot create {}: {e}", path.display())))?;
            write(&mut std::io::BufWriter::new(file))
                .map_err(|e| Failure::output(format!("cannot write {}: {e}", path.display())))
        }
        None => write(&mut std::io::BufWriter::new(std::io::stdout().lock()))
            .map_err(|e| Failure::output(format!("cannot write standard output: {e}"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_header_blank_lines_and_spaces() {
        let (p, l) = parse_csv("x, y\n\n 1.5 , 2\n3,4  \n\n", "t").ok().unwrap();
        assert_eq!(p, vec![[1.5, 2.0], [3.0, 4.0]]);
        assert_eq!(l, vec![3, 4]);
    }

    #[test]
    fn csv_errors_name_the_line() {
        let e = parse_csv("1,2\n3,x\n", "t").err().unwrap();
        assert_eq!(e.code, 2);
        assert!(e.message.contains("t:2"), "{}", e.message);
        let e = parse_csv("1,2\n3,4,5\n", "t").err().unwrap();
        assert!(e.message.contains("t:2"), "{}", e.message);
        assert!(parse_csv("\n\n", "t").is_err());
        assert!(parse_csv("x,y\n", "t").is_err());
    }

    #[test]
    fn example_has_a_group_and_a_duplicate() {
        let dt = Triangulation::new(&example_points()).ok().unwrap();
        assert_eq!(dt.duplicates(), &[(9, 64)]);
        let groups = dt.cocircular_groups();
        assert!(
            groups.contains(&(65..77).collect::<Vec<u32>>()),
            "{groups:?}"
        );
    }
}
