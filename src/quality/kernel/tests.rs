//! Tests of [`super`]: each fast path against its reference, bit for bit.

use super::*;
use crate::quality::{JACOBIAN_EDGES, RATIO_EDGES, SKEWNESS_EDGES};

/// The AVX2, AVX-512 and portable builds of the row tests agree, on rows with degenerate,
/// inverted, signed-zero and non-finite cells.
#[test]
fn wide_and_portable_row_tests_agree() {
    if !wide() {
        return;
    }
    let mut r = crate::layouts::SplitMix64(5);
    let vals = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        0.5,
        2.0,
        f64::NAN,
        f64::INFINITY,
        1e-300,
        3.0,
    ];
    for n in [2usize, 3, 5, 9, 17] {
        for _ in 0..3000 {
            let mut p = || {
                let mut v = || vals[(r.next_u64() % vals.len() as u64) as usize];
                [v(), v()]
            };
            let lo: Vec<Point> = (0..n).map(|_| p()).collect();
            let hi: Vec<Point> = (0..n).map(|_| p()).collect();
            // SAFETY: AVX2 was detected above.
            unsafe {
                assert_eq!(row_inverted_avx2(&lo, &hi), row_inverted_portable(&lo, &hi));
                if wider() {
                    assert_eq!(
                        row_inverted_avx512(&lo, &hi),
                        row_inverted_portable(&lo, &hi)
                    );
                    for t in [0.1, 1.0] {
                        assert_eq!(
                            row_corner_below_avx512(&lo, &hi, t),
                            row_corner_below_portable(&lo, &hi, t)
                        );
                    }
                }
                for t in [0.1, 1.0] {
                    assert_eq!(
                        row_corner_below_avx2(&lo, &hi, t),
                        row_corner_below_portable(&lo, &hi, t)
                    );
                }
            }
        }
    }
}

/// The arithmetic angle bin equals the search of [`bin`]: at, just around and between
/// every edge and every multiple of 10, on a fine sweep and far outside (both rules are
/// monotone step functions, so agreeing around every step is agreeing everywhere).
#[test]
fn angle_bins_equal_the_search() {
    use crate::quality::ANGLE_EDGES;
    let mut xs = vec![
        -1e300,
        -400.0,
        -2.0,
        -0.0,
        0.0,
        1e-300,
        1e300,
        500.0,
        f64::MAX,
    ];
    for m in -3..=40 {
        for e in [10.0 * m as f64, 135.0] {
            for k in -4i64..=4 {
                xs.push(f64::from_bits((e.to_bits() as i64 + k) as u64));
                xs.push(e + k as f64 * 1e-12);
                xs.push(e + k as f64 * 0.3);
            }
        }
    }
    for s in 0..400_000 {
        xs.push(-20.0 + 400.0 * s as f64 / 400_000.0);
    }
    for x in xs.into_iter().filter(|x| x.is_finite()) {
        let want = bin(&ANGLE_EDGES, x);
        if x >= 0.0 {
            assert_eq!(angle_bin_unsigned(x), want as f64, "{x:e}");
        }
    }
}

/// The division-free angle bin equals the division rule it replaced,
/// `min(floor(x / 10) + [x >= 135], 18)`: on 64 floats either side of every multiple of
/// 10 up to 400 and of the powers of two, on random angles of `[0, 360]` and random bit
/// patterns (every exponent), and at the specials.
#[test]
fn angle_bin_without_division_equals_the_quotient() {
    let by_division = |x: f64| {
        let q = (x / 10.0).floor();
        let b = if x >= 135.0 { q + 1.0 } else { q };
        if b < 18.0 {
            b
        } else {
            18.0
        }
    };
    let mut xs = vec![0.0, 5e-324, f64::MIN_POSITIVE, f64::MAX, f64::INFINITY];
    let centres = (0..=40)
        .map(|m| 10.0 * m as f64)
        .chain((-60..60).map(|e| f64::powi(2.0, e)))
        .chain([135.0, 360.0]);
    for c in centres {
        for k in -64i64..=64 {
            let x = f64::from_bits(c.to_bits().wrapping_add(k as u64));
            if x >= 0.0 {
                xs.push(x);
            }
        }
    }
    let mut r = crate::layouts::SplitMix64(17);
    for _ in 0..1_000_000 {
        xs.push(360.0 * r.next_f64());
        let b = f64::from_bits(r.next_u64() >> 1);
        if !b.is_nan() {
            xs.push(b);
        }
    }
    for x in xs {
        assert_eq!(
            angle_bin_unsigned(x).to_bits(),
            by_division(x).to_bits(),
            "{x:e}"
        );
    }
    assert_eq!(angle_bin_unsigned(f64::NAN), 18.0);
}

