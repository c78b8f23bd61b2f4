//! Issue #8: the adaptive sampling on the thread pool. `sampling::sample_adaptive_on` with
//! `parallel = true` samples the circles on the pool within the per-circle budget and checks the
//! total afterwards; with `false` it runs the serial loop (each circle within what the ones
//! before it left), the reference here. Both must give the same samples (bit for bit), the same
//! count of circles taken over from an earlier sampling, and the same error (`TooManySamples`:
//! the same circle, limit and kind), whatever the pool's thread count: on bubbles, lattices,
//! near-touching pairs, huge radius ratios, with densities and options varied, and with budgets
//! (total and per circle) that are hit exactly and passed by one. Every sample is also rebuilt
//! from its grid index with `unit_offset` (the samples do not come from its table).
//!
//! `MEDIAL_BLOCKS_LONG=1` adds larger layouts and more seeds.

use crate::common;

use medial_blocks::domain::{Circle, Domain, HoleIndex};
use medial_blocks::layouts::{self, SplitMix64};
use medial_blocks::sampling::{
    nearest_gaps, sample_adaptive, sample_adaptive_on, sample_and_triangulate, unit_offset,
    SampledDomain, Samples, SamplingOptions, TooManySamples,
};

fn long() -> bool {
    std::env::var_os("MEDIAL_BLOCKS_LONG").is_some()
}

/// Every field of `s`, floats as bits (so `-0.0` and `0.0` differ, and NaN gaps compare).
fn bits(s: &Samples) -> impl PartialEq + std::fmt::Debug {
    let f = |x: f64| x.to_bits();
    (
        s.points
            .iter()
            .map(|p| [f(p[0]), f(p[1])])
            .collect::<Vec<_>>(),
        s.circle_of.clone(),
        s.index_of.clone(),
        s.circles
            .iter()
            .map(|c| (c.circle, c.first, c.count, f(c.gap)))
            .collect::<Vec<_>>(),
        s.grid.clone(),
        s.grid_counts.clone(),
    )
}

/// The layout checks that do not trust the sampler: circles in slot order, contiguous, each
/// sample's indices, and each point rebuilt bitwise from its grid index with `unit_offset`.
fn check_layout(d: &Domain, s: &Samples) {
    assert_eq!(s.circles.len(), d.hole_count() + 1);
    assert_eq!(s.grid_counts.len(), s.circles.len());
    assert_eq!(s.grid.len(), s.len());
    let mut first = 0;
    for (slot, cs) in s.circles.iter().enumerate() {
        assert_eq!(cs.circle, slot as i32 - 1);
        assert_eq!(cs.first, first);
        first += cs.count;
        let c = d.circle(cs.circle);
        let n = s.grid_counts[slot];
        for k in 0..cs.count {
            let g = (cs.first + k) as usize;
            assert_eq!((s.circle_of[g], s.index_of[g]), (cs.circle, k));
            let u = unit_offset(s.grid[g], n);
            let p = [c.center[0] + c.radius * u[0], c.center[1] + c.radius * u[1]];
            assert_eq!(
                [p[0].to_bits(), p[1].to_bits()],
                [s.points[g][0].to_bits(), s.points[g][1].to_bits()],
                "circle {} sample {k}",
                cs.circle
            );
            assert!(k == 0 || s.grid[g - 1] < s.grid[g]);
        }
    }
    assert_eq!(first as usize, s.len());
}

/// `f` on a pool of `threads` threads.
fn on<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

type Outcome = Result<(Samples, usize), TooManySamples>;

/// The serial loop's outcome, and the parallel path's equal to it on pools of 1 to 3 threads
/// (and the default entry point's, `sample_adaptive` when there is no earlier sampling).
fn same_both_ways(
    d: &Domain,
    opts: &SamplingOptions,
    density: &[u32],
    previous: Option<&SampledDomain>,
) -> Outcome {
    let gaps = nearest_gaps(d);
    let serial = sample_adaptive_on(d, opts, &gaps, density, previous, false);
    let view = |o: &Outcome| match o {
        Ok((s, taken)) => Ok((bits(s), *taken)),
        Err(e) => Err(e.clone()),
    };
    for threads in [1, 2, 3] {
        let parallel = on(threads, || {
            sample_adaptive_on(d, opts, &gaps, density, previous, true)
        });
        assert_eq!(view(&parallel), view(&serial), "{threads} threads");
    }
    if previous.is_none() {
        let default = on(2, || sample_adaptive(d, opts, &gaps, density));
        assert_eq!(
            view(&default.map(|s| (s, 0))),
            view(&serial),
            "sample_adaptive"
        );
    }
    if let Ok((s, _)) = &serial {
        check_layout(d, s);
    }
    serial
}

