//! Predicates against independent exact arithmetic (`rug::Rational` / `Integer`, written here):
//! robust's adaptive signs on adversarial inputs, the engine's range-checked predicates over
//! extreme magnitudes, and the SoS tie-break against a brute-force symbolic determinant.

use medial_blocks::geometry::predicates::{incircle, incircle_sos, orient2d};
use medial_blocks::geometry::Point;
use rug::{Integer, Rational};
use std::cmp::Ordering;

use crate::common;
use common::XorShift as Rng;

fn q(x: f64) -> Rational {
    Rational::from_f64(x).expect("finite")
}

fn orient_rug(a: Point, b: Point, c: Point) -> Ordering {
    let (ax, ay, bx, by, cx, cy) = (q(a[0]), q(a[1]), q(b[0]), q(b[1]), q(c[0]), q(c[1]));
    let det = (bx - &ax) * (cy - &ay) - (by - &ay) * (cx - &ax);
    det.cmp0()
}

fn incircle_rug(a: Point, b: Point, c: Point, d: Point) -> Ordering {
    let (dx, dy) = (q(d[0]), q(d[1]));
    let rel = |p: Point| {
        let (x, y) = (q(p[0]) - &dx, q(p[1]) - &dy);
        let l = Rational::from(&x * &x) + Rational::from(&y * &y);
        (x, y, l)
    };
    let (ax, ay, al) = rel(a);
    let (bx, by, bl) = rel(b);
    let (cx, cy, cl) = rel(c);
    let det = al * (Rational::from(&bx * &cy) - Rational::from(&cx * &by))
        + bl * (Rational::from(&cx * &ay) - Rational::from(&ax * &cy))
        + cl * (Rational::from(&ax * &by) - Rational::from(&bx * &ay));
    det.cmp0()
}

fn sign(x: f64) -> Ordering {
    x.partial_cmp(&0.0).expect("not NaN")
}

fn rc(p: Point) -> robust::Coord<f64> {
    robust::Coord { x: p[0], y: p[1] }
}

fn ulps(x: f64, k: i64) -> f64 {
    if x == 0.0 {
        return f64::from_bits(k.unsigned_abs()) * if k < 0 { -1.0 } else { 1.0 };
    }
    let y = f64::from_bits((x.to_bits() as i64).wrapping_add(k) as u64);
    if y.is_finite() {
        y
    } else {
        x
    }
}

/// Check robust (raw) and the engine's predicates against rug on one orientation triple.
fn check_orient(a: Point, b: Point, c: Point, raw_ok: bool) {
    let truth = orient_rug(a, b, c);
    if raw_ok {
        assert_eq!(
            sign(robust::orient2d(rc(a), rc(b), rc(c))),
            truth,
            "{a:?} {b:?} {c:?}"
        );
    }
    assert_eq!(orient2d(a, b, c), truth, "{a:?} {b:?} {c:?}");
}

fn check_incircle(a: Point, b: Point, c: Point, d: Point, raw_ok: bool) {
    let truth = incircle_rug(a, b, c, d);
    if raw_ok {
        let r = robust::incircle(rc(a), rc(b), rc(c), rc(d));
        assert_eq!(sign(r), truth, "{a:?} {b:?} {c:?} {d:?}");
    }
    assert_eq!(incircle(a, b, c, d), truth, "{a:?} {b:?} {c:?} {d:?}");
}

#[test]
fn nearly_collinear_orientation() {
    let mut r = Rng(1);
    for _ in 0..3000 {
        let a = [r.unit() * 10.0 - 5.0, r.unit() * 10.0 - 5.0];
        let b = [r.unit() * 10.0 - 5.0, r.unit() * 10.0 - 5.0];
        let t = r.unit() * 3.0 - 1.0;
        let c0 = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
        let k = r.below(9) as i64 - 4;
        let c = [ulps(c0[0], k), ulps(c0[1], -k / 2)];
        check_orient(a, b, c, true);
    }
}

#[test]
fn shewchuk_perturbed_grid_orientation() {
    // The classic failure plot: c = (0.5 + i ulp, 0.5 + j ulp) against the line (12,12)-(24,24).
    let (a, b) = ([12.0, 12.0], [24.0, 24.0]);
    for i in 0..64 {
        for j in 0..64 {
            let c = [ulps(0.5, i), ulps(0.5, j)];
            check_orient(a, b, c, true);
            check_orient(c, a, b, true);
        }
    }
}