/// The ratio bins from the table equal the counted ones ([`weighted_bin`], itself checked
/// against the search of [`bin`]): at and around every edge and every group boundary of
/// the table (16 top bits), for zeros of both signs, negative, tiny, subnormal and huge
/// values, and random bit patterns of either sign; and [`RatioBins::bin_by_compares`]
/// equals the table on all of them, NaN and infinities too.
#[test]
fn ratio_bins_from_the_table_equal_the_counted_ones() {
    let table = RatioBins::new(&RATIO_EDGES, PACK[6]);
    let mut xs = vec![0.0, -0.0, 5e-324, -5e-324, f64::MAX, -f64::MAX, -1.0, 0.5];
    let group_starts = (0..=RATIO_GROUPS as i64 + 4)
        .map(|k| f64::from_bits(((ONE_TOP + k) as u64) << 48))
        .chain(RATIO_EDGES);
    for c in group_starts {
        for k in -3i64..=3 {
            xs.push(f64::from_bits(c.to_bits().wrapping_add(k as u64)));
        }
    }
    let mut r = crate::layouts::SplitMix64(19);
    for _ in 0..300_000 {
        xs.push(1.0 + 150.0 * r.next_f64());
        xs.push(f64::from_bits(r.next_u64()));
    }
    xs.extend([f64::NAN, -f64::NAN, f64::INFINITY, f64::NEG_INFINITY]);
    let mut nan = 0;
    for x in xs {
        // The comparisons give the table's bits on every input, NaN of either sign included.
        assert_eq!(
            table.bin(x).to_bits(),
            table.bin_by_compares(x).to_bits(),
            "{x:e} ({:#x})",
            x.to_bits()
        );
        if x.is_nan() {
            nan += 1;
            continue;
        }
        assert_eq!(
            table.bin(x).to_bits(),
            weighted_bin(x, &RATIO_EDGES, PACK[6]).to_bits(),
            "{x:e}"
        );
    }
    assert!(nan > 100, "{nan} NaN patterns");
}

/// Each skewness threshold is the first dividend where its test holds (and it fails on
/// the float just below); and on dividends around every threshold, every bin edge times 90
/// and a sweep, the thresholds give the bin and the acceptance of the divided skewness.
#[test]
fn skew_thresholds_equal_the_division() {
    use crate::quality::{SKEWNESS_ACCEPTABLE, SKEWNESS_EDGES};
    let th = SkewThresholds::new();
    let bins = skew_bin_thresholds();
    let below = f64::next_down;
    for (k, &t) in bins.iter().enumerate() {
        let e = SKEWNESS_EDGES[k + 1];
        assert!(t / 90.0 >= e && below(t) / 90.0 < e, "{t:e} for {e}");
    }
    assert!(th.lo / 90.0 >= 0.0 && below(th.lo) / 90.0 < 0.0);
    assert!(th.above / 90.0 > 0.5 && below(th.above) / 90.0 <= 0.5);
    let mut ds = vec![0.0, -0.0, 1e-310, -1e-310, -1.0, 400.0, 1e300, -1e300];
    for &t in bins.iter().chain([&th.lo, &th.above]) {
        let mut x = t;
        for _ in 0..4 {
            x = below(x);
        }
        for _ in 0..9 {
            ds.push(x);
            x = x.next_up();
        }
    }
    for &e in &SKEWNESS_EDGES {
        ds.push(90.0 * e);
    }
    for s in 0..200_000 {
        ds.push(-10.0 + 200.0 * s as f64 / 200_000.0);
    }
    for d in ds {
        let sk = d / 90.0;
        let by_threshold = bins.iter().filter(|&&t| d >= t).count();
        assert_eq!(by_threshold, bin(&SKEWNESS_EDGES, sk), "{d:e}");
        assert_eq!(StepBins::SKEW.count(d), by_threshold as f64, "{d:e}");
        let [lo, hi] = SKEWNESS_ACCEPTABLE;
        assert_eq!(
            (d >= th.lo) & (d < th.above),
            (sk >= lo) & (sk <= hi),
            "{d:e}"
        );
    }
}

