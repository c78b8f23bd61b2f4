//! `Q(sqrt D)` arithmetic and the correctly rounded conversions, against IEEE arithmetic (whose
//! division and square root are correctly rounded, so they are independent oracles).

use medial_blocks::apollonius::exact::{eq_across, round_rational, sqrt_bounds};
use medial_blocks::apollonius::{QSqrt, Sign};
use proptest::prelude::*;
use rug::{Integer, Rational};

fn q(v: f64) -> Rational {
    Rational::from_f64(v).unwrap()
}

fn qs(a: f64, b: f64) -> QSqrt {
    QSqrt::new(q(a), q(b))
}

#[test]
fn sign_cases() {
    let d = Rational::from(2);
    assert_eq!(qs(0.0, 0.0).sign(&d), Sign::Zero);
    assert_eq!(qs(1.0, 1.0).sign(&d), Sign::Positive);
    assert_eq!(qs(-1.0, -1.0).sign(&d), Sign::Negative);
    assert_eq!(qs(1.5, -1.0).sign(&d), Sign::Positive); // 1.5 > 1.414
    assert_eq!(qs(1.4, -1.0).sign(&d), Sign::Negative);
    assert_eq!(qs(-1.5, 1.0).sign(&d), Sign::Negative);
    assert_eq!(qs(0.0, -3.0).sign(&d), Sign::Negative);
    // D a square: 3 - 1 * sqrt(9) = 0.
    assert_eq!(qs(3.0, -1.0).sign(&Rational::from(9)), Sign::Zero);
    // D = 0: only a counts.
    assert_eq!(qs(-1.0, 5.0).sign(&Rational::new()), Sign::Negative);
}

#[test]
fn mul_inv_norm() {
    let d = Rational::from(3);
    let x = qs(2.0, 1.0); // 2 + sqrt3
    let y = qs(2.0, -1.0);
    let p = x.mul(&y, &d);
    assert_eq!(p, QSqrt::rational(Rational::from(1)));
    assert_eq!(x.norm(&d), Rational::from(1));
    assert_eq!(x.inv(&d).unwrap(), y);
    assert_eq!(x.square(&d), x.mul(&x, &d));
    assert!(QSqrt::default().inv(&d).is_none());
}

#[test]
fn round_rational_edges() {
    assert_eq!(round_rational(&Rational::new()), 0.0);
    assert_eq!(round_rational(&q(f64::MAX)), f64::MAX);
    assert_eq!(round_rational(&q(-f64::MIN_POSITIVE)), -f64::MIN_POSITIVE);
    let tiny = f64::from_bits(1);
    assert_eq!(round_rational(&q(tiny)), tiny);
    assert_eq!(round_rational(&(q(tiny) / 2u32)), 0.0); // tie to even (0)
    assert_eq!(round_rational(&(q(tiny) * 3u32 / 2u32)), 2.0 * tiny); // tie to even
    assert_eq!(round_rational(&(q(f64::MAX) * 2u32)), f64::INFINITY);
    // MAX + half an ulp rounds to even, i.e. up to infinity; a bit less stays at MAX.
    let half_ulp = Rational::from(Integer::from(1) << 970u32);
    assert_eq!(round_rational(&(q(f64::MAX) + &half_ulp)), f64::INFINITY);
    assert_eq!(round_rational(&(q(f64::MAX) + half_ulp / 2u32)), f64::MAX);
    // 1 + 2^-53 is a tie between 1 and 1 + 2^-52: even is 1.
    let t = Rational::from(1) + Rational::from((1, Integer::from(1) << 53u32));
    assert_eq!(round_rational(&t), 1.0);
    let t = Rational::from(1) + Rational::from((3, Integer::from(1) << 54u32));
    assert_eq!(round_rational(&t), 1.0 + f64::EPSILON);
}

