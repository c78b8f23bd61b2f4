//! Issue #8, the sampling round after refinement inserted holes. The sampling takes over the
//! samples of circles whose sampling cannot differ (`sampling::sample_adaptive_after`, also
//! where the samples do not extend the earlier ones); when they do, the triangulation is
//! extended and the classes, the invariant check and the medial graph reuse the earlier round
//! where the insertion kept the triangles (`medial::reuse`). Each is checked against the full
//! computation (on the same extended triangulation): the same samples, the same classes, the
//! check empty exactly when the full one is, the same medial graph (vertices, arcs, numbering,
//! bit for bit); and the reuse happens (most circles taken over, most arcs kept).

use crate::common;

use medial_blocks::domain::{Circle, Domain};
use medial_blocks::layouts::SplitMix64;
use medial_blocks::medial::reuse::{
    classify_after, invariants_hold_after, medial_graph_after, medial_graph_taking,
    same_earlier_circles, Kept,
};
use medial_blocks::medial::{classify, medial_graph};
use medial_blocks::refine::refine;
use medial_blocks::sampling::{
    check_invariants, classify_and_check, nearest_gaps, sample_adaptive, sample_adaptive_after,
    sample_and_triangulate, sample_and_triangulate_after, sample_and_triangulate_taking,
    SampledDomain, SamplingOptions,
};

/// Domains with holes appended to `d0`: refinement's inserted holes (each prefix of them),
/// then tiny random holes, each at the clearest of a few random points (far enough from the
/// others that their sampling is unchanged and the samples extend the earlier ones).
fn extensions(d0: &Domain, rng: &mut SplitMix64) -> Vec<Domain> {
    let mut out = Vec::new();
    if let Ok(r) = refine(d0, Some(2.0), 10_000, &SamplingOptions::default()) {
        for k in 1..=r.inserted.len() {
            let mut holes = d0.holes().to_vec();
            holes.extend_from_slice(&r.inserted[..k]);
            out.extend(Domain::bounded(d0.bounding(), holes).ok());
        }
    }
    let b = d0.bounding();
    for _ in 0..10 {
        let mut holes = d0.holes().to_vec();
        for _ in 0..1 + (rng.next_f64() * 3.0) as usize {
            let mut best = ([0.0; 2], 0.0);
            for _ in 0..20 {
                let a = rng.next_f64() * std::f64::consts::TAU;
                let d = 0.9 * b.radius * rng.next_f64().sqrt();
                let c = [b.center[0] + d * a.cos(), b.center[1] + d * a.sin()];
                let clear = holes
                    .iter()
                    .map(|o| (c[0] - o.center[0]).hypot(c[1] - o.center[1]) - o.radius)
                    .fold(b.radius - d, f64::min);
                if clear > best.1 {
                    best = (c, clear);
                }
            }
            let r = best.1 * 0.02 * (1.0 + rng.next_f64());
            holes.push(Circle {
                center: best.0,
                radius: r,
            });
        }
        out.extend(Domain::bounded(b, holes).ok());
    }
    out
}

fn domains() -> Vec<Domain> {
    let mut out = vec![
        Domain::from_json_str(common::INSERTING).unwrap(),
        Domain::from_json_str(common::PREFIX).unwrap(),
    ];
    for s in 1..=3 {
        out.push(medial_blocks::layouts::bubbles(200, s).unwrap());
    }
    let mut rng = SplitMix64(7);
    for _ in 0..4 {
        let holes = common::random_holes(&mut rng, 12, 1.0, [0.0, 0.0], 0.02);
        out.extend(Domain::bounded(Circle::new(0.0, 0.0, 1.0), holes).ok());
    }
    out
}

