//! Numbers as text for the writers: exactly the bytes `std::fmt` writes, several times faster
//! (issue 8: a 10 000-particle mesh puts about 60 million numbers into its `.vts` files, and
//! `write!` spent most of the writers' time in the formatting machinery).
//!
//! Each function appends to a byte buffer what `format!` gives for the same value:
//! - [`debug`]: `{:?}` of an `f64` (shortest round-trip digits; plain notation with at least
//!   one fractional digit for `1e-4 <= |x| < 1e16` and zero, exponent notation otherwise);
//! - [`exp`]: `{:e}` (shortest round-trip digits, always in exponent notation);
//! - [`fixed3`]: `{:.3}` (the exact binary value correctly rounded to three decimals, ties to
//!   even);
//! - [`int`]: `{}` of an integer.
//!
//! The shortest digits come from the `zmij` crate (the shortest digit string that reads back
//! to the value, and of those the closest to it). `std` picks the same digits except when the
//! value lies exactly halfway between the two closest shortest candidates: `zmij` then takes
//! the even one, `std` may not. Such a tie needs a value whose exact decimal expansion is one
//! digit longer than its shortest form (a dyadic rational with few digits, such as
//! `981446413237567.25`); `is_tie` detects it exactly and the value is then formatted by
//! `std` itself. Everything else is plain digit shuffling, tested against `std` on tens of
//! millions of values (`tests/perf_text_numbers.rs`).

use rayon::prelude::*;
use std::io::{self, Write};
use std::ops::Range;

