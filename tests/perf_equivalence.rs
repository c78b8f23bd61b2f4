//! The fast paths of issue #8 against independent slow references:
//! - cell quality: the one-pass kernel (`quality::measure`, `quality_metrics`, `cell_fields`,
//!   `inverted_cells`) against the reference formulas written out here (the corner angle as
//!   the difference of its edges' directions, each `quality::angle_deg` of the edge vector,
//!   tested against libm in `perf_quality_atan` and `perf_quality_corners`, or `angle_deg`
//!   of the corner's cross and dot products within `1e-9` degrees of flat; the edge
//!   length `sqrt(x² + y²)`, `hypot` near underflow and overflow), on random quads (degenerate, inverted, tiny, huge and non-finite ones
//!   included) and on perturbed lattices; every figure bit for bit, the means as sums of
//!   per-block sums (the documented reduction order);
//! - the whole pipeline gives identical meshes and files on 1 and 2 threads.
//!
//! `PERF_TIMINGS=1 cargo test --release --test suite -- --nocapture perf_equivalence::timings` prints
//! the triangulation of the pipeline's sample points against spade (no assertion on time).

use crate::common;

use medial_blocks::geometry::Point;
use medial_blocks::layout::BlockLayout;
use medial_blocks::layouts::SplitMix64;
use medial_blocks::mesh::BlockGrid;
use medial_blocks::quality::{
    cell_fields, inverted_cells, measure, measure_all, quality_metrics, Histogram,
};
use proptest::prelude::*;

// ----------------------------------------------------------------------------------------------
// The reference: the quality formulas, written out cell by cell.
// ----------------------------------------------------------------------------------------------

/// The corner angles and Jacobians of a cell as `quality::cell_corners` defines them: the
/// difference of the directions of the corner's two edges (the edges taken `p0 -> p1`,
/// `p1 -> p2`, `p3 -> p2`, `p0 -> p3`, 180 added or taken off where the corner uses one the
/// other way), brought into `[0, 360)`; where that is within `1e-9` degrees of 0, 180 or 360,
/// or on the wrong side of 180 for the sign of the cross product, `angle_deg(cross, dot)`.
fn ref_corners(p: [Point; 4]) -> ([f64; 4], [f64; 4]) {
    use medial_blocks::quality::angle_deg;
    let dir = |from: Point, to: Point| angle_deg(to[1] - from[1], to[0] - from[0]);
    let (b, q, t, a) = (
        dir(p[0], p[1]),
        dir(p[1], p[2]),
        dir(p[3], p[2]),
        dir(p[0], p[3]),
    );
    let turns = [a - b, (b - q) + 180.0, q - t, (t - a) - 180.0];
    let mut angles = [0.0; 4];
    let mut jacobian = [0.0; 4];
    for k in 0..4 {
        let o = p[k];
        let a = p[(k + 1) % 4];
        let b = p[(k + 3) % 4];
        let e1 = [a[0] - o[0], a[1] - o[1]];
        let e2 = [b[0] - o[0], b[1] - o[1]];
        let cross = e1[0] * e2[1] - e1[1] * e2[0];
        let dot = e1[0] * e2[0] + e1[1] * e2[1];
        let mut turn = turns[k];
        while turn < 0.0 {
            turn += 360.0;
        }
        if turn >= 360.0 {
            turn -= 360.0;
        }
        let m = 1e-9;
        let kept = if cross > 0.0 {
            (m..=180.0 - m).contains(&turn)
        } else if cross < 0.0 {
            (180.0 + m..=360.0 - m).contains(&turn)
        } else {
            false
        };
        angles[k] = if kept { turn } else { angle_deg(cross, dot) };
        jacobian[k] = cross;
    }
    (angles, jacobian)
}

fn fold(v: [f64; 4], op: fn(f64, f64) -> f64) -> f64 {
    op(op(v[0], v[1]), op(v[2], v[3]))
}

fn len(a: Point, b: Point) -> f64 {
    let (x, y) = (b[0] - a[0], b[1] - a[1]);
    let sq = x * x + y * y;
    if (1e-280..=1e280).contains(&sq) {
        sq.sqrt()
    } else {
        x.hypot(y)
    }
}

fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else if a > 0.0 {
        f64::INFINITY
    } else {
        1.0
    }
}

/// (angles, min, max, skewness, edge ratio, scaled Jacobian, aspect ratio, min Jacobian).
struct RefCell {
    angles: [f64; 4],
    lo: f64,
    hi: f64,
    skew: f64,
    er: f64,
    sj: f64,
    ar: f64,
    min_jac: f64,
    jac: [f64; 4],
}

fn ref_cell(p: [Point; 4]) -> RefCell {
    let (angles, jac) = ref_corners(p);
    let lo = fold(angles, f64::min);
    let hi = fold(angles, f64::max);
    let edges = [
        len(p[0], p[1]),
        len(p[1], p[2]),
        len(p[2], p[3]),
        len(p[3], p[0]),
    ];
    let mut sj = f64::INFINITY;
    for k in 0..4 {
        let (la, lb) = (edges[k], edges[(k + 3) % 4]);
        let s = if la > 0.0 && lb > 0.0 {
            jac[k] / (la * lb)
        } else {
            0.0
        };
        if s.is_nan() || s < sj {
            sj = s;
        }
    }
    let (elo, ehi) = (fold(edges, f64::min), fold(edges, f64::max));
    let li = 0.5 * (edges[0] + edges[2]);
    let lj = 0.5 * (edges[1] + edges[3]);
    let mut min_jac = jac[0];
    for &x in &jac[1..] {
        if x.is_nan() || x < min_jac {
            min_jac = x;
        }
    }
    RefCell {
        angles,
        lo,
        hi,
        skew: (hi - 90.0).max(90.0 - lo) / 90.0,
        er: ratio(ehi, elo),
        sj,
        ar: ratio(li.max(lj), li.min(lj)),
        min_jac,
        jac,
    }
}

fn well_formed(g: &BlockGrid) -> bool {
    (g.ni + 1).checked_mul(g.nj + 1) == Some(g.nodes.len())
}

fn cells(g: &BlockGrid) -> Vec<[Point; 4]> {
    let mut out = Vec::new();
    for j in 0..g.nj {
        for i in 0..g.ni {
            out.push([
                g.node(i, j),
                g.node(i + 1, j),
                g.node(i + 1, j + 1),
                g.node(i, j + 1),
            ]);
        }
    }
    out
}

/// A metric summary of the reference: (min, max, histogram counts, outside, samples).
#[derive(Debug, PartialEq)]
struct RefSummary {
    min: Option<u64>,
    max: Option<u64>,
    counts: Vec<u64>,
    outside: u64,
    samples: u64,
}

fn ref_summary(
    values: &[f64],
    edges: &[f64],
    acceptable: [f64; 2],
    outside: Option<u64>,
) -> RefSummary {
    let mut h = Histogram::new(edges);
    let (mut min, mut max): (Option<f64>, Option<f64>) = (None, None);
    let mut out = 0;
    for &x in values {
        h.add(x);
        if x.is_finite() {
            min = Some(min.map_or(x, |m| m.min(x)));
            max = Some(max.map_or(x, |m| m.max(x)));
        }
        if !(x >= acceptable[0] && x <= acceptable[1]) {
            out += 1;
        }
    }
    RefSummary {
        min: min.map(f64::to_bits),
        max: max.map(f64::to_bits),
        counts: h.counts,
        outside: outside.unwrap_or(out),
        samples: values.len() as u64,
    }
}

