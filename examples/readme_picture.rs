//! The README's picture: the built-in Hexagon example meshed with 8 cells per block side,
//! rendered 480 pixels wide into `docs/hexagon.png` (or the path given).
//!
//! `cargo run --release --example readme_picture [PATH]`

use medial_blocks::output::png;
use medial_blocks::{layouts, mesh, Options};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "docs/hexagon.png".into());
    let options = Options {
        cells: 8,
        ..Options::default()
    };
    let mesh = mesh(&layouts::hexagon(), &options)?;
    if let Some(parent) = std::path::Path::new(&path).parent() {
        std::fs::create_dir_all(parent)?;
    }
    png::write_with_width(&mesh, path.as_ref(), 480)?;
    println!("wrote {path}");
    Ok(())
}
