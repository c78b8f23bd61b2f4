//! The front end on the real engine: sampling invariants re-checked from the triangulation,
//! medial counts, and the block layout checked by oracles that do not trust the code
//! (geometry recomputed from the domain, wall coverage, sharing counts, orientation).

use medial_blocks::blocking::{build_layout, build_layout_with, Blocking};
use medial_blocks::domain::{Circle, CircleId, Domain};
use medial_blocks::layout::{Curve, EdgeKind};
use medial_blocks::mesher::{MeshError, Options};
use medial_blocks::sampling::SamplingOptions;
use proptest::prelude::*;
use std::collections::{HashMap, HashSet};
use std::f64::consts::TAU;

fn d2(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// The circle a sample lies on, found from its coordinates alone.
fn circle_of_point(d: &Domain, p: [f64; 2]) -> CircleId {
    let tol = 1e-12 * d.bounding().radius;
    let ids: Vec<CircleId> = d
        .circle_ids()
        .filter(|&id| {
            let c = d.circle(id);
            (d2(p, c.center) - c.radius).abs() <= tol
        })
        .collect();
    assert_eq!(ids.len(), 1, "sample {p:?} is on {} circles", ids.len());
    ids[0]
}

/// Invariants (a)-(c) of DESIGN section 4, from the triangulation and the domain directly.
fn check_sampling_invariants(d: &Domain, b: &Blocking) {
    let tri = &b.triangulation;
    let pts = tri.points();
    assert!(tri.duplicates().is_empty());
    let circle: Vec<CircleId> = pts.iter().map(|&p| circle_of_point(d, p)).collect();
    // Order the samples of each circle by angle.
    let mut by_circle: HashMap<CircleId, Vec<(f64, u32)>> = HashMap::new();
    for (s, &p) in pts.iter().enumerate() {
        let c = d.circle(circle[s]);
        let a = (p[1] - c.center[1])
            .atan2(p[0] - c.center[0])
            .rem_euclid(TAU);
        by_circle.entry(circle[s]).or_default().push((a, s as u32));
    }
    let mut next = vec![0u32; pts.len()];
    for v in by_circle.values_mut() {
        v.sort_by(|x, y| x.0.total_cmp(&y.0));
        for i in 0..v.len() {
            next[v[i].1 as usize] = v[(i + 1) % v.len()].1;
        }
    }
    let boundary = |a: u32, b: u32| next[a as usize] == b || next[b as usize] == a;
    let mut edges = HashSet::new();
    let mut interior = 0;
    for t in 0..tri.len() {
        let v = tri.triangle(t);
        let c = v.map(|s| circle[s as usize]);
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
        if c[0] == c[1] && c[1] == c[2] {
            assert!(
                c[0] >= 0,
                "triangle {t} has three vertices on the bounding circle"
            );
            continue; // inside a hole
        }
        let nb = (0..3).filter(|&k| boundary(v[k], v[(k + 1) % 3])).count();
        // (b)
        assert!(nb <= 1, "in-domain triangle {t} has {nb} boundary edges");
        if nb == 0 {
            interior += 1;
            // (c)
            assert!(
                c[0] != c[1] && c[1] != c[2] && c[0] != c[2],
                "interior triangle {t} has circles {c:?}"
            );
        }
    }
    // (a)
    for (s, &n) in next.iter().enumerate() {
        let s = s as u32;
        assert!(
            edges.contains(&(s.min(n), s.max(n))),
            "consecutive samples {s}, {n} are not joined"
        );
    }
    assert_eq!(interior, b.medial.vertex_count());
}

/// Oracles on the block layout.
fn check_layout(d: &Domain, b: &Blocking) {
    let l = &b.layout;
    let h = d.holes().len();
    let rr = d.bounding().radius;
    let tol = 1e-12 * rr;
    // Counting identities.
    assert_eq!(b.medial.vertex_count(), 2 * (h - 1));
    assert_eq!(b.medial.arc_count(), 3 * (h - 1));
    assert_eq!(l.blocks.len(), 6 * (h - 1));
    let nv = b.medial.vertex_count();
    // Medial vertices first, at circumcentres of their triangles.
    for (i, mv) in b.medial.vertices.iter().enumerate() {
        assert_eq!(l.vertices[i], mv.position);
        let p = mv.samples.map(|s| b.triangulation.points()[s as usize]);
        let r0 = d2(mv.position, p[0]);
        for q in p {
            assert!((d2(mv.position, q) - r0).abs() <= 1e-9 * r0.max(1e-300));
        }
    }
    // Sample vertices lie on circles.
    for v in &l.vertices[nv..] {
        circle_of_point(d, *v);
    }
    let mut refs = vec![0usize; l.edges.len()];
    let mut corner_uses = vec![0usize; l.vertices.len()];
    let mut swept: HashMap<CircleId, f64> = HashMap::new();
    for (bi, blk) in l.blocks.iter().enumerate() {
        for k in 0..4 {
            corner_uses[blk.corners[k] as usize] += 1;
            let sr = blk.sides[k];
            refs[sr.edge as usize] += 1;
            let e = &l.edges[sr.edge as usize];
            let mut ends = e.ends;
            if sr.reversed {
                ends.reverse();
            }
            assert_eq!(ends, l.side_ends(bi, k), "block {bi} side {k}");
            match (k, e.kind) {
                (0, EdgeKind::Wall(c)) => assert_eq!(Some(c), blk.wall),
                (2, EdgeKind::Medial) | (1, EdgeKind::Spoke) | (3, EdgeKind::Spoke) => {}
                _ => panic!("block {bi} side {k} has kind {:?}", e.kind),
            }
        }
        // Corners 2 and 3 are medial vertices, 0 and 1 samples.
        assert!((blk.corners[2] as usize) < nv && (blk.corners[3] as usize) < nv);
        assert!((blk.corners[0] as usize) >= nv && (blk.corners[1] as usize) >= nv);
        // The wall arc: on the true circle, from corner 0 to corner 1, the fluid on the left.
        let c = blk.wall.expect("medial blocks have a wall");
        let circ = d.circle(c);
        let wall = &l.edges[blk.sides[0].edge as usize];
        assert!(!blk.sides[0].reversed);
        let Curve::Arc {
            center,
            radius,
            start,
            sweep,
        } = wall.curve
        else {
            panic!("wall is not an arc")
        };
        assert_eq!((center, radius), (circ.center, circ.radius));
        let at = |a: f64| [center[0] + radius * a.cos(), center[1] + radius * a.sin()];
        assert!(d2(at(start), l.vertices[blk.corners[0] as usize]) <= tol);
        assert!(d2(at(start + sweep), l.vertices[blk.corners[1] as usize]) <= tol);
        if c < 0 {
            assert!(sweep >= 0.0);
        } else {
            assert!(sweep <= 0.0);
        }
        *swept.entry(c).or_default() += sweep.abs();
        // Orientation: the boundary polygon of the block (arc sampled) has positive area.
        let mut poly = Vec::new();
        for i in 0..64 {
            poly.push(at(start + sweep * i as f64 / 64.0));
        }
        poly.push(l.vertices[blk.corners[1] as usize]);
        let medial = &l.edges[blk.sides[2].edge as usize];
        let Curve::Polyline(pl) = &medial.curve else {
            panic!("medial is not a polyline")
        };
        assert_eq!(pl[0], l.vertices[medial.ends[0] as usize]);
        assert_eq!(*pl.last().unwrap(), l.vertices[medial.ends[1] as usize]);
        if blk.sides[2].reversed {
            poly.extend(pl.iter().rev());
        } else {
            poly.extend(pl.iter());
        }
        let area: f64 = (0..poly.len())
            .map(|i| {
                let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                p[0] * q[1] - p[1] * q[0]
            })
            .sum::<f64>()
            / 2.0;
        assert!(area > 0.0, "block {bi} has signed area {area}");
        // Spokes are normal to the wall up to the sampling approximation: the empty circle
        // E centred at the medial vertex m through the spoke's foot s meets the wall circle
        // in an arc centred on the direction c -> m, with s at one end; both neighbours of s
        // are not strictly inside E, so the angle at the circle's centre c between s and the
        // exact normal foot c + r (m - c)/|m - c| is at most half the wider sample interval
        // beside s.
        for (k, corner) in [(3usize, 0usize), (1, 1)] {
            let e = &l.edges[blk.sides[k].edge as usize];
            assert_eq!(e.curve, Curve::Segment);
            let m = l.vertices[e.ends[0] as usize];
            let s = l.vertices[e.ends[1] as usize];
            assert_eq!(s, l.vertices[blk.corners[corner] as usize]);
            let u = [s[0] - center[0], s[1] - center[1]];
            let w = [m[0] - center[0], m[1] - center[1]];
            let alpha = (u[0] * w[1] - u[1] * w[0])
                .atan2(u[0] * w[0] + u[1] * w[1])
                .abs();
            // Sampling is adaptive: the spacing is the wider interval beside the sample.
            let smp = b.vertex_samples[blk.corners[corner] as usize].expect("sample corner");
            let t = b.samples.angle(smp);
            let next = (b.samples.angle(b.samples.next(smp)) - t).rem_euclid(TAU);
            let prev = (t - b.samples.angle(b.samples.prev(smp))).rem_euclid(TAU);
            let half = next.max(prev) / 2.0;
            assert!(
                alpha <= half * (1.0 + 1e-9) + 1e-12,
                "block {bi} spoke {k}: foot {alpha} rad from the normal foot, spacing/2 = {half}"
            );
        }
    }
    // Walls tile every circle exactly once; each medial vertex is a corner of 6 blocks and
    // each sample corner of 2 (paper section 3).
    for id in d.circle_ids() {
        let s = swept.get(&id).copied().unwrap_or(0.0);
        assert!((s - TAU).abs() < 1e-9, "walls of circle {id} sweep {s}");
    }
    for (v, &u) in corner_uses.iter().enumerate() {
        if v < nv || b.thin_walls.is_empty() {
            assert_eq!(u, if v < nv { 6 } else { 2 }, "vertex {v}");
        } else {
            assert!(u % 2 == 0 && u >= 2, "vertex {v}");
        }
    }
    for (e, &r) in refs.iter().enumerate() {
        let want = match l.edges[e].kind {
            EdgeKind::Wall(_) => 1,
            _ => 2,
        };
        assert_eq!(r, want, "edge {e} ({:?})", l.edges[e].kind);
    }
    // Every geometric edge stored once.
    let mut keys = HashSet::new();
    for e in &l.edges {
        let k = (
            e.ends[0].min(e.ends[1]),
            e.ends[0].max(e.ends[1]),
            format!("{:?}", e.kind),
        );
        if e.kind == EdgeKind::Spoke {
            assert!(keys.insert(k), "spoke stored twice");
        }
    }
}

fn run(d: &Domain) -> Blocking {
    let b = build_layout(d, &Options::default()).expect("front end failed");
    check_sampling_invariants(d, &b);
    check_layout(d, &b);
    b
}

#[test]
fn hexagon_gives_36_blocks() {
    let d = Domain::hexagon_example();
    let b = run(&d);
    assert_eq!(b.layout.blocks.len(), 36);
    assert_eq!(b.medial.vertex_count(), 12);
    assert_eq!(b.medial.arc_count(), 18);
    // No single-sample wall, no zero-length arc, no resampling needed.
    assert!(b.thin_walls.is_empty());
    assert_eq!(b.medial.zero_length_arcs(), 0);
    assert_eq!(b.rounds, 0);
    // Deterministic.
    let again = build_layout(&d, &Options::default()).unwrap();
    assert_eq!(again.layout, b.layout);
}

#[test]
fn fewer_than_two_holes_is_a_typed_error() {
    for holes in [vec![], vec![Circle::new(0.0, 0.0, 1.0)]] {
        let d = Domain::bounded(Circle::new(0.0, 0.0, 5.0), holes).unwrap();
        assert!(matches!(
            build_layout(&d, &Options::default()),
            Err(MeshError::Options(_))
        ));
    }
}

#[test]
fn two_holes() {
    let d = Domain::bounded(
        Circle::new(0.0, 0.0, 5.0),
        vec![Circle::new(-1.5, 0.0, 1.0), Circle::new(1.5, 0.3, 0.7)],
    )
    .unwrap();
    let b = run(&d);
    assert_eq!(b.layout.blocks.len(), 6);
}

/// Square lattices: four holes tangent to one empty circle (exact ties from the symmetric
/// sampling) give zero- or near-zero-length arcs; nothing panics and the counts still hold.
#[test]
fn square_lattices_are_degenerate_but_fine() {
    for n in [2usize, 3, 4] {
        let mut holes = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let x = i as f64 - (n as f64 - 1.0) / 2.0;
                let y = j as f64 - (n as f64 - 1.0) / 2.0;
                holes.push(Circle::new(x, y, 0.3));
            }
        }
        let d = Domain::bounded(Circle::new(0.0, 0.0, n as f64), holes).unwrap();
        let b = build_layout(&d, &Options::default()).unwrap();
        check_sampling_invariants(&d, &b);
        let h = n * n;
        assert_eq!(b.layout.blocks.len(), 6 * (h - 1));
        let short = b
            .medial
            .arcs
            .iter()
            .filter(|a| {
                let len: f64 = a.polyline.windows(2).map(|w| d2(w[0], w[1])).sum();
                len < 1e-9
            })
            .count();
        assert!(short >= (n - 1) * (n - 1), "n = {n}: {short} short arcs");
    }
}