#[test]
fn sqrt_bounds_bracket() {
    for v in [2.0, 0.5, 1e-300, 1e300, 12345.678, 9.0] {
        let d = q(v);
        let (lo, hi) = sqrt_bounds(&d, 80);
        assert!(Rational::from(lo.square_ref()) <= d);
        assert!(Rational::from(hi.square_ref()) >= d);
        let w = Rational::from(&hi - &lo) / &lo;
        assert!(w < Rational::from((1, Integer::from(1) << 78u32)));
    }
    assert_eq!(sqrt_bounds(&q(9.0), 60).0, Rational::from(3));
}

#[test]
fn eq_across_fields() {
    // sqrt(8) = 2 sqrt(2); 1 + sqrt(2) != 1 + sqrt(3); -sqrt(2) != sqrt(2).
    let d2 = Rational::from(2);
    let d8 = Rational::from(8);
    let d3 = Rational::from(3);
    assert!(eq_across(&qs(1.0, 2.0), &d2, &qs(1.0, 1.0), &d8));
    assert!(!eq_across(&qs(1.0, 1.0), &d2, &qs(1.0, 1.0), &d3));
    assert!(!eq_across(&qs(0.0, -1.0), &d2, &qs(0.0, 1.0), &d2));
    // 3 + 0 sqrt(5) == 0 + 1 sqrt(9) (a rational in disguise).
    assert!(eq_across(
        &qs(3.0, 0.0),
        &Rational::from(5),
        &qs(0.0, 1.0),
        &Rational::from(9)
    ));
    // (1 + sqrt 2)^2 = 3 + 2 sqrt 2 = 3 + sqrt 8.
    assert!(eq_across(&qs(3.0, 2.0), &d2, &qs(3.0, 1.0), &d8));
    assert!(!eq_across(
        &qs(3.0, 2.0),
        &d2,
        &qs(3.0, 1.0),
        &Rational::from(7)
    ));
}

proptest! {
    /// (a / b) in IEEE double is correctly rounded; so must round_rational(a / b) be.
    #[test]
    fn round_matches_ieee_division(a in -(1i64 << 53)..(1i64 << 53), b in 1i64..(1i64 << 53),
                                   e in -1100i32..1100) {
        let exact = Rational::from((a, b));
        prop_assert_eq!(round_rational(&exact), a as f64 / b as f64);
        // Scaled by a power of two (exact in f64 while the result stays normal).
        let scaled = exact << e;
        let f = (a as f64 / b as f64) * 2f64.powi(e);
        if f.abs() >= f64::MIN_POSITIVE && f.is_finite() {
            prop_assert_eq!(round_rational(&scaled), f);
        }
    }

    /// to_f64 of sqrt(D) matches IEEE sqrt (correctly rounded), and a + b sqrt(D) for
    /// integer a, b small enough that IEEE's single rounding of b*sqrt(D) is exact-ish is
    /// within one ulp.
    #[test]
    fn sqrt_to_f64_matches_ieee(v in 1e-200f64..1e200, a in -1000i32..1000, b in 1i32..1000) {
        let d = q(v);
        prop_assert_eq!(QSqrt::new(Rational::new(), Rational::from(1)).to_f64(&d), v.sqrt());
        let x = QSqrt::new(Rational::from(a), Rational::from(b)).to_f64(&d);
        let approx = a as f64 + b as f64 * v.sqrt();
        prop_assert!((x - approx).abs() <= 4.0 * f64::EPSILON * (a.abs() as f64 + b as f64 * v.sqrt()));
    }

    /// Sign of a + b sqrt(D) against a naive evaluation where the latter is clear.
    #[test]
    fn sign_matches_float(a in -1e6f64..1e6, b in -1e6f64..1e6, v in 0.0f64..1e6) {
        let d = q(v);
        let s = qs(a, b).sign(&d);
        let f = a + b * v.sqrt();
        if f.abs() > 1e-6 * (a.abs() + b.abs() * v.sqrt()) {
            prop_assert_eq!(s, Sign::of_f64(f));
        }
    }
}
