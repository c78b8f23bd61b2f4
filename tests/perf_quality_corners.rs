//! The corner angles of the quality figures (`quality::cell_corners`) are differences of edge
//! directions (issue #8: one `atan2` per edge, shared by the two cells on either side, where
//! each corner took its own), except within `1e-9` degrees of flat. Checked here against a
//! formula that does not share that code: libm's `atan2(cross, dot)` of each corner, in
//! degrees, in `[0, 360)`, on random convex, non-convex, inverted, tiny and far-off cells,
//! and on nearly flat corners, where the angle keeps its relative accuracy.

use medial_blocks::layouts::SplitMix64;
use medial_blocks::quality::{angle_deg, cell_corners};

type Point = [f64; 2];

/// Corner `k`'s cross and dot products, `e1 = p[k+1] - p[k]`, `e2 = p[k-1] - p[k]`.
fn products(p: &[Point; 4], k: usize) -> (f64, f64) {
    let (o, a, b) = (p[k], p[(k + 1) % 4], p[(k + 3) % 4]);
    let e1 = [a[0] - o[0], a[1] - o[1]];
    let e2 = [b[0] - o[0], b[1] - o[1]];
    (e1[0] * e2[1] - e1[1] * e2[0], e1[0] * e2[0] + e1[1] * e2[1])
}

/// libm's angle of corner `k`, degrees, in `[0, 360)`.
fn libm_angle(p: &[Point; 4], k: usize) -> f64 {
    let (c, d) = products(p, k);
    crate::perf_quality_atan::libm_deg(c, d)
}

/// Distance between two angles on the circle, degrees.
fn apart(a: f64, b: f64) -> f64 {
    let d = (a - b).abs();
    d.min(360.0 - d)
}

/// A random quadrilateral: a jittered square (convex), or four random points (often
/// non-convex or inverted), scaled and moved far off the origin.
fn cell(r: &mut SplitMix64) -> [Point; 4] {
    let scale = 10f64.powf(r.next_f64() * 12.0 - 6.0);
    let off = 10f64.powf(r.next_f64() * 8.0 - 2.0) * scale;
    let (ox, oy) = (off * (r.next_f64() - 0.5), off * (r.next_f64() - 0.5));
    let jitter = [0.0, 0.1, 0.45, 2.0][(r.next_f64() * 4.0) as usize];
    let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let turn = r.next_f64() * std::f64::consts::TAU;
    let (s, c) = turn.sin_cos();
    square.map(|q| {
        let x = q[0] + jitter * (r.next_f64() - 0.5);
        let y = q[1] + jitter * (r.next_f64() - 0.5);
        [ox + scale * (c * x - s * y), oy + scale * (s * x + c * y)]
    })
}

/// Every corner within `1e-12` degrees of libm's angle, below 180 exactly where its cross
/// product is positive; the four angles of a cell with four positive products (convex)
/// add up to 360.
#[test]
fn corner_angles_agree_with_atan2_of_each_corner() {
    let mut r = SplitMix64(2026);
    let (mut convex, mut reflex) = (0, 0);
    for _ in 0..200_000 {
        let p = cell(&mut r);
        let got = cell_corners(p);
        for k in 0..4 {
            let (c, _) = products(&p, k);
            let (a, want) = (got.angle_deg[k], libm_angle(&p, k));
            assert_eq!(got.jacobian[k].to_bits(), c.to_bits(), "{p:?} corner {k}");
            assert!((0.0..360.0).contains(&a), "{p:?} corner {k}: {a}");
            assert!(
                apart(a, want) <= 1e-12,
                "{p:?} corner {k}: {a:e} vs {want:e}"
            );
            if c > 0.0 {
                assert!(a < 180.0, "{p:?} corner {k}: {a} with a positive Jacobian");
            } else if c < 0.0 {
                assert!(a > 180.0, "{p:?} corner {k}: {a} with a negative Jacobian");
                reflex += 1;
            }
        }
        if got.jacobian.iter().all(|&c| c > 0.0) {
            convex += 1;
            let sum: f64 = got.angle_deg.iter().sum();
            assert!(
                (sum - 360.0).abs() <= 4e-12,
                "{p:?}: angles add up to {sum}"
            );
        }
    }
    assert!(
        convex > 100_000 && reflex > 5_000,
        "{convex} convex, {reflex} reflex"
    );
}

/// Corners within a billionth of a degree of 0 or 180 (a thin sliver, a node nearly on the
/// line of its neighbours) take `angle_deg(cross, dot)`: the same bits, so a tiny angle keeps
/// its relative accuracy (the difference of two directions would leave only its absolute one,
/// about `1e-13` degrees).
#[test]
fn nearly_flat_corners_keep_their_relative_accuracy() {
    let mut r = SplitMix64(9);
    let mut tiny = 0;
    for _ in 0..20_000 {
        let scale = 10f64.powf(r.next_f64() * 6.0 - 3.0);
        let h = scale * 10f64.powf(-(r.next_f64() * 10.0 + 12.0));
        let len = scale * (0.5 + r.next_f64());
        // A sliver: p3 nearly on the line from p0 through p1, so the corner at p0 is below
        // 1e-9 degrees.
        let p = [
            [0.0, 0.0],
            [scale, 0.0],
            [scale + len * 0.1, h],
            [len, h * 0.5],
        ];
        let got = cell_corners(p);
        for k in 0..4 {
            let (c, d) = products(&p, k);
            let a = got.angle_deg[k];
            let near_flat = a.min((a - 180.0).abs()).min(360.0 - a) <= 1e-9;
            if near_flat {
                assert_eq!(a.to_bits(), angle_deg(c, d).to_bits(), "{p:?} corner {k}");
                let want = libm_angle(&p, k);
                if want < 1e-9 {
                    tiny += 1;
                    assert!(
                        (a - want).abs() <= 1e-12 * want,
                        "{p:?} corner {k}: {a:e} vs {want:e}"
                    );
                }
            }
        }
    }
    assert!(tiny > 10_000, "{tiny} tiny corners");
}