/// The reusing functions against the full ones on the extended triangulation.
#[test]
fn reuse_equals_the_full_computation() {
    let opts = SamplingOptions::default();
    let mut rng = SplitMix64(11);
    let (mut extended, mut walked, mut kept_arcs) = (0, 0, 0);
    let (mut circles, mut circles_taken) = (0, 0);
    let mut later_rounds = 0;
    for d0 in domains() {
        let s0 = sample_and_triangulate(&d0, &opts).unwrap();
        for d1 in extensions(&d0, &mut rng) {
            let Ok(fresh) = sample_and_triangulate(&d1, &opts) else {
                continue;
            };
            // The first sampling of d1, as the pipeline's round 0 sees it.
            let gaps = nearest_gaps(&d1);
            let samples = sample_adaptive(&d1, &opts, &gaps, &[]).unwrap();
            let (again, taken) = sample_adaptive_after(&d1, &opts, &gaps, &[], Some(&s0)).unwrap();
            assert_eq!(again, samples);
            circles_taken += taken;
            circles += d0.hole_count() + 1;
            let Some(tri) = s0.triangulation.extended(&samples.points).unwrap() else {
                continue;
            };
            assert!(same_earlier_circles(&s0.samples, &samples));
            extended += 1;
            let kept = Kept::new(&s0.triangulation, &tri);
            assert!(kept.changed().len() < tri.len() / 2);
            let kinds = classify(&samples, &tri);
            let full = check_invariants(&samples, &tri, &kinds);
            assert_eq!(
                classify_and_check(&samples, &tri),
                (kinds.clone(), full.clone())
            );
            assert_eq!(classify_after(&samples, &tri, &s0.kinds, &kept), kinds);
            let holds = invariants_hold_after(&samples, &tri, &kinds, &s0, &kept);
            assert_eq!(holds, full.is_empty(), "{full:?}");
            if !holds {
                continue;
            }
            let graph = medial_graph(&samples, &tri, &kinds).unwrap();
            let reused = medial_graph_after(&samples, &tri, &kinds, &s0, &kept).unwrap();
            assert_eq!(reused, graph);
            let mut arcs = s0.medial.arcs.clone();
            let taken = medial_graph_taking(
                &samples,
                &tri,
                &kinds,
                &s0.medial.vertices,
                &mut arcs,
                &kept,
            );
            assert_eq!(taken.unwrap(), graph);
            let same = graph
                .arcs
                .iter()
                .filter(|a| a.triangles.iter().all(|&t| kept.contains(t as usize)))
                .count();
            kept_arcs += same;
            walked += graph.arcs.len() - same;
            // The pipeline: the same samples as a fresh sampling, and its classes and graph
            // those of the full computation on its (extended) triangulation.
            let after = sample_and_triangulate_after(&d1, &opts, Some(&s0)).unwrap();
            assert_eq!(after.samples, fresh.samples);
            check_pipeline(&after);
            let mut given = s0.clone();
            let moved = sample_and_triangulate_taking(&d1, &opts, Some(&mut given)).unwrap();
            assert_eq!(
                (&moved.samples, &moved.kinds, &moved.medial, moved.rounds),
                (&after.samples, &after.kinds, &after.medial, after.rounds)
            );
            assert_eq!(moved.thin_walls, after.thin_walls);
            // The arrays moved out of `given` give the same triangulation, also after a
            // further attempt (soft rounds) had them given back.
            common::assert_same_triangulation(&moved.triangulation, &after.triangulation);
            assert_eq!(given.triangulation.len(), 0);
            later_rounds += usize::from(after.rounds > 0);
            assert_eq!(after.medial.arcs.len(), fresh.medial.arcs.len());
        }
    }
    assert!(extended >= 5, "only {extended} extensions");
    assert!(
        circles_taken > circles / 2,
        "{circles_taken} of {circles} circles taken over"
    );
    assert!(kept_arcs > walked, "{kept_arcs} kept, {walked} walked");
    eprintln!("{later_rounds} extensions with later sampling rounds");
}

/// The pipeline's result is the full computation on its own samples and triangulation.
fn check_pipeline(s: &SampledDomain) {
    let kinds = classify(&s.samples, &s.triangulation);
    assert_eq!(s.kinds, kinds);
    assert!(check_invariants(&s.samples, &s.triangulation, &kinds).is_empty());
    assert_eq!(
        s.medial,
        medial_graph(&s.samples, &s.triangulation, &kinds).unwrap()
    );
}

/// Refinement's final sampling (reached through the reusing path on layouts that insert
/// holes) is the full computation on its triangulation.
#[test]
fn refinement_rounds_equal_the_full_computation() {
    let mut inserting = 0;
    for d0 in domains() {
        let r = refine(&d0, Some(2.0), 10_000, &SamplingOptions::default()).unwrap();
        inserting += usize::from(!r.inserted.is_empty());
        check_pipeline(&r.sampled);
    }
    assert!(inserting >= 2);
}