/// The one-product bin rules ([`StepBins`]) count the thresholds a value reaches, as the
/// comparisons they replace: on every threshold and the 40 floats either side, signed zeros, subnormals, infinities,
/// NaN, huge values and sweeps across each range.
#[test]
fn step_bins_count_the_thresholds() {
    let jacobian_inner: Vec<f64> = JACOBIAN_EDGES[1..JACOBIAN_EDGES.len() - 1].to_vec();
    let rules: [(StepBins, Vec<f64>); 2] = [
        (StepBins::SKEW, skew_bin_thresholds().to_vec()),
        (StepBins::JACOBIAN, jacobian_inner),
    ];
    for (rule, thresholds) in &rules {
        let mut xs = vec![
            0.0,
            -0.0,
            f64::from_bits(1),
            -f64::from_bits(1),
            f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            -f64::NAN,
            1e300,
            -1e300,
            f64::MAX,
            f64::MIN,
        ];
        for &t in thresholds {
            let mut x = t;
            for _ in 0..40 {
                x = x.next_down();
            }
            for _ in 0..81 {
                xs.push(x);
                x = x.next_up();
            }
        }
        let (lo, hi) = (
            thresholds[0] - 3.0,
            thresholds[thresholds.len() - 1] * 3.0 + 3.0,
        );
        for k in 0..200_000 {
            xs.push(lo + (hi - lo) * k as f64 / 200_000.0);
        }
        for x in xs {
            let want = thresholds.iter().filter(|&&t| x >= t).count();
            assert_eq!(rule.count(x), want as f64, "{x:e} against {thresholds:?}");
        }
    }
    // The scaled Jacobian's rule is the loop's former comparisons, and the oracle's bin.
    let rule = StepBins::JACOBIAN;
    for k in -30_000..30_000 {
        let x = k as f64 * 4.1e-5;
        assert_eq!(
            rule.count(x),
            weighted_bin(x, &JACOBIAN_EDGES, 1.0),
            "{x:e}"
        );
        assert_eq!(rule.count(x), bin(&JACOBIAN_EDGES, x) as f64, "{x:e}");
    }
}

/// The cell loop's constant rules are those [`StepBins::new`] finds and checks; each needs
/// its one correction (the plain product misses one float, which is the correction's); and
/// rules that do not count their thresholds are refused.
#[test]
fn step_bins_refuse_rules_that_miss() {
    let skew = skew_bin_thresholds();
    assert_eq!(StepBins::new(&skew, 1.0 / 9.0, 0.0), Some(StepBins::SKEW));
    let inner = jacobian_bin_thresholds();
    assert_eq!(StepBins::new(&inner, 10.0, 1.0), Some(StepBins::JACOBIAN));
    let plain =
        |x: f64, scale: f64, offset: f64, n: f64| ((x * scale).floor() + offset).clamp(0.0, n);
    let missed: Vec<f64> = skew
        .iter()
        .flat_map(|&t| [t, t.next_down()])
        .filter(|&x| {
            plain(x, 1.0 / 9.0, 0.0, 10.0) != skew.iter().filter(|&&t| x >= t).count() as f64
        })
        .collect();
    assert_eq!(missed.len(), 1, "{missed:?}");
    assert_eq!(StepBins::SKEW.fix, missed[0]);
    let missed: Vec<f64> = inner
        .iter()
        .flat_map(|&t| [t, t.next_down()])
        .filter(|&x| {
            plain(x, 10.0, 1.0, 9.0 + 1.0) != inner.iter().filter(|&&t| x >= t).count() as f64
        })
        .collect();
    assert_eq!(missed.len(), 1, "{missed:?}");
    assert_eq!(StepBins::JACOBIAN.fix, missed[0]);
    // Wrong scales, offsets, unordered or NaN thresholds.
    assert!(StepBins::new(&skew, 1.0 / 8.0, 0.0).is_none());
    assert!(StepBins::new(&skew, 1.0 / 9.0, 1.0).is_none());
    assert!(StepBins::new(&[2.0, 1.0], 1.0, 0.0).is_none());
    assert!(StepBins::new(&[1.0, 1.0], 1.0, 0.0).is_none());
    assert!(StepBins::new(&[1.0, f64::NAN], 1.0, 0.0).is_none());
    assert!(StepBins::new(&[1.0, 2.0], f64::NAN, 0.0).is_none());
    // Integers counted by a product a little off: the plain rule holds.
    let ok = StepBins::new(&[1.0, 2.0, 3.0], 1.0, 0.0).unwrap();
    assert!(ok.fix.is_nan());
    assert_eq!(
        [0.5, 1.0, 2.9, 3.0, 7.0].map(|x| ok.count(x)),
        [0.0, 1.0, 2.0, 3.0, 3.0]
    );
    // Two floats to correct (each threshold one below an integer): refused; one: taken.
    assert!(StepBins::new(&[1.0f64.next_down(), 2.0f64.next_down()], 1.0, 0.0).is_none());
    let one = StepBins::new(&[1.0, 2.0f64.next_down()], 1.0, 0.0).unwrap();
    assert_eq!((one.fix, one.delta), (2.0f64.next_down(), 1.0));
    // Off by more than one float: refused.
    assert!(StepBins::new(&[1.0f64.next_down().next_down()], 1.0, 0.0).is_none());
}

