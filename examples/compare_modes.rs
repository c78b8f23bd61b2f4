//! Paper mode and exact mode side by side on the three layout kinds of the paper's section 5.
//!
//! `cargo run --release --example compare_modes [CELLS]` prints a markdown table (the README's
//! "Quality: paper mode vs exact mode" section is its output with the default `CELLS = 16`).

use medial_blocks::blocking::build_layout;
use medial_blocks::exact_mode::benchmarks::{bubbles, hex_packing, lattice, PAPER_TABLE};
use medial_blocks::exact_mode::exact_vertices;
use medial_blocks::exact_mode::metrics::{vertex_corner_limit, Figures};
use medial_blocks::{mesh, Domain, Mode, Options};

fn main() {
    let cells: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(16);
    let layouts: [(&str, Domain); 3] = [
        ("Hexagon (7-hole hexagonal packing)", hex_packing()),
        ("Lattice (12 large + 9 small)", lattice()),
        ("Bubble (20 random bubbles)", bubbles()),
    ];
    println!(
        "| layout | mode | blocks | cells | min angle | max angle | mean min | mean max | \
         min scaled Jacobian | max wall orthogonality dev. | max aspect ratio | inverted |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (k, (name, domain)) in layouts.iter().enumerate() {
        let p = PAPER_TABLE[k];
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
        println!(
            "| {name} | paper's table ({}) | | | {:.0} | {:.0} | {:.0} | {:.0} | | | | |",
            p.0, p.1, p.2, p.3, p.4
        );
        for (label, mode) in [("paper", Mode::Paper), ("exact", Mode::Exact)] {
            let options = Options {
                mode,
                cells,
                ..Options::default()
            };
            match mesh(domain, &options) {
                Ok(m) => {
                    let f = Figures::of(domain, &m);
                    println!(
                        "| {name} | {label} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.3} | \
                         {:.2e} | {:.1} | {} |",
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
                }
                Err(e) => println!("| {name} | {label} | error: {e} | | | | | | | | | |"),
            }
        }
    }
}
