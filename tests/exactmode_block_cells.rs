//! `--block-cells` (a fixed grid per block) on layouts with narrow gaps: no wall cell of a
//! medial block sweeps more than 15 degrees of its circle (the option's promise, see
//! `exact_mode::equidistribution::arc_params_into`), so exact mode meshes them without falling
//! back to the paper pipeline and without inverted cells.
//!
//! Every figure is recomputed here from the node coordinates: the angle a wall cell sweeps is
//! measured from its circle's centre, inverted cells by [`common::count_inverted_cells`].
//! Before the fix, a hole 6e-8 from the bounding circle drew every node of the bounding
//! circle's wall to the gap and left one cell sweeping 188 degrees: exact mode saw it
//! inverted, fell back to paper geometry, and the mesh had 176 inverted cells.

use crate::common;

use medial_blocks::domain::{Circle, Domain};
use medial_blocks::layouts::SplitMix64;
use medial_blocks::mesh::Geometry;
use medial_blocks::{mesh, Mesh, Options};

/// The option's limit, in degrees.
const LIMIT_DEG: f64 = 15.0;

/// What a cell may sweep over the limit, relative. The node parameters see the wall angle
/// through the arc's 256 sub-steps, each taken as turning evenly; near an arc's end one
/// sub-step can turn a few degrees, so a cell that starts inside it can sweep a little more
/// than 15 degrees (at most 17.7 over 1 500 random layouts of the test below; before the fix,
/// 55 to 188 degrees).
const SLACK: f64 = 1.0 / 3.0;

fn block_cells(n: usize) -> Options {
    Options {
        block_cells: Some(n),
        ..Options::default()
    }
}

fn circle_of(d: &Domain, id: i32) -> Circle {
    if id < 0 {
        d.bounding()
    } else {
        d.holes()[id as usize]
    }
}

/// The angle (degrees) between the wall nodes `a` and `b`, seen from the centre of `c`.
fn swept_deg(c: &Circle, a: [f64; 2], b: [f64; 2]) -> f64 {
    let u = [a[0] - c.center[0], a[1] - c.center[1]];
    let v = [b[0] - c.center[0], b[1] - c.center[1]];
    (u[0] * v[1] - u[1] * v[0])
        .atan2(u[0] * v[0] + u[1] * v[1])
        .abs()
        .to_degrees()
}

/// The largest angle (degrees) one wall cell of a block on an input circle sweeps, seen from
/// the circle's centre, and the block where it is.
fn largest_wall_cell_deg(d: &Domain, m: &Mesh) -> (f64, usize) {
    let mut worst = (0.0f64, usize::MAX);
    for (b, block) in m.layout.blocks.iter().enumerate() {
        let Some(id) = block.wall else { continue };
        if id >= d.holes().len() as i32 {
            continue; // an inserted hole's template block
        }
        let c = circle_of(d, id);
        let wall = m.grids[b].side(0);
        for w in wall.windows(2) {
            let angle = swept_deg(&c, w[0], w[1]);
            if angle > worst.0 {
                worst = (angle, b);
            }
        }
    }
    worst
}

fn check(d: &Domain, n: usize, what: &str) {
    let m = mesh(d, &block_cells(n)).unwrap_or_else(|e| panic!("{what}, {n}: {e}"));
    assert_eq!(m.geometry, Geometry::Exact, "{what}, block cells {n}");
    assert_eq!(
        common::count_inverted_cells(&m.grids),
        0,
        "{what}, block cells {n}"
    );
    let (deg, b) = largest_wall_cell_deg(d, &m);
    assert!(
        deg <= LIMIT_DEG * (1.0 + SLACK),
        "{what}, block cells {n}: a wall cell of block {b} sweeps {deg} degrees (holes {:?})",
        d.holes()
    );
    medial_blocks::fuzzing::check_mesh(d, &m).unwrap_or_else(|e| panic!("{what}, {n}: {e}"));
}

/// Two holes, one of them 6e-8 (and 1.2e-8) from the bounding circle: the layouts a random
/// search found falling back to paper geometry with inverted cells at every block count.
#[test]
fn holes_by_the_bounding_circle_keep_exact_geometry_at_every_block_count() {
    let cases = [
        (
            [4.312532000086559, 7.8434434819523835, 1.0491564107176061],
            [-9.554955410758646, 1.6487443220835647, 0.30383931874819936],
        ),
        (
            [-8.23925580565596, -1.5191551239518628, 1.6218625449097777],
            [-4.748773166321583, 8.559189696131579, 0.21171235238931327],
        ),
    ];
    for (k, (a, b)) in cases.into_iter().enumerate() {
        let d = Domain::bounded(
            Circle::new(0.0, 0.0, 10.0),
            vec![Circle::new(a[0], a[1], a[2]), Circle::new(b[0], b[1], b[2])],
        )
        .unwrap();
        for n in [1, 2, 3, 4, 8, 16] {
            check(&d, n, &format!("case {k}"));
        }
    }
}

