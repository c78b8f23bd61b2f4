//! Paper mode and exact mode side by side on the three layout kinds of the paper's section 5.
//!
//! `cargo run --release --example compare_modes [CELLS]` prints a markdown table (the README's
//! "Quality: paper mode vs exact mode" section is its output with the default `CELLS = 16`).
//! Rows per layout: the corner limit of the layout (half the smallest angle between two
//! spokes at a medial vertex: no spoke-aligned grid can do better), the paper's own figures
//! for its layout of that kind, then paper mode, exact mode, exact mode with about paper
//! mode's cell count, and exact mode with 20 Winslow sweeps, all with `--cells CELLS`.

use medial_blocks::blocking::build_layout;
use medial_blocks::exact_mode::benchmarks::{bubbles, hex_packing, lattice, PAPER_TABLE};
use medial_blocks::exact_mode::exact_vertices;
use medial_blocks::exact_mode::metrics::{vertex_corner_limit, Figures};
use medial_blocks::{mesh, Domain, Mode, Options};

fn row(name: &str, label: &str, domain: &Domain, options: &Options) -> Option<Figures> {
    match mesh(domain, options) {
        Ok(m) => {
            let f = Figures::of(domain, &m);
            println!(
                "| {name} | {label} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.3} | {:.1e} | \
                 {:.1} | {} |",
                f.blocks,
                f.cells,
                f.min_angle_deg,
                f.max_angle_deg,
                f.mean_min_angle_deg,
                f.mean_max_angle_deg,
                f.min_scaled_jacobian,
                f.max_wall_orthogonality_deviation_deg,
                f.max_aspect_ratio,
                f.inverted_cells
            );
            Some(f)
        }
        Err(e) => {
            println!("| {name} | {label} | error: {e} | | | | | | | | | |");
            None
        }
    }
}

fn main() {
    let cells: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(16);
    let layouts: [(&str, Domain); 3] = [
        ("Hexagon (7 holes)", hex_packing()),
        ("Lattice (12 + 9 holes)", lattice()),
        ("Bubble (20 holes)", bubbles()),
    ];
    println!(
        "| layout | mode | blocks | cells | min angle | max angle | mean min | mean max | \
         min scaled Jacobian | max wall orthogonality dev. (deg) | max aspect ratio | inverted |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (k, (name, domain)) in layouts.iter().enumerate() {
        let limit = build_layout(domain, &Options::default())
            .ok()
            .and_then(|b| exact_vertices(domain, &b.medial).ok())
            .map(|v| vertex_corner_limit(&v));
        if let Some((lo, hi)) = limit {
            println!(
                "| {name} | corner limit of the layout | | | {lo:.1} | {hi:.1} | | | {:.3} | | | |",
                lo.to_radians().sin()
            );
        }
        let p = PAPER_TABLE[k];
        println!(
            "| {name} | paper's table ({}) | | | {:.0} | {:.0} | {:.0} | {:.0} | | | | |",
            p.0, p.1, p.2, p.3, p.4
        );
        let base = Options {
            cells,
            ..Options::default()
        };
        let paper = row(
            name,
            "paper",
            domain,
            &Options {
                mode: Mode::Paper,
                ..base.clone()
            },
        );
        let exact = row(name, "exact", domain, &base);
        if let (Some(p), Some(e)) = (paper, exact) {
            // Cells grow with the square of `cells`.
            let scaled = (cells as f64 * (p.cells as f64 / e.cells as f64).sqrt()).round();
            let scaled = (scaled as usize).max(1);
            row(
                name,
                &format!("exact, --cells {scaled} (paper's cell budget)"),
                domain,
                &Options {
                    cells: scaled,
                    ..base.clone()
                },
            );
        }
        row(
            name,
            "exact, --smooth 20",
            domain,
            &Options {
                smooth: 20,
                ..base.clone()
            },
        );
    }
}
