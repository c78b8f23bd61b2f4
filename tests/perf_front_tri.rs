//! The front end's speed-ups must keep the triangulation's *structure* bit for bit (triangle
//! ids and vertex order, adjacency, vertex triangles, duplicates): downstream code numbers
//! everything by it. The hashes below were computed by the engine of main 06691b3, before the
//! `tri` session's changes to the insertion order and the insertion, on point sets chosen to
//! reach every path of the insertion: large cavities (a point at the centre of many co-circular
//! points), exact ties, collinear hull points, duplicates, random points (enough of them for the
//! insertion order's parallel keying); each is also checked exactly (`verify_exact`). Changed
//! on purpose since: "uniform 20000" is split in halves from the fifteenth session on (from
//! 2^13 points, was 2^15), so its hash is the new engine's.

use medial_blocks::geometry::verify::verify_exact;
use medial_blocks::geometry::{Point, Triangulation};

use crate::common;
use common::structure_hash;
use common::XorShift as Rng;

/// Rings of `k` points (exactly co-circular where the coordinates are exact, nearly elsewhere)
/// around centres that are inserted too: every centre opens a cavity of about `k` triangles.
fn rings(rings: usize, k: usize, seed: u64) -> Vec<Point> {
    let mut r = Rng(seed);
    let mut pts = Vec::new();
    for c in 0..rings {
        let (cx, cy) = ((c % 7) as f64 * 3.0, (c / 7) as f64 * 3.0);
        let rad = 1.0 + 0.2 * r.unit();
        for i in 0..k {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            pts.push([cx + rad * a.cos(), cy + rad * a.sin()]);
        }
        pts.push([cx, cy]);
    }
    pts
}

/// An integer grid (co-circular quadruples, collinear hull) with every fifth point repeated,
/// scrambled, plus exact Pythagorean circle points.
fn grid_with_dups() -> Vec<Point> {
    let mut pts: Vec<Point> = (0..400)
        .map(|i| [f64::from(i % 20), f64::from(i / 20)])
        .collect();
    let dups: Vec<Point> = pts.iter().step_by(5).copied().collect();
    pts.extend(dups);
    for (x, y) in [
        (5.0, 0.0),
        (4.0, 3.0),
        (3.0, 4.0),
        (0.0, 5.0),
        (-3.0, 4.0),
        (-4.0, -3.0),
    ] {
        pts.push([x + 30.0, y + 30.0]);
    }
    let n = pts.len();
    (0..n).map(|i| pts[(i * 211) % n]).collect()
}

fn uniform(n: usize, seed: u64) -> Vec<Point> {
    let mut r = Rng(seed);
    (0..n).map(|_| [r.unit(), r.unit()]).collect()
}

/// Every case is exactly valid and hashes as recorded (all hashes reported before failing).
#[test]
fn insertion_paths_keep_their_structure() {
    let ring = rings(30, 96, 7);
    let cut = ring.len() / 2;
    let ring_prefix = Triangulation::new(&ring[..cut]).unwrap();
    let ring_ext = ring_prefix.extended_full(&ring).unwrap().unwrap();
    let cases = [
        (
            "rings 96",
            Triangulation::new(&ring).unwrap(),
            0x3b10_8e95_853a_564e,
        ),
        ("rings 96 resumed", ring_ext, 0x0c74_f4a0_3086_c4d7),
        (
            "rings 12",
            Triangulation::new(&rings(40, 12, 3)).unwrap(),
            0xb1a1_9057_0e77_d549,
        ),
        (
            "grid with duplicates",
            Triangulation::new(&grid_with_dups()).unwrap(),
            0xe4f3_1558_e8a7_f6d4,
        ),
        (
            "uniform 20000",
            Triangulation::new(&uniform(20_000, 11)).unwrap(),
            0x470b_4ea5_369a_56fb,
        ),
    ];
    let mut wrong = Vec::new();
    for (name, dt, want) in &cases {
        verify_exact(dt).unwrap();
        let got = structure_hash(dt);
        if got != *want {
            wrong.push(format!("{name}: structure hash {got:#018x}"));
        }
    }
    assert!(wrong.is_empty(), "{wrong:?}");
}
