//! The fast Apollonius solve ([`medial_blocks::apollonius::apollonius`] rounds only the chosen
//! root, with one square root of `D` for all its roundings; issue #8) gives bit for bit the
//! values of the reference path (every root rounded, each rounding with its own square root:
//! `choose(apollonius_roots(..), choice).to_apollonius()`) and the correctly rounded values of
//! the exact root computed with the rational arithmetic of `QSqrt::to_f64` (another code path),
//! on random, near-tangent, co-circular and integer triples and under proptest. The in-place
//! tangent points (another formula) and orientation sums equal those of the plain `ZSqrt` formulas, and the rational oracle's
//! tangent points come from that plain formula.

use crate::common;

use medial_blocks::apollonius::exact::ZSqrt;
use medial_blocks::apollonius::{
    apollonius, apollonius_roots, choose, Apollonius, Choice, ExactApollonius, Site,
};
use medial_blocks::layouts::SplitMix64;
use proptest::prelude::*;
use rug::Integer;
use std::cell::Cell;

fn hole(x: f64, y: f64, r: f64) -> Site {
    common::hole_site(x, y, r)
}

fn bounding(x: f64, y: f64, r: f64) -> Site {
    common::bounding_site(x, y, r)
}

thread_local! {
    /// Orientation-filter statistics of this test's `check` calls: (roots, decided).
    static FILTER: Cell<(usize, usize)> = const { Cell::new((0, 0)) };
}

fn bits(ap: &Apollonius) -> Vec<u64> {
    let mut v = vec![ap.center[0], ap.center[1], ap.radius];
    v.extend(ap.tangent_points.iter().flatten());
    v.into_iter().map(f64::to_bits).collect()
}

/// The rounded values of `ex` from its exact `QSqrt` parts (rational rounding).
fn rational_rounding(ex: &ExactApollonius) -> Option<Vec<u64>> {
    let d = ex.d();
    let mut v = vec![ex.x().to_f64(&d), ex.y().to_f64(&d), ex.rho().to_f64(&d)];
    for i in 0..3 {
        let t = ex.tangent_point_exact(i)?;
        v.extend([t[0].to_f64(&d), t[1].to_f64(&d)]);
    }
    Some(v.into_iter().map(f64::to_bits).collect())
}

/// Fast against both oracles for the choices exact mode makes; returns whether a circle was
/// found.
fn check(sites: [Site; 3], hint: [f64; 2]) -> bool {
    let mut found = false;
    for choice in [
        Choice::ccw().near(hint),
        Choice::any().near(hint),
        Choice::any(),
    ] {
        let fast = apollonius(sites, choice);
        let reference = apollonius_roots(&sites).map(|r| choose(r, choice));
        match (&fast, reference) {
            (Ok(f), Ok(Some(r))) => {
                let r = r.to_apollonius().expect("fast path rounded it");
                assert_eq!(bits(f), bits(&r), "{sites:?} {choice:?}");
                assert_eq!(f.exact, r.exact, "{sites:?} {choice:?}");
                assert_eq!(Some(bits(f)), rational_rounding(&f.exact), "{sites:?}");
                for root in apollonius_roots(&sites).unwrap() {
                    let (same_sum, o, filter, exact) =
                        root.orientation_reference().expect("same frame");
                    assert!(same_sum, "orientation sum {sites:?}");
                    assert_eq!(o, root.orientation(), "{sites:?}");
                    assert!(filter.is_none() || filter == Some(exact), "{sites:?}");
                    FILTER.with(|c| {
                        let (n, k) = c.get();
                        c.set((n + 1, k + usize::from(filter.is_some())));
                    });
                }
                for i in 0..3 {
                    // Same values (reduced rationals), over different denominators.
                    let value = |t: Option<([ZSqrt; 2], Integer)>| {
                        t.map(|(xy, den)| xy.map(|z| z.to_qsqrt(&den, 0)))
                    };
                    assert_eq!(
                        value(f.exact.tangent_point_frac(i)),
                        value(f.exact.tangent_point_frac_reference(i)),
                        "{sites:?}"
                    );
                }
                found = true;
            }
            (Err(_), Ok(Some(r))) => assert!(r.to_apollonius().is_err(), "{sites:?}"),
            (Err(_), _) => {}
            (Ok(_), _) => panic!("fast path found a circle the reference did not: {sites:?}"),
        }
    }
    found
}

