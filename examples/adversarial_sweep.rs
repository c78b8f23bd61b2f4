//! Mesh many awkward random layouts in exact mode and check every mesh: the sweep a change to
//! the pipeline should pass before it lands (issue 8's speed work changes sampling, collapse
//! and geometry, and the tests cover only the layouts they name).
//!
//! ```sh
//! cargo run --release --example adversarial_sweep                     # 20 layouts of each kind
//! cargo run --release --example adversarial_sweep -- --count 50 --seed 7 --kinds near_touch,ring
//! cargo run --release --example adversarial_sweep -- --save layouts  # also write each layout
//! ```
//!
//! Kinds: `near_touch` (bubbles grown until some nearly touch a neighbour, gaps down to 1e-7
//! of a radius), `boundary` (holes nearly touching the bounding circle), `sizes` (radii over
//! four decades), `lattice` (square and hexagonal arrays perturbed by 0 to 1e-3: co-circular
//! quadruples), `ring` (holes evenly on one or two rings, with or without a centre hole),
//! `dense` (random packings with gaps down to 1e-6), `periodic` (periodic boxes of 3 to 40
//! holes, gaps down to 1e-5 across the period too). Each layout is meshed with random
//! options (`block_cells` 4 to 32 or the default counts, smoothing). A case fails when meshing
//! returns an error, when [`medial_blocks::fuzzing::check_mesh_with`] refuses the mesh
//! (conformity, walls on their circles, areas, no inverted cell;
//! [`medial_blocks::fuzzing::periodic::check_periodic_mesh`] for a box), or when exact mode fell
//! back to the paper pipeline; the smallest corner angle of every mesh (`quality::measure`) is
//! printed, and the smallest over the sweep. The exit status is 1 when a case failed.

use medial_blocks::domain::{AnyDomain, Circle, Domain};
use medial_blocks::fuzzing::periodic::check_periodic_mesh;
use medial_blocks::fuzzing::{check_mesh_with, Checks};
use medial_blocks::layouts::SplitMix64;
use medial_blocks::mesh::Geometry;
use medial_blocks::quality::measure;
use medial_blocks::{mesh_any, Options, PeriodicDomain};
use std::time::Instant;

/// A deterministic generator ([`SplitMix64`]) with the draws the layouts use.
struct Rng(SplitMix64);

impl Rng {
    fn f(&mut self) -> f64 {
        self.0.next_f64()
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.0.next_u64() % n as u64) as usize
    }
}

const KINDS: [&str; 7] = [
    "near_touch",
    "boundary",
    "sizes",
    "lattice",
    "ring",
    "dense",
    "periodic",
];

/// Every mesh must pass the invariants with no inverted cell.
const CHECKS: Checks = Checks {
    no_inverted_cells: true,
};

fn dist(a: &Circle, b: &Circle) -> f64 {
    (a.center[0] - b.center[0]).hypot(a.center[1] - b.center[1])
}

/// Random non-overlapping holes in a bounding circle of radius `big`, radii from `radius`,
/// at least `gap(r)` apart and from the bounding circle (quadratic rejection: a few hundred
/// holes).
fn scatter(
    rng: &mut Rng,
    big: f64,
    n: usize,
    mut radius: impl FnMut(&mut Rng) -> f64,
    gap: impl Fn(f64) -> f64,
) -> Vec<Circle> {
    let mut holes: Vec<Circle> = Vec::new();
    for _ in 0..200 * n {
        if holes.len() == n {
            break;
        }
        let r = radius(rng);
        let reach = big - r - gap(r);
        if reach <= 0.0 {
            continue;
        }
        let (rho, phi) = (
            reach * rng.f().sqrt(),
            rng.range(0.0, std::f64::consts::TAU),
        );
        let c = Circle::new(rho * phi.cos(), rho * phi.sin(), r);
        if holes
            .iter()
            .all(|o| dist(o, &c) >= o.radius + r + gap(r.min(o.radius)))
        {
            holes.push(c);
        }
    }
    holes
}

