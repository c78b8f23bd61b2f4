//! Issue #8, the blocking stage: its fast paths against the slow references computed
//! alongside.
//! - the indexed contraction (block successors computed once per graph, flat clusters and
//!   sector extensions) equals the contraction as first written
//!   (`collapse::reference::contract`), errors included, for the selections of the pipeline,
//!   random exclusions and arbitrary flag sets (cycles and loops);
//! - the local rebuild (`CollapsedBlocking::recollapse`) takes over the arcs and curves its
//!   changes cannot reach: the same layout, contraction, choice and exclusions as the rebuild
//!   from scratch, after chains of rebuilds giving up many short collapses and forcing arcs,
//!   and the counting identity of the collapse.

use crate::common;

use medial_blocks::blocking::{collapsed_blocking_with, CollapsedBlocking};
use medial_blocks::cocircular::vertex_circles;
use medial_blocks::collapse::{contract, reference, Contracted};
use medial_blocks::domain::Domain;
use medial_blocks::layouts::SplitMix64;
use medial_blocks::mesher::MeshError;
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};
use medial_blocks::Options;

/// Bubbles (with many short collapses at 300), the inserting layout and a lattice.
fn domains() -> Vec<Domain> {
    let mut out: Vec<Domain> = [(20, 1), (200, 2), (300, 1), (300, 3)]
        .iter()
        .map(|&(n, s)| medial_blocks::layouts::bubbles(n, s).unwrap())
        .collect();
    out.push(Domain::from_json_str(common::INSERTING).unwrap());
    out.push(medial_blocks::layouts::lattice().unwrap());
    out
}

fn same_result(a: Result<Contracted, MeshError>, b: Result<Contracted, MeshError>) {
    match (a, b) {
        (Ok(a), Ok(b)) => assert_eq!(a, b),
        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
        (a, b) => panic!("one contraction failed: {:?} / {:?}", a.err(), b.err()),
    }
}

/// The indexed contraction equals the one as first written on the pipeline's choice, on
/// choices with random exclusions and forced arcs, and on arbitrary flags (errors compared).
#[test]
fn indexed_contraction_equals_the_reference() {
    let mut rng = SplitMix64(11);
    let (mut ok, mut failed) = (0, 0);
    for d in domains() {
        for thin in [false, true] {
            let cb = collapsed_blocking_with(&d, &Options::default(), &Default::default(), thin)
                .unwrap();
            let medial = &cb.refined.sampled.medial;
            let m = medial.arcs.len();
            let mut sets: Vec<Vec<bool>> = Vec::new();
            let mut chosen = vec![false; m];
            for c in &cb.chosen {
                chosen[c.arc as usize] = true;
            }
            sets.push(chosen);
            for p in [0.1, 0.5, 0.9] {
                let mut flags =
                    |p: f64| -> Vec<bool> { (0..m).map(|_| rng.next_f64() < p).collect() };
                let (exclude, forced) = (flags(p), flags(p / 4.0));
                let mut f = vec![false; m];
                for c in cb.selection.select(&exclude, &forced) {
                    f[c.arc as usize] = true;
                }
                sets.push(f);
                // Arbitrary flags: cycles and loops for the error paths.
                sets.push(flags(p / 3.0));
            }
            sets.push(vec![true; m]);
            sets.push(vec![false; m + 1]);
            for flags in &sets {
                let expected = reference::contract(medial, flags);
                if expected.is_ok() {
                    ok += 1;
                } else {
                    failed += 1;
                }
                same_result(contract(medial, flags), reference::contract(medial, flags));
                same_result(cb.selection.contract(medial, flags), expected);
            }
        }
    }
    assert!(
        ok >= 40 && failed >= 20,
        "{ok} contractions, {failed} errors"
    );
}

fn assert_same(a: &CollapsedBlocking, b: &CollapsedBlocking) {
    // Not printed when they differ: they are large.
    assert!(a.layout == b.layout, "the layouts differ");
    assert!(a.contracted == b.contracted, "the contractions differ");
    assert_eq!(a.chosen, b.chosen);
    assert_eq!(a.collapsed, b.collapsed);
    assert_eq!(a.excluded, b.excluded);
    assert_eq!(a.forced, b.forced);
}

