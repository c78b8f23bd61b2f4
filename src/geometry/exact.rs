//! Exact evaluation of the planar predicates with `rug` integers.
//!
//! Every finite `f64` is a dyadic rational `m * 2^e` with `m` an integer. Predicates are
//! homogeneous polynomials in coordinate differences, so multiplying every coordinate of one
//! call by the same power of two does not change the sign: we shift all coordinates of a call
//! to integers at the smallest exponent present and evaluate the determinant in `Integer`.
//! This is slow but exact for every finite input, including huge and subnormal magnitudes.

use super::Point;
use rug::Integer;
use std::cmp::Ordering;

/// `x = m * 2^e` with `m` odd (or `(0, 0)` for zero). `x` must be finite.
pub(crate) fn decompose(x: f64) -> (i64, i32) {
    let bits = x.to_bits();
    let negative = bits >> 63 == 1;
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1u64 << 52) - 1);
    let (mut m, mut e) = if biased == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1u64 << 52), biased - 1075)
    };
    if m == 0 {
        return (0, 0);
    }
    let tz = m.trailing_zeros();
    m >>= tz;
    e += tz as i32;
    // m < 2^53, so it fits an i64 with its sign.
    let m = m as i64;
    (if negative { -m } else { m }, e)
}

/// The coordinates as integers, all scaled by the same power of two.
fn to_integers<const N: usize>(coords: [f64; N]) -> [Integer; N] {
    let parts = coords.map(decompose);
    let emin = parts
        .iter()
        .filter(|(m, _)| *m != 0)
        .map(|&(_, e)| e)
        .min()
        .unwrap_or(0);
    parts.map(|(m, e)| Integer::from(m) << (e - emin) as u32)
}

fn sign(x: &Integer) -> Ordering {
    x.cmp0()
}

/// Exact orientation: `Greater` when `a, b, c` turn counter-clockwise.
/// All coordinates must be finite.
pub fn orient2d_exact(a: Point, b: Point, c: Point) -> Ordering {
    let [ax, ay, bx, by, cx, cy] = to_integers([a[0], a[1], b[0], b[1], c[0], c[1]]);
    let l = Integer::from(&bx - &ax) * Integer::from(&cy - &ay);
    let r = Integer::from(&by - &ay) * Integer::from(&cx - &ax);
    sign(&(l - r))
}

/// Exact in-circle test: `Greater` when `d` is strictly inside the circle through `a, b, c`
/// (taken counter-clockwise), `Equal` when the four points are co-circular.
/// All coordinates must be finite.
pub fn incircle_exact(a: Point, b: Point, c: Point, d: Point) -> Ordering {
    let [ax, ay, bx, by, cx, cy, dx, dy] =
        to_integers([a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]]);
    let adx = Integer::from(&ax - &dx);
    let ady = Integer::from(&ay - &dy);
    let bdx = Integer::from(&bx - &dx);
    let bdy = Integer::from(&by - &dy);
    let cdx = Integer::from(&cx - &dx);
    let cdy = Integer::from(&cy - &dy);
    let alift = Integer::from(adx.square_ref()) + Integer::from(ady.square_ref());
    let blift = Integer::from(bdx.square_ref()) + Integer::from(bdy.square_ref());
    let clift = Integer::from(cdx.square_ref()) + Integer::from(cdy.square_ref());
    let ab = Integer::from(&adx * &bdy) - Integer::from(&bdx * &ady);
    let bc = Integer::from(&bdx * &cdy) - Integer::from(&cdx * &bdy);
    let ca = Integer::from(&cdx * &ady) - Integer::from(&adx * &cdy);
    let det = alift * bc + blift * ca + clift * ab;
    sign(&det)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decompose_roundtrip() {
        for x in [1.0, -3.5, 0.1, 1e300, -5e-324, f64::MIN_POSITIVE, f64::MAX] {
            let (m, e) = decompose(x);
            assert!(m % 2 != 0);
            let back =
                (m as f64) * 2f64.powi(e.clamp(-1000, 1000)) * 2f64.powi(e - e.clamp(-1000, 1000));
            assert_eq!(back, x);
        }
        assert_eq!(decompose(0.0), (0, 0));
        assert_eq!(decompose(-0.0), (0, 0));
    }

    #[test]
    fn simple_signs() {
        assert_eq!(
            orient2d_exact([0.0, 0.0], [1.0, 0.0], [0.0, 1.0]),
            Ordering::Greater
        );
        assert_eq!(
            orient2d_exact([0.0, 0.0], [1.0, 1.0], [2.0, 2.0]),
            Ordering::Equal
        );
        let (a, b, c) = ([1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]);
        assert_eq!(incircle_exact(a, b, c, [0.0, 0.0]), Ordering::Greater);
        assert_eq!(incircle_exact(a, b, c, [0.0, -1.0]), Ordering::Equal);
        assert_eq!(incircle_exact(a, b, c, [0.0, -2.0]), Ordering::Less);
        assert_eq!(
            incircle_exact([1e300, 0.0], [0.0, 1e300], [-1e300, 0.0], [0.0, 5e-324]),
            Ordering::Greater
        );
    }
}