/// Grow some holes until they nearly touch their nearest neighbour (or the bounding circle
/// when `boundary`), leaving a gap of `10^-k` times the radius, `k` in 2..7.
fn grow_to_touch(rng: &mut Rng, big: f64, holes: &mut [Circle], boundary: bool) {
    let n = holes.len();
    for _ in 0..(n / 4).max(1) {
        let i = rng.below(n);
        let rel = 10f64.powf(-rng.range(2.0, 7.0));
        let c = holes[i];
        // The room to the bounding circle and to the nearest other hole.
        let wall = big - dist(&c, &Circle::new(0.0, 0.0, 0.0)) - c.radius;
        let mut others = f64::INFINITY;
        for (j, o) in holes.iter().enumerate() {
            if j != i {
                others = others.min(dist(&c, o) - c.radius - o.radius);
            }
        }
        // Grow towards the bounding circle (`boundary`) or the nearest hole, never past
        // the other.
        let (target, other) = if boundary {
            (wall, others)
        } else {
            (others, wall)
        };
        let leave = rel * (c.radius + target);
        if target > leave && other > target {
            holes[i].radius += target - leave;
        }
    }
}

/// A periodic box `[lx, 1]` (`lx` 1 to 2.5) with 3 to 40 holes, radii 0.03 to 0.15, at least
/// `10^-u` apart across the period too (`u` 1 to 5).
fn periodic_layout(rng: &mut Rng) -> Option<AnyDomain> {
    let size = [rng.range(1.0, 2.5), 1.0];
    let (n, gap) = (3 + rng.below(38), 10f64.powf(-rng.range(1.0, 5.0)));
    let mut holes: Vec<Circle> = Vec::new();
    for _ in 0..200 * n {
        if holes.len() == n {
            break;
        }
        let c = Circle::new(rng.f() * size[0], rng.f() * size[1], rng.range(0.03, 0.15));
        let apart = holes.iter().all(|o| {
            let wrapped = |k: usize| {
                let d = c.center[k] - o.center[k];
                d - (d / size[k]).round() * size[k]
            };
            wrapped(0).hypot(wrapped(1)) >= c.radius + o.radius + gap
        });
        if apart {
            holes.push(c);
        }
    }
    match PeriodicDomain::new(size, holes) {
        Ok(d) => Some(AnyDomain::Periodic(d)),
        Err(e) => {
            eprintln!("skipped a periodic layout: {e}");
            None
        }
    }
}