/// Corners of cells that tie or nearly tie: exact squares and rectangles (axis-aligned,
/// rotated), mirror-symmetric trapezoids, kites, random cells on a coarse integer lattice
/// (many equal products) and at several scales.
fn tie_prone_cell(r: &mut crate::layouts::SplitMix64) -> [Point; 4] {
    let mut u = || r.next_f64();
    let scale = [1.0, 1e-100, 1e100, 3.0e-7, 0.1][(u() * 5.0) as usize];
    let p: [Point; 4] = match (u() * 6.0) as u32 {
        0 => {
            let (w, h) = (
                (1.0 + (u() * 4.0).floor()) * 0.25,
                (1.0 + (u() * 4.0).floor()) * 0.5,
            );
            [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]
        }
        1 => {
            let (a, w, h) = (u() * 6.3, 0.1 + u(), 0.1 + u());
            let (c, s) = (a.cos(), a.sin());
            [
                [0.0, 0.0],
                [w * c, w * s],
                [w * c - h * s, w * s + h * c],
                [-h * s, h * c],
            ]
        }
        2 => {
            let (b, t, h) = (0.5 + u(), 0.1 + u(), 0.1 + u());
            [[-b, 0.0], [b, 0.0], [t, h], [-t, h]]
        }
        3 => {
            let (a, b, w) = (0.1 + u(), 0.1 + u(), 0.1 + u());
            [[0.0, -a], [w, 0.0], [0.0, b], [-w, 0.0]]
        }
        4 => {
            let mut q = || (u() * 4.0).floor() - 1.0;
            [
                [q(), q()],
                [q() + 3.0, q()],
                [q() + 3.0, q() + 3.0],
                [q(), q() + 3.0],
            ]
        }
        _ => {
            let mut q = || u() * 2.0 - 1.0;
            [
                [q(), q()],
                [q() + 2.0, q()],
                [q() + 2.0, q() + 2.0],
                [q(), q() + 2.0],
            ]
        }
    };
    let o = [u() * 8.0 - 4.0, u() * 8.0 - 4.0];
    p.map(|[x, y]| [scale * (x + o[0]), scale * (y + o[1])])
}

/// [`least_scaled_jacobian`] gives the bits of [`length_figures`] whenever it says it is
/// certain, on tie-prone, inverted and random cells (and it is certain on most of them).
#[test]
fn least_scaled_jacobian_equals_the_four_divisions() {
    let mut r = crate::layouts::SplitMix64(11);
    let (mut certain, mut total) = (0, 0);
    for round in 0..300_000 {
        let mut p = tie_prone_cell(&mut r);
        if round % 7 == 0 {
            p.swap(1, 3);
        }
        let (cross, _) = corner_products(&p);
        let edges = [0, 1, 2, 3].map(|k| {
            let (a, b) = (p[k], p[(k + 1) % 4]);
            crate::geometry::length(b[0] - a[0], b[1] - a[1])
        });
        let ok = edges.iter().all(|&l| (SQ_MIN..=SQ_MAX).contains(&(l * l)))
            && cross.iter().all(|&c| c != 0.0 && c.is_finite());
        if !ok {
            continue;
        }
        total += 1;
        let (want, _, _) = length_figures(&cross, &edges);
        let (got, sure) = least_scaled_jacobian(&cross, &edges);
        if sure {
            certain += 1;
            assert_eq!(got.to_bits(), want.to_bits(), "{p:?}");
        }
    }
    // About half of these tie-prone cells are decided (rotated rectangles mostly not).
    assert!(certain * 3 > total, "{certain} of {total}");
}

