//! The Apollonius solve: residuals in f64, exact residuals in Q(sqrt D) evaluated with formulas
//! written here (not the library's arithmetic), root selection, and degenerate inputs.

use crate::common;

use medial_blocks::apollonius::{
    apollonius, apollonius_roots, Apollonius, ApolloniusError, Choice, ExactApollonius, QSqrt,
    Sign, Site,
};
use proptest::prelude::*;
use rug::Rational;

/// splitmix64: a small deterministic generator for bulk cases.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unit()
    }
}

fn hole(x: f64, y: f64, r: f64) -> Site {
    common::hole_site(x, y, r)
}

fn bounding(x: f64, y: f64, r: f64) -> Site {
    common::bounding_site(x, y, r)
}

/// `F_i = |p - c_i|^2 - (rho + s_i)^2` at the exact root, as `A + B sqrt(D)`, evaluated here from
/// the components: `(u + v sqrt D)^2 = u^2 + v^2 D + 2 u v sqrt D`.
fn exact_residual(root: &ExactApollonius, site: &Site) -> (Rational, Rational) {
    let d = &root.d();
    let parts = [
        (root.x(), -Rational::from_f64(site.center[0]).unwrap(), 1),
        (root.y(), -Rational::from_f64(site.center[1]).unwrap(), 1),
        (root.rho(), Rational::from_f64(site.s).unwrap(), -1),
    ];
    let mut a = Rational::new();
    let mut b = Rational::new();
    for (v, shift, sgn) in parts {
        let QSqrt { a: va, b: vb } = v;
        let u = va + &shift;
        let sq_a = Rational::from(u.square_ref()) + Rational::from(vb.square_ref()) * d;
        let sq_b = Rational::from(&u * &vb) * 2u32;
        if sgn > 0 {
            a += sq_a;
            b += sq_b;
        } else {
            a -= sq_a;
            b -= sq_b;
        }
    }
    (a, b)
}

fn assert_exact_root(root: &ExactApollonius) {
    let d = &root.d();
    assert!(*d >= 0);
    if *d > 0 {
        // Normalised: a square radicand is folded into the rational part.
        assert!(!(d.numer().is_perfect_square() && d.denom().is_perfect_square()));
    }
    for site in root.sites() {
        let (a, b) = exact_residual(root, site);
        assert_eq!(a, 0, "rational part of the residual");
        if *d > 0 {
            assert_eq!(b, 0, "sqrt part of the residual");
        }
    }
}

/// Residual checks on the rounded circle and its tangent points.
fn assert_float_root(ap: &Apollonius) {
    let sites = ap.exact.sites();
    let [px, py] = ap.center;
    let rho = ap.radius;
    assert!(rho >= 0.0);
    let mut scale = rho.max(px.abs()).max(py.abs());
    for s in sites {
        scale = scale
            .max(s.center[0].abs() + s.s.abs())
            .max(s.center[1].abs() + s.s.abs());
    }
    let tol = 1e-12 * scale;
    for (s, t) in sites.iter().zip(ap.tangent_points) {
        let dist = (px - s.center[0]).hypot(py - s.center[1]);
        let sigma = rho + s.s;
        assert!((dist - sigma.abs()).abs() <= tol, "tangency residual");
        if s.is_bounding() {
            assert!(sigma <= tol);
        }
        let on_site = (t[0] - s.center[0]).hypot(t[1] - s.center[1]);
        let on_circle = (t[0] - px).hypot(t[1] - py);
        assert!(
            (on_site - s.radius()).abs() <= tol,
            "tangent point off the site"
        );
        assert!(
            (on_circle - rho).abs() <= tol,
            "tangent point off the circle"
        );
    }
    // Orientation of the rounded tangent points agrees with the exact one when clear.
    let [a, b, c] = ap.tangent_points;
    let o = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if o.abs() > 1e-9 * scale * scale {
        assert_eq!(ap.exact.orientation(), Sign::of_f64(o));
    }
}

