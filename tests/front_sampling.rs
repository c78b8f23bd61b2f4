//! Boundary sampling: counts are multiples of 8, samples lie on their circle in
//! counter-clockwise order, and mirror-symmetric layouts give bitwise mirror-symmetric samples.

use medial_blocks::domain::{Circle, CircleId, Domain};
use medial_blocks::sampling::{initial_counts, nearest_gaps, sample, Samples, SamplingOptions};
use proptest::prelude::*;

fn samples_of(d: &Domain, opts: &SamplingOptions) -> Samples {
    let gaps = nearest_gaps(d);
    let counts = initial_counts(d, &gaps, opts);
    sample(d, &counts, &gaps)
}

/// The id of the circle equal to `c` (exact comparison), bounding included.
fn find(d: &Domain, c: Circle) -> Option<CircleId> {
    d.circle_ids().find(|&id| d.circle(id) == c)
}

/// Check that `map` (a mirror applied to points) maps the samples of every circle onto the
/// samples of its mirror circle bitwise, with sample `k` going to `mirror_index(k, n)`.
fn check_mirror(
    d: &Domain,
    s: &Samples,
    map: impl Fn([f64; 2]) -> [f64; 2],
    mirror_index: impl Fn(u32, u32) -> u32,
) {
    for id in d.circle_ids() {
        let c = d.circle(id);
        let mc = Circle {
            center: map(c.center),
            radius: c.radius,
        };
        let mid = find(d, mc).expect("layout is not mirror-symmetric");
        let (cs, ms) = (s.of_circle(id), s.of_circle(mid));
        assert_eq!(cs.count, ms.count, "circle {id} vs its mirror {mid}");
        assert_eq!(cs.gap.to_bits(), ms.gap.to_bits());
        for k in 0..cs.count {
            let p = s.points[(cs.first + k) as usize];
            let q = s.points[(ms.first + mirror_index(k, cs.count)) as usize];
            let mp = map(p);
            // Bitwise, up to the sign of zero (`+ 0.0` folds -0.0 into 0.0).
            assert_eq!(
                [(mp[0] + 0.0).to_bits(), (mp[1] + 0.0).to_bits()],
                [(q[0] + 0.0).to_bits(), (q[1] + 0.0).to_bits()],
                "circle {id} sample {k}: {p:?} mirrors to {mp:?}, found {q:?}"
            );
        }
    }
}

fn check_basic(d: &Domain, s: &Samples) {
    for id in d.circle_ids() {
        let c = d.circle(id);
        let cs = s.of_circle(id);
        assert!(cs.count.is_multiple_of(8) && cs.count >= 8);
        for k in 0..cs.count {
            let g = (cs.first + k) as usize;
            assert_eq!(s.circle_of[g], id);
            assert_eq!(s.index_of[g], k);
            let p = s.points[g];
            let (dx, dy) = (p[0] - c.center[0], p[1] - c.center[1]);
            assert!(((dx * dx + dy * dy).sqrt() - c.radius).abs() <= 1e-12 * d.bounding().radius);
            // Counter-clockwise: the angle increases by 2 pi / n.
            let want = std::f64::consts::TAU * k as f64 / cs.count as f64;
            let got = dy.atan2(dx).rem_euclid(std::f64::consts::TAU);
            let diff = (got - want).abs();
            assert!(diff < 1e-9 || (diff - std::f64::consts::TAU).abs() < 1e-9);
        }
    }
}

/// A layout with the full symmetry of the square (mirrors about both axes and both
/// diagonals).
fn d4_layout() -> Domain {
    let mut holes = vec![Circle::new(0.0, 0.0, 0.7)];
    for (x, y) in [(2.0, 1.0), (1.0, 2.0), (3.1, 0.0), (0.0, 3.1)] {
        for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
            let c = Circle::new(sx * x, sy * y, 0.45);
            if !holes.contains(&c) {
                holes.push(c);
            }
        }
    }
    Domain::bounded(Circle::new(0.0, 0.0, 4.4), holes).unwrap()
}