fn summary_of(m: &medial_blocks::quality::MetricSummary) -> RefSummary {
    RefSummary {
        min: m.min.map(f64::to_bits),
        max: m.max.map(f64::to_bits),
        counts: m.histogram.counts.clone(),
        outside: m.outside,
        samples: m.samples,
    }
}

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Check every figure of `measure`, `quality_metrics`, `cell_fields` and `inverted_cells`
/// against the reference.
fn check_grids(grids: &[BlockGrid]) {
    let q = measure(grids);
    let (q2, m) = measure_all(&BlockLayout::default(), grids);
    assert_eq!(format!("{q:?}"), format!("{q2:?}"));
    assert_eq!(
        format!("{m:?}"),
        format!("{:?}", quality_metrics(&BlockLayout::default(), grids))
    );
    // Quality, reduced like the documented order: per-block sums, then blocks in order.
    let (mut n, mut inv, mut malformed) = (0usize, 0usize, 0usize);
    let (mut lo, mut hi, mut msj) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
    let (mut smin, mut smax) = (0.0, 0.0);
    let mut all: Vec<RefCell> = Vec::new();
    for g in grids {
        if !well_formed(g) {
            malformed += 1;
            assert!(cell_fields(g).min_angle_deg.is_empty());
            continue;
        }
        let (mut bmin, mut bmax) = (0.0, 0.0);
        let fields = cell_fields(g);
        for (c, p) in cells(g).into_iter().enumerate() {
            let r = ref_cell(p);
            n += 1;
            bmin += r.lo;
            bmax += r.hi;
            lo = lo.min(r.lo);
            hi = hi.max(r.hi);
            if r.jac.iter().any(|&x| x.is_nan() || x <= 0.0) {
                inv += 1;
            }
            if r.sj.is_nan() || (!msj.is_nan() && r.sj < msj) {
                msj = r.sj;
            }
            let got = [
                fields.min_angle_deg[c],
                fields.max_angle_deg[c],
                fields.min_jacobian[c],
                fields.equiangle_skewness[c],
                fields.edge_ratio[c],
                fields.scaled_jacobian[c],
                fields.aspect_ratio[c],
            ];
            let want = [r.lo, r.hi, r.min_jac, r.skew, r.er, r.sj, r.ar];
            for (k, (a, b)) in got.iter().zip(&want).enumerate() {
                assert!(same(*a, *b), "cell field {k} of {p:?}: {a:e} vs {b:e}");
            }
            all.push(r);
        }
        smin += bmin;
        smax += bmax;
    }
    assert_eq!(q.cells, n);
    assert_eq!(q.malformed_grids, malformed);
    assert_eq!(q.inverted_cells, inv);
    assert_eq!(inverted_cells(grids), inv);
    if n > 0 {
        assert!(same(q.min_angle_deg, lo), "{} vs {lo}", q.min_angle_deg);
        assert!(same(q.max_angle_deg, hi));
        assert!(
            same(q.min_scaled_jacobian, msj),
            "{} vs {msj}",
            q.min_scaled_jacobian
        );
        assert!(same(q.mean_min_angle_deg, smin / n as f64));
        assert!(same(q.mean_max_angle_deg, smax / n as f64));
    }
    use medial_blocks::quality::{
        ANGLE_ACCEPTABLE, ASPECT_ACCEPTABLE, EDGE_RATIO_ACCEPTABLE, SCALED_JACOBIAN_ACCEPTABLE,
        SKEWNESS_ACCEPTABLE,
    };
    let angles: Vec<f64> = all.iter().flat_map(|r| r.angles).collect();
    let angle_out = all
        .iter()
        .filter(|r| {
            let ok = |x: f64| (ANGLE_ACCEPTABLE[0]..=ANGLE_ACCEPTABLE[1]).contains(&x);
            !(ok(r.lo) && ok(r.hi))
        })
        .count() as u64;
    let mut want = ref_summary(
        &angles,
        &m.angle_deg.histogram.edges,
        ANGLE_ACCEPTABLE,
        None,
    );
    want.outside = angle_out;
    assert_eq!(summary_of(&m.angle_deg), want, "angle_deg");
    for (name, got, vals, acc) in [
        (
            "skewness",
            &m.equiangle_skewness,
            all.iter().map(|r| r.skew).collect::<Vec<_>>(),
            SKEWNESS_ACCEPTABLE,
        ),
        (
            "edge_ratio",
            &m.edge_ratio,
            all.iter().map(|r| r.er).collect(),
            EDGE_RATIO_ACCEPTABLE,
        ),
        (
            "scaled_jacobian",
            &m.scaled_jacobian,
            all.iter().map(|r| r.sj).collect(),
            SCALED_JACOBIAN_ACCEPTABLE,
        ),
        (
            "aspect_ratio",
            &m.aspect_ratio,
            all.iter().map(|r| r.ar).collect(),
            ASPECT_ACCEPTABLE,
        ),
    ] {
        let want = ref_summary(&vals, &got.histogram.edges, acc, None);
        assert_eq!(summary_of(got), want, "{name}");
    }
}

