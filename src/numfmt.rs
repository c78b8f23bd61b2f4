//! Numbers in messages: every float an error message shows goes through [`Num`], so `1e300`
//! reads `1e300`, not a 301-digit integer, and `0.5` reads `0.5`, not `5e-1`.

use std::fmt;

/// A float printed readably: the shortest decimal that reads back as the same `f64` (so two
/// different values never print alike), in plain form when `1e-4 <= |x| < 1e6` (`0.5`,
/// `123456.7`) and in exponent form otherwise (`1e300`, `-2.5e-7`, `5e-324`). Zero prints `0`
/// (also `-0.0`), NaN `NaN`, the infinities `inf` and `-inf`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Num(pub f64);

impl Num {
    /// Below this magnitude (and from [`Num::LARGE`] on) the exponent form is used.
    pub const SMALL: f64 = 1e-4;
    /// From this magnitude on the exponent form is used.
    pub const LARGE: f64 = 1e6;
}

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x == 0.0 {
            f.write_str("0")
        } else if !x.is_finite() || (Self::SMALL..Self::LARGE).contains(&x.abs()) {
            // Rust's `Display` for f64 is the shortest round trip; "NaN", "inf", "-inf".
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// A point `(x, y)` with both coordinates as [`Num`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NumPair(pub [f64; 2]);

impl fmt::Display for NumPair {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {})", Num(self.0[0]), Num(self.0[1]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn readable_forms() {
        let cases: [(f64, &str); 16] = [
            (0.0, "0"),
            (-0.0, "0"),
            (0.5, "0.5"),
            (-0.5, "-0.5"),
            (1.0, "1"),
            (123456.7, "123456.7"),
            (999999.0, "999999"),
            (1e6, "1e6"),
            (1.0000001e6, "1.0000001e6"),
            (1e300, "1e300"),
            (1e-4, "0.0001"),
            (9.9e-5, "9.9e-5"),
            (-2e-301, "-2e-301"),
            (5e-324, "5e-324"),
            (f64::INFINITY, "inf"),
            (f64::NAN, "NaN"),
        ];
        for (x, want) in cases {
            assert_eq!(Num(x).to_string(), want, "{x:?}");
        }
        assert_eq!(Num(f64::NEG_INFINITY).to_string(), "-inf");
        assert_eq!(NumPair([1e300, -0.25]).to_string(), "(1e300, -0.25)");
    }

    /// Every printed number reads back as the same double (shortest round trip, both forms),
    /// and none is longer than 24 characters.
    #[test]
    fn round_trips_and_stays_short() {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..20_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let x = f64::from_bits(s);
            if !x.is_finite() {
                continue;
            }
            let t = Num(x).to_string();
            assert!(t.len() <= 24, "{t}");
            let back: f64 = t.parse().unwrap();
            assert!(back == x, "{x:?} printed {t}");
        }
    }
}
