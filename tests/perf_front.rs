//! Issue #8, the front end at scale: the fast paths of refinement and Blocking2D against
//! slow references computed alongside.
//! - refinement reuses the Apollonius solves of the previous round for vertices with the same
//!   circles and position ([`vertex_circles_reusing`]): the circles it returns equal a fresh
//!   solve of every vertex of the final graph, and reuse actually happens; taking them
//!   (moved, [`vertex_circles_taking`]) gives the same circles as cloning them;
//! - Blocking2D's corner and spoke maps indexed by sample (not hashed), the block area with
//!   reused buffers and the contraction's sorted corner lookup: checked against hash maps and
//!   the area as first written, on bubbles and refined layouts;
//! - the collapse selection's per-arc data kept for the local rebuilds: the same choice as
//!   `select_forced` from scratch for random exclusions and forced arcs;
//! - the extended triangulation (new samples inserted into the previous round's): the triangle
//!   set of a fresh one, and refined meshes that use it pass `check_mesh`.

use crate::common;

use medial_blocks::blocking::{block_area, blocks, collapsed_blocking_with};
use medial_blocks::cocircular::{vertex_circles, vertex_circles_reusing, vertex_circles_taking};
use medial_blocks::collapse::{select_forced, ArcLength, Selection};
use medial_blocks::domain::{Circle, Domain};
use medial_blocks::geometry::verify::verify_exact;
use medial_blocks::geometry::Triangulation;
use medial_blocks::layout::{BlockLayout, Curve, EdgeKind, SideRef};
use medial_blocks::layouts::SplitMix64;
use medial_blocks::refine::refine;
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
use medial_blocks::Options;
use proptest::prelude::*;
use std::collections::HashMap;

/// `n` random bubbles for seeds 1 to 3, then [`layouts`].
fn bubbles_and_layouts(n: usize) -> Vec<Domain> {
    let mut domains: Vec<Domain> = (1..=3)
        .map(|s| medial_blocks::layouts::bubbles(n, s).unwrap())
        .collect();
    domains.extend(layouts());
    domains
}

