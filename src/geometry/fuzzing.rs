//! Fuzzing support (shared by the cargo-fuzz target and the corpus replay test): decode bytes
//! into an awkward point set, triangulate it, and check the result exactly.

use super::verify::{verify_error, verify_exact};
use super::{Point, Triangulation};

/// A little-endian byte reader that yields zeros when the input runs out.
struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }
    fn u16(&mut self) -> u16 {
        u16::from(self.u8()) | (u16::from(self.u8()) << 8)
    }
    fn u64(&mut self) -> u64 {
        (0..8).fold(0u64, |acc, i| acc | (u64::from(self.u8()) << (8 * i)))
    }
    fn done(&self) -> bool {
        self.pos >= self.data.len()
    }
    /// A small signed integer.
    fn small(&mut self) -> f64 {
        f64::from(self.u8() as i8)
    }
}

/// Powers of two from tiny to huge, so scaling stays exact.
fn scale_of(b: u8) -> f64 {
    const SCALES: [f64; 10] = [
        1.0, 0.125, 1024.0, 1e-9, 1e9, 1e-150, 1e150, 1e300, 1e-300, 5e-324,
    ];
    SCALES[b as usize % SCALES.len()]
}

/// Decode bytes into points. The input is a sequence of commands; each appends points from a
/// degenerate generator: integer grids, Pythagorean circles, duplicates of earlier points,
/// collinear runs, raw `f64` bit patterns (NaN and infinities included), ulp-perturbed points.
/// At most 512 points.
pub fn decode_points(data: &[u8]) -> Vec<Point> {
    let mut b = Bytes { data, pos: 0 };
    let mut pts: Vec<Point> = Vec::new();
    const MAX: usize = 512;
    // Pythagorean points on the circle of radius 5 (and 25, below).
    const CIRCLE: [(f64, f64); 12] = [
        (5.0, 0.0),
        (4.0, 3.0),
        (3.0, 4.0),
        (0.0, 5.0),
        (-3.0, 4.0),
        (-4.0, 3.0),
        (-5.0, 0.0),
        (-4.0, -3.0),
        (-3.0, -4.0),
        (0.0, -5.0),
        (3.0, -4.0),
        (4.0, -3.0),
    ];
    while !b.done() && pts.len() < MAX {
        let cmd = b.u8();
        let s = scale_of(b.u8());
        let (ox, oy) = (b.small(), b.small());
        match cmd % 8 {
            0 => {
                let (w, h) = (1 + b.u8() % 8, 1 + b.u8() % 8);
                for i in 0..w {
                    for j in 0..h {
                        pts.push([(ox + f64::from(i)) * s, (oy + f64::from(j)) * s]);
                    }
                }
            }
            1 => {
                let mask = b.u16();
                let r = if b.u8().is_multiple_of(2) { 1.0 } else { 5.0 };
                for (k, &(cx, cy)) in CIRCLE.iter().enumerate() {
                    if mask & (1 << k) != 0 {
                        pts.push([(ox + r * cx) * s, (oy + r * cy) * s]);
                    }
                }
            }
            2 => {
                let count = 1 + b.u8() % 8;
                for _ in 0..count {
                    if let Some(&p) = pts.get(b.u16() as usize % pts.len().max(1)) {
                        pts.push(p);
                    }
                }
            }
            3 => {
                let (dx, dy, count) = (b.small(), b.small(), 2 + b.u8() % 16);
                for i in 0..count {
                    let t = f64::from(i);
                    pts.push([(ox + t * dx) * s, (oy + t * dy) * s]);
                }
            }
            4 => pts.push([f64::from_bits(b.u64()), f64::from_bits(b.u64())]),
            5 => {
                // Ulp steps around a base point: Shewchuk-style near-degenerate sets.
                let base = [ox * s + 0.5, oy * s + 0.5];
                let count = 1 + b.u8() % 8;
                for _ in 0..count {
                    let (ux, uy) = (i64::from(b.u8() as i8 % 8), i64::from(b.u8() as i8 % 8));
                    let step = |v: f64, u: i64| f64::from_bits((v.to_bits() as i64 + u) as u64);
                    pts.push([step(base[0], ux), step(base[1], uy)]);
                }
            }
            6 => pts.push([ox * s, oy * s]),
            _ => {
                let k = b.u8() as usize % CIRCLE.len();
                let (cx, cy) = CIRCLE[k];
                pts.push([(ox + 25.0 * cx) * s, (oy + 25.0 * cy) * s]);
            }
        }
    }
    pts.truncate(MAX);
    pts
}

/// Decode, triangulate, and check the outcome exactly (a result with [`verify_exact`], an error
/// with [`verify_error`]).
pub fn check_bytes(data: &[u8]) -> Result<(), String> {
    let pts = decode_points(data);
    check_points(&pts)
}

/// Triangulate `pts` and check the outcome exactly; on success also check that the reversed
/// input gives the same triangles (as coordinate triples).
pub fn check_points(pts: &[Point]) -> Result<(), String> {
    let dt = match Triangulation::new(pts) {
        Ok(dt) => dt,
        Err(e) => return verify_error(pts, &e),
    };
    verify_exact(&dt)?;
    let reversed: Vec<Point> = pts.iter().rev().copied().collect();
    let rt = Triangulation::new(&reversed).map_err(|e| format!("reversed input failed: {e}"))?;
    if coordinate_triangles(&dt) != coordinate_triangles(&rt) {
        return Err("reversed input gives different triangles".into());
    }
    Ok(())
}

/// Triangles as sorted coordinate-bit triples, rotated to start at their smallest corner.
fn coordinate_triangles(dt: &Triangulation) -> Vec<[[u64; 2]; 3]> {
    let key = |v: u32| {
        let p = dt.points()[v as usize];
        [(p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()]
    };
    let mut v: Vec<[[u64; 2]; 3]> = dt
        .triangles()
        .map(|t| {
            let k = t.map(key);
            let s = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
            [k[s], k[(s + 1) % 3], k[(s + 2) % 3]]
        })
        .collect();
    v.sort_unstable();
    v
}