#[test]
fn random_and_near_tangent_triples() {
    let mut rng = SplitMix64(5);
    let mut found = 0;
    for case in 0..1200 {
        let mut f = |a: f64, b: f64| a + (b - a) * rng.next_f64();
        let p = [f(-10.0, 10.0), f(-10.0, 10.0)];
        let rho = match case % 3 {
            0 => f(0.05, 3.0),
            1 => f(1e-9, 1e-6), // nearly touching circles
            _ => f(1e-3, 1e-2),
        };
        let mut sites = [hole(0.0, 0.0, 0.0); 3];
        for (i, s) in sites.iter_mut().enumerate() {
            let t = f(0.0, std::f64::consts::TAU);
            if i == 0 && case % 4 == 0 {
                let gap = f(0.1, 5.0);
                *s = common::bounding_tangent(p, rho, t, gap);
            } else {
                let r = f(0.01, 2.0);
                *s = common::hole_tangent(p, rho, t, r);
            }
        }
        found += usize::from(check(sites, p));
    }
    assert!(found > 1000, "{found}");
    // The orientation filter decides typical roots (it is not dead code).
    let (roots, decided) = FILTER.with(Cell::get);
    assert!(
        decided * 10 > roots * 9,
        "orientation filter: {decided} of {roots}"
    );
}

#[test]
fn co_circular_and_integer_triples() {
    let mut found = 0;
    // Equal holes at the corners of squares (four co-circular circles, the centre is rational
    // and rho irrational), with every triple and orientation.
    for k in 1..=12 {
        let (a, r) = (k as f64 * 0.5, 0.1 * k as f64);
        let c = [[0.0, 0.0], [a, 0.0], [a, a], [0.0, a]];
        for skip in 0..4 {
            let t: Vec<Site> = (0..4)
                .filter(|&i| i != skip)
                .map(|i| hole(c[i][0], c[i][1], r))
                .collect();
            found += usize::from(check([t[0], t[1], t[2]], [0.5 * a, 0.5 * a]));
            found += usize::from(check([t[2], t[1], t[0]], [0.5 * a, 0.5 * a]));
        }
    }
    // Small integers: rational roots (D a square) and both roots present.
    let mut rng = SplitMix64(9);
    for _ in 0..600 {
        let mut i = |n: u64| (rng.next_u64() % n) as f64;
        let sites = [
            hole(i(20), i(20), 1.0 + i(3)),
            hole(i(20), i(20), 1.0 + i(3)),
            hole(i(20), i(20), i(3)),
        ];
        found += usize::from(check(sites, [10.0, 10.0]));
    }
    assert!(found > 300, "{found}");
}

proptest! {
    #[test]
    fn prop_fast_solve_equals_the_reference(
        c in proptest::array::uniform3((-100.0f64..100.0, -100.0f64..100.0, 0.0f64..20.0)),
        b in proptest::bool::ANY,
        h in (-100.0f64..100.0, -100.0f64..100.0),
    ) {
        let mut sites = c.map(|(x, y, r)| hole(x, y, r));
        if b {
            sites[0] = bounding(sites[0].center[0], sites[0].center[1], 300.0);
        }
        check(sites, [h.0, h.1]);
    }
}

/// The orientation filter against the exact sign on random triples (every root of each):
/// 10 000 triples, or 1 000 000 with `MB_APOLLO_MANY=1`; it must decide nearly all of them.
#[test]
fn orientation_filter_on_many_random_triples() {
    let n = if std::env::var_os("MB_APOLLO_MANY").is_some() {
        1_000_000
    } else {
        10_000
    };
    let mut rng = SplitMix64(41);
    let (mut roots, mut decided) = (0usize, 0usize);
    for case in 0..n {
        let mut f = |a: f64, b: f64| a + (b - a) * rng.next_f64();
        let scale = [1.0, 1e-6, 1e6][case % 3];
        let mut sites = [hole(0.0, 0.0, 0.0); 3];
        for s in &mut sites {
            *s = hole(
                f(-1.0, 1.0) * scale,
                f(-1.0, 1.0) * scale,
                f(0.0, 0.3) * scale,
            );
        }
        if case % 5 == 0 {
            sites[0] = bounding(0.0, 0.0, 3.0 * scale);
        }
        let Ok(rs) = apollonius_roots(&sites) else {
            continue;
        };
        for r in rs {
            let (same_sum, o, filter, exact) = r.orientation_reference().expect("same frame");
            assert!(same_sum && o == r.orientation(), "{sites:?}");
            assert!(filter.is_none() || filter == Some(exact), "{sites:?}");
            roots += 1;
            decided += usize::from(filter.is_some());
        }
    }
    assert!(roots > n / 2, "{roots}");
    assert!(
        decided * 100 > roots * 95,
        "orientation filter: {decided} of {roots}"
    );
}