/// Pythagorean points of the circle x² + y² = 25² (exact lattice points).
const CIRCLE: [(f64, f64); 12] = [
    (25.0, 0.0),
    (24.0, 7.0),
    (20.0, 15.0),
    (15.0, 20.0),
    (7.0, 24.0),
    (0.0, 25.0),
    (-7.0, 24.0),
    (-15.0, 20.0),
    (-24.0, 7.0),
    (-25.0, 0.0),
    (-20.0, -15.0),
    (7.0, -24.0),
];

#[test]
fn nearly_cocircular_incircle() {
    let mut r = Rng(2);
    for _ in 0..3000 {
        // Scale by a non-dyadic factor (rounding) or a power of two (exact), then nudge by ulps.
        let s = if r.below(2) == 0 {
            0.1 + r.unit()
        } else {
            2f64.powi(r.below(20) as i32 - 10)
        };
        let (cx, cy) = (r.unit() * 8.0 - 4.0, r.unit() * 8.0 - 4.0);
        let mut pick = || {
            let (x, y) = CIRCLE[r.below(12) as usize];
            [cx + s * x, cy + s * y]
        };
        let (a, b, c, d0) = (pick(), pick(), pick(), pick());
        let k = r.below(5) as i64 - 2;
        let d = [ulps(d0[0], k), ulps(d0[1], k)];
        check_incircle(a, b, c, d, true);
    }
}

#[test]
fn ulp_grid_incircle() {
    let mut r = Rng(3);
    for _ in 0..3000 {
        let mut p = || [ulps(0.5, r.below(16) as i64), ulps(0.5, r.below(16) as i64)];
        let (a, b, c, d) = (p(), p(), p(), p());
        check_incircle(a, b, c, d, true);
        check_orient(a, b, c, true);
    }
}

#[test]
fn extreme_magnitudes_use_the_exact_path() {
    let mut r = Rng(4);
    let scales = [
        1e300,
        1e-300,
        5e-324,
        1e-310,
        1e200,
        1e-200,
        f64::MAX / 64.0,
        1.0,
    ];
    for _ in 0..2000 {
        let mut p = || {
            let s = scales[r.below(scales.len() as u64) as usize];
            let k = r.below(5) as i64 - 2;
            [
                ulps((r.below(7) as f64 - 3.0) * s, k),
                ulps((r.below(7) as f64 - 3.0) * s, -k),
            ]
        };
        let (a, b, c, d) = (p(), p(), p(), p());
        check_orient(a, b, c, false);
        check_incircle(a, b, c, d, false);
    }
}

// ---- Simulation of simplicity against a brute-force symbolic determinant ----

/// A polynomial in ε with integer coefficients (index = degree).
#[derive(Clone)]
struct Poly(Vec<Integer>);

impl Poly {
    fn constant(c: Integer) -> Self {
        Poly(vec![c])
    }
    fn mul(&self, o: &Poly) -> Poly {
        let mut v = vec![Integer::new(); self.0.len() + o.0.len() - 1];
        for (i, a) in self.0.iter().enumerate() {
            for (j, b) in o.0.iter().enumerate() {
                v[i + j] += Integer::from(a * b);
            }
        }
        Poly(v)
    }
    fn add_signed(&mut self, o: &Poly, negative: bool) {
        if self.0.len() < o.0.len() {
            self.0.resize(o.0.len(), Integer::new());
        }
        for (i, c) in o.0.iter().enumerate() {
            if negative {
                self.0[i] -= c;
            } else {
                self.0[i] += c;
            }
        }
    }
    /// Sign for ε → 0+: the sign of the lowest-degree non-zero coefficient.
    fn sign(&self) -> Ordering {
        self.0
            .iter()
            .map(|c| c.cmp0())
            .find(|s| *s != Ordering::Equal)
            .unwrap_or(Ordering::Equal)
    }
}

