//! The quality report's per-block pass (issue #8: vectorised row loop, table bins) against a
//! straightforward loop over the library's reference formula `quality::cell_metrics`, on random
//! grids with degenerate, inverted, tiny, huge and non-finite cells; and the same report for 1
//! and 2 threads.

use crate::common;

use medial_blocks::geometry::Point;
use medial_blocks::layout::BlockLayout;
use medial_blocks::layouts::SplitMix64;
use medial_blocks::mesh::BlockGrid;
use medial_blocks::quality::{
    cell_corners, cell_metrics, inverted_blocks, measure_all, Histogram, MetricSummary, Quality,
    QualityMetrics,
};
use proptest::prelude::*;

/// One metric the straightforward way: every value in visiting order.
struct Summary {
    min: Option<f64>,
    max: Option<f64>,
    hist: Histogram,
    outside: u64,
    samples: u64,
}

impl Summary {
    fn new(like: &MetricSummary) -> Summary {
        Summary {
            min: None,
            max: None,
            hist: Histogram::new(&like.histogram.edges),
            outside: 0,
            samples: 0,
        }
    }
    fn value(&mut self, x: f64) {
        self.samples += 1;
        self.hist.add(x);
        if x.is_finite() {
            self.min = Some(self.min.map_or(x, |m| m.min(x)));
            self.max = Some(self.max.map_or(x, |m| m.max(x)));
        }
    }
    fn check(&self, got: &MetricSummary, name: &str) {
        let bits = |v: Option<f64>| v.map(f64::to_bits);
        assert_eq!(bits(got.min), bits(self.min), "{name} min");
        assert_eq!(bits(got.max), bits(self.max), "{name} max");
        assert_eq!(got.histogram.counts, self.hist.counts, "{name} counts");
        assert_eq!(got.outside, self.outside, "{name} outside");
        assert_eq!(got.samples, self.samples, "{name} samples");
    }
}

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// The report of `measure_all` against a loop over `cell_metrics`.
fn check(grids: &[BlockGrid]) {
    let (q, m): (Quality, QualityMetrics) = measure_all(&BlockLayout::default(), grids);
    let mut s = [
        Summary::new(&m.angle_deg),
        Summary::new(&m.equiangle_skewness),
        Summary::new(&m.edge_ratio),
        Summary::new(&m.scaled_jacobian),
        Summary::new(&m.aspect_ratio),
    ];
    let (mut cells, mut inverted, mut malformed) = (0usize, 0usize, 0usize);
    let (mut lo, mut hi, mut msj) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
    let (mut sum_min, mut sum_max) = (0.0, 0.0);
    for g in grids {
        if (g.ni + 1).checked_mul(g.nj + 1) != Some(g.nodes.len()) {
            malformed += 1;
            continue;
        }
        let (mut bmin, mut bmax) = (0.0, 0.0);
        for j in 0..g.nj {
            for i in 0..g.ni {
                let p: [Point; 4] = [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ];
                let c = cell_metrics(p);
                cells += 1;
                bmin += c.min_angle_deg;
                bmax += c.max_angle_deg;
                lo = lo.min(c.min_angle_deg);
                hi = hi.max(c.max_angle_deg);
                if cell_corners(p)
                    .jacobian
                    .iter()
                    .any(|&x| x.is_nan() || x <= 0.0)
                {
                    inverted += 1;
                }
                if c.scaled_jacobian.is_nan() || (!msj.is_nan() && c.scaled_jacobian < msj) {
                    msj = c.scaled_jacobian;
                }
                for a in c.angle_deg {
                    s[0].value(a);
                }
                let ok = |x: f64, r: [f64; 2]| x >= r[0] && x <= r[1];
                let acc = m.angle_deg.acceptable;
                s[0].outside += u64::from(!(ok(c.min_angle_deg, acc) && ok(c.max_angle_deg, acc)));
                let figs = [
                    c.equiangle_skewness,
                    c.edge_ratio,
                    c.scaled_jacobian,
                    c.aspect_ratio,
                ];
                let accs = [
                    m.equiangle_skewness.acceptable,
                    m.edge_ratio.acceptable,
                    m.scaled_jacobian.acceptable,
                    m.aspect_ratio.acceptable,
                ];
                for k in 0..4 {
                    s[k + 1].value(figs[k]);
                    s[k + 1].outside += u64::from(!ok(figs[k], accs[k]));
                }
            }
        }
        sum_min += bmin;
        sum_max += bmax;
    }
    assert_eq!(q.cells, cells);
    assert_eq!(q.inverted_cells, inverted);
    assert_eq!(q.malformed_grids, malformed);
    if cells > 0 {
        assert!(same(q.min_angle_deg, lo), "{} vs {lo}", q.min_angle_deg);
        assert!(same(q.max_angle_deg, hi), "{} vs {hi}", q.max_angle_deg);
        assert!(
            same(q.min_scaled_jacobian, msj),
            "{} vs {msj}",
            q.min_scaled_jacobian
        );
        assert!(same(q.mean_min_angle_deg, sum_min / cells as f64));
        assert!(same(q.mean_max_angle_deg, sum_max / cells as f64));
    }
    s[0].check(&m.angle_deg, "angle");
    s[1].check(&m.equiangle_skewness, "skewness");
    s[2].check(&m.edge_ratio, "edge ratio");
    s[3].check(&m.scaled_jacobian, "scaled jacobian");
    s[4].check(&m.aspect_ratio, "aspect ratio");
}

