//! The writers' number formatting (`medial_blocks::output::text`) against `std::fmt` itself,
//! the independent oracle: `{:?}`, `{:e}` and `{:.3}` of the same `f64`, byte for byte, on
//! random bit patterns, short dyadic rationals (where shortest-digit ties live), integers,
//! mesh-like coordinates, three-decimal ties and the notation boundaries. Set
//! `MEDIAL_TEXT_SAMPLES` for a longer run (default 100 000 per family).

use medial_blocks::output::text;

fn samples() -> usize {
    std::env::var("MEDIAL_TEXT_SAMPLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000)
}

/// xorshift64*: a fixed sequence, no dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
}

fn check(x: f64, buf: &mut Vec<u8>) {
    for (name, f, want) in [
        (
            "{:?}",
            text::debug as fn(&mut Vec<u8>, f64),
            format!("{x:?}"),
        ),
        ("{:e}", text::exp, format!("{x:e}")),
        ("{:.3}", text::fixed3, format!("{x:.3}")),
    ] {
        buf.clear();
        f(buf, x);
        assert_eq!(
            std::str::from_utf8(buf).unwrap(),
            want,
            "{name} of {x:e} (bits {:#x})",
            x.to_bits()
        );
    }
}

#[test]
fn random_bit_patterns_format_as_std() {
    let mut r = Rng(0x9E37_79B9_7F4A_7C15);
    let mut buf = Vec::new();
    for _ in 0..samples() {
        check(f64::from_bits(r.next()), &mut buf);
    }
}

/// Whether `x`'s exact decimal expansion is its shortest form plus one digit, a 5: the two
/// closest shortest candidates are then equally close (found with `std`'s exact mode).
fn is_tie(x: f64) -> bool {
    if x == 0.0 || !x.is_finite() {
        return false;
    }
    let short = format!("{:e}", x.abs());
    let n = short.split('e').next().unwrap().replace('.', "").len();
    let longer = format!("{:.*e}", n, x.abs());
    longer.parse::<f64>() == Ok(x.abs()) && longer.split('e').next().unwrap().ends_with('5')
}

#[test]
fn short_dyadics_and_integers_format_as_std() {
    // k / 2^j has a short exact decimal expansion: the values where the two closest
    // shortest candidates can tie, and where `{:.3}` meets exact halves.
    let mut r = Rng(7);
    let mut buf = Vec::new();
    let mut ties = 0;
    for _ in 0..samples() {
        let v = r.next();
        let k = (v >> 11) as i64 >> (v % 40);
        let j = (v >> 3) % 64;
        let x = k as f64 / (1u64 << j) as f64;
        check(x, &mut buf);
        check((v >> 11) as f64, &mut buf);
        check((v >> 30) as f64 / 2000.0, &mut buf);
        // Exact three-decimal ties: n + d/1000 + 1/2000 with a power-of-two denominator.
        let t = (v >> 20) as f64 / 16.0 + 0.0625;
        check(t, &mut buf);
        ties += usize::from(is_tie(x));
    }
    assert!(ties > 100, "the family holds shortest-digit ties ({ties})");
}

#[test]
fn mesh_like_coordinates_and_boundaries_format_as_std() {
    let mut r = Rng(0xDEAD_BEEF);
    let mut buf = Vec::new();
    for _ in 0..samples() {
        let v = r.next();
        let u = (v >> 11) as f64 / (1u64 << 53) as f64;
        for scale in [1e-6, 1e-4, 1.0, 100.0, 1e6, 1e15, 1e16, 1e300] {
            check((u - 0.5) * scale, &mut buf);
        }
    }
    // The neighbours of every power of ten: the notation switches at 1e-4 and 1e16.
    for p in -320..=308 {
        let x: f64 = format!("1e{p}").parse().unwrap();
        for d in -3i64..=3 {
            let y = f64::from_bits((x.to_bits() as i64 + d) as u64);
            check(y, &mut buf);
            check(-y, &mut buf);
        }
    }
}