/// Chains of local rebuilds: each gives up a random part of the short collapses (up to all
/// of them) and forces a few kept arcs; the rebuild taking over the unchanged arcs gives what
/// the rebuild from scratch gives, after every step (errors included).
#[test]
fn recollapse_equals_the_rebuild_from_scratch() {
    let mut rng = SplitMix64(5);
    let (mut given_up, mut steps) = (0, 0);
    for (d, fraction) in domains()
        .into_iter()
        .flat_map(|d| [(d.clone(), 0.05), (d, 0.4)])
    {
        // A large collapse fraction: many short collapses, many clusters of several vertices.
        let options = Options {
            collapse_fraction: fraction,
            ..Options::default()
        };
        let cb = collapsed_blocking_with(&d, &options, &Default::default(), false).unwrap();
        let (mut fast, mut slow) = (cb.clone(), cb);
        for step in 0..5 {
            let short: Vec<u32> = fast
                .chosen
                .iter()
                .filter(|c| !c.zero)
                .map(|c| c.arc)
                .collect();
            let p = [0.1, 0.3, 0.05, 1.0, 0.5][step];
            let give_up: Vec<u32> = short.into_iter().filter(|_| rng.next_f64() < p).collect();
            let force: Vec<u32> = if step % 2 == 1 {
                let k = &fast.contracted.kept;
                (0..2)
                    .map(|_| k[(rng.next_f64() * k.len() as f64) as usize])
                    .collect()
            } else {
                Vec::new()
            };
            given_up += give_up.len();
            steps += 1;
            let a = fast.recollapse(&Options::default(), &give_up, &force);
            let b = slow.recollapse_from_scratch(&give_up, &force);
            match (&a, &b) {
                (Ok(()), Ok(())) => {}
                (Err(x), Err(y)) => assert_eq!(x.to_string(), y.to_string()),
                _ => panic!("one rebuild failed: {a:?} / {b:?}"),
            }
            assert_same(&fast, &slow);
            // The counting identity of the collapse: two blocks per kept arc.
            let m = fast.refined.sampled.medial.arcs.len();
            assert_eq!(fast.contracted.graph.arcs.len(), m - fast.chosen.len());
            assert_eq!(
                fast.layout.blocks.len(),
                2 * fast.contracted.graph.arcs.len()
            );
        }
    }
    assert!(
        given_up >= 300,
        "only {given_up} collapses given up in {steps} steps"
    );
}

/// A co-circular group as compared: circles, centre, radius, vertices.
type Group = (Vec<i32>, [f64; 2], f64, Vec<u32>);

/// The co-circular groups as first written: one list per vertex in a `BTreeMap` by root.
fn groups_reference(
    medial: &medial_blocks::medial::MedialGraph,
    circles: &[Option<medial_blocks::apollonius::Apollonius>],
) -> Vec<Group> {
    use medial_blocks::apollonius::same_circle;
    let n = medial.vertices.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            x = parent[x as usize];
        }
        x
    }
    for arc in &medial.arcs {
        let [a, b] = arc.ends;
        if a == b {
            continue;
        }
        if let (Some(x), Some(y)) = (&circles[a as usize], &circles[b as usize]) {
            if same_circle(&x.exact, &y.exact) {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                }
            }
        }
    }
    let mut members: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for v in 0..n as u32 {
        let r = find(&mut parent, v);
        members.entry(r).or_default().push(v);
    }
    let mut groups: Vec<Group> = members
        .into_iter()
        .filter(|(_, vs)| vs.len() >= 2)
        .filter_map(|(root, vertices)| {
            let c = circles[root as usize].as_ref()?;
            let mut holes: Vec<i32> = vertices
                .iter()
                .flat_map(|&v| medial.vertices[v as usize].circles)
                .collect();
            holes.sort_unstable();
            holes.dedup();
            Some((holes, c.center, c.radius, vertices))
        })
        .collect();
    groups.sort_by(|a, b| a.0.cmp(&b.0));
    groups
}

/// The co-circular groups (one list per group, not per vertex) equal the reference's on the
/// degenerate lattices (many groups) and bubbles (none).
#[test]
fn cocircular_groups_equal_the_reference() {
    use medial_blocks::cocircular::cocircular_groups;
    let mut found = 0;
    let domains = [
        medial_blocks::layouts::hexagon(),
        medial_blocks::layouts::lattice().unwrap(),
        medial_blocks::layouts::square_lattice(16).unwrap(),
        medial_blocks::layouts::square_lattice(49).unwrap(),
        medial_blocks::layouts::bubbles(200, 1).unwrap(),
    ];
    for d in &domains {
        let s = sample_and_triangulate(d, &SamplingOptions::default()).unwrap();
        let circles = vertex_circles(d, &s.medial);
        let got: Vec<_> = cocircular_groups(&s.medial, &circles)
            .into_iter()
            .map(|g| (g.holes, g.center, g.radius, g.vertices))
            .collect();
        assert_eq!(got, groups_reference(&s.medial, &circles));
        found += got.len();
    }
    assert!(found >= 10, "{found}");
}