/// Two holes `gap` apart (and a third far off), inside a unit bounding circle.
fn pair(gap: f64, r: f64) -> Domain {
    let holes = vec![
        Circle::new(-r - 0.5 * gap, 0.0, r),
        Circle::new(r + 0.5 * gap, 0.0, r),
        Circle::new(0.0, 0.7, 0.05),
    ];
    Domain::bounded(Circle::new(0.0, 0.0, 1.0), holes).unwrap()
}

/// One big hole among tiny ones (radius ratio `ratio`), some close to it and to each other.
fn ratio(ratio: f64, n: usize, seed: u64) -> Domain {
    let big = 0.5;
    let small = big / ratio;
    let mut rng = SplitMix64(seed);
    let mut holes = vec![Circle::new(0.0, 0.0, big)];
    while holes.len() < n {
        let a = rng.next_f64() * std::f64::consts::TAU;
        let d = big + small * (1.0 + 20.0 * rng.next_f64()) + 0.4 * rng.next_f64().powi(3);
        let c = Circle::new(d * a.cos(), d * a.sin(), small * (0.5 + rng.next_f64()));
        let clear = holes.iter().all(|h| {
            (c.center[0] - h.center[0]).hypot(c.center[1] - h.center[1]) - c.radius - h.radius
                > 0.05 * small
        });
        if clear && d + c.radius < 0.99 {
            holes.push(c);
        }
    }
    Domain::bounded(Circle::new(0.0, 0.0, 1.0), holes).unwrap()
}

fn domains() -> Vec<Domain> {
    let mut out = vec![
        layouts::hexagon(),
        layouts::lattice().unwrap(),
        layouts::square_lattice(12).unwrap(),
        pair(1e-7, 0.3),
        pair(1e-3, 0.01),
        ratio(1e4, 150, 1),
        ratio(30.0, 300, 2),
    ];
    let sizes: &[(usize, u64)] = if long() {
        &[(2, 1), (60, 3), (150, 4), (700, 2), (3000, 5), (20_000, 1)]
    } else {
        &[(2, 1), (60, 3), (150, 4), (700, 2)]
    };
    for &(n, seed) in sizes {
        out.push(layouts::bubbles(n, seed).unwrap());
    }
    let mut rng = SplitMix64(3);
    for _ in 0..3 {
        let holes = common::random_holes(&mut rng, 200, 1.0, [0.0, 0.0], 0.002);
        out.extend(Domain::bounded(Circle::new(0.0, 0.0, 1.0), holes).ok());
    }
    out
}

/// Option sets: the default, exact mode's, coarse and fine, odd multiples of 8, and densities.
fn option_sets(slots: usize, rng: &mut SplitMix64) -> Vec<(SamplingOptions, Vec<u32>)> {
    let d = SamplingOptions::default();
    let mut out = vec![
        (d.clone(), vec![]),
        (
            SamplingOptions {
                soft_rounds: false,
                ..d.clone()
            },
            vec![0; slots],
        ),
        (
            SamplingOptions {
                min_per_circle: 8,
                spacing_per_gap: 0.5,
                ..d.clone()
            },
            vec![],
        ),
        (
            SamplingOptions {
                min_per_circle: 20,
                max_per_circle: 4000,
                ..d.clone()
            },
            vec![],
        ),
    ];
    // Random densities (0 to 3 doublings), on a few of the circles.
    let density = (0..slots)
        .map(|_| {
            let r = rng.next_u64();
            if r.is_multiple_of(5) {
                (r >> 8) as u32 % 4
            } else {
                0
            }
        })
        .collect();
    out.push((d, density));
    out
}

/// The parallel path equals the serial loop (samples bit for bit, or the same error: the
/// near-touching pair needs more than 4000 samples on a circle) on every layout and option set,
/// on pools of 1 to 3 threads.
#[test]
fn parallel_sampling_equals_the_serial_loop() {
    let mut rng = SplitMix64(5);
    let (mut sampled, mut refused) = (0, 0);
    for d in domains() {
        for (opts, density) in option_sets(d.hole_count() + 1, &mut rng) {
            match same_both_ways(&d, &opts, &density, None) {
                Ok(_) => sampled += 1,
                Err(_) => refused += 1,
            }
        }
    }
    assert!(sampled >= 60 && refused >= 1, "{sampled} {refused}");
}

