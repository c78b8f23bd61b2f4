//! The three layout kinds of the paper's section 5, rebuilt for the paper-vs-exact comparison
//! (`cargo run --release --example compare_modes`) and the quality tests.
//!
//! - [`hex_packing`]: 7 equal holes in hexagonal packing (the paper's *Hexagon*), with the
//!   bounding radius chosen so that every medial vertex sees its three circles at 120 degrees
//!   (the topological limit: 60/120-degree cells at the valence-6 corners);
//! - [`lattice`]: 12 large holes at the half-integer points of a 4 x 4 grid without its corners,
//!   interleaved with 9 small holes at the integer points (the paper's *Lattice*, 120 blocks);
//! - [`bubbles`]: 20 random bubbles of varied radii (the paper's *Bubble* kind), rejection
//!   sampled with a fixed seed.
//!
//! Exact mode's extreme angles on a layout are fixed by its medial vertices (see
//! [`super::metrics::vertex_corner_limit`]): the sizes below were chosen, within each kind, for
//! layouts whose vertices see their circles at reasonable angles (the lattice's bounding
//! radius and the bubbles' density). The paper-mode figures are measured on the same layouts.

use crate::domain::{Circle, Domain};

/// The paper's reported figures for its own meshes: `(name, min, max, mean min, mean max)`
/// angles in degrees (section 5).
pub const PAPER_TABLE: [(&str, f64, f64, f64, f64); 3] = [
    ("Hexagon", 46.0, 130.0, 75.0, 104.0),
    ("Lattice", 39.0, 138.0, 73.0, 106.0),
    ("Bubble", 31.0, 148.0, 65.0, 112.0),
];

/// Seven holes of radius `0.3` at the origin and at distance 1 at multiples of 60 degrees,
/// inside a bounding circle of radius `sqrt(3) - 0.3` centred at the origin: the empty circle
/// tangent to two neighbouring outer holes and the bounding circle then has its centre at
/// `2 / sqrt(3)` on their bisector, seeing the three circles at 120 degrees, like the inner
/// vertices.
pub fn hex_packing() -> Domain {
    let d = 1.0_f64;
    let r = 0.3;
    let mut holes = vec![Circle::new(0.0, 0.0, r)];
    for k in 0..6 {
        let a = k as f64 * std::f64::consts::FRAC_PI_3;
        holes.push(Circle::new(d * a.cos(), d * a.sin(), r));
    }
    Domain::bounded(Circle::new(0.0, 0.0, 3f64.sqrt() * d - r), holes)
        .expect("the hexagonal packing is a valid domain")
}

/// 12 large holes (radius 0.3) at `(x, y)` with `x, y` in `{-1.5, -0.5, 0.5, 1.5}` except the
/// four corners, 9 small holes (radius 0.15) at the integer points of `[-1, 1]^2`, bounding
/// radius 2.05 (gap 0.17 to the outer holes, 0.4 between neighbouring large holes).
pub fn lattice() -> Domain {
    let mut holes = Vec::new();
    for &x in &[-1.5, -0.5, 0.5, 1.5f64] {
        for &y in &[-1.5, -0.5, 0.5, 1.5f64] {
            if x.abs() == 1.5 && y.abs() == 1.5 {
                continue;
            }
            holes.push(Circle::new(x, y, 0.3));
        }
    }
    for x in -1..=1 {
        for y in -1..=1 {
            holes.push(Circle::new(x as f64, y as f64, 0.15));
        }
    }
    Domain::bounded(Circle::new(0.0, 0.0, 2.05), holes).expect("the lattice is a valid domain")
}

/// 20 bubbles with radii in `[0.3, 0.5]` in a bounding circle of radius 2.4, gaps at least
/// `0.06` (rejection sampling from a fixed SplitMix64 seed; deterministic): a dense bubbly
/// packing.
pub fn bubbles() -> Domain {
    let mut state: u64 = 0x5EED;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let big_r = 2.4;
    let min_gap = 0.06;
    let mut holes: Vec<Circle> = Vec::new();
    let mut tries = 0;
    while holes.len() < 20 && tries < 100_000 {
        tries += 1;
        let r = 0.3 + 0.2 * next();
        let a = next() * std::f64::consts::TAU;
        let d = (big_r - r - min_gap) * next().sqrt();
        let c = [d * a.cos(), d * a.sin()];
        if holes
            .iter()
            .all(|o| (c[0] - o.center[0]).hypot(c[1] - o.center[1]) - r - o.radius > min_gap)
        {
            holes.push(Circle::new(c[0], c[1], r));
        }
    }
    Domain::bounded(Circle::new(0.0, 0.0, big_r), holes).expect("the bubbles are a valid domain")
}
