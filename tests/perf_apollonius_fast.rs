//! The certified fast path of the Apollonius solve (`apollonius_fast`, double-double balls;
//! issue #8) against the exact solve (`apollonius_exact`, the oracle): whenever the fast path
//! answers, every answer is equal: the rounded centre, radius and tangent points (bits), the
//! orientation, and the exact root itself (its lazily built frame equals the exact solve's
//! root, so same-circle and tangency queries are unchanged). Random, nearly co-circular,
//! nearly tangent, tiny/huge, bounding-circle, integer and nearly collinear triples, inputs
//! at the edges of the fast path's range, and a proptest over exponent spreads. The fast path
//! must also answer nearly all typical calls (it is not dead code).

use crate::common;

use medial_blocks::apollonius::{
    apollonius, apollonius_exact, apollonius_fast, same_circle, tangency, Apollonius, Choice, Site,
};
use medial_blocks::layouts::SplitMix64;
use proptest::prelude::*;

fn hole(x: f64, y: f64, r: f64) -> Site {
    common::hole_site(x, y, r)
}

fn bounding(x: f64, y: f64, r: f64) -> Site {
    common::bounding_site(x, y, r)
}

fn bits(ap: &Apollonius) -> Vec<u64> {
    let mut v = vec![ap.center[0], ap.center[1], ap.radius];
    v.extend(ap.tangent_points.iter().flatten());
    v.into_iter().map(f64::to_bits).collect()
}

/// Fast against exact for the choices the mesher makes; returns how many calls the fast path
/// answered and how many have a circle.
fn check(sites: [Site; 3], hint: [f64; 2]) -> (usize, usize) {
    let (mut answered, mut circles) = (0, 0);
    for choice in [
        Choice::ccw().near(hint),
        Choice::any().near(hint),
        Choice::any(),
    ] {
        let exact = apollonius_exact(sites, choice);
        circles += usize::from(exact.is_ok());
        let Some(fast) = apollonius_fast(sites, choice) else {
            continue;
        };
        answered += 1;
        let exact = exact.unwrap_or_else(|e| panic!("fast found a circle, exact {e}: {sites:?}"));
        assert_eq!(bits(&fast), bits(&exact), "{sites:?} {choice:?}");
        assert_eq!(
            fast.exact.orientation(),
            exact.exact.orientation(),
            "{sites:?}"
        );
        // The public entry point answers the same, and the lazy exact root is the same root.
        assert_eq!(apollonius(sites, choice).as_ref(), Ok(&fast), "{sites:?}");
        assert_eq!(fast.exact, exact.exact, "{sites:?} {choice:?}");
        assert!(same_circle(&fast.exact, &exact.exact), "{sites:?}");
        for s in sites {
            assert_eq!(
                tangency(&fast.exact, &s).unwrap(),
                medial_blocks::apollonius::Sign::Zero,
                "{sites:?}"
            );
        }
    }
    (answered, circles)
}

#[test]
fn random_near_tangent_and_bounding_triples() {
    let mut rng = SplitMix64(77);
    let (mut calls, mut answered) = (0, 0);
    for case in 0..1500 {
        let mut f = |a: f64, b: f64| a + (b - a) * rng.next_f64();
        let p = [f(-30.0, 30.0), f(-30.0, 30.0)];
        let rho = match case % 4 {
            0 => f(0.05, 3.0),
            1 => f(1e-9, 1e-6), // nearly touching circles
            2 => f(1e-3, 1e-2),
            _ => f(10.0, 1e3),
        };
        let mut sites = [hole(0.0, 0.0, 0.0); 3];
        for (i, s) in sites.iter_mut().enumerate() {
            let t = f(0.0, std::f64::consts::TAU);
            if i == case % 3 && case % 5 == 0 {
                let gap = f(0.1, 5.0);
                *s = common::bounding_tangent(p, rho, t, gap);
            } else {
                let r = [f(0.01, 2.0), f(1e-8, 1e-6), f(1e2, 1e4)][(case / 4 + i) % 3];
                *s = common::hole_tangent(p, rho, t, r);
            }
        }
        let (a, c) = check(sites, p);
        answered += a;
        calls += c;
    }
    assert!(
        answered * 20 > calls * 19,
        "fast path answered {answered} of {calls}"
    );
}

#[test]
fn co_circular_integer_and_symmetric_triples() {
    let mut answered = 0;
    // Equal holes at the corners of squares: irrational rho, rational centre.
    for k in 1..=12 {
        let (a, r) = (k as f64 * 0.37, 0.1 * k as f64);
        let c = [
            [0.25, 0.5],
            [a + 0.25, 0.5],
            [a + 0.25, a + 0.5],
            [0.25, a + 0.5],
        ];
        for skip in 0..4 {
            let t: Vec<Site> = (0..4)
                .filter(|&i| i != skip)
                .map(|i| hole(c[i][0], c[i][1], r))
                .collect();
            let hint = [0.5 * a + 0.25, 0.5 * a + 0.5];
            answered += check([t[0], t[1], t[2]], hint).0;
            answered += check([t[2], t[1], t[0]], hint).0;
        }
    }
    // Small integers: rational roots (D a square), zeros (given up), both roots present.
    let mut rng = SplitMix64(19);
    for _ in 0..600 {
        let mut i = |n: u64| (rng.next_u64() % n) as f64;
        let sites = [
            hole(i(20), i(20), 1.0 + i(3)),
            hole(i(20), i(20), 1.0 + i(3)),
            hole(i(20), i(20), i(3)),
        ];
        answered += check(sites, [10.0, 10.0]).0;
    }
    assert!(answered > 300, "{answered}");
}

