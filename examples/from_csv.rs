//! Read holes from a CSV file (`x,y,r` per line), put them in a bounding circle that encloses
//! them with a margin, mesh, and write the VTK unstructured grid and the report.
//!
//! `cargo run --release --example from_csv -- holes.csv [DIR]`
//! Without arguments it meshes a small built-in CSV text.

use medial_blocks::output::{write_files, Format};
use medial_blocks::{mesh, Circle, Domain, Options};

const DEMO: &str = "x,y,r\n-1.0,0.0,0.4\n1.0,0.2,0.5\n0.0,1.6,0.3\n0.2,-1.5,0.45\n";

/// Parse `x,y,r` lines; a non-numeric first line is a header.
fn parse(text: &str) -> Result<Vec<Circle>, String> {
    let mut holes = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let v: Result<Vec<f64>, _> = line.split(',').map(|f| f.trim().parse::<f64>()).collect();
        match v {
            Ok(v) if v.len() == 3 => holes.push(Circle::new(v[0], v[1], v[2])),
            Err(_) if n == 0 => continue, // header
            _ => return Err(format!("line {}: expected x,y,r", n + 1)),
        }
    }
    Ok(holes)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let text = match args.next() {
        Some(path) => std::fs::read_to_string(path)?,
        None => DEMO.to_string(),
    };
    let dir = args.next().unwrap_or_else(|| "out_csv".into());
    let holes = parse(&text)?;
    // Bounding circle: centred on the holes' bounding box, one largest radius of margin.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut rmax: f64 = 0.0;
    for h in &holes {
        for k in 0..2 {
            lo[k] = lo[k].min(h.center[k] - h.radius);
            hi[k] = hi[k].max(h.center[k] + h.radius);
        }
        rmax = rmax.max(h.radius);
    }
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let reach = holes
        .iter()
        .map(|h| (h.center[0] - c[0]).hypot(h.center[1] - c[1]) + h.radius)
        .fold(0.0, f64::max);
    let domain = Domain::bounded(Circle::new(c[0], c[1], reach + 2.0 * rmax), holes)?;
    let mesh = mesh(&domain, &Options::default())?;
    write_files(&mesh, dir.as_ref(), &[Format::Vtu, Format::Json])?;
    println!("{} blocks written to {dir}/", mesh.layout.blocks.len());
    Ok(())
}