/// A sheared, stretched, jittered lattice at scale `scale`, with `wild` spoiled nodes:
/// duplicated (zero-length edges), collinear, swapped (inverted cells), scaled to extreme
/// magnitudes, NaN or infinite.
fn grid(r: &mut SplitMix64, ni: usize, nj: usize, scale: f64, wild: u32) -> BlockGrid {
    let (sx, sy) = (
        scale * (0.05 + 20.0 * r.next_f64()),
        scale * (0.05 + 3.0 * r.next_f64()),
    );
    let (shear, jitter) = (2.0 * r.next_f64() - 1.0, 0.6 * r.next_f64());
    let mut nodes = common::jittered_lattice(r, ni, nj, [sx, sy], shear, jitter);
    for _ in 0..wild {
        let k = (r.next_u64() % nodes.len() as u64) as usize;
        let o = (r.next_u64() % nodes.len() as u64) as usize;
        match r.next_u64() % 8 {
            0 => nodes[k] = nodes[o],
            1 => nodes[k] = [f64::NAN, nodes[k][1]],
            2 => nodes[k] = [nodes[k][0], f64::INFINITY],
            3 => nodes[k] = [nodes[k][0] * 1e145, nodes[k][1] * 1e145],
            4 => nodes[k] = [nodes[k][0] * 1e-145, nodes[k][1] * 1e-150],
            5 => {
                nodes[k] = [
                    0.5 * (nodes[k][0] + nodes[o][0]),
                    0.5 * (nodes[k][1] + nodes[o][1]),
                ]
            }
            _ => nodes.swap(k, o),
        }
    }
    BlockGrid { ni, nj, nodes }
}