/// Budgets hit exactly and passed by one: the total limit at the samples needed (the same
/// samples) and one below (the serial loop's error: its circle and limit, `total` set); the
/// per-circle limit at the largest circle's count (the same samples) and the multiple of 8
/// below (a per-circle error) -- the same outcome on the pool as in the serial loop. Also
/// limits in the middle of the slots, and a per-circle limit below the coarse count.
#[test]
fn budgets_hit_exactly_or_by_one_give_the_serial_outcome() {
    let mut errors = (0, 0);
    for d in domains() {
        let base = SamplingOptions::default();
        let (s, _) = same_both_ways(&d, &base, &[], None).unwrap();
        let total = s.len();
        let largest = s.circles.iter().map(|c| c.count as usize).max().unwrap();
        let mut limits = vec![
            (total, base.max_per_circle),
            (total - 1, base.max_per_circle),
            (total / 2, base.max_per_circle),
            (s.circles[0].count as usize, base.max_per_circle),
            (s.circles[0].count as usize - 1, base.max_per_circle),
            (1, base.max_per_circle),
            (base.max_total, largest),
            (base.max_total, largest.div_ceil(8) * 8 - 8),
            (base.max_total, 16),
            (total - 1, largest.div_ceil(8) * 8 - 8),
        ];
        if d.hole_count() > 4 {
            let half = s.circles[d.hole_count() / 2];
            limits.push(((half.first + half.count) as usize, base.max_per_circle));
            limits.push(((half.first + half.count) as usize - 1, base.max_per_circle));
        }
        for (max_total, max_per_circle) in limits {
            let opts = SamplingOptions {
                max_total,
                max_per_circle,
                ..base.clone()
            };
            match same_both_ways(&d, &opts, &[], None) {
                Ok((again, _)) => {
                    assert!(again.len() <= max_total);
                    if max_total >= total && max_per_circle >= largest {
                        assert_eq!(bits(&again), bits(&s));
                    }
                }
                Err(e) => {
                    if e.total {
                        assert_eq!(e.limit, max_total);
                        errors.0 += 1;
                    } else {
                        assert_eq!(e.limit, (max_per_circle / 8 * 8).max(32));
                        errors.1 += 1;
                    }
                }
            }
        }
        // Exactly at the limits: no error.
        let exact = SamplingOptions {
            max_total: total,
            max_per_circle: largest.div_ceil(8) * 8,
            ..base.clone()
        };
        assert!(same_both_ways(&d, &exact, &[], None).is_ok());
    }
    assert!(errors.0 >= 20 && errors.1 >= 10, "{errors:?}");
}

/// Holes appended to `d0`: tiny ones at clear random points (most circles keep their
/// sampling) and one close to an earlier hole (its neighbours are resampled).
fn extensions(d0: &Domain, rng: &mut SplitMix64) -> Vec<Domain> {
    let b = d0.bounding();
    let mut out = Vec::new();
    for _ in 0..3 {
        let mut holes = d0.holes().to_vec();
        for _ in 0..1 + (rng.next_f64() * 3.0) as usize {
            let mut best = ([0.0; 2], 0.0);
            for _ in 0..20 {
                let a = rng.next_f64() * std::f64::consts::TAU;
                let d = 0.9 * b.radius * rng.next_f64().sqrt();
                let c = [b.center[0] + d * a.cos(), b.center[1] + d * a.sin()];
                let clear = holes
                    .iter()
                    .map(|o| (c[0] - o.center[0]).hypot(c[1] - o.center[1]) - o.radius)
                    .fold(b.radius - d, f64::min);
                if clear > best.1 {
                    best = (c, clear);
                }
            }
            holes.push(Circle {
                center: best.0,
                radius: best.1 * 0.02 * (1.0 + rng.next_f64()),
            });
        }
        out.extend(Domain::bounded(b, holes).ok());
    }
    // Beside hole 0, at a tenth of its radius.
    let h = d0.holes()[0];
    let mut holes = d0.holes().to_vec();
    holes.push(Circle::new(
        h.center[0] + 1.15 * h.radius,
        h.center[1],
        0.05 * h.radius,
    ));
    out.extend(Domain::bounded(b, holes).ok());
    out
}