/// Hand-made extensions that break the invariants: eight samples of a small new circle placed
/// next to an earlier circle's surface (a gap far below the sample spacing) or straddling the
/// midpoint between two circles. The reusing check refuses exactly when the full check finds
/// violations, and some placements do break them.
#[test]
fn the_reusing_check_refuses_what_the_full_check_finds() {
    let opts = SamplingOptions::default();
    let (mut broken, mut cases) = (0, 0);
    for d0 in domains() {
        let s0 = sample_and_triangulate(&d0, &opts).unwrap();
        let holes = d0.holes();
        for (i, h) in holes.iter().enumerate().take(8) {
            for (gap, r) in [(1e-3, 0.05), (0.02, 0.3), (0.2, 0.5)] {
                let o = &holes[(i + 1) % holes.len()];
                let (dx, dy) = (o.center[0] - h.center[0], o.center[1] - h.center[1]);
                let l = dx.hypot(dy);
                let rad = r * h.radius;
                let along = h.radius + gap * h.radius + rad;
                let c = [h.center[0] + along * dx / l, h.center[1] + along * dy / l];
                let mut samples = s0.samples.clone();
                let id = holes.len() as i32;
                let first = samples.points.len() as u32;
                for (k, u) in medial_blocks::sampling::unit_offsets(8).iter().enumerate() {
                    samples.points.push([c[0] + rad * u[0], c[1] + rad * u[1]]);
                    samples.circle_of.push(id);
                    samples.index_of.push(k as u32);
                    samples.grid.push(k as u64);
                }
                samples.grid_counts.push(8);
                samples
                    .circles
                    .push(medial_blocks::sampling::CircleSamples {
                        circle: id,
                        first,
                        count: 8,
                        gap: gap * h.radius,
                    });
                let Ok(Some(tri)) = s0.triangulation.extended(&samples.points) else {
                    continue;
                };
                cases += 1;
                let kept = Kept::new(&s0.triangulation, &tri);
                let kinds = classify_after(&samples, &tri, &s0.kinds, &kept);
                assert_eq!(kinds, classify(&samples, &tri));
                let full = check_invariants(&samples, &tri, &kinds);
                assert_eq!(
                    classify_and_check(&samples, &tri),
                    (kinds.clone(), full.clone())
                );
                let holds = invariants_hold_after(&samples, &tri, &kinds, &s0, &kept);
                assert_eq!(holds, full.is_empty(), "{full:?}");
                broken += usize::from(!holds);
                if holds {
                    assert_eq!(
                        medial_graph_after(&samples, &tri, &kinds, &s0, &kept).unwrap(),
                        medial_graph(&samples, &tri, &kinds).unwrap()
                    );
                }
            }
        }
    }
    assert!(broken >= 5 && broken < cases, "{broken} of {cases} broken");
}

/// The fused pass on coarse uniform samplings (8 to 32 per circle) and on random points
/// dealt to five "circles" (the classes are combinatorial), which break every invariant
/// somewhere: the classes and violations of the two separate functions, in order.
#[test]
fn classify_and_check_is_classify_then_check() {
    use medial_blocks::geometry::Triangulation;
    use medial_blocks::sampling::{sample, CircleSamples, Samples};
    let mut cases: Vec<Samples> = Vec::new();
    for d in domains() {
        for n in [8, 16, 32] {
            let gaps = nearest_gaps(&d);
            cases.push(sample(&d, &vec![n; d.hole_count() + 1], &gaps));
        }
    }
    let mut rng = SplitMix64(5);
    for per in [3u32, 5, 12, 40] {
        let mut s = Samples::default();
        for id in -1..4 {
            s.circles.push(CircleSamples {
                circle: id,
                first: s.points.len() as u32,
                count: per,
                gap: 0.0,
            });
            for k in 0..per {
                s.points.push([rng.next_f64(), rng.next_f64()]);
                s.circle_of.push(id);
                s.index_of.push(k);
            }
        }
        cases.push(s);
    }
    let mut kinds_seen = std::collections::HashSet::new();
    for samples in cases {
        let Ok(tri) = Triangulation::new(&samples.points) else {
            continue;
        };
        let kinds = classify(&samples, &tri);
        let full = check_invariants(&samples, &tri, &kinds);
        kinds_seen.extend(full.iter().map(|v| std::mem::discriminant(&v.kind)));
        assert_eq!(classify_and_check(&samples, &tri), (kinds, full));
    }
    assert!(
        kinds_seen.len() >= 3,
        "{} kinds of violation",
        kinds_seen.len()
    );
}