#[test]
fn nearly_degenerate_and_range_edges() {
    let mut rng = SplitMix64(3);
    for case in 0..600 {
        let mut f = |a: f64, b: f64| a + (b - a) * rng.next_f64();
        let eps = [1e-6, 1e-10, 1e-14, 0.0][case % 4];
        // Nearly collinear centres (det ~ 0), nearly equal radii.
        let sites = [
            hole(0.0, 0.0, 0.3),
            hole(1.0, eps, 0.3 + eps),
            hole(2.0 + f(-eps, eps), f(-eps, eps), 0.3),
        ];
        check(sites, [1.0, 1.0]);
        // A fourth circle nearly tangent to the circle of three (nearly co-circular groups).
        let base = [
            hole(0.0, 0.0, 0.5),
            hole(3.0, 0.0, 0.5),
            hole(0.0, 3.0, 0.5),
        ];
        if let Ok(ap) = apollonius_exact(base, Choice::ccw()) {
            let (c, r) = (ap.center, ap.radius);
            let t = f(0.0, std::f64::consts::TAU);
            let rr = 0.5 + eps;
            let l = hole(c[0] + (r + rr) * t.cos(), c[1] + (r + rr) * t.sin(), rr);
            check([base[0], base[1], l], c);
            check([l, base[2], base[0]], c);
        }
    }
    // Magnitudes at and beyond the fast path's range 2^-200..2^200 (beyond: given up).
    for e in [-205, -200, -199, -100, 0, 100, 199, 200, 205] {
        let s = 2f64.powi(e);
        let sites = [
            hole(0.1 * s, 0.2 * s, 0.05 * s),
            hole(1.3 * s, 0.1 * s, 0.07 * s),
            hole(0.6 * s, 1.1 * s, 0.02 * s),
        ];
        check(sites, [0.6 * s, 0.4 * s]);
        // Exponent spread: one tiny radius next to large coordinates.
        let spread = [
            hole(1e3, 2e3, s.min(1e-3)),
            hole(1.3e3, 2.1e3, 50.0),
            hole(1.1e3, 2.4e3, 70.0),
        ];
        check(spread, [1.15e3, 2.2e3]);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    #[test]
    fn prop_fast_equals_exact(
        c in proptest::array::uniform3((-1.0f64..1.0, -1.0f64..1.0, 0.0f64..0.4)),
        scale in -60i32..60,
        spread in 0i32..40,
        b in 0u8..3,
        h in (-1.0f64..1.0, -1.0f64..1.0),
    ) {
        let s = 2f64.powi(scale);
        let mut sites = c.map(|(x, y, r)| hole(x * s, y * s, r * s));
        // One radius many binades below the rest.
        sites[1].s *= 2f64.powi(-spread);
        if b == 0 {
            sites[0] = bounding(sites[0].center[0], sites[0].center[1], 5.0 * s);
        }
        check(sites, [h.0 * s, h.1 * s]);
    }
}

/// On the sampled medial graphs of the pipeline's layouts (degenerate lattices with many
/// co-circular groups, bubbles), every vertex circle of `vertex_circles` (fast path first)
/// equals the exact solve's with the same sites and choice, exact root included, and the
/// fast path answers nearly every bubble vertex.
#[test]
fn vertex_circles_of_layouts_equal_the_exact_solve() {
    use medial_blocks::cocircular::{site, vertex_circles};
    use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
    let domains = [
        (medial_blocks::layouts::hexagon(), false),
        (medial_blocks::layouts::lattice().unwrap(), false),
        (medial_blocks::layouts::square_lattice(16).unwrap(), false),
        (medial_blocks::layouts::bubbles(300, 2).unwrap(), true),
    ];
    for (d, typical) in &domains {
        let s = sample_and_triangulate(d, &SamplingOptions::default()).unwrap();
        let circles = vertex_circles(d, &s.medial);
        let (mut fast, mut solved) = (0, 0);
        for (v, got) in s.medial.vertices.iter().zip(&circles) {
            if v.circles
                .iter()
                .any(|&c| c < -1 || c >= d.hole_count() as i32)
            {
                continue;
            }
            let sites = v.circles.map(|c| site(d, c));
            let choice = Choice::ccw().near(v.position);
            let exact = apollonius_exact(sites, choice).ok();
            assert_eq!(got.as_ref().map(bits), exact.as_ref().map(bits));
            assert_eq!(got, &exact);
            solved += usize::from(exact.is_some());
            fast += usize::from(apollonius_fast(sites, choice).is_some());
        }
        if *typical {
            assert!(fast * 100 >= solved * 99, "fast path {fast} of {solved}");
        }
    }
}