/// Random layouts for [`no_wall_cell_sweeps_more_than_15_degrees_near_narrow_gaps`]: 24, or
/// `BLOCK_CELLS_CASES` (a long run: `BLOCK_CELLS_CASES=2000 cargo test --release --test
/// suite exactmode_block_cells::`).
fn cases() -> u64 {
    std::env::var("BLOCK_CELLS_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(24)
}

/// Random layouts whose holes sit 1e-7..1e-2 from the bounding circle or from each other, at
/// random block counts: the limit holds on every wall cell of every medial block.
#[test]
fn no_wall_cell_sweeps_more_than_15_degrees_near_narrow_gaps() {
    let mut rng = SplitMix64(0x6a09_e667_f3bc_c908);
    let big_r = 10.0;
    for case in 0..cases() {
        let count = 1 + (rng.next_f64() * 8.0) as usize;
        let mut holes: Vec<Circle> = Vec::new();
        let mut tries = 0;
        while holes.len() < count && tries < 2_000 {
            tries += 1;
            let r = big_r * (0.01 + 0.15 * rng.next_f64());
            let gap = big_r * 10f64.powf(-8.0 + 6.0 * rng.next_f64());
            let angle = rng.next_f64() * std::f64::consts::TAU;
            let c = if holes.is_empty() || rng.next_f64() < 0.5 {
                // By the bounding circle.
                let dist = big_r - r - gap;
                [dist * angle.cos(), dist * angle.sin()]
            } else {
                // By an earlier hole.
                let o = holes[(rng.next_f64() * holes.len() as f64) as usize];
                let dist = o.radius + r + gap;
                [
                    o.center[0] + dist * angle.cos(),
                    o.center[1] + dist * angle.sin(),
                ]
            };
            let inside = c[0].hypot(c[1]) + r < big_r - 1e-7 * big_r;
            let apart = holes.iter().all(|o| {
                (c[0] - o.center[0]).hypot(c[1] - o.center[1]) - r - o.radius > 1e-7 * big_r
            });
            if inside && apart {
                holes.push(Circle::new(c[0], c[1], r));
            }
        }
        let d = Domain::bounded(Circle::new(0.0, 0.0, big_r), holes).unwrap();
        let n = 1 + (rng.next_f64() * 12.0) as usize;
        check(&d, n, &format!("random case {case}"));
    }
}

/// A periodic box with holes 1e-7..1e-3 apart (the periodic build shares the arc node
/// parameters): every wall cell within the limit, no inverted cell, exact geometry.
#[test]
fn periodic_narrow_gaps_keep_wall_cells_within_15_degrees() {
    use medial_blocks::periodic::{mesh_periodic, PeriodicDomain};
    let mut rng = SplitMix64(0xbb67_ae85_84ca_a73b);
    for case in 0..6 {
        let size = [4.0, 3.0];
        let r0 = 0.3 + 0.4 * rng.next_f64();
        let r1 = 0.1 + 0.3 * rng.next_f64();
        let gap = 10f64.powf(-7.0 + 4.0 * rng.next_f64());
        let angle = rng.next_f64() * std::f64::consts::TAU;
        let c0 = [2.0, 1.5];
        let dist = r0 + r1 + gap;
        let c1 = [c0[0] + dist * angle.cos(), c0[1] + dist * angle.sin()];
        let holes = vec![Circle::new(c0[0], c0[1], r0), Circle::new(c1[0], c1[1], r1)];
        let pd = PeriodicDomain::new(size, holes.clone()).unwrap();
        let n = 1 + (rng.next_f64() * 10.0) as usize;
        let m = mesh_periodic(&pd, &block_cells(n)).unwrap();
        let what = format!("periodic case {case}, gap {gap:e}, block cells {n}");
        assert_eq!(m.geometry, Geometry::Exact, "{what}");
        assert_eq!(common::count_inverted_cells(&m.grids), 0, "{what}");
        for (b, block) in m.layout.blocks.iter().enumerate() {
            if block.wall.is_none() {
                continue;
            }
            let wall = m.grids[b].side(0);
            // The hole whose circle carries the wall (relative 1e-9).
            let c = holes
                .iter()
                .find(|c| {
                    wall.iter().all(|p| {
                        ((p[0] - c.center[0]).hypot(p[1] - c.center[1]) - c.radius).abs()
                            <= 1e-9 * c.radius
                    })
                })
                .unwrap_or_else(|| panic!("{what}: block {b}'s wall is on no hole"));
            for w in wall.windows(2) {
                let deg = swept_deg(c, w[0], w[1]);
                assert!(
                    deg <= LIMIT_DEG * (1.0 + SLACK),
                    "{what}: a wall cell of block {b} sweeps {deg} degrees"
                );
            }
        }
    }
}
