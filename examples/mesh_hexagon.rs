//! Mesh the paper's Hexagon and write every format into `out_hexagon/`.
//!
//! `cargo run --release --example mesh_hexagon [DIR]`

use medial_blocks::output::{report::Report, write_files, Format};
use medial_blocks::{layouts, mesh, Options};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "out_hexagon".into());
    let domain = layouts::hexagon();
    let mesh = mesh(&domain, &Options::default())?;
    write_files(&mesh, dir.as_ref(), Format::ALL)?;
    let r = Report::from_mesh(&mesh);
    println!(
        "{} blocks, {} cells, angles {:.1}..{:.1} deg (means {:.1}/{:.1}); written to {dir}/",
        r.blocks,
        r.cells,
        r.min_angle_deg,
        r.max_angle_deg,
        r.mean_min_angle_deg,
        r.mean_max_angle_deg
    );
    Ok(())
}
