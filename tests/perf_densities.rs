//! The fast sub-step densities of exact mode
//! ([`medial_blocks::exact_mode::densities`], issue #8) against the plain formula (every point
//! from the arc's parametrisation with `sin_cos`, `hypot` and both walls' `atan2`), computed
//! alongside: on every piece (and both halves of each, as inserted holes split them) of real
//! layouts (bounded and periodic), and on random arcs between holes and with the bounding
//! circle. There also the batched passes against the point-by-point loop they replaced
//! (`Deviation::batched_bits`): equal bit for bit, in every compiled build the CPU can run
//! (baseline, AVX2, AVX-512) as well as the one chosen at run time.

use crate::common;

use medial_blocks::blocking::collapsed_blocking_excluding;
use medial_blocks::exact_mode::densities::{deviation, deviation_of_arc, Deviation};
use medial_blocks::layouts::{self, SplitMix64};
use medial_blocks::mesher::Options;
use medial_blocks::sampling::SamplingOptions;
use medial_blocks::{Circle, Domain};

/// Largest sub-step difference allowed, relative to the arc's mean density: rounding only
/// (the recurrence drifts a few ulps over 16 steps; a short arc's `atan2` of rounded points is
/// off by `eps / step`).
const TOL: f64 = 1e-9;

/// Largest difference of an arc's count target kept at the coarse sub-steps from the plain
/// formula's at all of them, relative (the coarse chords of a curved spoke mid-curve fall
/// short of the fine ones by up to about 1e-3).
const COARSE_TARGET_TOL: f64 = 2e-3;

/// Largest difference of the node parameters (over `[0, 1]`) kept at the coarse sub-steps
/// from the plain formula's at all of them: a small part of one cell.
const COARSE_PARAMS_TOL: f64 = 1e-2;

fn check(d: Deviation, what: &str) {
    println!("{what}: {d:?}");
    assert!(d.arcs > 0, "{what}");
    assert!(d.sq < TOL && d.ang < TOL, "{what}: {d:?}");
    assert_eq!(d.mismatches, 0, "{what}: {d:?}");
    assert_eq!(d.batched_bits, 0, "{what}: {d:?}");
    assert!(d.coarse_target < COARSE_TARGET_TOL, "{what}: {d:?}");
    assert!(d.coarse_params < COARSE_PARAMS_TOL, "{what}: {d:?}");
    assert_eq!(d.coarse_bounds, 0, "{what}: {d:?}");
}

fn on_layout(d: &Domain, what: &str) {
    let s = SamplingOptions {
        soft_rounds: false,
        ..SamplingOptions::default()
    };
    let cb = collapsed_blocking_excluding(d, &Options::default(), &s, false, &[]).unwrap();
    let dev = deviation(&cb).unwrap();
    check(dev, what);
    // Most arcs of a real layout are smooth enough for the coarse sub-steps (issue 8).
    assert!(2 * dev.coarse > dev.arcs, "{what}: {dev:?}");
}

#[test]
fn real_layouts_match_the_plain_formula() {
    for seed in 1..=3 {
        on_layout(
            &layouts::bubbles(200, seed).unwrap(),
            &format!("bubbles 200/{seed}"),
        );
    }
    on_layout(&layouts::hexagon(), "hexagon");
    on_layout(&layouts::lattice().unwrap(), "lattice");
    on_layout(&layouts::square_lattice(16).unwrap(), "square lattice");
    // Nearly touching holes (gaps down to 1e-6 of the radius) and inserted holes.
    for seed in 1..=4 {
        let mut rng = SplitMix64(seed);
        let big_r = 1.0 + 4.0 * rng.next_f64();
        let holes = common::random_holes(&mut rng, 40, big_r, [0.0, 0.0], 1e-6);
        let d = Domain::bounded(Circle::new(0.0, 0.0, big_r), holes).unwrap();
        on_layout(&d, &format!("near-touching {seed}"));
    }
}

/// Random arcs with long sweeps (to the tolerance of the real layouts) and very short ones
/// (sweeps of 1e-9 to 1e-6 rad): there the plain formula's `atan2` of points rounded to
/// `eps r` is itself only good to about `eps / step` relative (`step = sweep / 256`, 1e-4 at
/// 1e-9 rad) while the fast path's wall turn is the step itself, so they agree to that
/// (and such arcs are collapsed in a real layout).
/// Periodic layouts: the arc orbits exact mode builds (`exact_mode::periodic`).
#[test]
fn periodic_layouts_match_the_plain_formula() {
    use medial_blocks::periodic::{periodic_layout, PeriodicDomain};
    let options = Options {
        collapse_fraction: 0.0,
        ..Options::default()
    };
    let mut checked = 0;
    for seed in 1..=4 {
        let mut rng = SplitMix64(seed);
        let size = [2.0, 1.0 + rng.next_f64()];
        let mut holes: Vec<Circle> = Vec::new();
        for _ in 0..20_000 {
            if holes.len() == 12 {
                break;
            }
            let r = 0.04 + 0.12 * rng.next_f64();
            let c = [rng.next_f64() * size[0], rng.next_f64() * size[1]];
            let apart = holes.iter().all(|o| {
                (-1..=1).all(|a| {
                    (-1..=1).all(|b| {
                        let dx = c[0] - o.center[0] + a as f64 * size[0];
                        let dy = c[1] - o.center[1] + b as f64 * size[1];
                        dx.hypot(dy) > r + o.radius + 0.02
                    })
                })
            });
            if apart {
                holes.push(Circle::new(c[0], c[1], r));
            }
        }
        let pd = PeriodicDomain::new(size, holes).unwrap();
        let p = periodic_layout(&pd, &options).unwrap();
        let Some(pb) = &p.blocking else { continue };
        let d = medial_blocks::exact_mode::periodic::density_deviation(pb, &options).unwrap();
        check(d, &format!("periodic {seed}"));
        checked += 1;
    }
    assert!(checked >= 2, "{checked}");
}

#[test]
fn random_arcs_match_the_plain_formula() {
    let mut rng = SplitMix64(17);
    let mut long = Deviation::default();
    let mut short = Deviation::default();
    for k in 0..3000 {
        let mut f = || rng.next_f64();
        let p = [f(), f(), 0.05 + 0.3 * f()];
        let q = if k % 3 == 0 {
            [0.5, 0.5, -3.0]
        } else {
            [1.5 + f(), f(), 0.05 + 0.3 * f()]
        };
        let t0 = 6.0 * f();
        let is_short = k % 4 == 0;
        let t1 = if is_short {
            t0 + 1e-9 + 1e-6 * f()
        } else {
            6.0 * f()
        };
        let Some(d) = deviation_of_arc(p, q, t0, t1) else {
            continue;
        };
        let total = if is_short { &mut short } else { &mut long };
        total.arcs += d.arcs;
        total.sq = total.sq.max(d.sq);
        total.ang = total.ang.max(d.ang);
        total.mismatches += d.mismatches;
        total.batched_bits += d.batched_bits;
        total.coarse += d.coarse;
        total.coarse_target = total.coarse_target.max(d.coarse_target);
        total.coarse_params = total.coarse_params.max(d.coarse_params);
        total.coarse_bounds += d.coarse_bounds;
    }
    assert!(long.arcs > 1000 && short.arcs > 300, "{long:?} {short:?}");
    check(long, "random arcs");
    println!("short random arcs: {short:?}");
    assert!(short.sq < 1e-3 && short.ang < 1e-3, "{short:?}");
    assert_eq!(short.mismatches, 0);
    assert_eq!(short.batched_bits, 0, "{short:?}");
}