/// Write the text of the items `0..n` to `w`: `f(range, out)` appends the text of the items
/// in `range` (a chunk of `chunk` items), the chunks are formatted on the rayon pool a few per
/// thread at a time (memory stays bounded) and written in order, so the bytes are those of
/// formatting every item in turn, for any number of threads.
pub fn write_chunked<W: Write + ?Sized>(
    w: &mut W,
    n: usize,
    chunk: usize,
    f: impl Fn(Range<usize>, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    // The chunks' buffers go back to a pool once written: the next waves format into memory
    // already touched and grown, not fresh pages grown by doubling (on a virtual machine
    // every fresh page costs a fault the host serves).
    let pool: std::sync::Mutex<Vec<Vec<u8>>> = std::sync::Mutex::new(Vec::new());
    let spare = || pool.lock().map(|mut p| p.pop()).ok().flatten();
    in_waves(
        n,
        chunk,
        |r| {
            let mut out = spare().unwrap_or_default();
            out.clear();
            f(r, &mut out);
            out
        },
        |_, text| {
            w.write_all(&text)?;
            if let Ok(mut p) = pool.lock() {
                p.push(text);
            }
            Ok(())
        },
    )
}

/// The items `0..n` in chunks of `chunk`: `make(range)` on the rayon pool, a few chunks per
/// thread at a time (memory stays bounded), then `take(range, made)` for each chunk in
/// order, so what `take` sees does not depend on the number of threads. The first error of
/// `take` stops it.
pub(crate) fn in_waves<T: Send>(
    n: usize,
    chunk: usize,
    make: impl Fn(Range<usize>) -> T + Sync,
    mut take: impl FnMut(Range<usize>, T) -> io::Result<()>,
) -> io::Result<()> {
    let chunk = chunk.max(1);
    let chunks = n.div_ceil(chunk);
    let wave = 4 * rayon::current_num_threads().max(1);
    let range = |c: usize| c * chunk..((c + 1) * chunk).min(n);
    let mut first = 0;
    while first < chunks {
        let last = (first + wave).min(chunks);
        let made: Vec<T> = (first..last)
            .into_par_iter()
            .map(|c| make(range(c)))
            .collect();
        for (c, m) in (first..last).zip(made) {
            take(range(c), m)?;
        }
        first = last;
    }
    Ok(())
}

/// The shortest round-trip digits of a finite `x > 0`: `n` significant digits in `d[..n]`
/// (no leading or trailing zero) and the decimal exponent `q` of the last one, so that
/// `x ~ d × 10^q`; `None` when `std` might choose other digits (a tie, see the module doc).
fn shortest(x: f64) -> Option<([u8; 20], usize, i32)> {
    let mut zb = zmij::Buffer::new();
    let s = zb.format_finite(x).as_bytes();
    let (mant, e) = match s.iter().position(|&c| c == b'e') {
        Some(k) => (&s[..k], parse_exponent(&s[k + 1..])?),
        None => (s, 0),
    };
    let mut d = [0u8; 20];
    let mut n = 0;
    let mut frac = 0i32;
    let mut after_dot = false;
    for &c in mant {
        match c {
            b'.' => after_dot = true,
            b'0'..=b'9' => {
                frac += i32::from(after_dot);
                // Leading zeros are not significant.
                if n == 0 && c == b'0' {
                    continue;
                }
                *d.get_mut(n)? = c;
                n += 1;
            }
            _ => return None,
        }
    }
    let mut q = e - frac;
    while n > 0 && d[n - 1] == b'0' {
        n -= 1;
        q += 1;
    }
    (n > 0 && !is_tie(x, q)).then_some((d, n, q))
}

/// The exponent after `e` in `zmij`'s output (`+16`, `-7`, `308`).
fn parse_exponent(s: &[u8]) -> Option<i32> {
    let (neg, digits) = match s.first()? {
        b'-' => (true, &s[1..]),
        b'+' => (false, &s[1..]),
        _ => (false, s),
    };
    let mut v: i32 = 0;
    for &c in digits {
        if !c.is_ascii_digit() {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(i32::from(c - b'0'))?;
    }
    Some(if neg { -v } else { v })
}

/// Whether the finite `x > 0` lies exactly halfway between two multiples of `10^q`, i.e.
/// whether `2 x / 10^q` is an odd integer. With `x = m 2^e` and `m` odd: for `q <= 0` that is
/// `m 5^(-q) 2^(e + 1 - q)`, an odd integer exactly when `e + 1 = q`; for `q > 0` it is
/// `m 2^(e + 1 - q) / 5^q`, an odd integer exactly when `e + 1 = q` and `5^q` divides `m`.
fn is_tie(x: f64, q: i32) -> bool {
    let (mut m, mut e) = integer_and_exponent(x);
    if m == 0 {
        return false;
    }
    let tz = m.trailing_zeros();
    m >>= tz;
    e += tz as i32;
    if e + 1 != q {
        return false;
    }
    if q <= 0 {
        return true;
    }
    // m < 2^53 < 5^23: a larger power of 5 cannot divide it.
    q < 23 && m.is_multiple_of(5u64.pow(q as u32))
}

/// Whether a finite `x > 0` of at least `1e-4` can be a tie at all (see [`is_tie`]): its
/// shortest digits end at `q >= -21` (at most 17 significant digits, the first at `10^-4` or
/// above), and a tie at `q` needs `x = m 2^(q - 1)` with `m` odd, so `x` must be a multiple of
/// `2^-22`. Mesh coordinates almost never are: they skip the digit parsing.
fn may_tie(x: f64) -> bool {
    let (m, e) = integer_and_exponent(x);
    // The exponent of the lowest set bit of x.
    e + m.trailing_zeros() as i32 >= -22
}

/// `|x| = m 2^e` with the integer `m < 2^53` and `e` as in the IEEE encoding (subnormals:
/// `e = -1074`).
fn integer_and_exponent(x: f64) -> (u64, i32) {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let m = bits & ((1u64 << 52) - 1);
    if biased == 0 {
        (m, -1074)
    } else {
        (m | (1u64 << 52), biased - 1075)
    }
}

/// Append `std`'s formatting of `x` (the rare cases this module does not do itself).
fn by_std(out: &mut Vec<u8>, args: std::fmt::Arguments) {
    // Writing into a `Vec` cannot fail.
    let _ = out.write_fmt(args);
}

/// Append `n` zeros.
fn zeros(out: &mut Vec<u8>, n: usize) {
    out.resize(out.len() + n, b'0');
}

/// Append the exponent-notation body `D[0].D[1..]eE` of the digits (`E = n + q - 1`).
fn exponent_body(out: &mut Vec<u8>, d: &[u8], q: i32) {
    out.push(d[0]);
    if d.len() > 1 {
        out.push(b'.');
        out.extend_from_slice(&d[1..]);
    }
    out.push(b'e');
    int(out, d.len() as i32 + q - 1);
}

/// `std`'s text of `x` for one of this module's formats (the cases it leaves to `std`).
type Fallback = fn(&mut Vec<u8>, f64);

/// The part [`debug`] and [`exp`] share: infinities and NaN by `fallback`, the sign, `zero` for
/// a zero; `Some(|x|)` for the rest (sign written).
fn sign_of_nonzero(out: &mut Vec<u8>, x: f64, zero: &[u8], fallback: Fallback) -> Option<f64> {
    if !x.is_finite() {
        fallback(out, x);
        return None;
    }
    if x.is_sign_negative() {
        out.push(b'-');
    }
    if x == 0.0 {
        out.extend_from_slice(zero);
        return None;
    }
    Some(x.abs())
}

/// [`shortest`] digits of `|x|` after [`sign_of_nonzero`] wrote the sign; on a tie the sign is
/// taken back and `fallback` writes the whole text.
fn digits_or_fallback(
    out: &mut Vec<u8>,
    x: f64,
    fallback: Fallback,
) -> Option<([u8; 20], usize, i32)> {
    let digits = shortest(x.abs());
    if digits.is_none() {
        out.truncate(out.len() - usize::from(x.is_sign_negative()));
        fallback(out, x);
    }
    digits
}

/// Append `format!("{x:?}")`.
pub fn debug(out: &mut Vec<u8>, x: f64) {
    let fallback: Fallback = |out, x| by_std(out, format_args!("{x:?}"));
    let Some(a) = sign_of_nonzero(out, x, b"0.0", fallback) else {
        return;
    };
    if (1e-4..1e16).contains(&a) && !may_tie(a) {
        // zmij writes this range as `std` does: plain notation, `.0` after an integer.
        let mut zb = zmij::Buffer::new();
        out.extend_from_slice(zb.format_finite(a).as_bytes());
        return;
    }
    let Some((d, n, q)) = digits_or_fallback(out, x, fallback) else {
        return;
    };
    let d = &d[..n];
    if !(1e-4..1e16).contains(&a) {
        return exponent_body(out, d, q);
    }
    // Plain notation, at least one fractional digit: `point` digits before the point.
    let point = n as i32 + q;
    if point <= 0 {
        out.extend_from_slice(b"0.");
        zeros(out, (-point) as usize);
        out.extend_from_slice(d);
    } else if point as usize >= n {
        out.extend_from_slice(d);
        zeros(out, point as usize - n);
        out.extend_from_slice(b".0");
    } else {
        let (int_part, frac) = d.split_at(point as usize);
        out.extend_from_slice(int_part);
        out.push(b'.');
        out.extend_from_slice(frac);
    }
}

/// Append `format!("{x:e}")`.
pub fn exp(out: &mut Vec<u8>, x: f64) {
    let fallback: Fallback = |out, x| by_std(out, format_args!("{x:e}"));
    if sign_of_nonzero(out, x, b"0e0", fallback).is_none() {
        return;
    }
    if let Some((d, n, q)) = digits_or_fallback(out, x, fallback) {
        exponent_body(out, &d[..n], q);
    }
}

/// Append `format!("{x:.3}")`: `round(|x| 1000)` computed exactly from `x = m 2^e` (ties to
/// even, as `std`), with `std`'s sign rule (a minus for every negative number, `-0.0` and
/// values that round to zero included). Values of `1e15` and more, infinities and NaN are
/// left to `std`.
pub fn fixed3(out: &mut Vec<u8>, x: f64) {
    if x.is_nan() || x.abs() >= 1e15 {
        return by_std(out, format_args!("{x:.3}"));
    }
    let (m, e) = integer_and_exponent(x);
    // |x| < 1e15 < 2^50: m 2^e < 2^50, so e < 50 and m 1000 2^e < 2^60.
    let p = u128::from(m) * 1000;
    let scaled: u128 = if e >= 0 {
        p << e
    } else {
        let s = (-e) as u32;
        if s >= 100 {
            // p < 2^63 < 2^(s - 1): below half a unit, rounds to 0.
            0
        } else {
            let q = p >> s;
            let r = p - (q << s);
            let half = 1u128 << (s - 1);
            q + u128::from(r > half || (r == half && q & 1 == 1))
        }
    };
    if x.is_sign_negative() {
        out.push(b'-');
    }
    int(out, (scaled / 1000) as u64);
    let f = (scaled % 1000) as u16;
    out.extend_from_slice(&[
        b'.',
        b'0' + (f / 100) as u8,
        b'0' + (f / 10 % 10) as u8,
        b'0' + (f % 10) as u8,
    ]);
}

/// Append `format!("{v}")` of an integer.
pub fn int<I: itoa::Integer>(out: &mut Vec<u8>, v: I) {
    out.extend_from_slice(itoa::Buffer::new().format(v).as_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;

    fn same(x: f64) {
        let mut b = Vec::new();
        debug(&mut b, x);
        assert_eq!(
            String::from_utf8(b).unwrap(),
            format!("{x:?}"),
            "debug {x:e}"
        );
        let mut b = Vec::new();
        exp(&mut b, x);
        assert_eq!(String::from_utf8(b).unwrap(), format!("{x:e}"), "exp {x:e}");
        let mut b = Vec::new();
        fixed3(&mut b, x);
        assert_eq!(
            String::from_utf8(b).unwrap(),
            format!("{x:.3}"),
            "fixed3 {x:e}"
        );
    }

    #[test]
    fn special_values_and_notation_boundaries_are_std_s() {
        for x in [
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1.0,
            -1.0,
            0.1,
            1e-4,
            1e16,
            f64::from_bits(1e16f64.to_bits() - 1),
            1e-5,
            9.99e-5,
            1e15,
            1e-7,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            0.0625,
            2.0625,
            0.0005,
            -0.0001,
            999.9995,
            981446413237567.0 + 0.25,
            123456.789,
        ] {
            same(x);
            same(-x);
            same(f64::from_bits(x.to_bits().wrapping_add(1)));
            same(f64::from_bits(x.to_bits().wrapping_sub(1)));
        }
    }

    #[test]
    fn ties_are_detected_exactly() {
        // 0.25 × 10^0 and 0.5 × 10^0 sit halfway between one-digit decimals at q = -1: 2.5 is
        // a tie at q = 0 (between 2 and 3), 0.25 at q = -1, 1e15 + 0.5 at q = 0.
        assert!(is_tie(2.5, 0));
        assert!(is_tie(0.25, -1));
        assert!(is_tie(1e15 + 0.5, 0));
        assert!(is_tie(25.0, 1)); // between 20 and 30
        assert!(!is_tie(2.5, -1));
        assert!(!is_tie(0.1, -2));
        assert!(!is_tie(35.0, 0));
    }
}
