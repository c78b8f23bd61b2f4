//! Blocking2D with the curves of each wave of arcs computed in parallel
//! (`blocking::blocks`) against the one-arc-after-the-other construction it replaces
//! (`blocking::blocks_one_by_one`): the same layout and vertex samples on sampled and
//! contracted medial graphs (several waves of arcs), with one and two threads, and the same
//! error on graphs broken at arcs early, late and across waves.

use medial_blocks::blocking::{
    blocks, blocks_in_waves, blocks_one_by_one, collapsed_blocking_with,
};
use medial_blocks::domain::Domain;
use medial_blocks::medial::MedialGraph;
use medial_blocks::sampling::{sample_and_triangulate, Samples, SamplingOptions};
use medial_blocks::Options;

fn domains() -> Vec<Domain> {
    vec![
        medial_blocks::layouts::hexagon(),
        medial_blocks::layouts::square_lattice(16).unwrap(),
        medial_blocks::layouts::bubbles(30, 1).unwrap(),
        medial_blocks::layouts::bubbles(1500, 2).unwrap(),
    ]
}

fn same(domain: &Domain, samples: &Samples, g: &MedialGraph) -> bool {
    let reference = blocks_one_by_one(domain, samples, g);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        // `blocks` itself (one by one below 1024 arcs, in waves of a sixth of the arcs, 256
        // to 2048, above), and the waves forced on graphs of every size, the pipeline's
        // largest wave and small ones.
        for wave in [None, Some(2048), Some(97)] {
            let got = pool.install(|| match wave {
                None => blocks(domain, samples, g),
                Some(w) => blocks_in_waves(domain, samples, g, w),
            });
            match (&got, &reference) {
                (Ok(a), Ok(b)) => assert!(a == b, "{threads} threads, {wave:?}: layouts differ"),
                (Err(a), Err(b)) => {
                    assert_eq!(a.to_string(), b.to_string(), "{threads} threads, {wave:?}")
                }
                _ => panic!(
                    "{threads} threads, {wave:?}: {:?} / {:?}",
                    got.is_ok(),
                    reference.is_ok()
                ),
            }
        }
    }
    reference.is_ok()
}

#[test]
fn parallel_curves_give_the_one_by_one_layout() {
    let mut arcs = 0;
    for d in domains() {
        let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
        assert!(same(&d, &s.samples, &s.medial));
        arcs = arcs.max(s.medial.arcs.len());
        let cb =
            collapsed_blocking_with(&d, &Options::default(), &SamplingOptions::default(), false)
                .unwrap();
        let r = &cb.refined;
        assert!(same(&r.domain, &r.sampled.samples, &cb.contracted.graph));
        let (layout, _) = blocks(&r.domain, &r.sampled.samples, &cb.contracted.graph).unwrap();
        assert!(layout == cb.layout);
    }
    assert!(arcs > 2 * 2048, "three waves of arcs covered ({arcs} arcs)");
}

/// A graph large enough for `blocks` to go in waves (1024 arcs and more), in a local rebuild
/// that takes the unchanged arcs' curves over from the previous layout: the layout is the
/// rebuild from scratch's, with one and two threads.
#[test]
fn local_rebuild_in_waves_equals_the_rebuild_from_scratch() {
    let d = medial_blocks::layouts::bubbles(3000, 4).unwrap();
    let cb = collapsed_blocking_with(&d, &Options::default(), &SamplingOptions::default(), false)
        .unwrap();
    let m = cb.contracted.graph.arcs.len();
    assert!(
        m >= 4 * 2048,
        "{m} kept arcs: the rebuild would not go in waves"
    );
    let give_up: Vec<u32> = cb
        .chosen
        .iter()
        .filter(|c| !c.zero)
        .map(|c| c.arc)
        .step_by(3)
        .collect();
    assert!(!give_up.is_empty());
    let mut slow = cb.clone();
    slow.recollapse_from_scratch(&give_up, &[]).unwrap();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut fast = cb.clone();
        pool.install(|| fast.recollapse(&Options::default(), &give_up, &[]))
            .unwrap();
        assert!(
            fast.layout == slow.layout,
            "{threads} threads: the layouts differ"
        );
        assert!(fast.contracted == slow.contracted, "{threads} threads");
        assert_eq!(
            fast.layout.blocks.len(),
            2 * fast.contracted.graph.arcs.len()
        );
    }
}

