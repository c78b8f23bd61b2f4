//! The core polygon of an inserted-hole template ([`medial_blocks::templates::core_angles`]):
//! its vertices leave the rays through the arc ends only where two of them would nearly
//! coincide, by the least-squares smallest move to a minimum gap.
//!
//! Oracles: the projection onto the cyclic gap constraints by Dykstra's alternating
//! projections (an independent slow solver of the same least-squares problem), the corner
//! angles of regular templates worked out by hand, and a layout from a sweep of unseen
//! layouts whose inserted hole is touched by a 3-degree arc (cells of 3.4 degrees before).
//! Where the ladder of the core starts ([`medial_blocks::templates::ladder_turn`]): the same
//! template quality whichever arc the angles start from (they are sorted from 0, so rounding
//! decided it), checked against every start.

use medial_blocks::domain::Domain;
use medial_blocks::mesh::BlockGrid;
use medial_blocks::templates::{
    core_angles, ladder_core, ladder_turn, spread_angles, template_min_angle, Core, GridCore,
};
use medial_blocks::{mesh, Options};
use proptest::prelude::*;
use std::f64::consts::{PI, TAU};

/// The cyclic gaps of increasing angles within one turn.
fn gaps(phi: &[f64]) -> Vec<f64> {
    let k = phi.len();
    (0..k)
        .map(|i| {
            if i + 1 < k {
                phi[i + 1] - phi[i]
            } else {
                phi[0] + TAU - phi[k - 1]
            }
        })
        .collect()
}

/// The least-squares nearest point to `theta` with every cyclic gap at least `gap`, by
/// Dykstra's alternating projections onto the `k` half-spaces `phi_{i+1} - phi_i >= gap`
/// (the last one across the turn). Slow and independent of the pool-adjacent-violators code.
fn dykstra(theta: &[f64], gap: f64) -> Vec<f64> {
    let k = theta.len();
    let mut x = theta.to_vec();
    let mut inc = vec![[0.0f64; 2]; k];
    for _ in 0..200_000 {
        let mut moved = 0.0f64;
        for i in 0..k {
            let j = (i + 1) % k;
            let wrap = if j == 0 { TAU } else { 0.0 };
            // y = x + increment of this half-space, then project y onto it.
            let yi = x[i] + inc[i][0];
            let yj = x[j] + inc[i][1];
            let short = gap - (yj + wrap - yi);
            let (pi, pj) = if short > 0.0 {
                (yi - short / 2.0, yj + short / 2.0)
            } else {
                (yi, yj)
            };
            inc[i] = [yi - pi, yj - pj];
            moved = moved.max((pi - x[i]).abs()).max((pj - x[j]).abs());
            x[i] = pi;
            x[j] = pj;
        }
        if moved < 1e-15 {
            break;
        }
    }
    x
}

/// The increasing angles `theta` (within one turn) taken from index `s` on, those before it
/// one turn up: the same arcs listed from arc `s`.
fn starting_at(theta: &[f64], s: usize) -> Vec<f64> {
    let k = theta.len();
    (0..k)
        .map(|i| theta[(i + s) % k] + if i + s >= k { TAU } else { 0.0 })
        .collect()
}