/// With an earlier sampling to take over: the same samples, the same count of circles taken
/// over and the same errors, on the pool and in the serial loop, including budgets hit exactly
/// and by one (which decide whether an earlier circle may be taken over).
#[test]
fn taking_over_an_earlier_sampling_is_the_same_on_the_pool() {
    let mut rng = SplitMix64(9);
    let (mut taken, mut circles, mut errors) = (0, 0, 0);
    let mut earlier: Vec<Domain> = vec![layouts::lattice().unwrap(), pair(1e-5, 0.2)];
    for (n, seed) in [(150, 1), (700, 2)] {
        earlier.push(layouts::bubbles(n, seed).unwrap());
    }
    for d0 in earlier {
        for opts in [
            SamplingOptions::default(),
            SamplingOptions {
                soft_rounds: false,
                min_per_circle: 24,
                ..SamplingOptions::default()
            },
        ] {
            let s0 = sample_and_triangulate(&d0, &opts).unwrap();
            for d1 in extensions(&d0, &mut rng) {
                let (s, t) = same_both_ways(&d1, &opts, &[], Some(&s0)).unwrap();
                // Taking over changes nothing: the samples of a fresh sampling.
                let (fresh, none) = same_both_ways(&d1, &opts, &[], None).unwrap();
                assert_eq!((bits(&s), none), (bits(&fresh), 0));
                taken += t;
                circles += d1.hole_count() + 1;
                let total = s.len();
                for max_total in [total, total - 1, total / 2] {
                    let tight = SamplingOptions {
                        max_total,
                        ..opts.clone()
                    };
                    // The earlier sampling was made with other options: nothing is taken over.
                    let r = same_both_ways(&d1, &tight, &[], Some(&s0));
                    errors += usize::from(r.is_err());
                    // Made with these options: taken over when it fits.
                    if let Ok(s0) = sample_and_triangulate(&d0, &tight) {
                        let r = same_both_ways(&d1, &tight, &[], Some(&s0));
                        errors += usize::from(r.is_err());
                    }
                }
            }
        }
    }
    assert!(
        taken * 2 > circles,
        "{taken} of {circles} circles taken over"
    );
    assert!(errors >= 10, "{errors}");
}

/// The whole sampling stage (sampling, triangulation, classes, checks, medial graph) gives the
/// same samples and triangles on pools of 1, 2 and 3 threads.
#[test]
fn sampled_domains_do_not_depend_on_the_thread_count() {
    let mut ds = vec![layouts::bubbles(700, 3).unwrap(), ratio(1e3, 200, 4)];
    if long() {
        ds.push(layouts::bubbles(10_000, 1).unwrap());
    }
    for d in ds {
        for opts in [
            SamplingOptions::default(),
            SamplingOptions {
                soft_rounds: false,
                ..SamplingOptions::default()
            },
        ] {
            let one = on(1, || sample_and_triangulate(&d, &opts).unwrap());
            for threads in [2, 3] {
                let other = on(threads, || sample_and_triangulate(&d, &opts).unwrap());
                assert_eq!(bits(&other.samples), bits(&one.samples));
                common::assert_same_triangulation(&other.triangulation, &one.triangulation);
                assert_eq!(other.kinds, one.kinds);
                assert_eq!(other.medial, one.medial);
                assert_eq!(other.rounds, one.rounds);
            }
        }
    }
}

/// The nearest-gap queries split between threads answer as the serial ones, on layouts with
/// exact ties (lattices), overlaps and single holes.
#[test]
fn nearest_gaps_on_the_pool_equal_the_serial_queries() {
    let mut sets: Vec<Vec<Circle>> = domains().iter().map(|d| d.holes().to_vec()).collect();
    sets.push(vec![Circle::new(0.0, 0.0, 1.0)]);
    sets.push(Vec::new());
    // Overlapping and duplicate circles (the index does not validate).
    let mut rng = SplitMix64(13);
    sets.push(
        (0..3000)
            .map(|_| Circle::new(rng.next_f64(), rng.next_f64(), 0.05 * rng.next_f64()))
            .chain([Circle::new(0.5, 0.5, 0.1), Circle::new(0.5, 0.5, 0.1)])
            .collect(),
    );
    for holes in sets {
        let index = HoleIndex::new(&holes);
        let serial = index.nearest_gap_each_on(false);
        for (i, &found) in serial.iter().enumerate() {
            assert_eq!(found, index.nearest_gap(i));
        }
        for threads in [1, 2, 3] {
            let parallel = on(threads, || index.nearest_gap_each_on(true));
            assert_eq!(parallel, serial, "{threads} threads, {} holes", holes.len());
            assert_eq!(on(threads, || index.nearest_gap_each()), serial);
        }
    }
}