/// Three sites tangent (up to rounding of the centres) to the circle (p, rho).
fn tangent_triple(rng: &mut Rng, with_bounding: bool) -> ([Site; 3], [f64; 2], f64) {
    let p = [rng.range(-10.0, 10.0), rng.range(-10.0, 10.0)];
    let rho = rng.range(0.05, 3.0);
    let mut sites = [hole(0.0, 0.0, 0.0); 3];
    for (i, s) in sites.iter_mut().enumerate() {
        let t = rng.range(0.0, std::f64::consts::TAU);
        if i == 0 && with_bounding {
            let gap = rng.range(0.1, 5.0);
            let r = rho + gap;
            *s = bounding(p[0] + gap * t.cos(), p[1] + gap * t.sin(), r);
        } else {
            let r = rng.range(0.01, 2.0);
            *s = hole(p[0] + (rho + r) * t.cos(), p[1] + (rho + r) * t.sin(), r);
        }
    }
    (sites, p, rho)
}

#[test]
fn random_tangent_triples() {
    let mut rng = Rng(1);
    let mut found = 0;
    for case in 0..1500 {
        let with_bounding = case % 3 == 0;
        let (sites, p, rho) = tangent_triple(&mut rng, with_bounding);
        let roots = apollonius_roots(&sites).expect("generic triple");
        for r in &roots {
            assert_exact_root(r);
            assert_float_root(&r.to_apollonius().unwrap());
        }
        let ap = apollonius(sites, Choice::any().near(p)).expect("the constructed circle");
        // Rounding the centres moved the circle a little; with angles spread it stays close.
        let err = (ap.center[0] - p[0]).hypot(ap.center[1] - p[1]) + (ap.radius - rho).abs();
        if err < 1e-6 {
            found += 1;
        }
    }
    assert!(
        found > 1400,
        "constructed circle recovered in {found} cases"
    );
}

#[test]
fn random_disjoint_triples() {
    let mut rng = Rng(2);
    let mut counts = [0usize; 3];
    for _ in 0..1500 {
        let mut sites = Vec::new();
        while sites.len() < 3 {
            let s = hole(
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
                rng.range(0.0, 1.5),
            );
            let apart = sites.iter().all(|t: &Site| {
                (s.center[0] - t.center[0]).hypot(s.center[1] - t.center[1]) > s.s + t.s
            });
            if apart {
                sites.push(s);
            }
        }
        let sites = [sites[0], sites[1], sites[2]];
        let roots = apollonius_roots(&sites).unwrap();
        counts[roots.len()] += 1;
        for r in &roots {
            assert_exact_root(r);
            assert_float_root(&r.to_apollonius().unwrap());
        }
        if roots.len() == 2 {
            assert!(roots[0].radius_f64() <= roots[1].radius_f64());
        }
    }
    assert!(counts[1] + counts[2] > 1000, "{counts:?}");
}

#[test]
fn integer_triples_with_rational_roots() {
    // Circle centre (1, 2), radius 3; holes tangent along Pythagorean directions.
    let sites = [
        hole(1.0 + 6.0, 2.0 + 8.0, 7.0),   // |(6, 8)| = 10 = 3 + 7
        hole(1.0 - 5.0, 2.0 + 12.0, 10.0), // 13 = 3 + 10
        hole(1.0 - 8.0, 2.0 - 15.0, 14.0), // 17 = 3 + 14
    ];
    let ap = apollonius(sites, Choice::any().near([1.0, 2.0])).unwrap();
    assert_eq!(ap.center, [1.0, 2.0]);
    assert_eq!(ap.radius, 3.0);
    assert_eq!(ap.tangent_points[0], [2.8, 4.4]);
    assert_exact_root(&ap.exact);
    assert_eq!(ap.exact.d(), 0); // rational root: D is a square and was folded
                                 // Same circle with the bounding circle: centre (1, 2) + (3, 4), R = 3 + 5.
    let sites = [bounding(4.0, 6.0, 8.0), sites[1], sites[2]];
    let ap = apollonius(sites, Choice::any().near([1.0, 2.0])).unwrap();
    assert_eq!((ap.center, ap.radius), ([1.0, 2.0], 3.0));
    // Tangent point on the bounding circle is away from its centre: (1,2) - 3 (3,4)/5.
    assert_eq!(ap.tangent_points[0], [-0.8, -0.4]);
    assert_float_root(&ap);
}