/// A way of breaking arc `e` of a graph.
type Break = Box<dyn Fn(&mut MedialGraph, usize)>;

/// Arcs broken in each way the construction checks (an empty chain, a sample out of range, a
/// vertex or circle out of range, a wall chain that is not a run of consecutive samples, one
/// running the wrong way round), alone or two at once in different waves.
#[test]
fn broken_arcs_give_the_one_by_one_error() {
    let d = medial_blocks::layouts::bubbles(1500, 3).unwrap();
    let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
    let g = &s.medial;
    let m = g.arcs.len();
    let breaks: Vec<Break> = vec![
        Box::new(|g, e| g.arcs[e].c1.clear()),
        Box::new(|g, e| g.arcs[e].c2.clear()),
        Box::new(|g, e| *g.arcs[e].c2.last_mut().unwrap() = u32::MAX),
        Box::new(|g, e| g.arcs[e].ends[1] = u32::MAX),
        Box::new(|g, e| g.arcs[e].circles[0] = 1 << 30),
        Box::new(|g, e| {
            let c = &mut g.arcs[e].c1;
            let first = c[0];
            c.push(first);
        }),
        Box::new(|g, e| g.arcs[e].c2.reverse()),
        Box::new(|g, e| {
            let c = g.arcs[e].c1.clone();
            g.arcs[e].c1 = c.into_iter().rev().collect();
        }),
    ];
    let mut failed = 0;
    for (k, brk) in breaks.iter().enumerate() {
        for at in [0, 1, 2047, 2048, m / 2, m - 1] {
            let mut broken = g.clone();
            brk(&mut broken, at);
            if !same(&d, &s.samples, &broken) {
                failed += 1;
            }
            // A second break in a later wave: the first one's error wins.
            let later = (at + 2 * 2048 + 5) % m;
            brk(&mut broken, later);
            let other = &breaks[(k + 1) % breaks.len()];
            other(&mut broken, (at + 3000) % m);
            same(&d, &s.samples, &broken);
        }
    }
    assert!(failed > 30, "only {failed} broken graphs failed");
}

/// The collapse selection's per-arc data computed in parallel equal those computed one arc
/// after the other, for the collapse fractions of the pipeline, none and NaN, with one and
/// two threads.
#[test]
fn parallel_selection_equals_the_one_by_one_selection() {
    use medial_blocks::collapse::{ArcLength, Selection};
    for d in domains() {
        let cb =
            collapsed_blocking_with(&d, &Options::default(), &SamplingOptions::default(), false)
                .unwrap();
        let s = sample_and_triangulate(&cb.refined.domain, &SamplingOptions::default()).unwrap();
        let circles = medial_blocks::cocircular::vertex_circles(&cb.refined.domain, &s.medial);
        let groups = medial_blocks::cocircular::cocircular_groups(&s.medial, &circles);
        let fractions = [Options::default().collapse_fraction, 0.0, 0.5, f64::NAN];
        for (fraction, how) in fractions
            .into_iter()
            .flat_map(|f| [(f, ArcLength::Polyline), (f, ArcLength::Chord)])
        {
            let args = (&s.medial, &s.triangulation, &circles[..], &groups[..]);
            let reference = Selection::new_one_by_one(
                args.0,
                args.1,
                args.2,
                args.3,
                &s.samples.points,
                fraction,
                how,
            );
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| {
                    let points = &s.samples.points;
                    Selection::new(args.0, args.1, args.2, args.3, points, fraction, how)
                });
                assert!(
                    got == reference,
                    "fraction {fraction}, {how:?}, {threads} threads"
                );
            }
        }
    }
}
