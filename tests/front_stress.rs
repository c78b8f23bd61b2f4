//! Larger random layouts (hundreds to thousands of holes, tiny gaps, offset and tiny
//! coordinates): counts must hold and nothing may fail. Slow-ish, so ignored by default:
//! `cargo test --release --test suite -- --ignored --nocapture front_stress::`.

use medial_blocks::blocking::build_layout;
use medial_blocks::domain::{Circle, Domain};
use medial_blocks::mesher::Options;
use std::f64::consts::TAU;

fn layout(seed: u64, h: usize, rmin: f64, rmax: f64, cx: f64, scale: f64, min_gap: f64) -> Domain {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let rr = 10.0 * scale;
    let b = Circle::new(cx, -cx * 0.5, rr);
    let mut holes: Vec<Circle> = Vec::new();
    let mut tries = 0;
    // Grid-free rejection using Domain validation is quadratic-ish; fine for scratch.
    while holes.len() < h && tries < 20 * h + 1000 {
        tries += 1;
        let r = (rmin + (rmax - rmin) * rnd()) * scale;
        let t = TAU * rnd();
        let q = (rr - r - min_gap * scale) * rnd().sqrt();
        let c = Circle::new(b.center[0] + q * t.cos(), b.center[1] + q * t.sin(), r);
        if holes.iter().all(|o| {
            let d =
                ((o.center[0] - c.center[0]).powi(2) + (o.center[1] - c.center[1]).powi(2)).sqrt();
            d - o.radius - c.radius > min_gap * scale
        }) && rr
            - ((c.center[0] - b.center[0]).powi(2) + (c.center[1] - b.center[1]).powi(2)).sqrt()
            - r
            > min_gap * scale
        {
            holes.push(c);
        }
    }
    Domain::bounded(b, holes).unwrap()
}

#[test]
#[ignore]
fn stress() {
    // (name, seed, holes, rmin, rmax, centre offset, scale, minimum gap)
    type Case = (&'static str, u64, usize, f64, f64, f64, f64, f64);
    let cases: Vec<Case> = vec![
        ("many small", 1, 1000, 0.05, 0.15, 0.0, 1.0, 0.01),
        ("dense", 2, 300, 0.2, 0.5, 0.0, 1.0, 1e-4),
        ("tiny gaps", 3, 60, 0.3, 1.0, 0.0, 1.0, 1e-7),
        ("offset big coords", 4, 50, 0.1, 1.0, 1e6, 1.0, 0.01),
        ("small scale", 5, 50, 0.1, 1.0, 1e-3, 1e-6, 0.01),
        ("mixed radii", 6, 200, 0.005, 2.0, 0.0, 1.0, 0.001),
        ("thousands", 7, 3000, 0.02, 0.08, 0.0, 1.0, 0.005),
    ];
    for (name, seed, h, rmin, rmax, cx, scale, g) in cases {
        let d = layout(seed, h, rmin, rmax, cx, scale, g);
        let hh = d.holes().len();
        let t = std::time::Instant::now();
        match build_layout(&d, &Options::default()) {
            Ok(b) => {
                let thin = b.thin_walls.len();
                assert_eq!(b.layout.blocks.len(), 6 * (hh - 1), "{name}");
                eprintln!(
                    "{name}: h {hh} blocks {} (want {}) samples {} rounds {} thin {thin} in {:?}",
                    b.layout.blocks.len(),
                    6 * (hh - 1),
                    b.samples.len(),
                    b.rounds,
                    t.elapsed()
                );
            }
            Err(e) => panic!("{name}: h {hh} ERROR {e} in {:?}", t.elapsed()),
        }
    }
}

/// Sample count and time of the sampling + triangulation on `layouts::bubbles(n, 1)`, for the
/// record (issue 8): `cargo test --release --test suite -- --ignored front_stress::bubbles --nocapture`.
/// Asserts only what must hold: every hard invariant, counts of 6(h - 1) blocks' medial graph.
#[test]
#[ignore]
fn bubbles_sampling_cost() {
    use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
    for n in [1000, 10000] {
        let d = medial_blocks::layouts::bubbles(n, 1).unwrap();
        let t = std::time::Instant::now();
        let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
        let h = d.hole_count();
        assert_eq!(s.medial.vertices.len(), 2 * (h - 1));
        eprintln!(
            "bubbles({n}, 1): {} samples, {} rounds, {} thin walls, {:?}",
            s.samples.len(),
            s.rounds,
            s.thin_walls.len(),
            t.elapsed()
        );
    }
}