/// Bins weighted by [`PACK`] and summed in any grouping give, through [`packed_bins`],
/// the 5-bit fields packed with shifts (every bin value, extreme words included).
#[test]
fn packed_sums_equal_the_shifted_fields() {
    let mut r = crate::layouts::SplitMix64(13);
    for round in 0..20_000 {
        let b: [u64; 8] = std::array::from_fn(|k| match round % 3 {
            0 => r.next_u64() % 32,
            1 => [0, 31][(r.next_u64() % 2) as usize],
            _ => [18, 10, 9, k as u64][(r.next_u64() % 4) as usize],
        });
        let want = (0..8).fold(0, |w, k| w | b[k] << (5 * k));
        let t: [f64; 8] = std::array::from_fn(|k| b[k] as f64 * PACK[k]);
        let grouped = ((t[0] + t[1]) + (t[2] + t[3])) + (t[4] + ((t[5] + t[6]) + t[7]));
        let serial = t.iter().fold(0.0, |s, x| s + x);
        assert_eq!(packed_bins(grouped), want, "{b:?}");
        assert_eq!(packed_bins(serial), want, "{b:?}");
    }
}

/// Values at, just around and between every edge, and far outside, for every histogram
/// counted by [`weighted_bin`]: its bin equals the search of [`bin`].
#[test]
fn counted_bins_equal_the_search() {
    fn check<const N: usize>(edges: &[f64; N]) {
        let mut xs = vec![-1e300, -400.0, -2.0, 0.0, -0.0, 1e-300, 1e300, 500.0, 150.0];
        for &e in edges {
            for k in -3i64..=3 {
                // Neighbouring floats (for 0.0, NaN patterns below it are skipped).
                xs.push(f64::from_bits((e.to_bits() as i64 + k) as u64));
                xs.push(-f64::from_bits(k.unsigned_abs()));
                xs.push(e + k as f64 * 1e-3);
                xs.push(e + k as f64 * 0.07);
            }
        }
        let (lo, hi) = (edges[0] - 5.0, edges[N - 1] + 5.0);
        for s in 0..100_000 {
            xs.push(lo + (hi - lo) * s as f64 / 100_000.0);
        }
        for x in xs.into_iter().filter(|x| x.is_finite()) {
            assert_eq!(
                weighted_bin(x, edges, 1.0),
                bin(edges, x) as f64,
                "{x:e} in {edges:?}"
            );
        }
    }
    check(&SKEWNESS_EDGES);
    check(&JACOBIAN_EDGES);
    check(&RATIO_EDGES);
}

/// The edge-direction candidates of [`corner_candidates`] are the corner angles (within
/// `1e-12` degrees of libm's `atan2(cross, dot)`) and [`settled`] keeps every one of them
/// more than `1e-6` degrees from flat: the reference's `angle_deg(cross, dot)` fallback is
/// only for nearly flat corners (a wrong candidate would hide behind it otherwise), on random
/// convex, non-convex and inverted cells.
#[test]
fn direction_candidates_are_the_corner_angles() {
    let mut r = crate::layouts::SplitMix64(17);
    let mut kept = 0;
    for _ in 0..100_000 {
        let jitter = [0.1, 0.45, 2.0][(r.next_u64() % 3) as usize];
        let p: [Point; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|q| {
            [
                q[0] + jitter * (r.next_f64() - 0.5),
                q[1] + jitter * (r.next_f64() - 0.5),
            ]
        });
        let (cross, dot) = corner_products(&p);
        let dir = |a: Point, b: Point| super::super::angle_deg(b[1] - a[1], b[0] - a[0]);
        let cand = corner_candidates(
            dir(p[0], p[1]),
            dir(p[1], p[2]),
            dir(p[3], p[2]),
            dir(p[0], p[3]),
        );
        for k in 0..4 {
            let want = cross[k].atan2(dot[k]).to_degrees();
            let want = if want < 0.0 { want + 360.0 } else { want };
            let d = (cand[k] - want).abs();
            assert!(
                d.min(360.0 - d) <= 1e-12,
                "{p:?} corner {k}: {} vs {want}",
                cand[k]
            );
            let flat = want.min((want - 180.0).abs()).min(360.0 - want);
            if flat > 1e-6 {
                assert!(settled(cand[k], cross[k]), "{p:?} corner {k}: {want}");
                kept += 1;
            }
        }
    }
    assert!(kept > 390_000, "{kept}");
}
