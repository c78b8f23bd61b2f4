//! Remesh a few frames of particles moving through a container: each frame is a new domain,
//! meshed from scratch (the blocking is automatic, so topology changes are no problem), and
//! written as `DIR/frame_NNN/mesh.vtu` with its report.
//!
//! `cargo run --release --example moving_particles [DIR] [FRAMES]`

use medial_blocks::output::{report::Report, write_files, Format};
use medial_blocks::{mesh, Circle, Domain, Options};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = args.next().unwrap_or_else(|| "out_frames".into());
    let frames: usize = args.next().map_or(Ok(4), |s| s.parse())?;
    let options = Options {
        cells: 8,
        ..Options::default()
    };
    for f in 0..frames {
        let t = f as f64 * 0.15;
        // Five particles: a central one and four orbiting it at different speeds.
        let mut holes = vec![Circle::new(0.0, 0.0, 0.4)];
        for k in 0..4 {
            let a = std::f64::consts::FRAC_PI_2 * k as f64 + t * (1.0 + 0.25 * k as f64);
            let d = 1.2 + 0.1 * k as f64;
            holes.push(Circle::new(d * a.cos(), d * a.sin(), 0.3));
        }
        let domain = Domain::bounded(Circle::new(0.0, 0.0, 2.5), holes)?;
        let m = mesh(&domain, &options)?;
        let out = std::path::Path::new(&dir).join(format!("frame_{f:03}"));
        write_files(&m, &out, &[Format::Vtu, Format::Json])?;
        let r = Report::from_mesh(&m);
        println!(
            "frame {f}: {} blocks, {} cells, angles {:.1}..{:.1} deg, inverted {}",
            r.blocks, r.cells, r.min_angle_deg, r.max_angle_deg, r.inverted_cells
        );
    }
    Ok(())
}