/// A perturbed, sheared, stretched lattice block with random spoilers: a few nodes moved
/// anywhere, duplicated, scaled to extreme magnitudes or made non-finite.
fn lattice(rng: &mut SplitMix64, ni: usize, nj: usize, wild: u32) -> BlockGrid {
    let (sx, sy) = (0.01 + 100.0 * rng.next_f64(), 0.01 + 3.0 * rng.next_f64());
    let shear = 2.0 * rng.next_f64() - 1.0;
    let jitter = 0.45 * rng.next_f64();
    let mut nodes = common::jittered_lattice(rng, ni, nj, [sx, sy], shear, jitter);
    for _ in 0..wild {
        let k = (rng.next_u64() % nodes.len() as u64) as usize;
        let other = (rng.next_u64() % nodes.len() as u64) as usize;
        nodes[k] = match rng.next_u64() % 9 {
            0 => nodes[other],
            1 => [f64::NAN, 0.0],
            2 => [f64::INFINITY, 1.0],
            3 => [nodes[k][0] * 1e150, nodes[k][1] * 1e150],
            4 => [nodes[k][0] * 1e-150, nodes[k][1] * 1e-160],
            5 => [nodes[other][0], nodes[k][1]],
            6 => [0.5 * (nodes[k][0] + nodes[other][0]), nodes[other][1]],
            _ => [
                100.0 * (rng.next_f64() - 0.5),
                100.0 * (rng.next_f64() - 0.5),
            ],
        };
    }
    BlockGrid { ni, nj, nodes }
}

fn coord() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => -10.0..10.0f64,
        1 => (-3i32..4).prop_map(f64::from),
        1 => prop_oneof![Just(0.0), Just(-0.0), Just(1e-170), Just(1e170), Just(f64::NAN)],
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Single random quads, any shape (degenerate, inverted, non-finite).
    #[test]
    fn random_quads_match_the_reference(q in prop::collection::vec(coord(), 8)) {
        let nodes = vec![[q[0], q[1]], [q[2], q[3]], [q[6], q[7]], [q[4], q[5]]];
        check_grids(&[BlockGrid { ni: 1, nj: 1, nodes }]);
    }

    /// Whole blocks (bins, extremes and sums across many cells), some malformed.
    #[test]
    fn random_blocks_match_the_reference(seed in any::<u64>(), blocks in 1usize..6) {
        let mut rng = SplitMix64(seed);
        let grids: Vec<BlockGrid> = (0..blocks)
            .map(|_| {
                let ni = 1 + (rng.next_u64() % 12) as usize;
                let nj = 1 + (rng.next_u64() % 12) as usize;
                let wild = (rng.next_u64() % 4) as u32;
                let mut g = lattice(&mut rng, ni, nj, wild);
                if rng.next_u64().is_multiple_of(10) {
                    g.nodes.pop();
                }
                g
            })
            .collect();
        check_grids(&grids);
    }
}

/// Exact axis-aligned squares sit on bin edges (angles of exactly 90 degrees, ratios of
/// exactly 1): every tie-break goes through the exact formulas.
#[test]
fn exact_squares_match_the_reference() {
    let mut nodes = Vec::new();
    for j in 0..=5 {
        for i in 0..=7 {
            nodes.push([i as f64 * 0.25, j as f64 * 0.25]);
        }
    }
    let g = BlockGrid {
        ni: 7,
        nj: 5,
        nodes,
    };
    check_grids(std::slice::from_ref(&g));
    let q = measure(&[g]);
    assert_eq!(q.min_angle_deg, 90.0);
    assert_eq!(q.max_angle_deg, 90.0);
}

