//! Shuffle invariance: permuting the input only renumbers the triangulation, also for grids,
//! co-circular points and duplicates (SoS is keyed to the points, never to insertion order).
//! Case counts are moderate; raise them with `PROPTEST_CASES`.

use medial_blocks::geometry::verify::verify_exact;
use medial_blocks::geometry::{Point, Triangulation};
use proptest::prelude::*;

type Key = [u64; 2];

fn key(p: Point) -> Key {
    [(p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()]
}

/// The triangulation as a sorted list of coordinate triangles (rotated to a canonical start),
/// plus the co-circular groups as sorted coordinate sets, plus the number of duplicates.
type Canonical = (Vec<[Key; 3]>, Vec<Vec<Key>>, usize);

fn canonical(pts: &[Point]) -> Canonical {
    let dt = Triangulation::new(pts).expect("triangulation");
    if let Err(e) = verify_exact(&dt) {
        panic!("verification failed: {e}");
    }
    let mut tris: Vec<[Key; 3]> = dt
        .triangles()
        .map(|t| {
            let k = t.map(|v| key(pts[v as usize]));
            let s = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
            [k[s], k[(s + 1) % 3], k[(s + 2) % 3]]
        })
        .collect();
    tris.sort_unstable();
    let mut groups: Vec<Vec<Key>> = dt
        .cocircular_groups()
        .into_iter()
        .map(|g| {
            let mut g: Vec<Key> = g.into_iter().map(|v| key(pts[v as usize])).collect();
            g.sort_unstable();
            g
        })
        .collect();
    groups.sort();
    (tris, groups, dt.duplicates().len())
}

fn generic() -> impl Strategy<Value = Vec<Point>> {
    prop::collection::vec((-1000i32..1000, -1000i32..1000), 3..200).prop_map(|v| {
        v.into_iter()
            .map(|(x, y)| [f64::from(x) * 0.37, f64::from(y) * 1.3])
            .collect()
    })
}

fn grid() -> impl Strategy<Value = Vec<Point>> {
    (2usize..12, 2usize..12, 0usize..20).prop_map(|(w, h, dups)| {
        let mut v: Vec<Point> = (0..w * h)
            .map(|i| [(i % w) as f64, (i / w) as f64 * 0.5])
            .collect();
        for d in 0..dups {
            v.push(v[(d * 7) % (w * h)]);
        }
        v
    })
}

/// Lattice points of x² + y² = 25 and 625 (two concentric exact circles), a few grid points
/// inside, and collinear points on a diameter.
fn cocircular() -> impl Strategy<Value = Vec<Point>> {
    (prop::collection::vec(0usize..24, 3..24), 0usize..4).prop_map(|(pick, inner)| {
        const C: [(f64, f64); 6] = [
            (25.0, 0.0),
            (24.0, 7.0),
            (20.0, 15.0),
            (15.0, 20.0),
            (7.0, 24.0),
            (0.0, 25.0),
        ];
        let mut v = Vec::new();
        for p in pick {
            let (x, y) = C[p % 6];
            let (sx, sy) = [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)][p / 6];
            v.push([sx * x, sy * y]);
            v.push([sx * x / 5.0, sy * y / 5.0]);
        }
        for i in 0..inner {
            v.push([i as f64 - 1.5, 0.0]);
        }
        v.extend([[0.0, 0.0], [25.0, 0.0], [-25.0, 0.0], [0.0, 25.0]]);
        v
    })
}

fn shuffled(v: Vec<Point>) -> impl Strategy<Value = (Vec<Point>, Vec<Point>)> {
    let original = v.clone();
    Just(v)
        .prop_shuffle()
        .prop_map(move |s| (original.clone(), s))
}

fn config() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(96);
    ProptestConfig::with_cases(cases)
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn generic_points((a, b) in generic().prop_flat_map(shuffled)) {
        if Triangulation::new(&a).is_ok() {
            prop_assert_eq!(canonical(&a), canonical(&b));
        }
    }

    #[test]
    fn grids_with_duplicates((a, b) in grid().prop_flat_map(shuffled)) {
        prop_assert_eq!(canonical(&a), canonical(&b));
    }

    #[test]
    fn cocircular_sets((a, b) in cocircular().prop_flat_map(shuffled)) {
        prop_assert_eq!(canonical(&a), canonical(&b));
    }
}

#[test]
fn negative_zero_is_the_same_point() {
    let a = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [-0.0, 1.0]];
    let b = [[0.0, 0.0], [1.0, 0.0], [-0.0, 1.0], [1.0, 1.0], [0.0, 1.0]];
    assert_eq!(canonical(&a), canonical(&b));
}