#[test]
fn d4_symmetric_layout_gives_mirrored_samples() {
    let d = d4_layout();
    for opts in [
        SamplingOptions::default(),
        SamplingOptions {
            min_per_circle: 8,
            spacing_per_gap: 0.37,
            ..SamplingOptions::default()
        },
    ] {
        let s = samples_of(&d, &opts);
        check_basic(&d, &s);
        // Mirror about x = 0: angle k -> n/2 - k.
        check_mirror(&d, &s, |p| [-p[0], p[1]], |k, n| (n / 2 + n - k) % n);
        // Mirror about y = 0: k -> n - k.
        check_mirror(&d, &s, |p| [p[0], -p[1]], |k, n| (n - k) % n);
        // Mirror about y = x: k -> n/4 - k.
        check_mirror(&d, &s, |p| [p[1], p[0]], |k, n| (n / 4 + n - k) % n);
        // Mirror about y = -x: k -> 3n/4 - k.
        check_mirror(&d, &s, |p| [-p[1], -p[0]], |k, n| (3 * n / 4 + n - k) % n);
    }
}

#[test]
fn hexagon_samples_are_mirror_symmetric() {
    let d = Domain::hexagon_example();
    let s = samples_of(&d, &SamplingOptions::default());
    check_basic(&d, &s);
    check_mirror(&d, &s, |p| [-p[0], p[1]], |k, n| (n / 2 + n - k) % n);
    check_mirror(&d, &s, |p| [p[0], -p[1]], |k, n| (n - k) % n);
}