/// Nearly equal cells: a sheared lattice whose nodes move by relative 1e-16..1e-9, so the
/// figures of many cells tie or nearly tie with each other and with the block's extremes,
/// rising, falling and alternating along the rows.
#[test]
fn near_ties_match_the_reference() {
    let mut rng = SplitMix64(11);
    for scale in [1e-16, 1e-13, 1e-11, 1e-10, 3e-10, 1e-9] {
        for order in 0..3 {
            let (ni, nj) = (9, 7);
            let mut nodes = Vec::new();
            for j in 0..=nj {
                for i in 0..=ni {
                    let step = match order {
                        0 => (i + j * ni) as f64,
                        1 => -((i + j * ni) as f64),
                        _ => ((i + j) % 2) as f64,
                    };
                    let r = rng.next_f64();
                    let d = scale * (step + r);
                    let (x, y) = (i as f64 * (1.0 + d), j as f64 * 0.7 * (1.0 - d));
                    nodes.push([x + 0.3 * y, y]);
                }
            }
            check_grids(&[BlockGrid { ni, nj, nodes }]);
        }
    }
}

/// Real meshes (both modes) against the reference.
#[test]
fn pipeline_meshes_match_the_reference() {
    for (domain, opts) in [
        (
            medial_blocks::Domain::hexagon_example(),
            medial_blocks::Options::default(),
        ),
        (
            medial_blocks::Domain::hexagon_example(),
            medial_blocks::Options::paper(),
        ),
    ] {
        let m = medial_blocks::mesh(&domain, &opts).expect("mesh");
        check_grids(&m.grids);
    }
}

/// The pipeline and its report give identical results on 1 and 2 threads.
#[test]
fn one_and_two_threads_agree() {
    let domain = medial_blocks::layouts::bubbles(40, 7).expect("layout");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let mut out = Vec::new();
            for opts in [
                medial_blocks::Options::default(),
                medial_blocks::Options::paper(),
            ] {
                let m = medial_blocks::mesh(&domain, &opts).expect("mesh");
                let r = medial_blocks::output::report::Report::from_mesh(&m);
                let bits = common::node_bits(&m);
                out.push((serde_json::to_string(&r).expect("json"), bits));
            }
            out
        })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.0, y.0);
        assert!(x.1 == y.1, "grid nodes differ between 1 and 2 threads");
        assert!(!x.1.is_empty());
    }
}

/// Triangulation of the pipeline's own sample points (random bubbles, final sampling) by this
/// engine and by spade on the same points, best of 3 runs each. Printed only, with
/// `PERF_TIMINGS=1` (sizes from `PERF_HOLES`, default `1000,10000`); the assertion is that both
/// give the same number of triangles (a function of the point set for points in general
/// position; ties may differ, so only when no co-circular group is reported).
#[test]
fn timings_triangulation_vs_spade() {
    use spade::Triangulation as _;
    if std::env::var_os("PERF_TIMINGS").is_none() {
        return;
    }
    let sizes = std::env::var("PERF_HOLES").unwrap_or_else(|_| "1000,10000".into());
    for holes in sizes
        .split(',')
        .filter_map(|s| s.trim().parse::<usize>().ok())
    {
        let domain = medial_blocks::layouts::bubbles(holes, 1).expect("layout");
        let sampled = medial_blocks::sampling::sample_and_triangulate(
            &domain,
            &medial_blocks::sampling::SamplingOptions::default(),
        )
        .expect("sampling");
        let pts = sampled.samples.points.clone();
        let best = |f: &dyn Fn() -> usize| {
            let mut t = f64::INFINITY;
            let mut n = 0;
            for _ in 0..3 {
                let s = std::time::Instant::now();
                n = f();
                t = t.min(s.elapsed().as_secs_f64());
            }
            (t, n)
        };
        let (te, ne) = best(&|| {
            medial_blocks::geometry::Triangulation::new(&pts)
                .expect("triangulate")
                .len()
        });
        let (ts, ns) = best(&|| {
            let v: Vec<spade::Point2<f64>> =
                pts.iter().map(|p| spade::Point2::new(p[0], p[1])).collect();
            spade::DelaunayTriangulation::<spade::Point2<f64>>::bulk_load(v)
                .expect("spade")
                .num_inner_faces()
        });
        println!(
            "{holes} holes, {} points: engine {:.1} ms ({ne} triangles), spade bulk_load {:.1} ms \
             ({ns} triangles), ratio {:.2}",
            pts.len(),
            te * 1e3,
            ts * 1e3,
            te / ts
        );
        if sampled.triangulation.cocircular_groups().is_empty() {
            assert_eq!(ne, ns);
        }
    }
}