#[test]
fn collinear_centres() {
    // Middle hole smaller: two mirror circles; orientation picks one. Exactly:
    // |y| = rho + 1/2 and sqrt(16 + y^2) = rho + 1 give |y| = 63/4, rho = 61/4.
    let sites = [
        hole(-4.0, 0.0, 1.0),
        hole(0.0, 0.0, 0.5),
        hole(4.0, 0.0, 1.0),
    ];
    // Middle hole larger: it sticks out of every circle touching the outer two from outside.
    let bigger = [
        hole(-4.0, 0.0, 1.0),
        hole(0.0, 0.0, 2.0),
        hole(4.0, 0.0, 1.0),
    ];
    assert!(apollonius_roots(&bigger).unwrap().is_empty());
    let roots = apollonius_roots(&sites).unwrap();
    assert_eq!(roots.len(), 2);
    for r in &roots {
        assert_exact_root(r);
        assert_eq!(r.center_f64()[0], 0.0);
    }
    let up = apollonius(sites, Choice::ccw()).unwrap();
    assert_eq!((up.center, up.radius), ([0.0, 15.75], 15.25));
    assert_eq!(up.exact.orientation(), Sign::Positive);
    let down = apollonius(
        sites,
        Choice {
            orientation: Some(Sign::Negative),
            hint: None,
        },
    )
    .unwrap();
    assert_eq!(down.center, [0.0, -up.center[1]]);
    assert_eq!(down.radius, up.radius);
    // Hint picks the nearer one.
    let near_down = apollonius(sites, Choice::any().near([0.0, -1.0])).unwrap();
    assert_eq!(near_down.center, down.center);
    assert_float_root(&up);
    // Equal holes in a row: the only "tangent circles" are lines, no circle.
    let row = [
        hole(-4.0, 0.0, 1.0),
        hole(0.0, 0.0, 1.0),
        hole(4.0, 0.0, 1.0),
    ];
    assert_eq!(apollonius_roots(&row).unwrap().len(), 0);
    assert_eq!(
        apollonius(row, Choice::any()).unwrap_err(),
        ApolloniusError::NoCircle
    );
    // Collinear along a slanted line with radii not in arithmetic progression.
    let slant = [
        hole(0.0, 0.0, 0.5),
        hole(3.0, 3.0, 1.0),
        hole(5.0, 5.0, 0.25),
    ];
    for r in apollonius_roots(&slant).unwrap() {
        assert_exact_root(&r);
        assert_float_root(&r.to_apollonius().unwrap());
    }
}