#[test]
fn density_follows_the_gap() {
    // Two close holes get many more samples than a lonely one of the same radius.
    let d = Domain::bounded(
        Circle::new(0.0, 0.0, 20.0),
        vec![
            Circle::new(-1.005, 0.0, 1.0),
            Circle::new(1.005, 0.0, 1.0),
            Circle::new(0.0, 10.0, 1.0),
        ],
    )
    .unwrap();
    let s = samples_of(&d, &SamplingOptions::default());
    let close = s.of_circle(0).count;
    let lonely = s.of_circle(2).count;
    assert_eq!(close, s.of_circle(1).count);
    assert!(close >= 8 * lonely, "close {close}, lonely {lonely}");
    // Spacing at most the gap (0.01).
    assert!(std::f64::consts::TAU / close as f64 <= 0.01 + 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    /// Random layouts mirrored about x = 0 (and holes on the axis) sample bitwise
    /// symmetrically.
    #[test]
    fn random_mirror_layouts(
        raw in prop::collection::vec((0.05f64..4.0, -4.0f64..4.0, 0.05f64..0.8, any::<bool>()), 1..12),
        spacing in 0.3f64..2.0,
    ) {
        let mut holes: Vec<Circle> = Vec::new();
        for (x, y, r, on_axis) in raw {
            let cand: Vec<Circle> = if on_axis {
                vec![Circle::new(0.0, y, r)]
            } else {
                vec![Circle::new(x, y, r), Circle::new(-x, y, r)]
            };
            let mut trial = holes.clone();
            trial.extend(cand);
            if Domain::bounded(Circle::new(0.0, 0.0, 6.0), trial.clone()).is_ok() {
                holes = trial;
            }
        }
        prop_assume!(!holes.is_empty());
        let d = Domain::bounded(Circle::new(0.0, 0.0, 6.0), holes).unwrap();
        let opts = SamplingOptions { min_per_circle: 16, spacing_per_gap: spacing, max_per_circle: 4096, ..SamplingOptions::default() };
        let s = samples_of(&d, &opts);
        check_basic(&d, &s);
        check_mirror(&d, &s, |p| [-p[0], p[1]], |k, n| (n / 2 + n - k) % n);
    }
}

mod adaptive {
    use super::*;
    use medial_blocks::sampling::sample_adaptive;
    use std::f64::consts::TAU;

    fn adaptive(d: &Domain, opts: &SamplingOptions) -> Samples {
        let gaps = nearest_gaps(d);
        sample_adaptive(d, opts, &gaps, &vec![0; gaps.len()]).unwrap()
    }

    fn key(p: [f64; 2]) -> (u64, u64) {
        ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits())
    }

    /// The samples of every circle, mirrored by `map`, are bitwise the samples of its mirror
    /// circle (compared as sets: adaptive counts need not follow index arithmetic).
    fn check_mirror_sets(d: &Domain, s: &Samples, map: impl Fn([f64; 2]) -> [f64; 2]) {
        for id in d.circle_ids() {
            let c = d.circle(id);
            let mc = Circle {
                center: map(c.center),
                radius: c.radius,
            };
            let mid = find(d, mc).expect("layout is not mirror-symmetric");
            let set = |id: CircleId, f: &dyn Fn([f64; 2]) -> [f64; 2]| {
                let cs = s.of_circle(id);
                let mut v: Vec<(u64, u64)> = (cs.first..cs.first + cs.count)
                    .map(|g| key(f(s.points[g as usize])))
                    .collect();
                v.sort_unstable();
                v
            };
            assert_eq!(
                set(id, &map),
                set(mid, &|p| p),
                "circle {id} vs mirror {mid}"
            );
        }
    }

    /// Samples lie on their circle, strictly counter-clockwise in grid order, at their grid
    /// angle; and every interval between consecutive samples is at most `spacing_per_gap`
    /// times the gap from its two ends and its midpoint to every other circle, found by brute
    /// force over all circles (an oracle that does not use the k-d tree).
    fn check_adaptive(d: &Domain, s: &Samples, opts: &SamplingOptions) {
        let circles: Vec<(CircleId, Circle)> = d.circle_ids().map(|i| (i, d.circle(i))).collect();
        let local_gap = |me: CircleId, p: [f64; 2]| {
            circles
                .iter()
                .filter(|(i, _)| *i != me)
                .map(|(i, c)| {
                    let r = (p[0] - c.center[0]).hypot(p[1] - c.center[1]);
                    if *i < 0 {
                        c.radius - r
                    } else {
                        r - c.radius
                    }
                })
                .fold(f64::INFINITY, f64::min)
        };
        for &(id, c) in &circles {
            let cs = s.of_circle(id);
            let n = s.grid_count(id);
            assert!(cs.count >= 8 && n.is_multiple_of(8));
            for k in 0..cs.count {
                let g = cs.first + k;
                assert_eq!(s.circle_of[g as usize], id);
                assert_eq!(s.index_of[g as usize], k);
                if k > 0 {
                    assert!(s.grid_index(g) > s.grid_index(g - 1));
                }
                let p = s.points[g as usize];
                let (dx, dy) = (p[0] - c.center[0], p[1] - c.center[1]);
                assert!((dx.hypot(dy) - c.radius).abs() <= 1e-12 * d.bounding().radius);
                let want = s.angle(g);
                let got = dy.atan2(dx).rem_euclid(TAU);
                let diff = (got - want).abs();
                assert!(diff < 1e-9 || (diff - TAU).abs() < 1e-9);
                // The interval to the next sample.
                let q = s.next(g);
                let len = (s.angle(q) - want).rem_euclid(TAU) * c.radius;
                let mid = want + 0.5 * len / c.radius;
                let pm = [
                    c.center[0] + c.radius * mid.cos(),
                    c.center[1] + c.radius * mid.sin(),
                ];
                let gap = local_gap(id, p)
                    .min(local_gap(id, s.points[q as usize]))
                    .min(local_gap(id, pm));
                assert!(
                    len <= opts.spacing_per_gap * gap * (1.0 + 1e-9),
                    "circle {id} sample {k}: interval {len} for local gap {gap}"
                );
            }
        }
    }

    #[test]
    fn d4_symmetric_layout_gives_mirrored_adaptive_samples() {
        let d = d4_layout();
        for opts in [
            SamplingOptions::default(),
            SamplingOptions {
                min_per_circle: 8,
                spacing_per_gap: 0.37,
                ..SamplingOptions::default()
            },
        ] {
            let s = adaptive(&d, &opts);
            check_adaptive(&d, &s, &opts);
            check_mirror_sets(&d, &s, |p| [-p[0], p[1]]);
            check_mirror_sets(&d, &s, |p| [p[0], -p[1]]);
            check_mirror_sets(&d, &s, |p| [p[1], p[0]]);
            check_mirror_sets(&d, &s, |p| [-p[1], -p[0]]);
        }
    }

    #[test]
    fn density_is_spent_only_near_the_close_pair() {
        let d = Domain::bounded(
            Circle::new(0.0, 0.0, 20.0),
            vec![
                Circle::new(-1.005, 0.0, 1.0),
                Circle::new(1.005, 0.0, 1.0),
                Circle::new(0.0, 10.0, 1.0),
            ],
        )
        .unwrap();
        let opts = SamplingOptions::default();
        let s = adaptive(&d, &opts);
        check_adaptive(&d, &s, &opts);
        let uniform = samples_of(&d, &opts);
        // Hole 0 faces hole 1 at angle 0: most of its samples are within 30 degrees of it.
        let cs = s.of_circle(0);
        let facing = (cs.first..cs.first + cs.count)
            .filter(|&g| {
                let a = s.angle(g);
                a.min(TAU - a) < TAU / 12.0
            })
            .count();
        assert!(2 * facing > cs.count as usize, "{facing} of {}", cs.count);
        assert!(
            s.of_circle(2).count == 32,
            "the lonely hole keeps the coarse count"
        );
        assert!(
            4 * s.len() < uniform.len(),
            "adaptive {} vs uniform {}",
            s.len(),
            uniform.len()
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]

        /// Random layouts mirrored about x = 0 sample adaptively and bitwise symmetrically,
        /// and every interval satisfies the spacing criterion by brute force.
        #[test]
        fn random_mirror_layouts_adaptive(
            raw in prop::collection::vec((0.05f64..4.0, -4.0f64..4.0, 0.05f64..0.8, any::<bool>()), 1..10),
            spacing in 0.3f64..2.0,
        ) {
            let mut holes: Vec<Circle> = Vec::new();
            for (x, y, r, on_axis) in raw {
                let cand: Vec<Circle> = if on_axis {
                    vec![Circle::new(0.0, y, r)]
                } else {
                    vec![Circle::new(x, y, r), Circle::new(-x, y, r)]
                };
                let mut trial = holes.clone();
                trial.extend(cand);
                if Domain::bounded(Circle::new(0.0, 0.0, 6.0), trial.clone()).is_ok() {
                    holes = trial;
                }
            }
            prop_assume!(!holes.is_empty());
            let d = Domain::bounded(Circle::new(0.0, 0.0, 6.0), holes).unwrap();
            let opts = SamplingOptions { min_per_circle: 16, spacing_per_gap: spacing, ..SamplingOptions::default() };
            let s = adaptive(&d, &opts);
            check_adaptive(&d, &s, &opts);
            check_mirror_sets(&d, &s, |p| [-p[0], p[1]]);
        }
    }
}