/// Touching-close particles (gap 1e-6 of the radius): sampling is capped, still valid.
#[test]
fn nearly_touching_holes() {
    let d = Domain::bounded(
        Circle::new(0.0, 0.0, 4.0),
        vec![
            Circle::new(-1.0 - 5e-7, 0.0, 1.0),
            Circle::new(1.0 + 5e-7, 0.0, 1.0),
            Circle::new(0.0, 2.2, 0.5),
        ],
    )
    .unwrap();
    run(&d);
}

#[test]
fn sampling_limits_give_typed_errors() {
    let d = Domain::hexagon_example();
    let opts = SamplingOptions {
        max_total: 100,
        ..SamplingOptions::default()
    };
    assert!(matches!(
        build_layout_with(&d, &Options::default(), &opts),
        Err(MeshError::Sampling { .. })
    ));
}

/// A random layout of about `h` holes in a bounding circle of radius 10, by rejection.
fn random_layout(seed: u64, h: usize, rmin: f64, rmax: f64) -> Domain {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let b = Circle::new(0.0, 0.0, 10.0);
    let mut holes: Vec<Circle> = Vec::new();
    let mut tries = 0;
    while holes.len() < h && tries < 5000 {
        tries += 1;
        let r = rmin + (rmax - rmin) * rnd();
        let t = TAU * rnd();
        let q = (10.0 - r) * rnd().sqrt();
        let c = Circle::new(q * t.cos(), q * t.sin(), r);
        let mut trial = holes.clone();
        trial.push(c);
        if Domain::bounded(b, trial).is_ok() {
            holes.push(c);
        }
    }
    Domain::bounded(b, holes).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    /// V = 2(h-1), E = 3(h-1), blocks = 6(h-1), and every layout oracle, on random
    /// non-overlapping layouts with random radii and gaps.
    #[test]
    fn random_layouts(seed in any::<u64>(), h in 2usize..40, rmax in 0.3f64..2.5) {
        let d = random_layout(seed, h, 0.05, rmax);
        prop_assume!(d.holes().len() >= 2);
        run(&d);
    }
}
