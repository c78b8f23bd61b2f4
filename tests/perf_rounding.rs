//! The filtered correctly rounded division of the Apollonius solve (issue #8):
//! `round_scaled` (top-64-bit `u128` bracket, exact division only when undecided) against
//! `round_scaled_exact` (exact integer division) bit for bit, on random sizes, exact rounding
//! midpoints and values an ulp away from them, the subnormal/overflow edges, and under
//! proptest; the filter must decide most random inputs (it is not dead code). `dyadic` (read
//! from the `f64` bits) against `Rational::from_f64`. Set `MB_ROUNDING_MANY=1` for 2 million
//! random cases instead of 20 000.

use medial_blocks::apollonius::exact::{
    dyadic, dyadic_reference, round_scaled, round_scaled_exact, round_scaled_filter,
};
use medial_blocks::layouts::SplitMix64;
use proptest::prelude::*;
use rug::Integer;

fn random_int(rng: &mut SplitMix64, max_limbs: u64) -> Integer {
    let limbs = 1 + rng.next_u64() % max_limbs;
    let mut v = Integer::new();
    for _ in 0..limbs {
        v <<= 64u32;
        v += rng.next_u64();
    }
    // Random bit length within the top limb, sometimes sparse (long runs of zeros).
    v >>= (rng.next_u64() % 64) as u32;
    if rng.next_u64().is_multiple_of(8) {
        v = (v >> 100u32 << 100u32) + 1u32;
    }
    v
}

fn same(num: &Integer, den: &Integer, exp: i64) -> bool {
    let fast = round_scaled(num, den, exp);
    let exact = round_scaled_exact(num, den, exp);
    assert_eq!(fast.to_bits(), exact.to_bits(), "{num} / {den} * 2^{exp}");
    if let Some(f) = round_scaled_filter(num, den, exp) {
        assert_eq!(
            f.to_bits(),
            exact.to_bits(),
            "filter {num} / {den} * 2^{exp}"
        );
        true
    } else {
        false
    }
}

#[test]
fn random_quotients_round_like_the_exact_division() {
    let n = if std::env::var_os("MB_ROUNDING_MANY").is_some() {
        2_000_000
    } else {
        20_000
    };
    let mut rng = SplitMix64(17);
    let mut decided = 0;
    for _ in 0..n {
        let mut num = random_int(&mut rng, 6);
        let den = random_int(&mut rng, 6) + 1u32;
        if rng.next_u64().is_multiple_of(2) {
            num = -num;
        }
        let exp = (rng.next_u64() % 400) as i64 - 200;
        decided += usize::from(same(&num, &den, exp));
    }
    assert!(
        decided * 100 > n * 95,
        "the filter decided {decided} of {n}"
    );
}

#[test]
fn midpoints_and_their_neighbours_agree() {
    let mut rng = SplitMix64(23);
    for _ in 0..5000 {
        // m + 1/2 for a 53-bit m: an exact midpoint; scaled by a common factor, and nudged by
        // one part in den either way.
        let m = (rng.next_u64() >> 11) | (1 << 52);
        let k = random_int(&mut rng, 3) + 1u32;
        let mid = Integer::from(2 * m + 1) * &k;
        let den = Integer::from(&k << 1u32);
        let exp = (rng.next_u64() % 100) as i64 - 50;
        for delta in [-1i32, 0, 1] {
            let num = Integer::from(&mid << 64u32) + delta;
            let den = Integer::from(&den << 64u32);
            same(&num, &den, exp);
        }
        // Exactly representable values are decided.
        let num = Integer::from(m) * &k;
        assert!(same(&num, &k, exp));
    }
}

#[test]
fn range_edges() {
    let one = Integer::from(1);
    for exp in [
        -1200i64, -1100, -1075, -1074, -1030, -1023, -1022, -1000, 900, 1000, 1023, 1024,
    ] {
        for num in [
            Integer::from(1),
            Integer::from(3),
            Integer::from(u64::MAX),
            Integer::from(1) << 200u32,
        ] {
            same(&num, &one, exp - num.significant_bits() as i64);
            same(&num, &Integer::from(7), exp);
        }
    }
    assert_eq!(round_scaled(&Integer::new(), &one, 5), 0.0);
}

#[test]
fn dyadic_matches_the_reduced_rational() {
    let mut rng = SplitMix64(31);
    let mut vals = vec![
        0.0,
        -0.0,
        1.0,
        -3.0,
        0.5,
        f64::MIN_POSITIVE,
        f64::from_bits(1),
        f64::MAX,
        -f64::MAX,
        1e300,
        2f64.powi(60),
    ];
    for _ in 0..20_000 {
        vals.push(f64::from_bits(rng.next_u64()));
    }
    for v in vals {
        assert_eq!(dyadic(v), dyadic_reference(v), "{v:e}");
    }
    assert_eq!(dyadic(f64::NAN), None);
    assert_eq!(dyadic(f64::INFINITY), None);
}

proptest! {
    #[test]
    fn prop_round_scaled(a in any::<u128>(), b in 1u128.., s in 0u32..300, exp in -1100i64..1100) {
        let num = Integer::from(a) << s;
        same(&num, &Integer::from(b), exp);
        same(&Integer::from(b), &num.clone().max(Integer::from(1)), exp);
    }
}

/// `ZSqrt::sign` (interval filter first) against the exact comparison of squares, on random
/// mixed-sign values and on near-cancelling ones (`a = -round(b sqrt(D))` +- small), with a
/// count that the filter decides the random ones.
#[test]
fn zsqrt_sign_filter_matches_the_squares() {
    use medial_blocks::apollonius::exact::ZSqrt;
    let mut rng = SplitMix64(53);
    let (mut decided, n) = (0usize, 20_000usize);
    for case in 0..n {
        let d = random_int(&mut rng, 4) + 2u32;
        let b = random_int(&mut rng, 4) + 1u32;
        let a = if case % 2 == 0 {
            -random_int(&mut rng, 6)
        } else {
            // -floor(b sqrt(D)) + small: cancels to the last bits.
            let mut t = Integer::from(&b * &b) * &d;
            t.sqrt_mut();
            -t + (rng.next_u64() % 5) as i32 - 2
        };
        for z in [ZSqrt::new(a.clone(), b.clone()), ZSqrt::new(-a, -b)] {
            assert_eq!(z.sign(&d), z.sign_exact(&d), "{z:?} {d}");
            if let Some(s) = z.sign_filter(&d) {
                assert_eq!(s, z.sign_exact(&d), "{z:?} {d}");
                decided += usize::from(case % 2 == 0);
            }
        }
    }
    assert!(decided * 10 > n * 9, "{decided} of {n}");
}
