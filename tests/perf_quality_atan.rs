//! `quality::angle_deg`, the corner angle of the quality figures (issue #8: an `atan2` written
//! in the crate, cheap enough to vectorise), against libm's `atan2(y, x).to_degrees()` taken in
//! `[0, 360)`, the formula it replaced: within 4 ulp of the result on millions of random inputs
//! and on hard ones (axes, signed zeros, tiny and huge ratios, every quadrant, near 45 degrees
//! and the reduction thresholds, subnormals, infinities, NaN).

use medial_blocks::layouts::SplitMix64;
use medial_blocks::quality::angle_deg;

/// The replaced formula (libm's `atan2` in degrees, in `[0, 360)`).
pub(crate) fn libm_deg(y: f64, x: f64) -> f64 {
    let a = y.atan2(x).to_degrees();
    if a < 0.0 {
        a + 360.0
    } else {
        a
    }
}

/// Distance in ulps between two non-negative results (0 when equal, `-0.0 == 0.0`).
fn ulps(a: f64, b: f64) -> u64 {
    if a == b {
        0
    } else {
        a.to_bits().abs_diff(b.to_bits())
    }
}

/// The documented bound against libm (the measured maximum is 2).
const MAX_ULPS: u64 = 4;

fn check(y: f64, x: f64, worst: &mut u64) {
    let (got, want) = (angle_deg(y, x), libm_deg(y, x));
    if want.is_nan() {
        assert!(got.is_nan(), "({y:e}, {x:e}): {got} vs NaN");
        return;
    }
    assert!((0.0..=360.0).contains(&got), "({y:e}, {x:e}): {got}");
    // For y < 0 far smaller than x the angle is 360 - (something that underflows): libm's
    // formula then gives -0.0 (atan2 underflowed to -0) or 360, this function 360 or 0: the
    // same direction.
    let full = |a: f64| a == 0.0 || a == 360.0;
    if full(got) && full(want) {
        return;
    }
    let d = ulps(got, want);
    assert!(
        d <= MAX_ULPS,
        "({y:e}, {x:e}): {got:e} vs libm {want:e}, {d} ulp"
    );
    *worst = (*worst).max(d);
}

#[test]
fn random_inputs_are_within_the_bound() {
    let mut r = SplitMix64(0x5eed);
    let mut worst = 0;
    for i in 0..3_000_000u32 {
        let (y, x) = match i % 4 {
            // Unit square, every quadrant.
            0 => (2.0 * r.next_f64() - 1.0, 2.0 * r.next_f64() - 1.0),
            // Uniform angles.
            1 => {
                let a = std::f64::consts::TAU * r.next_f64();
                (a.sin(), a.cos())
            }
            // Wide exponents.
            2 => {
                let e = |r: &mut SplitMix64| 10f64.powf(600.0 * r.next_f64() - 300.0);
                let s = |r: &mut SplitMix64| if r.next_u64() & 1 == 0 { 1.0 } else { -1.0 };
                (s(&mut r) * e(&mut r), s(&mut r) * e(&mut r))
            }
            // Random bit patterns of finite doubles (any exponent, subnormals included).
            _ => {
                let mut f = || loop {
                    let v = f64::from_bits(r.next_u64());
                    if v.is_finite() {
                        break v;
                    }
                };
                (f(), f())
            }
        };
        check(y, x, &mut worst);
    }
    println!("worst {worst} ulp");
}

#[test]
fn hard_inputs_are_within_the_bound() {
    let mut worst = 0;
    let t8 = (std::f64::consts::PI / 8.0).tan();
    let mut r = SplitMix64(7);
    for _ in 0..20_000 {
        let x = 0.5 + r.next_f64();
        // Near the diagonals and the reduction thresholds tan(π/8), 1/tan(π/8), a few ulps
        // either side, in every quadrant.
        for ratio in [1.0, t8, 1.0 / t8, 0.5, 2.0] {
            let y0 = x * ratio;
            for k in -4i64..=4 {
                let y = f64::from_bits((y0.to_bits() as i64 + k) as u64);
                for (sy, sx) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    check(sy * y, sx * x, &mut worst);
                    check(sx * x, sy * y, &mut worst);
                }
            }
        }
    }
    let specials = [
        0.0,
        -0.0,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        5e-324,
        -5e-324,
        1e-300,
        1e300,
        f64::MAX,
        -f64::MAX,
        1.0,
        -1.0,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
    ];
    for y in specials {
        for x in specials {
            let (got, want) = (angle_deg(y, x), libm_deg(y, x));
            if y == 0.0 && x == 0.0 {
                // Zeros count as +0 (the documented difference from libm).
                assert_eq!(got.to_bits(), 0, "({y}, {x})");
                continue;
            }
            if y == 0.0 && x > 0.0 {
                // libm gives -0.0 for y = -0.0; this function +0.0.
                assert_eq!(got.to_bits(), 0, "({y}, {x})");
                continue;
            }
            if y == 0.0 && x < 0.0 {
                assert_eq!(got, 180.0, "({y}, {x})");
                continue;
            }
            if want.is_nan() {
                assert!(got.is_nan(), "({y}, {x}): {got}");
                continue;
            }
            check(y, x, &mut worst);
        }
    }
    println!("worst {worst} ulp");
}

/// Exact at the axes and diagonals; and an angle does not depend on the sign of a zero.
#[test]
fn exact_values_and_signed_zeros() {
    for s in [1e-200, 0.25, 1.0, 3.0, 1e200] {
        assert_eq!(angle_deg(0.0, s), 0.0);
        assert_eq!(angle_deg(s, s), 45.0);
        assert_eq!(angle_deg(s, 0.0), 90.0);
        assert_eq!(angle_deg(s, -s), 135.0);
        assert_eq!(angle_deg(0.0, -s), 180.0);
        assert_eq!(angle_deg(-s, -s), 225.0);
        assert_eq!(angle_deg(-s, 0.0), 270.0);
        assert_eq!(angle_deg(-s, s), 315.0);
        for (y, x) in [(0.0, s), (0.0, -s)] {
            assert_eq!(angle_deg(y, x).to_bits(), angle_deg(-y, x).to_bits());
        }
        for (y, x) in [(s, 0.0), (-s, 0.0)] {
            assert_eq!(angle_deg(y, x).to_bits(), angle_deg(y, -x).to_bits());
        }
    }
}

/// Monotone along the unit circle, in steps of a few ulps of the angle (the bins of the
/// histograms do not rely on it; a sanity check of the reduction's joins).
#[test]
fn monotone_across_the_octant_joins() {
    let t8 = (std::f64::consts::PI / 8.0).tan();
    for ratio in [t8, 1.0, 1.0 / t8] {
        let mut prev = f64::NEG_INFINITY;
        let y0 = ratio.to_bits() as i64;
        for k in -2000i64..=2000 {
            let y = f64::from_bits((y0 + k) as u64);
            let a = angle_deg(y, 1.0);
            assert!(a >= prev, "ratio {ratio}: {a} after {prev}");
            prev = a;
        }
    }
}