fn grids(seed: u64, blocks: usize) -> Vec<BlockGrid> {
    let mut r = SplitMix64(seed);
    (0..blocks)
        .map(|_| {
            let ni = 1 + (r.next_u64() % 20) as usize;
            let nj = 1 + (r.next_u64() % 8) as usize;
            let scale = [1.0, 1e-120, 1e120, 1e-160, 1e-3][(r.next_u64() % 5) as usize];
            let wild = [0, 0, 1, 3][(r.next_u64() % 4) as usize];
            let mut g = grid(&mut r, ni, nj, scale, wild);
            if r.next_u64().is_multiple_of(16) {
                g.nodes.pop();
            }
            g
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// The inverted-block check finds exactly the well-formed blocks (a malformed grid, one
    /// node short, has no cells to count) with a cell whose corner Jacobian is not positive in
    /// the cell-by-cell reference, in increasing order.
    #[test]
    fn inverted_blocks_equal_the_cell_by_cell_reference(seed in any::<u64>(), blocks in 1usize..40) {
        let g = grids(seed, blocks);
        let want: Vec<usize> = (0..g.len())
            .filter(|&b| {
                let gr = &g[b];
                gr.nodes.len() == (gr.ni + 1) * (gr.nj + 1)
                    && (0..gr.nj).flat_map(|j| (0..gr.ni).map(move |i| (i, j))).any(|(i, j)| {
                    let p = [gr.node(i, j), gr.node(i + 1, j), gr.node(i + 1, j + 1), gr.node(i, j + 1)];
                    cell_corners(p).jacobian.iter().any(|&x| x.is_nan() || x <= 0.0)
                })
            })
            .collect();
        prop_assert_eq!(inverted_blocks(&g), want);
    }

    #[test]
    fn report_equals_a_loop_over_cell_metrics(seed in any::<u64>(), blocks in 1usize..8) {
        check(&grids(seed, blocks));
    }
}

/// Exact squares: every angle on a bin edge (90), every ratio 1.
#[test]
fn squares_sit_on_bin_edges() {
    let nodes = (0..=4)
        .flat_map(|j| (0..=6).map(move |i| [i as f64 * 0.5, j as f64 * 0.5]))
        .collect();
    check(&[BlockGrid {
        ni: 6,
        nj: 4,
        nodes,
    }]);
}

/// Blocks too wide or tall for one band of rows (the block pass measures a band of about 512
/// nodes at once, one row at a time when a row alone is longer), with spoiled nodes: the
/// report of the loop over `cell_metrics`.
#[test]
fn wide_and_tall_blocks_in_bands() {
    let mut r = SplitMix64(5);
    let shapes = [
        (600, 2, 0),
        (700, 1, 3),
        (300, 5, 2),
        (40, 30, 1),
        (16, 16, 0),
        (1, 600, 3),
    ];
    let g: Vec<BlockGrid> = shapes
        .iter()
        .map(|&(ni, nj, wild)| grid(&mut r, ni, nj, 1.0, wild))
        .collect();
    check(&g);
}

/// Several chunks of blocks (the parallel unit), on 1 and 2 threads: the same report, bit for
/// bit, and that of the loop over `cell_metrics`.
#[test]
fn one_and_two_threads_give_the_same_report() {
    let g = grids(99, 300);
    check(&g);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| format!("{:?}", measure_all(&BlockLayout::default(), &g)))
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(1));
}

/// Annular sectors (nodes `c + r_j (cos t_i, sin t_i)`): every cell an isosceles trapezoid,
/// whose four corners have the same scaled Jacobian in exact arithmetic, so the cell pass's
/// one-division pick of the least is often undecided (two products compare equal) and loop 2
/// takes the scaled Jacobian by the reference expression for those cells (`REDO`), as around
/// a centred hole: the report of the loop over `cell_metrics`, bit for bit. Some sectors have
/// a node moved, so exact and redone cells mix in a band.
#[test]
fn annular_sectors_of_isosceles_trapezoids() {
    let mut r = SplitMix64(11);
    let sector = |c: Point, r0: f64, r1: f64, t0: f64, t1: f64, ni: usize, nj: usize| {
        let nodes: Vec<Point> = (0..=nj)
            .flat_map(|j| {
                (0..=ni).map(move |i| {
                    let rad = r0 + (r1 - r0) * j as f64 / nj as f64;
                    let t = t0 + (t1 - t0) * i as f64 / ni as f64;
                    [c[0] + rad * t.cos(), c[1] + rad * t.sin()]
                })
            })
            .collect();
        BlockGrid { ni, nj, nodes }
    };
    let mut g = vec![
        sector(
            [0.0, 0.0],
            1.0,
            1.0001,
            0.0,
            std::f64::consts::FRAC_PI_4,
            700,
            4,
        ),
        sector(
            [0.0, 0.0],
            1.0,
            2.0,
            0.0,
            std::f64::consts::FRAC_PI_2,
            64,
            64,
        ),
        sector([3.5, -1.25], 0.5, 0.75, 1.0, 2.0, 16, 16),
        sector([1e3, 1e3], 1e-3, 2e-3, -0.5, 0.5, 32, 8),
    ];
    for _ in 0..4 {
        let mut s = sector([0.0, 0.0], 1.0, 1.5, 0.25, 1.25, 24, 12);
        let k = (r.next_f64() * s.nodes.len() as f64) as usize % s.nodes.len();
        s.nodes[k][0] += 1e-3 * (r.next_f64() - 0.5);
        g.push(s);
    }
    check(&g);
}
