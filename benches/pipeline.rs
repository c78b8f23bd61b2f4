//! The whole pipeline and each stage on random bubbles (issue #8): `layouts::bubbles(n, 1)`
//! for n = 1e2, 1e3, 1e4, 1e5, exact mode with a 16 x 16 grid per block
//! (`Options::block_cells`).
//!
//! Benchmarks (`pipeline/<stage>/<n>`): `whole` (`mesh`), `generate` (the layout itself),
//! `validate` (`Domain::bounded`), `sampling_triangulation` (sampling with resampling,
//! triangulation, classes and medial graph), `triangulation` (the engine alone on the
//! pipeline's final sample points), `medial_graph` (classes + Algorithm 1), `blocking`
//! (Algorithm 2), `exact_mode` (Apollonius vertices, conic arcs, node counts and the spoke
//! grids: one call, `exact_mode::build`), `quality` (the report's figures) and `write_<format>`
//! (one writer into a temporary directory). For the split of `exact_mode` into geometry,
//! counts and grids run `medial-blocks mesh --timings`.
//!
//! The largest size is capped by `MEDIAL_BENCH_MAX` (default `1e4`; `1e5` adds 100 000
//! particles, which needs minutes per benchmark and several GB of memory); a filter selects
//! stages as usual: `MEDIAL_BENCH_MAX=1e3 cargo bench --bench pipeline -- whole`.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use medial_blocks::geometry::Triangulation;
use medial_blocks::output::{report::Report, write_files, Format};
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
use medial_blocks::{blocking, exact_mode, layouts, medial, mesh, Domain, Options};
use std::time::Duration;

const SEED: u64 = 1;
const SIZES: [usize; 4] = [100, 1_000, 10_000, 100_000];

/// `MEDIAL_BENCH_MAX` (`1e4`, `10000`, ...), default 1e4.
fn max_particles() -> usize {
    std::env::var("MEDIAL_BENCH_MAX")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 1.0)
        .map_or(10_000, |v| v as usize)
}

fn options() -> Options {
    Options {
        block_cells: Some(16),
        ..Options::default()
    }
}

fn bench(c: &mut Criterion) {
    let max = max_particles();
    let opts = options();
    for n in SIZES.into_iter().filter(|&n| n <= max) {
        let domain = layouts::bubbles(n, SEED).expect("bubbles");
        let sampled =
            sample_and_triangulate(&domain, &SamplingOptions::default()).expect("sampling");
        let blocks = blocking::build_layout(&domain, &opts).expect("blocking");
        let m = mesh(&domain, &opts).expect("mesh");
        let dir = tempfile::tempdir().expect("temporary directory");

        let mut g = c.benchmark_group("pipeline");
        g.sample_size(10);
        g.warm_up_time(Duration::from_secs(1));
        g.measurement_time(Duration::from_secs(if n >= 10_000 { 20 } else { 5 }));
        let id = |stage: &str| BenchmarkId::new(stage, n);

        g.bench_function(id("whole"), |b| {
            b.iter(|| mesh(black_box(&domain), &opts).map(|m| m.grids.len()))
        });
        // The CLI's `--format json` job: the mesh and its report, with the nodes held until
        // the report has read them, and measured as the grids are made without holding them
        // (`Options::keep_nodes`; in a loop the allocator hands back warm memory, so the
        // fresh pages a single CLI run saves do not show here).
        let measured = Options {
            keep_nodes: false,
            ..opts.clone()
        };
        for (name, o) in [
            ("whole_report", &opts),
            ("whole_report_measured", &measured),
        ] {
            g.bench_function(id(name), |b| {
                b.iter(|| mesh(black_box(&domain), o).map(|m| Report::from_mesh(&m).cells))
            });
        }
        g.bench_function(id("generate"), |b| {
            b.iter(|| layouts::bubbles(black_box(n), SEED).map(|d| d.hole_count()))
        });
        g.bench_function(id("validate"), |b| {
            b.iter(|| {
                Domain::bounded(domain.bounding(), black_box(domain.holes().to_vec()))
                    .map(|d| d.hole_count())
            })
        });
        g.bench_function(id("sampling_triangulation"), |b| {
            b.iter(|| {
                sample_and_triangulate(black_box(&domain), &SamplingOptions::default())
                    .map(|s| s.samples.len())
            })
        });
        g.bench_function(id("triangulation"), |b| {
            b.iter(|| Triangulation::new(black_box(&sampled.samples.points)).map(|t| t.len()))
        });
        g.bench_function(id("medial_graph"), |b| {
            b.iter(|| {
                let kinds = medial::classify(&sampled.samples, &sampled.triangulation);
                medial::medial_graph(&sampled.samples, &sampled.triangulation, &kinds)
                    .map(|g| g.arc_count())
            })
        });
        g.bench_function(id("blocking"), |b| {
            b.iter(|| {
                blocking::blocks(black_box(&domain), &sampled.samples, &sampled.medial)
                    .map(|(l, _)| l.blocks.len())
            })
        });
        g.bench_function(id("exact_mode"), |b| {
            b.iter(|| exact_mode::build(black_box(&domain), &blocks, &opts).map(|e| e.grids.len()))
        });
        g.bench_function(id("quality"), |b| {
            b.iter(|| Report::from_mesh(black_box(&m)).cells)
        });
        for f in [
            Format::Vtk,
            Format::Vtu,
            Format::Plot3d,
            Format::Gmsh,
            Format::Svg,
            Format::Json,
        ] {
            let out = dir.path().join(f.name());
            g.bench_function(id(&format!("write_{}", f.name())), |b| {
                b.iter(|| write_files(black_box(&m), &out, &[f]).is_ok())
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
