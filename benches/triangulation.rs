//! This engine vs spade (`bulk_load`) vs delaunator on the same inputs:
//! uniform random points and circle-sampled points (non-overlapping circles, 32 samples each),
//! sizes 1e4, 1e5, 1e6 (select with e.g. `cargo bench --bench triangulation -- 1000000`); and
//! the pipeline's own sample points (`triangulate/pipeline/<engine>/<particles>`): the
//! boundary samples exact mode triangulates first (`sample_and_triangulate` with
//! `mesher::exact_sampling()`, as the mesher samples) on `layouts::bubbles(n, 1)` for n = 1e3, 1e4,
//! 1e5, capped by `MEDIAL_BENCH_MAX` (default `1e4`) as in the pipeline bench.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use medial_blocks::geometry::{Point, Triangulation};
use medial_blocks::layouts;
use medial_blocks::sampling::sample_and_triangulate;
use spade::{DelaunayTriangulation, Point2, Triangulation as _};
use std::time::Duration;

struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn uniform(n: usize) -> Vec<Point> {
    let mut r = Rng(0x1234_5678);
    (0..n).map(|_| [r.unit(), r.unit()]).collect()
}

/// `n / 32` circles on a jittered grid of unit cells, radius 0.3..0.45, 32 samples each.
fn circles(n: usize) -> Vec<Point> {
    let mut r = Rng(0x9abc_def0);
    let m = n / 32;
    let side = (m as f64).sqrt().ceil() as usize;
    let mut pts = Vec::with_capacity(n);
    for c in 0..m {
        let (cx, cy) = ((c % side) as f64 + 0.5, (c / side) as f64 + 0.5);
        let rad = 0.3 + 0.15 * r.unit();
        let (cx, cy) = (cx + 0.04 * (r.unit() - 0.5), cy + 0.04 * (r.unit() - 0.5));
        for k in 0..32 {
            let a = std::f64::consts::TAU * k as f64 / 32.0;
            pts.push([cx + rad * a.cos(), cy + rad * a.sin()]);
        }
    }
    pts
}

/// `MEDIAL_BENCH_MAX` (`1e4`, `10000`, ...), default 1e4.
fn max_particles() -> usize {
    std::env::var("MEDIAL_BENCH_MAX")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 1.0)
        .map_or(10_000, |v| v as usize)
}

/// The three engines on `pts`, in one group, same run.
fn compare(
    group: &mut criterion::BenchmarkGroup<criterion::measurement::WallTime>,
    n: usize,
    pts: &[Point],
) {
    group.bench_with_input(BenchmarkId::new("engine", n), pts, |b, pts| {
        b.iter(|| Triangulation::new(black_box(pts)).map(|t| t.len()))
    });
    let spade_pts: Vec<Point2<f64>> = pts.iter().map(|p| Point2::new(p[0], p[1])).collect();
    group.bench_with_input(BenchmarkId::new("spade", n), &spade_pts, |b, pts| {
        b.iter(|| {
            DelaunayTriangulation::<Point2<f64>>::bulk_load(black_box(pts.clone()))
                .map(|t| t.num_inner_faces())
        })
    });
    let del_pts: Vec<delaunator::Point> = pts
        .iter()
        .map(|p| delaunator::Point { x: p[0], y: p[1] })
        .collect();
    group.bench_with_input(BenchmarkId::new("delaunator", n), &del_pts, |b, pts| {
        b.iter(|| delaunator::triangulate(black_box(pts)).triangles.len())
    });
}

/// The pipeline's own sample points: bubbles of 1e3, 1e4, 1e5 particles (capped).
fn bench_pipeline_points(c: &mut Criterion) {
    let mut group = c.benchmark_group("triangulate/pipeline");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(5));
    for n in [1_000usize, 10_000, 100_000] {
        if n > max_particles() {
            continue;
        }
        let domain = layouts::bubbles(n, 1).expect("bubbles");
        let exact_mode = medial_blocks::mesher::exact_sampling();
        let sampled = sample_and_triangulate(&domain, &exact_mode).expect("sampling");
        compare(&mut group, n, &sampled.samples.points);
    }
    group.finish();
}

fn bench(c: &mut Criterion) {
    for (name, make) in [
        ("uniform", uniform as fn(usize) -> Vec<Point>),
        ("circles", circles),
    ] {
        let mut group = c.benchmark_group(format!("triangulate/{name}"));
        for n in [10_000usize, 100_000, 1_000_000] {
            let pts = make(n);
            if n >= 1_000_000 {
                group.sample_size(10);
                group.measurement_time(Duration::from_secs(8));
            } else {
                group.sample_size(20);
                group.measurement_time(Duration::from_secs(4));
            }
            compare(&mut group, n, &pts);
        }
        group.finish();
    }
}

criterion_group!(benches, bench_pipeline_points, bench);
criterion_main!(benches);