/// Random layouts with tiny holes near the others, so that refinement often inserts holes.
fn layouts() -> Vec<Domain> {
    let mut out = vec![
        Domain::from_json_str(common::INSERTING).expect("valid layout"),
        Domain::from_json_str(common::PREFIX).expect("valid layout"),
    ];
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
/// count of vertices with the same circles and position bits, computed here). Taking the
/// previous round's circles (moved, not cloned) gives the same circles; on the same graph
/// twice every vertex is taken over.
#[test]
fn reusing_the_previous_round_is_exact() {
    let sampling = SamplingOptions::default();
    let d0 = Domain::from_json_str(common::INSERTING).unwrap();
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
        let taken = vertex_circles_taking(&d1, &s1.medial, Some((&s0.medial, c0.clone())));
        assert_eq!(taken, reused);
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
    let again = vertex_circles_taking(&d0, &s0.medial, Some((&s0.medial, c0.clone())));
    assert_eq!(again, c0);
    assert_eq!(vertex_circles_taking(&d0, &s0.medial, None), c0);
}

/// The outline area of a block as first written (a fresh vector per side and per block),
/// verbatim: the reference for the buffered [`block_area`].
fn area_reference(layout: &BlockLayout, b: usize) -> f64 {
    let side_points = |side: SideRef| -> Vec<[f64; 2]> {
        let Some(edge) = layout.edges.get(side.edge as usize) else {
            return Vec::new();
        };
        let v = |i: u32| layout.vertices.get(i as usize).copied().unwrap_or([0.0; 2]);
        let mut pts: Vec<[f64; 2]> = match &edge.curve {
            Curve::Segment => vec![v(edge.ends[0]), v(edge.ends[1])],
            Curve::Arc {
                center,
                radius,
                start,
                sweep,
            } => (0..=8)
                .map(|k| {
                    let a = start + sweep * k as f64 / 8.0;
                    [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
                })
                .collect(),
            Curve::Polyline(p) => p.clone(),
        };
        if let Some(first) = pts.first_mut() {
            *first = v(edge.ends[0]);
        }
        if let Some(last) = pts.last_mut() {
            *last = v(edge.ends[1]);
        }
        if side.reversed {
            pts.reverse();
        }
        pts
    };
    let Some(block) = layout.blocks.get(b) else {
        return 0.0;
    };
    let mut outline: Vec<[f64; 2]> = Vec::new();
    for s in block.sides {
        let pts = side_points(s);
        outline.extend_from_slice(&pts[..pts.len().saturating_sub(1)]);
    }
    let n = outline.len();
    if n < 3 {
        return 0.0;
    }
    let o = outline[0];
    let mut twice = 0.0;
    for k in 1..n - 1 {
        let (a, c) = (outline[k], outline[k + 1]);
        twice += (a[0] - o[0]) * (c[1] - o[1]) - (a[1] - o[1]) * (c[0] - o[0]);
    }
    0.5 * twice
}

/// Blocking2D with indexed (not hashed) corner and spoke maps, and the buffered block area:
/// one layout vertex per corner sample and one spoke edge per (medial vertex, sample) pair,
/// checked with hash maps built here; spokes shared by exactly two blocks; every block area
/// bit for bit the reference's; contraction keeps the counting identity of the collapse.
#[test]
fn blocking_maps_and_areas_match_hashed_references() {
    let domains = bubbles_and_layouts(60);
    for d in &domains {
        let options = Options::default();
        let cb = collapsed_blocking_with(d, &options, &SamplingOptions::default(), true).unwrap();
        let samples = &cb.refined.sampled.samples;
        let graph = &cb.contracted.graph;
        let (layout, vertex_samples) = blocks(&cb.refined.domain, samples, graph).unwrap();
        assert_eq!(layout, cb.layout);
        // Walls (the B side's from a reused reversed-chain buffer): every arc ends on its
        // vertices, and runs clockwise round a hole, counter-clockwise round the bounding
        // circle.
        medial_blocks::grid::validate_layout(&layout).unwrap();
        for block in &layout.blocks {
            let wall = &layout.edges[block.sides[0].edge as usize];
            if let (EdgeKind::Wall(c), Curve::Arc { sweep, .. }) = (wall.kind, &wall.curve) {
                assert!(
                    *sweep == 0.0 || (*sweep > 0.0) == (c < 0),
                    "circle {c} sweep {sweep}"
                );
            }
        }
        let mut seen: HashMap<u32, usize> = HashMap::new();
        for (v, s) in vertex_samples.iter().enumerate() {
            if let Some(s) = s {
                assert!(seen.insert(*s, v).is_none(), "sample {s} has two vertices");
                assert_eq!(layout.vertices[v], samples.points[*s as usize]);
            }
        }
        let nv = graph.vertices.len() as u32;
        let mut spokes: HashMap<(u32, u32), u32> = HashMap::new();
        let mut uses: HashMap<u32, usize> = HashMap::new();
        for block in &layout.blocks {
            for k in [1, 3] {
                let e = block.sides[k].edge;
                let [m, sv] = layout.edges[e as usize].ends;
                assert!(m < nv && sv >= nv);
                assert_eq!(layout.edges[e as usize].kind, EdgeKind::Spoke);
                let s = vertex_samples[sv as usize].unwrap();
                assert_eq!(*spokes.entry((m, s)).or_insert(e), e, "two spokes {m}->{s}");
                *uses.entry(e).or_default() += 1;
            }
        }
        assert!(
            uses.values().all(|&n| n == 2),
            "a spoke not shared by two blocks"
        );
        for b in 0..layout.blocks.len() {
            let (fast, slow) = (block_area(&layout, b), area_reference(&layout, b));
            assert_eq!(fast.to_bits(), slow.to_bits(), "block {b}");
        }
        let m = cb.refined.sampled.medial.arcs.len();
        assert_eq!(graph.arcs.len(), m - cb.collapsed);
        assert_eq!(layout.blocks.len(), 2 * (m - cb.collapsed));
    }
}

/// A triangle rotated to start at its smallest vertex (orientation kept).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).unwrap();
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

fn triangle_set(dt: &Triangulation) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = dt.triangles().map(canonical).collect();
    v.sort_unstable();
    v
}

/// Points on a coarse lattice (many co-circular quadruples, collinear hull points, exact
/// duplicates) or spread at random.
fn points_strategy() -> impl Strategy<Value = Vec<[f64; 2]>> {
    let lattice = (0i32..6, 0i32..6).prop_map(|(x, y)| [f64::from(x) * 0.5, f64::from(y) * 0.5]);
    let spread = (-1e3f64..1e3, -1e3f64..1e3).prop_map(|(x, y)| [x, y]);
    proptest::collection::vec(prop_oneof![lattice, spread], 3..60)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Inserting the points after a prefix into the prefix's triangulation gives the triangle
    /// set and duplicates of a triangulation from scratch, and passes the exact verifier.
    #[test]
    fn extended_triangulation_equals_a_fresh_one(pts in points_strategy(), cut in 0.0f64..1.0) {
        let Ok(full) = Triangulation::new(&pts) else { return Ok(()); };
        let n0 = ((pts.len() as f64 * cut) as usize).max(3);
        let Ok(prefix) = Triangulation::new(&pts[..n0]) else { return Ok(()); };
        let Some(ext) = prefix.extended(&pts).unwrap() else { return Ok(()); };
        prop_assert_eq!(triangle_set(&ext), triangle_set(&full));
        prop_assert_eq!(ext.duplicates(), full.duplicates());
        prop_assert!(verify_exact(&ext).is_ok(), "{:?}", verify_exact(&ext));
    }
}

/// The same on the samples of a refined layout whose samples before refinement are a prefix
/// of those after (the case refinement meets), and `None` when the prefix differs.
#[test]
fn extended_triangulation_on_refinement_samples() {
    let sampling = SamplingOptions {
        soft_rounds: false,
        ..SamplingOptions::default()
    };
    let mut extended = 0;
    for d in layouts() {
        let Ok(r) = refine(&d, Some(2.0), 10_000, &sampling) else {
            continue;
        };
        let s0 = sample_and_triangulate(&d, &sampling).unwrap();
        let (p0, p1) = (&s0.samples.points, &r.sampled.samples.points);
        let prefix = p1.len() >= p0.len() && p1[..p0.len()] == p0[..];
        match s0.triangulation.extended(p1).unwrap() {
            Some(ext) => {
                assert!(prefix);
                let full = Triangulation::new(p1).unwrap();
                assert_eq!(triangle_set(&ext), triangle_set(&full));
                verify_exact(&ext).unwrap();
                extended += usize::from(p1.len() > p0.len());
            }
            None => assert!(!prefix || p1.len() == p0.len()),
        }
    }
    assert!(extended >= 1, "no layout exercised the extension");
}

/// Meshes of layouts whose refinement inserts holes (the extended triangulation's path
/// included: PREFIX and bubbles 200 seed 3) pass `check_mesh` in both modes, with and without
/// `block_cells`, and the counting identity of refinement and collapse.
#[test]
fn refined_meshes_pass_check_mesh() {
    let mut domains = layouts();
    domains.push(medial_blocks::layouts::bubbles(200, 3).unwrap());
    let mut inserted = 0;
    for d in &domains {
        for options in [
            Options::default(),
            Options::paper(),
            Options {
                block_cells: Some(16),
                ..Options::default()
            },
        ] {
            let m = medial_blocks::mesh(d, &options).unwrap();
            medial_blocks::fuzzing::check_mesh(d, &m).unwrap();
            inserted += usize::from(!m.inserted_holes.is_empty());
            let h = m.holes + m.inserted_holes.len();
            assert_eq!(m.medial_arcs, 3 * (h - 1));
        }
    }
    assert!(inserted >= 6, "{inserted}");
}

/// The kept per-arc data of the collapse selection (`collapse::Selection`) chooses exactly
/// what `select_forced` computes from scratch, for random exclusions and forced arcs on the
/// sampled graphs of bubbles and refined layouts (the calls of the local rebuilds).
#[test]
fn kept_selection_equals_select_forced() {
    let mut rng = SplitMix64(7);
    let domains = bubbles_and_layouts(80);
    for d in &domains {
        let options = Options::default();
        let cb = collapsed_blocking_with(d, &options, &SamplingOptions::default(), false).unwrap();
        // The collapsed blocking releases its triangulation after the selection: the same
        // (deterministic) refinement again gives it back, with the same medial graph.
        assert!(cb.refined.sampled.triangulation.is_empty());
        assert!(cb.refined.sampled.kinds.is_empty());
        let refined = refine(
            d,
            options.refine_ratio,
            options.max_inserted_holes,
            &SamplingOptions::default(),
        )
        .unwrap();
        assert_eq!(refined.sampled.medial, cb.refined.sampled.medial);
        assert_eq!(
            refined.sampled.samples.points,
            cb.refined.sampled.samples.points
        );
        let s = &refined.sampled;
        let m = s.medial.arcs.len();
        for fraction in [0.0, 0.05, 0.3] {
            let kept = Selection::new(
                &s.medial,
                &s.triangulation,
                &cb.refined.circles,
                &cb.groups,
                &s.samples.points,
                fraction,
                ArcLength::Polyline,
            );
            for round in 0..6 {
                let p = [0.0, 0.1, 0.5][round % 3];
                let mut flags =
                    |p: f64| -> Vec<bool> { (0..m).map(|_| rng.next_f64() < p).collect() };
                let (exclude, forced) = (flags(p), flags(p / 2.0));
                let fresh = select_forced(
                    &s.medial,
                    &s.triangulation,
                    &cb.refined.circles,
                    &cb.groups,
                    &s.samples.points,
                    fraction,
                    &exclude,
                    &forced,
                );
                assert_eq!(kept.select(&exclude, &forced), fresh);
            }
        }
    }
}

/// The medial graph without its per-triangle circumcentre cache: every arc's polyline is, bit
/// for bit, its start vertex's position, the circumcentres of its boundary triangles (computed
/// here from the triangulation's points in triangle order) and its end vertex's position, and
/// no boundary triangle is walked by two arcs.
#[test]
fn medial_polylines_are_the_walked_circumcentres() {
    use medial_blocks::medial::{circumcenter, TriangleKind};
    for d in bubbles_and_layouts(60) {
        let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
        let (tri, g) = (&s.triangulation, &s.medial);
        let cc = |t: u32| {
            let p = tri.triangle(t as usize).map(|v| tri.points()[v as usize]);
            circumcenter(p[0], p[1], p[2]).unwrap()
        };
        let mut seen = vec![false; tri.len()];
        for v in &g.vertices {
            assert_eq!(v.position, cc(v.triangle));
        }
        for a in &g.arcs {
            assert_eq!(a.polyline.len(), a.triangles.len() + 2);
            assert_eq!(a.polyline[0], g.vertices[a.ends[0] as usize].position);
            assert_eq!(
                *a.polyline.last().unwrap(),
                g.vertices[a.ends[1] as usize].position
            );
            for (k, &t) in a.triangles.iter().enumerate() {
                assert!(matches!(s.kinds[t as usize], TriangleKind::Boundary { .. }));
                assert!(
                    !std::mem::replace(&mut seen[t as usize], true),
                    "triangle {t}"
                );
                let (x, y) = (a.polyline[k + 1], cc(t));
                assert_eq!(
                    [x[0].to_bits(), x[1].to_bits()],
                    [y[0].to_bits(), y[1].to_bits()]
                );
            }
        }
    }
}

/// Refinement takes each round's minimum gap from the sampling's recorded per-circle gaps
/// instead of a second nearest-gap search: bitwise `min_gap` of the round's domain, checked on
/// the first round (the input domain) and the last (the refined domain), on layouts that do
/// and do not insert holes.
#[test]
fn refinement_min_gaps_are_min_gap_of_the_domains() {
    use medial_blocks::refine::min_gap;
    let options = Options::default();
    let mut inserting = 0;
    for d in bubbles_and_layouts(50) {
        let r = refine(
            &d,
            options.refine_ratio,
            options.max_inserted_holes,
            &SamplingOptions::default(),
        )
        .unwrap();
        assert_eq!(r.min_gaps[0].to_bits(), min_gap(&d).to_bits());
        let last = r.min_gaps.last().unwrap();
        assert_eq!(last.to_bits(), min_gap(&r.domain).to_bits());
        inserting += usize::from(!r.inserted.is_empty());
    }
    assert!(inserting > 0, "some layout inserts holes");
}