/// Absurd sampling options are typed errors, never an abort on a huge allocation: the total
/// budget bounds every circle, and a coarse count beyond the caps is refused.
#[test]
fn sampling_budgets_are_typed_errors() {
    use medial_blocks::sampling::sample_and_triangulate;
    use medial_blocks::MeshError;
    let d = Domain::hexagon_example();
    for opts in [
        SamplingOptions {
            min_per_circle: usize::MAX,
            ..SamplingOptions::default()
        },
        SamplingOptions {
            max_total: 100,
            ..SamplingOptions::default()
        },
        SamplingOptions {
            spacing_per_gap: 1e-12,
            ..SamplingOptions::default()
        },
    ] {
        match sample_and_triangulate(&d, &opts) {
            Err(MeshError::Sampling { message, .. }) => assert!(!message.is_empty()),
            other => panic!("{opts:?}: {other:?}"),
        }
    }
}

/// `SamplingOptions::boost` refines only the boosted circle and the circles of the same
/// radius and gap (mirror images), at least doubling their samples per doubling asked.
#[test]
fn boost_refines_only_the_named_circles() {
    use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
    use medial_blocks::{Circle, Domain};
    // Holes 0 and 1 are mirror images (same radius and gap); hole 2 differs.
    let d = Domain::bounded(
        Circle::new(0.0, 0.0, 4.0),
        vec![
            Circle::new(-1.0, 0.5, 0.6),
            Circle::new(1.0, 0.5, 0.6),
            Circle::new(0.0, -1.6, 0.9),
        ],
    )
    .unwrap();
    let plain = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
    let boosted = sample_and_triangulate(
        &d,
        &SamplingOptions {
            boost: vec![0, 2],
            ..SamplingOptions::default()
        },
    )
    .unwrap();
    let count = |s: &medial_blocks::sampling::SampledDomain, id| s.samples.of_circle(id).count;
    for id in [0, 1] {
        assert!(
            count(&boosted, id) >= 3 * count(&plain, id),
            "hole {id}: {} vs {}",
            count(&boosted, id),
            count(&plain, id)
        );
    }
    assert_eq!(count(&boosted, 2), count(&plain, 2));
    assert_eq!(count(&boosted, -1), count(&plain, -1));
}
