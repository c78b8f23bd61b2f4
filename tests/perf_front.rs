//! Issue #8, the front end at scale: the fast paths of refinement and Blocking2D against
//! slow references computed alongside.
//! - refinement reuses the Apollonius solves of the previous round for vertices with the same
//!   circles and position ([`vertex_circles_reusing`]): the circles it returns equal a fresh
//!   solve of every vertex of the final graph, and reuse actually happens.

mod common;

use medial_blocks::cocircular::{vertex_circles, vertex_circles_reusing};
use medial_blocks::domain::{Circle, Domain};
use medial_blocks::layouts::SplitMix64;
use medial_blocks::refine::refine;
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};

/// A layout whose refinement inserts holes (tiny holes next to larger ones).
const INSERTING: &str = r#"{"bounding": {"center": [0.0, 0.0], "radius": 1.0}, "holes": [{"center": [0.3191541531691544, -0.3717929964389844], "radius": 0.24464422640973763}, {"center": [-0.11404744597041541, 0.08146095395643421], "radius": 0.11128467651604039}, {"center": [-0.42552889518459386, -0.38974998510540637], "radius": 0.0750062319977368}, {"center": [0.2359704484055954, 0.25273697336967405], "radius": 0.13286706779388338}, {"center": [-0.42666764696355597, -0.6507308368236295], "radius": 0.09961340826274921}, {"center": [-0.23212309121288838, 0.8791544668853195], "radius": 0.05751471364390008}, {"center": [-0.32687904034838855, -0.5760590860014616], "radius": 0.024988992683331306}, {"center": [-0.24251728387830382, 0.7025270240084398], "radius": 0.11940545640071007}, {"center": [-0.4207493523072746, 0.7239570940575171], "radius": 0.060101631399608516}, {"center": [-0.05955622155850428, -0.08922488265519388], "radius": 0.00012118752906053852}, {"center": [-0.07489413579200777, 0.6892364901244837], "radius": 0.00010388535976705469}, {"center": [0.9854949986492719, -0.13332433619018963], "radius": 0.00010024369325342005}]}"#;

/// Random layouts with tiny holes near the others, so that refinement often inserts holes.
fn layouts() -> Vec<Domain> {
    let mut out = vec![Domain::from_json_str(INSERTING).expect("valid layout")];
    for seed in 0..12u64 {
        let mut rng = SplitMix64(seed);
        let mut holes = common::random_holes(&mut rng, 8, 1.0, [0.0, 0.0], 0.02);
        for _ in 0..3 {
            let r = 1e-4 * (1.0 + rng.next_f64());
            let a = rng.next_f64() * std::f64::consts::TAU;
            let d = 0.9 * rng.next_f64().sqrt();
            let c = [d * a.cos(), d * a.sin()];
            let clear = holes
                .iter()
                .all(|o| (c[0] - o.center[0]).hypot(c[1] - o.center[1]) - o.radius - r > 1e-3);
            if clear {
                holes.push(Circle {
                    center: c,
                    radius: r,
                });
            }
        }
        if let Ok(d) = Domain::bounded(Circle::new(0.0, 0.0, 1.0), holes) {
            out.push(d);
        }
    }
    out
}

/// The circles refinement returns are a fresh solve of every vertex of its final graph.
#[test]
fn refinement_circles_equal_fresh_solves() {
    let sampling = SamplingOptions::default();
    let mut inserting = 0;
    for d in layouts() {
        let Ok(r) = refine(&d, Some(2.0), 10_000, &sampling) else {
            continue;
        };
        inserting += usize::from(!r.inserted.is_empty());
        let fresh = vertex_circles(&r.domain, &r.sampled.medial);
        assert_eq!(r.circles, fresh);
    }
    assert!(inserting >= 2, "only {inserting} layouts insert holes");
}

/// Reuse across an appended hole: equal to a fresh solve, and most vertices are reused (the
/// count of vertices with the same circles and position bits, computed here).
#[test]
fn reusing_the_previous_round_is_exact() {
    let sampling = SamplingOptions::default();
    let d0 = Domain::from_json_str(INSERTING).unwrap();
    let r = refine(&d0, Some(2.0), 10_000, &sampling).unwrap();
    assert!(!r.inserted.is_empty());
    let s0 = sample_and_triangulate(&d0, &sampling).unwrap();
    let c0 = vertex_circles(&d0, &s0.medial);
    for k in 1..=r.inserted.len() {
        let mut holes = d0.holes().to_vec();
        holes.extend_from_slice(&r.inserted[..k]);
        let d1 = Domain::bounded(d0.bounding(), holes).unwrap();
        let s1 = sample_and_triangulate(&d1, &sampling).unwrap();
        let reused = vertex_circles_reusing(&d1, &s1.medial, Some((&s0.medial, &c0)));
        assert_eq!(reused, vertex_circles(&d1, &s1.medial));
        let same = s1
            .medial
            .vertices
            .iter()
            .filter(|v| {
                s0.medial.vertices.iter().any(|u| {
                    u.circles == v.circles
                        && u.position.map(f64::to_bits) == v.position.map(f64::to_bits)
                })
            })
            .count();
        assert!(same > 0, "no vertex survives the insertion of {k} holes");
    }
}