#[test]
fn degenerate_inputs_do_not_panic() {
    let a = hole(0.0, 0.0, 1.0);
    let b = hole(3.0, 0.0, 1.0);
    let c = hole(0.0, 3.0, 0.5);
    // Coincident sites.
    assert_eq!(
        apollonius_roots(&[a, a, a]).unwrap_err(),
        ApolloniusError::Continuum
    );
    assert!(matches!(
        apollonius_roots(&[a, a, b]),
        Err(ApolloniusError::Continuum) | Ok(_)
    ));
    // Concentric circles.
    let _ = apollonius_roots(&[a, hole(0.0, 0.0, 2.0), hole(0.0, 0.0, 3.0)]);
    let _ = apollonius_roots(&[bounding(0.0, 0.0, 5.0), a, hole(0.0, 0.0, 2.0)]);
    // Same centre, opposite senses.
    let _ = apollonius_roots(&[bounding(0.0, 0.0, 1.0), a, b]);
    // Non-finite.
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(
            apollonius_roots(&[hole(bad, 0.0, 1.0), b, c]).unwrap_err(),
            ApolloniusError::NonFinite
        );
        assert_eq!(
            apollonius([a, b, hole(0.0, 0.0, bad)], Choice::any()).unwrap_err(),
            ApolloniusError::NonFinite
        );
        // A non-finite hint is ignored.
        assert!(apollonius([a, b, c], Choice::any().near([bad, 0.0])).is_ok());
    }
    // Extreme magnitudes.
    let big = [
        hole(1e300, 0.0, 1e299),
        hole(-1e300, 0.0, 1e299),
        hole(0.0, 1e300, 1e298),
    ];
    for r in apollonius_roots(&big).unwrap() {
        let _ = r.to_apollonius();
    }
    let tiny = f64::from_bits(1);
    let small = [
        hole(0.0, 0.0, tiny),
        hole(4.0 * tiny, 0.0, tiny),
        hole(0.0, 5.0 * tiny, 0.0),
    ];
    for r in apollonius_roots(&small).unwrap() {
        assert_exact_root(&r);
        let _ = r.to_apollonius();
    }
    // Zero radii: the circumcircle of three points.
    let pts = [
        hole(0.0, 0.0, 0.0),
        hole(2.0, 0.0, 0.0),
        hole(0.0, 2.0, 0.0),
    ];
    let ap = apollonius(pts, Choice::ccw()).unwrap();
    assert_eq!(ap.center, [1.0, 1.0]);
    assert_eq!(ap.tangent_points[1], [2.0, 0.0]);
    // Three circles through one point (overlapping, but no panic): a rho = 0 solution.
    let touching = [
        hole(-1.0, 0.0, 1.0),
        hole(1.0, 0.0, 1.0),
        hole(0.0, 4.0, 4.0),
    ];
    let roots = apollonius_roots(&touching).unwrap();
    let point = roots
        .iter()
        .find(|r| r.radius_f64() == 0.0)
        .expect("rho = 0 root");
    assert_exact_root(point);
    let ap = point.to_apollonius().unwrap();
    assert_eq!(
        (ap.center, ap.tangent_points),
        ([0.0, 0.0], [[0.0, 0.0]; 3])
    );
    // Directions (-1, 0), (1, 0), (0, 1) from the centre: counter-clockwise.
    assert_eq!(ap.exact.orientation(), Sign::Positive);
}

#[test]
fn circle_equal_to_bounding_circle() {
    // Zero-radius holes on the bounding circle: the tangent circle is the bounding circle, whose
    // tangent point is undefined.
    let sites = [
        bounding(0.0, 0.0, 5.0),
        hole(3.0, 4.0, 0.0),
        hole(-5.0, 0.0, 0.0),
    ];
    let roots = apollonius_roots(&sites).unwrap();
    let whole = roots
        .iter()
        .find(|r| r.radius_f64() == 5.0)
        .expect("R itself");
    assert_exact_root(whole);
    assert_eq!(whole.orientation(), Sign::Zero);
    assert_eq!(
        whole.to_apollonius().unwrap_err(),
        ApolloniusError::UndefinedTangentPoint
    );
}

proptest! {
    #[test]
    fn prop_roots_are_exact_and_valid(
        c in proptest::array::uniform3((-100.0f64..100.0, -100.0f64..100.0, 0.0f64..20.0)),
        b in proptest::bool::ANY,
    ) {
        let mut sites = c.map(|(x, y, r)| hole(x, y, r));
        if b {
            sites[0] = bounding(sites[0].center[0], sites[0].center[1], 300.0);
        }
        match apollonius_roots(&sites) {
            Ok(roots) => {
                prop_assert!(roots.len() <= 2);
                for r in &roots {
                    assert_exact_root(r);
                    prop_assert!(r.rho().sign(&r.d()) != Sign::Negative);
                    if let Ok(ap) = r.to_apollonius() {
                        assert_float_root(&ap);
                    }
                }
            }
            Err(e) => prop_assert_eq!(e, ApolloniusError::Continuum),
        }
    }
}