/// Increasing angles within one turn: `k` sorted uniform draws, some pulled together.
fn angles() -> impl Strategy<Value = Vec<f64>> {
    (
        4usize..12,
        prop::collection::vec(0.0f64..1.0, 12),
        0.0f64..1.0,
    )
        .prop_map(|(k, u, squeeze)| {
            let mut t: Vec<f64> = u[..k].iter().map(|x| x * TAU).collect();
            t.sort_by(f64::total_cmp);
            // Pull the second angle towards the first (a narrow arc).
            t[1] = t[0] + squeeze * squeeze * (t[1] - t[0]);
            t
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Where it answers, `spread_angles` keeps the order, leaves every gap at least `gap`
    /// and is the least-squares projection (Dykstra's answer).
    #[test]
    fn spread_angles_is_the_least_squares_projection(theta in angles(), fraction in 0.1f64..0.9) {
        prop_assume!(theta.windows(2).all(|w| w[0] < w[1]));
        let k = theta.len();
        let gap = fraction * TAU / k as f64;
        if let Some(phi) = spread_angles(&theta, gap) {
            for g in gaps(&phi) {
                prop_assert!(g >= gap - 1e-12, "gap {g} < {gap}");
            }
            let oracle = dykstra(&theta, gap);
            for (a, b) in phi.iter().zip(&oracle) {
                prop_assert!((a - b).abs() < 1e-9, "{phi:?} vs Dykstra {oracle:?}");
            }
            if gaps(&theta).iter().all(|&g| g >= gap) {
                prop_assert_eq!(&phi, &theta);
            }
        }
    }

    /// The ladder's start makes the template as good as any start can, whichever arc the
    /// (sorted) angles begin with: every cyclic start `s` of the same arcs (as a layout
    /// rotated so that arc `s` starts first) reaches the same smallest corner angle, which is
    /// the best over all `k` starts with their own core angles.
    #[test]
    fn the_ladder_start_does_not_depend_on_the_first_arc(theta in angles(), half in 0usize..2) {
        prop_assume!(theta.windows(2).all(|w| w[0] < w[1]));
        // An even count, as the template needs.
        let theta: Vec<f64> = if theta.len() % 2 == 1 {
            theta[half..theta.len() - 1 + half].to_vec()
        } else {
            theta
        };
        let k = theta.len();
        prop_assume!(k >= 4);
        let score = |t: &[f64]| {
            let (turn, phi) = ladder_turn(t);
            prop_assert!(turn < k / 2);
            Ok(template_min_angle(&starting_at(t, turn), &phi))
        };
        let best = (0..k)
            .map(|s| {
                let t = starting_at(&theta, s);
                template_min_angle(&t, &core_angles(&t))
            })
            .fold(f64::NEG_INFINITY, f64::max);
        for s in 0..k {
            let got = score(&starting_at(&theta, s))?;
            prop_assert!((got - best).abs() <= 1e-9, "start {s}: {got} against the best {best}");
        }
    }

    /// The chosen core is never worse than the rays (by the templates' smallest corner
    /// angle), and when it moves, no core gap is below a quarter of the regular one.
    #[test]
    fn core_angles_never_lower_the_smallest_corner(theta in angles()) {
        prop_assume!(theta.windows(2).all(|w| w[0] < w[1]));
        let k = theta.len();
        let phi = core_angles(&theta);
        prop_assert!(template_min_angle(&theta, &phi) >= template_min_angle(&theta, &theta));
        if phi != theta {
            for g in gaps(&phi) {
                prop_assert!(g >= 0.25 * TAU / k as f64 - 1e-12);
            }
        }
    }
}

/// Increasing angles within one turn, an even count from 4 to 64 (many arcs: a void that
/// dozens of particles border), some of them bunched.
fn many_angles() -> impl Strategy<Value = Vec<f64>> {
    (2usize..33, prop::collection::vec(0.05f64..1.0, 64)).prop_map(|(m, w)| {
        let k = 2 * m;
        let total: f64 = w[..k].iter().sum();
        let mut acc = 0.0;
        (0..k)
            .map(|i| {
                let t = acc / total * TAU;
                acc += w[i];
                t
            })
            .collect()
    })
}

/// The smallest and largest corner angles (radians) of the blocks of an inserted-hole
/// template on a unit hole with arc ends at `theta` and core vertices `q`: the ring blocks
/// (the arc's tangent at `p_i`) and the `core` quadrilaterals, each from `atan2` of its two
/// edges (reflex corners count as their full angle). Independent of the template code.
fn template_corners(theta: &[f64], q: &[[f64; 2]], core: &[[[f64; 2]; 4]]) -> (f64, f64) {
    let k = theta.len();
    let angle = |u: [f64; 2], v: [f64; 2]| {
        // Counter-clockwise from u to v, in [0, 2 pi).
        (u[0] * v[1] - u[1] * v[0])
            .atan2(u[0] * v[0] + u[1] * v[1])
            .rem_euclid(TAU)
    };
    let sub = |a: [f64; 2], b: [f64; 2]| [a[0] - b[0], a[1] - b[1]];
    let neg = |a: [f64; 2]| [-a[0], -a[1]];
    let mut quads: Vec<[([f64; 2], [f64; 2]); 4]> = Vec::new();
    for i in 0..k {
        let j = (i + 1) % k;
        let (pi, pj) = (
            [theta[i].cos(), theta[i].sin()],
            [theta[j].cos(), theta[j].sin()],
        );
        let (ti, tj) = (
            [-theta[i].sin(), theta[i].cos()],
            [-theta[j].sin(), theta[j].cos()],
        );
        // Corner: (direction to the next corner, direction to the previous one).
        quads.push([
            (ti, sub(q[i], pi)),
            (sub(q[j], pj), neg(tj)),
            (sub(q[i], q[j]), sub(pj, q[j])),
            (sub(pi, q[i]), sub(q[j], q[i])),
        ]);
    }
    for c in core {
        quads.push([0, 1, 2, 3].map(|t| (sub(c[(t + 1) % 4], c[t]), sub(c[(t + 3) % 4], c[t]))));
    }
    let (mut least, mut most) = (f64::INFINITY, 0.0f64);
    for quad in quads {
        for (next, prev) in quad {
            let a = angle(next, prev);
            least = least.min(a);
            most = most.max(a);
        }
    }
    (least, most)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The core [`ladder_core`] picks is never worse than the ladder on the circle
    /// ([`ladder_turn`]): a grid core is taken only when the circle's blocks have a corner
    /// below 20 degrees, and then its blocks' corners are all further from 0 and from half a
    /// turn than the circle ladder's worst.
    #[test]
    fn a_grid_core_is_taken_only_when_it_beats_the_circle(theta in many_angles()) {
        let k = theta.len();
        let (turn, phi) = ladder_turn(&theta);
        let t = starting_at(&theta, turn);
        let circle_q: Vec<[f64; 2]> =
            phi.iter().map(|a| [0.5 * a.cos(), 0.5 * a.sin()]).collect();
        let ladder: Vec<[[f64; 2]; 4]> = (0..k / 2 - 1)
            .map(|j| [circle_q[j], circle_q[j + 1], circle_q[k - 2 - j], circle_q[k - 1 - j]])
            .collect();
        let (lo, hi) = template_corners(&t, &circle_q, &ladder);
        let circle_score = lo.min(PI - hi);
        match ladder_core(&theta) {
            (r, Core::Circle(p)) => {
                prop_assert_eq!(r, turn);
                prop_assert_eq!(p, phi);
            }
            (r, Core::Grid(g)) => {
                prop_assert!(template_min_angle(&t, &phi).to_degrees() < 20.0);
                prop_assert_eq!(2 * (g.a + g.b), k);
                prop_assert!(g.a >= g.b && g.b >= 1);
                let t = starting_at(&theta, r);
                let q = g.ring();
                for (i, v) in q.iter().enumerate() {
                    prop_assert_eq!(GridCore::of_ring(g.a, g.b, i), {
                        let at = (0..=g.b)
                            .flat_map(|y| (0..=g.a).map(move |x| (x, y)))
                            .find(|&(x, y)| g.at(x, y) == *v);
                        at.unwrap()
                    });
                }
                let blocks: Vec<[[f64; 2]; 4]> = g.blocks().collect();
                prop_assert_eq!(blocks.len(), g.a * g.b);
                let (lo, hi) = template_corners(&t, &q, &blocks);
                prop_assert!(hi < PI, "a reflex corner");
                prop_assert!(
                    lo.min(PI - hi) > circle_score,
                    "grid {} x {}: corners {lo}..{hi} against the circle's {circle_score}",
                    g.a,
                    g.b
                );
            }
        }
    }
}

#[test]
fn regular_templates_have_the_corner_angles_worked_out_by_hand() {
    // k = 4: ring blocks with right angles at the arc, 135 degrees at the core; a square core.
    let square: Vec<f64> = (0..4).map(|i| i as f64 * TAU / 4.0).collect();
    assert!((template_min_angle(&square, &square) - PI / 2.0).abs() < 1e-12);
    // k = 6: the core hexagon's ladder is two trapezoids with 60-degree corners.
    let hexagon: Vec<f64> = (0..6).map(|i| 0.3 + i as f64 * TAU / 6.0).collect();
    assert!((template_min_angle(&hexagon, &hexagon) - PI / 3.0).abs() < 1e-12);
    // Regular templates are good: the rays stay.
    assert_eq!(core_angles(&square), square);
    assert_eq!(core_angles(&hexagon), hexagon);
    // A core vertex turned past its neighbour folds the blocks.
    let mut folded = square.clone();
    folded[1] = folded[2] + 0.1;
    assert!(template_min_angle(&square, &folded) < 0.0);
}

#[test]
fn three_arc_ends_within_seven_degrees_move_apart() {
    // The arc ends of the inserted hole of `data/inserted_narrow_arc.json` (rounded): arcs of
    // 1.1 and 5 degrees side by side put three core vertices within 7 degrees, and the core
    // block on them was a triangle with a 3.4-degree corner.
    let theta = [
        0.0432, 0.0629, 0.9377, 1.7565, 2.6679, 4.2920, 5.1029, 6.2262,
    ];
    let radial = template_min_angle(&theta, &theta);
    assert!(radial.to_degrees() < 4.0);
    let phi = core_angles(&theta);
    assert!(gaps(&phi).iter().all(|&g| g >= 0.25 * TAU / 8.0 - 1e-12));
    // Half the regular gap won: corners of at least 22.5 degrees.
    assert!(template_min_angle(&theta, &phi).to_degrees() > 22.0);
    // Only the crowded vertices moved.
    for i in 2..7 {
        assert_eq!(phi[i], theta[i]);
    }
}

/// Smallest interior angle (degrees) of the cells of `grid`, from `atan2` of each corner's
/// two edges (independent of the quality module).
fn min_cell_angle(grid: &BlockGrid) -> f64 {
    let w = grid.ni + 1;
    let mut least = f64::INFINITY;
    for j in 0..grid.nj {
        for i in 0..grid.ni {
            let c = [
                grid.nodes[i + j * w],
                grid.nodes[i + 1 + j * w],
                grid.nodes[i + 1 + (j + 1) * w],
                grid.nodes[i + (j + 1) * w],
            ];
            for t in 0..4 {
                let (o, a, b) = (c[t], c[(t + 1) % 4], c[(t + 3) % 4]);
                let u = [a[0] - o[0], a[1] - o[1]];
                let v = [b[0] - o[0], b[1] - o[1]];
                let ang = (u[0] * v[1] - u[1] * v[0])
                    .abs()
                    .atan2(u[0] * v[0] + u[1] * v[1]);
                least = least.min(ang.to_degrees());
            }
        }
    }
    least
}

/// 23 holes on a ring around an inserted centre hole, and 23 more on a second ring: the
/// centre hole's template has 24 arcs (one split in two), and its smallest angle was 15.7 or
/// 7.8 degrees depending on which arc's start angle rounded below zero (it did at 24
/// samples per circle, not at 32). Meshed at four rotations of the whole layout.
#[test]
fn a_ring_around_an_inserted_hole_keeps_its_smallest_angle_at_every_rotation() {
    let mut least = Vec::new();
    for rotation in [0.0, 1e-3, 0.05, 1.0] {
        let mut holes = Vec::new();
        for (ring, radius, phase) in [(1.0, 0.0687, 0.0), (2.0, 0.0687, PI / 23.0)] {
            for i in 0..23 {
                let t = rotation + phase + TAU * i as f64 / 23.0;
                holes.push(medial_blocks::Circle::new(
                    ring * t.cos(),
                    ring * t.sin(),
                    radius,
                ));
            }
        }
        let domain = Domain::bounded(medial_blocks::Circle::new(0.0, 0.0, 3.19), holes).unwrap();
        let options = Options {
            block_cells: Some(8),
            ..Options::default()
        };
        let m = mesh(&domain, &options).unwrap();
        assert_eq!(m.inserted_holes.len(), 1, "rotation {rotation}");
        let first_template = m.layout.blocks.len() - m.template_blocks;
        least.push(
            m.grids[first_template..]
                .iter()
                .map(min_cell_angle)
                .fold(f64::INFINITY, f64::min),
        );
    }
    for a in &least {
        assert!(*a > 15.0, "template cells down to {a} degrees ({least:?})");
    }
}

#[test]
fn an_inserted_hole_touched_by_a_narrow_arc_has_no_sliver_cells() {
    let domain = Domain::from_json_str(include_str!("data/inserted_narrow_arc.json")).unwrap();
    let m = mesh(&domain, &Options::default()).unwrap();
    assert_eq!(m.inserted_holes.len(), 1);
    assert!(m.template_blocks > 0);
    let first_template = m.layout.blocks.len() - m.template_blocks;
    let least = m.grids[first_template..]
        .iter()
        .map(min_cell_angle)
        .fold(f64::INFINITY, f64::min);
    // With the core vertices on the rays, a ring block and a core block were slivers whose
    // cells went down to 3.4 degrees.
    assert!(least > 10.0, "template cells down to {least} degrees");
    medial_blocks::fuzzing::check_mesh(&domain, &m).unwrap();
}

/// `n` holes evenly on the unit circle around an empty centre (the sweep's `ring` kind): macro
/// Delaunay refinement inserts a hole at the centre that all `n` gaps reach, so its template
/// has `n` arcs or more. On the ladder of a circle core the two end blocks have corners of
/// about `360 / k` degrees (8.8 degrees for 41 holes, the smallest angle of the sweep); the
/// grid core ([`medial_blocks::templates::grid_cores`]) has no corner that sharp.
#[test]
fn a_hole_ringed_by_many_others_gets_a_grid_core_without_slivers() {
    for n in [29usize, 41, 60] {
        let r = 0.3 * PI / n as f64;
        let holes: Vec<_> = (0..n)
            .map(|i| {
                let t = TAU * i as f64 / n as f64;
                medial_blocks::Circle::new(t.cos(), t.sin(), r)
            })
            .collect();
        let domain = Domain::bounded(medial_blocks::Circle::new(0.0, 0.0, 2.45), holes).unwrap();
        let options = Options {
            block_cells: Some(8),
            ..Options::default()
        };
        let m = mesh(&domain, &options).unwrap();
        let centre = m
            .inserted_holes
            .iter()
            .filter(|c| c.center[0].hypot(c.center[1]) < 1e-9)
            .count();
        assert_eq!(centre, 1, "n = {n}: {:?}", m.inserted_holes);
        let first_template = m.layout.blocks.len() - m.template_blocks;
        let least = m.grids[first_template..]
            .iter()
            .map(min_cell_angle)
            .fold(f64::INFINITY, f64::min);
        assert!(
            least > 14.0,
            "n = {n}: template cells down to {least} degrees"
        );
        medial_blocks::fuzzing::check_mesh(&domain, &m).unwrap();
    }
}

/// The periodic build fills its inserted holes with the same templates: 30 holes on a ring in
/// a 4 x 4 box leave a void whose inserted hole all 30 gaps reach (template cells of 12
/// degrees on the circle ladder), and it meshes exact with the grid core, no cell under 14
/// degrees, and passes the periodic mesh checks.
#[test]
fn a_periodic_void_ringed_by_many_holes_gets_a_grid_core() {
    let n = 30;
    let holes: Vec<_> = (0..n)
        .map(|i| {
            let t = TAU * i as f64 / n as f64;
            medial_blocks::Circle::new(2.0 + t.cos(), 2.0 + t.sin(), 0.3 * PI / n as f64)
        })
        .collect();
    let pd = medial_blocks::PeriodicDomain::new([4.0, 4.0], holes).unwrap();
    let options = Options {
        block_cells: Some(8),
        ..Options::default()
    };
    let m = medial_blocks::periodic::mesh_periodic(&pd, &options).unwrap();
    assert_eq!(m.geometry, medial_blocks::mesh::Geometry::Exact);
    assert!(m
        .inserted_holes
        .iter()
        .any(|c| (c.center[0] - 2.0).hypot(c.center[1] - 2.0) < 1e-9));
    let least = m
        .grids
        .iter()
        .map(min_cell_angle)
        .fold(f64::INFINITY, f64::min);
    assert!(least > 14.0, "cells down to {least} degrees");
    medial_blocks::fuzzing::periodic::check_periodic_mesh(&pd, &m, Default::default()).unwrap();
}