/// det[x, y, x²+y² + ε^(rank+1), 1] over rows a, b, c, d by Leibniz expansion, where rank is
/// the lexicographic rank among the four points. Coordinates are brought to integers first.
fn symbolic_incircle(pts: [Point; 4]) -> Ordering {
    let rats: Vec<[Rational; 2]> = pts.iter().map(|p| [q(p[0]), q(p[1])]).collect();
    let mut den = Integer::from(1);
    for r in &rats {
        for v in r {
            den.lcm_mut(v.denom());
        }
    }
    let ints: Vec<[Integer; 2]> = rats
        .iter()
        .map(|r| r.clone().map(|v| (v * &den).into_numer_denom().0))
        .collect();
    let mut rank = [0usize; 4];
    for i in 0..4 {
        rank[i] = (0..4)
            .filter(|&j| (&ints[j][0], &ints[j][1]) < (&ints[i][0], &ints[i][1]))
            .count();
    }
    let entry = |row: usize, col: usize| -> Poly {
        let [x, y] = &ints[row];
        match col {
            0 => Poly::constant(x.clone()),
            1 => Poly::constant(y.clone()),
            2 => {
                let mut v = vec![Integer::new(); rank[row] + 2];
                v[0] = Integer::from(x * x) + Integer::from(y * y);
                v[rank[row] + 1] = Integer::from(1);
                Poly(v)
            }
            _ => Poly::constant(Integer::from(1)),
        }
    };
    let mut det = Poly(vec![Integer::new()]);
    let mut perm = [0usize, 1, 2, 3];
    // All 24 permutations via Heap's algorithm, tracking parity.
    fn heap(k: usize, perm: &mut [usize; 4], odd: bool, out: &mut Vec<([usize; 4], bool)>) -> bool {
        let mut odd = odd;
        if k == 1 {
            out.push((*perm, odd));
            return odd;
        }
        for i in 0..k - 1 {
            odd = heap(k - 1, perm, odd, out);
            if k.is_multiple_of(2) {
                perm.swap(i, k - 1);
            } else {
                perm.swap(0, k - 1);
            }
            odd = !odd;
        }
        heap(k - 1, perm, odd, out)
    }
    let mut all = Vec::new();
    heap(4, &mut perm, false, &mut all);
    assert_eq!(all.len(), 24);
    for (p, odd) in all {
        let mut term = Poly::constant(Integer::from(1));
        for (row, &col) in p.iter().enumerate() {
            term = term.mul(&entry(row, col));
        }
        det.add_signed(&term, odd);
    }
    det.sign()
}

#[test]
fn symbolic_determinant_agrees_with_incircle_off_ties() {
    let mut r = Rng(5);
    for _ in 0..300 {
        let mut p = || [(r.below(16) as f64) * 0.5, (r.below(16) as f64) * 0.25];
        let pts = [p(), p(), p(), p()];
        let exact = incircle_rug(pts[0], pts[1], pts[2], pts[3]);
        if exact != Ordering::Equal {
            assert_eq!(symbolic_incircle(pts), exact, "{pts:?}");
        }
    }
}

#[test]
fn sos_cofactor_signs_match_symbolic_expansion_on_ties() {
    let mut r = Rng(6);
    let mut ties = 0;
    for _ in 0..1500 {
        let s = 2f64.powi(r.below(12) as i32 - 6);
        let (cx, cy) = (
            (r.below(64) as f64 - 32.0) * 0.125,
            (r.below(64) as f64 - 32.0) * 0.5,
        );
        let mut idx: Vec<usize> = (0..12).collect();
        for i in (1..12).rev() {
            idx.swap(i, r.below(i as u64 + 1) as usize);
        }
        let pts: [Point; 4] = [0, 1, 2, 3].map(|k| {
            let (x, y) = CIRCLE[idx[k]];
            [cx + s * x, cy + s * y]
        });
        assert_eq!(
            incircle_rug(pts[0], pts[1], pts[2], pts[3]),
            Ordering::Equal
        );
        ties += 1;
        let expected = symbolic_incircle(pts);
        assert_ne!(expected, Ordering::Equal);
        assert_eq!(
            incircle_sos(pts[0], pts[1], pts[2], pts[3]),
            expected,
            "{pts:?}"
        );
    }
    assert_eq!(ties, 1500);
}

#[test]
fn sos_is_consistent_on_square_grid_ties() {
    // Every 4-subset of a grid cell and of larger lattice circles: SoS must match the expansion.
    let mut r = Rng(7);
    for _ in 0..500 {
        let pick = |r: &mut Rng| [r.below(3) as f64, r.below(3) as f64];
        let pts = [pick(&mut r), pick(&mut r), pick(&mut r), pick(&mut r)];
        let distinct = (0..4).all(|i| (0..i).all(|j| pts[i] != pts[j]));
        if !distinct || orient_rug(pts[0], pts[1], pts[2]) == Ordering::Equal {
            continue;
        }
        assert_eq!(
            incircle_sos(pts[0], pts[1], pts[2], pts[3]),
            symbolic_incircle(pts),
            "{pts:?}"
        );
    }
}