fn layout(kind: &str, rng: &mut Rng) -> Option<AnyDomain> {
    if kind == "periodic" {
        return periodic_layout(rng);
    }
    let n = 20 + rng.below(280);
    let (big, holes) = match kind {
        "near_touch" | "boundary" => {
            let big = (n as f64 * 0.26 / 0.35).sqrt() + 1.0;
            let mut h = scatter(rng, big, n, |r| r.range(0.3, 0.6), |_| 0.1);
            grow_to_touch(rng, big, &mut h, kind == "boundary");
            (big, h)
        }
        "sizes" => {
            let big = 10.0;
            let decades = 4.0;
            let h = scatter(
                rng,
                big,
                n.min(150),
                |r| 10f64.powf(-r.range(0.0, decades)) * 1.5,
                |r| 0.2 * r,
            );
            (big, h)
        }
        "lattice" => {
            let m = 3 + rng.below(12);
            let hex = rng.below(2) == 1;
            let eps = if rng.below(3) == 0 {
                0.0
            } else {
                10f64.powf(-rng.range(3.0, 12.0))
            };
            let r = rng.range(0.1, 0.45);
            let mut h = Vec::new();
            for j in 0..m {
                for i in 0..m {
                    let shift = if hex && j % 2 == 1 { 0.5 } else { 0.0 };
                    let y = if hex {
                        j as f64 * 0.75f64.sqrt()
                    } else {
                        j as f64
                    };
                    let x = i as f64 + shift - 0.5 * m as f64;
                    let y = y - 0.5 * m as f64;
                    h.push(Circle::new(
                        x + eps * rng.range(-1.0, 1.0),
                        y + eps * rng.range(-1.0, 1.0),
                        r,
                    ));
                }
            }
            (0.75 * m as f64 + 1.0, h)
        }
        "ring" => {
            let k = 3 + rng.below(40);
            let rings = 1 + rng.below(2);
            let mut h = Vec::new();
            if rng.below(2) == 0 {
                h.push(Circle::new(0.0, 0.0, rng.range(0.2, 0.5)));
            }
            for ring in 0..rings {
                let rr = 1.0 + ring as f64;
                let r = (std::f64::consts::PI * rr / k as f64 * rng.range(0.3, 0.95)).min(0.45);
                let phase = if ring == 1 {
                    std::f64::consts::PI / k as f64
                } else {
                    0.0
                };
                for i in 0..k {
                    let t = phase + std::f64::consts::TAU * i as f64 / k as f64;
                    h.push(Circle::new(rr * t.cos(), rr * t.sin(), r));
                }
            }
            (rings as f64 + rng.range(0.7, 2.0), h)
        }
        "dense" => {
            let big = (n as f64 * 0.26 / 0.55).sqrt() + 1.0;
            let gap = 10f64.powf(-rng.range(1.0, 6.0));
            (big, scatter(rng, big, n, |r| r.range(0.3, 0.6), |_| gap))
        }
        _ => return None,
    };
    if holes.len() < 2 {
        return None;
    }
    match Domain::bounded(Circle::new(0.0, 0.0, big), holes) {
        Ok(d) => Some(AnyDomain::Bounded(d)),
        Err(e) => {
            eprintln!("skipped a {kind} layout: {e}");
            None
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1).cloned())
    };
    if args.iter().any(|a| a == "--help" || a == "-h") {
        println!("adversarial_sweep [--count N] [--seed S] [--kinds a,b,...] [--save DIR]");
        println!("kinds: {KINDS:?}");
        return;
    }
    let count: usize = value("--count").and_then(|v| v.parse().ok()).unwrap_or(20);
    let seed: u64 = value("--seed").and_then(|v| v.parse().ok()).unwrap_or(1);
    let kinds: Vec<String> = value("--kinds")
        .map(|k| k.split(',').map(str::to_string).collect())
        .unwrap_or_else(|| KINDS.iter().map(|k| k.to_string()).collect());
    // Write every layout as DIR/KIND-CASE.json (to rerun one with the CLI).
    let save = value("--save");
    let (mut failed, mut meshed, mut least) = (0, 0, f64::INFINITY);
    for kind in &kinds {
        if !KINDS.contains(&kind.as_str()) {
            eprintln!("unknown kind {kind}; kinds: {KINDS:?}");
            std::process::exit(2);
        }
        for case in 0..count {
            let mut rng = Rng(SplitMix64(
                seed.wrapping_mul(1_000_003) ^ (case as u64) << 20 ^ kind.len() as u64,
            ));
            let Some(d) = layout(kind, &mut rng) else {
                continue;
            };
            let options = Options {
                block_cells: [None, Some(4), Some(8), Some(16), Some(32)][rng.below(5)],
                smooth: [0, 0, 5][rng.below(3)],
                ..Options::default()
            };
            if let Some(dir) = &save {
                let path = format!("{dir}/{kind}-{case}.json");
                let json = match &d {
                    AnyDomain::Bounded(d) => d.to_json_string(),
                    AnyDomain::Periodic(d) => d.to_json_string(),
                };
                if let Err(e) = std::fs::write(&path, json) {
                    eprintln!("cannot write {path}: {e}");
                }
            }
            let start = Instant::now();
            let outcome = mesh_any(&d, &options);
            let seconds = start.elapsed().as_secs_f64();
            let name = format!("{kind} case {case} ({} holes)", d.hole_count());
            let verdict = match &outcome {
                Err(e) => Err(format!("error: {e}")),
                Ok(m) => match match &d {
                    AnyDomain::Bounded(d) => check_mesh_with(d, m, CHECKS),
                    AnyDomain::Periodic(d) => check_periodic_mesh(d, m, CHECKS),
                } {
                    Err(e) => Err(format!("check: {e}")),
                    Ok(_) if m.geometry != Geometry::Exact => Err("paper fallback".into()),
                    Ok(_) => Ok(m),
                },
            };
            match verdict {
                Ok(m) => {
                    meshed += 1;
                    let angle = measure(&m.grids).min_angle_deg;
                    least = least.min(angle);
                    println!(
                        "ok   {name}: {} blocks, smallest angle {angle:.2} deg, {seconds:.3} s",
                        m.layout.blocks.len()
                    );
                }
                Err(why) => {
                    failed += 1;
                    println!("FAIL {name}: {why}; options {options:?}");
                }
            }
        }
    }
    println!("{meshed} meshed, {failed} failed; smallest angle {least:.2} deg");
    if failed > 0 {
        std::process::exit(1);
    }
}
