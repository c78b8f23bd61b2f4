//! Exact mode's per-piece memo across rebuilds ([`medial_blocks::exact_mode::piece_cache`],
//! issue #8): a rebuild with the memo of the previous build gives bit for bit the mesh a
//! build from scratch gives (the oracle: `build_collapsed_on`, which starts from an empty
//! memo every time), and does reuse work; the inverted blocks a build finds as it makes (or
//! takes) its grids are those of a pass over the finished grids.

use crate::common;

use medial_blocks::blocking::{collapsed_blocking_excluding, CollapsedBlocking};
use medial_blocks::exact_mode::collapsed::{build_collapsed_cached, build_collapsed_on};
use medial_blocks::exact_mode::{exact_vertices_with, ExactMesh, ExactVertex, PieceCache};
use medial_blocks::layouts::{self, SplitMix64};
use medial_blocks::mesher::{exact_sampling, Options};
use medial_blocks::{Circle, Domain};

fn single(cb: &CollapsedBlocking) -> Vec<ExactVertex> {
    exact_vertices_with(
        &cb.refined.domain,
        &cb.refined.sampled.medial,
        &cb.refined.circles,
    )
    .unwrap()
}

/// Everything a build returns, compared bit for bit (floats by their bit patterns), and the
/// inverted blocks each build found as it made its grids against a pass over the finished
/// grids (`quality::inverted_blocks`). Returns how many blocks are inverted (0 on errors).
fn assert_same(a: &Result<ExactMesh, String>, b: &Result<ExactMesh, String>, what: &str) -> usize {
    let (a, b) = match (a, b) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(x), Err(y)) => {
            assert_eq!(x, y, "{what}");
            return 0;
        }
        _ => panic!("{what}: one build failed, the other did not"),
    };
    for m in [a, b] {
        let pass = medial_blocks::quality::inverted_blocks(&m.grids);
        assert_eq!(m.inverted_blocks, pass, "{what}: inverted blocks");
    }
    assert_eq!(a.counts, b.counts, "{what}");
    assert_eq!(a.grids.len(), b.grids.len(), "{what}");
    for (k, (ga, gb)) in a.grids.iter().zip(&b.grids).enumerate() {
        assert_eq!((ga.ni, ga.nj), (gb.ni, gb.nj), "{what}: block {k}");
        let bits = |g: &medial_blocks::mesh::BlockGrid| -> Vec<u64> {
            g.nodes
                .iter()
                .flat_map(|p| [p[0].to_bits(), p[1].to_bits()])
                .collect()
        };
        assert!(bits(ga) == bits(gb), "{what}: block {k} nodes differ");
    }
    // The layout's floats all print distinctly with `{:?}` (shortest round trip).
    assert_eq!(
        format!("{:?}", a.layout),
        format!("{:?}", b.layout),
        "{what}"
    );
    assert_eq!(
        format!("{:?}", a.vertices),
        format!("{:?}", b.vertices),
        "{what}"
    );
    assert_eq!(a.cell_size.to_bits(), b.cell_size.to_bits(), "{what}");
    assert_eq!(
        (&a.inconsistent_arcs, a.split_arcs, a.template_blocks),
        (&b.inconsistent_arcs, b.split_arcs, b.template_blocks),
        "{what}"
    );
    a.inverted_blocks.len()
}

fn build(
    cb: &CollapsedBlocking,
    o: &Options,
    cache: Option<&mut PieceCache>,
) -> Result<ExactMesh, String> {
    let s = single(cb);
    match cache {
        Some(c) => build_collapsed_cached(cb, o, &s, c),
        None => build_collapsed_on(cb, o, &s),
    }
    .map_err(|e| e.to_string())
}

/// First build (empty memo), then a rebuild after giving up every short collapse, each with
/// the memo and from scratch. Returns how many pieces the rebuild reused (0 when there was
/// nothing to give up) and how many inverted blocks the builds found.
fn rebuild_matches(d: &Domain, o: &Options, what: &str) -> (usize, usize) {
    let mut cb = collapsed_blocking_excluding(d, o, &exact_sampling(), false, &[]).unwrap();
    let mut cache = PieceCache::default();
    let first = build(&cb, o, Some(&mut cache));
    let mut inverted = assert_same(&first, &build(&cb, o, None), what);
    if first.is_err() {
        return (0, inverted);
    }
    // The same skeleton again: every piece is reused, grids included once handed back.
    let again = build(&cb, o, Some(&mut cache));
    inverted += assert_same(&again, &first, what);
    let pieces = first.as_ref().unwrap().counts.arc.len();
    assert_eq!(cache.reused(), pieces, "{what}: identical rebuild");
    assert_eq!(cache.reused_grids(), 0, "{what}: no grids handed back");
    assert_eq!(cache.spare_capacity(), 0, "{what}: nothing handed back yet");
    cache.keep(again.unwrap());
    // The handed-back layout's vectors wait, empty, for the next build, which fills them
    // (`assert_same` compares its contents with the build from scratch).
    assert!(cache.spare_capacity() > 0, "{what}: layout kept for reuse");
    let third = build(&cb, o, Some(&mut cache));
    assert_eq!(cache.spare_capacity(), 0, "{what}: spare vectors taken");
    inverted += assert_same(&third, &first, what);
    assert_eq!(cache.reused_grids(), pieces, "{what}: grids handed back");
    cache.keep(third.unwrap());
    let short: Vec<u32> = cb
        .chosen
        .iter()
        .filter(|c| !c.zero)
        .map(|c| c.arc)
        .collect();
    if short.is_empty() || cb.recollapse(o, &short, &[]).is_err() {
        return (0, inverted);
    }
    let cached = build(&cb, o, Some(&mut cache));
    inverted += assert_same(&cached, &build(&cb, o, None), &format!("{what} (given up)"));
    assert!(cache.reused_grids() <= cache.reused());
    (cache.reused_grids(), inverted)
}

fn random_layout(seed: u64, h: usize, min_gap: f64) -> Domain {
    let mut rng = SplitMix64(seed);
    let big_r = 1.0 + 4.0 * rng.next_f64();
    let holes = common::random_holes(&mut rng, h, big_r, [0.0, 0.0], min_gap);
    Domain::bounded(Circle::new(0.0, 0.0, big_r), holes).expect("valid layout")
}

fn option_sets() -> Vec<(&'static str, Options)> {
    vec![
        (
            "block-cells 6",
            Options {
                block_cells: Some(6),
                ..Options::default()
            },
        ),
        (
            "cells 3",
            Options {
                cells: 3,
                ..Options::default()
            },
        ),
        (
            "cells 2, smooth 2, fraction 0.3",
            Options {
                cells: 2,
                smooth: 2,
                collapse_fraction: 0.3,
                ..Options::default()
            },
        ),
    ]
}

#[test]
fn rebuilds_with_the_memo_equal_builds_from_scratch() {
    let mut domains: Vec<(String, Domain)> = vec![
        ("hexagon".into(), layouts::hexagon()),
        (
            "square lattice 9".into(),
            layouts::square_lattice(9).unwrap(),
        ),
    ];
    for seed in 1..=4u64 {
        domains.push((
            format!("bubbles 60 seed {seed}"),
            layouts::bubbles(60, seed).unwrap(),
        ));
    }
    // Near-touching holes: refinement inserts holes (templates, split arcs).
    for seed in [3u64, 11, 29, 14924378680947049249] {
        domains.push((format!("poor seed {seed}"), random_layout(seed, 10, 0.004)));
    }
    let mut reused = 0;
    let mut inserted = 0;
    let mut inverted = 0;
    for (name, d) in &domains {
        for (oname, o) in option_sets() {
            let (r, i) = rebuild_matches(d, &o, &format!("{name}, {oname}"));
            reused += r;
            inverted += i;
        }
        let cb =
            collapsed_blocking_excluding(d, &Options::default(), &exact_sampling(), false, &[])
                .unwrap();
        inserted += cb.refined.inserted.len();
    }
    assert!(reused > 0, "no rebuild reused a piece");
    assert!(inverted > 0, "no build had an inverted block");
    assert!(inserted > 0, "no layout had inserted holes");
}

/// A memo filled on one sampling and used on a finer one (as `mesh_exact` does after a local
/// resampling): the same mesh as from scratch.
#[test]
fn the_memo_survives_a_resampling() {
    for seed in 1..=3u64 {
        let d = layouts::bubbles(40, seed).unwrap();
        let o = Options {
            block_cells: Some(5),
            ..Options::default()
        };
        let mut cache = PieceCache::default();
        let cb = collapsed_blocking_excluding(&d, &o, &exact_sampling(), false, &[]).unwrap();
        if let Ok(m) = build(&cb, &o, Some(&mut cache)) {
            cache.keep(m);
        }
        let mut finer = exact_sampling();
        finer.boost = vec![0, 2, 0, 2];
        let cb = collapsed_blocking_excluding(&d, &o, &finer, false, &[]).unwrap();
        let cached = build(&cb, &o, Some(&mut cache));
        assert_same(&cached, &build(&cb, &o, None), &format!("seed {seed}"));
        assert!(cache.reused_grids() > 0, "seed {seed}");
    }
}

/// The tiny holes of `reliability_inserted::tiny_holes_do_not_explode_the_node_count`: the
/// default target size is coarsened, so the counts are solved for several `nbar`.
fn tiny_holes() -> Domain {
    Domain::from_json_str(r#"{"bounding":{"center":[-400.0817856577331,33.87822533056584],"radius":1.0},"holes":[{"center":[-400.08312479371654,33.44838334890991],"radius":0.0990630459071938},{"center":[-399.7947884873536,34.381635245660654],"radius":0.10418356028060242},{"center":[-400.34032909914225,34.13765904541643],"radius":0.15484414181549747},{"center":[-400.0938468361977,33.637360311276765],"radius":0.08959851009587018},{"center":[-400.07449930958086,33.975518636641894],"radius":0.15651953635017232},{"center":[-400.20025144500437,34.06995272688713],"radius":0.00005517186456721176},{"center":[-400.2002104163847,34.070164390528866],"radius":0.00009968364075799228},{"center":[-400.21574421724756,34.04455227047863],"radius":0.00006730713755663978}]}"#).unwrap()
}

/// The summaries a first build keeps instead of the densities (lower bound, target and node
/// parameters for the predicted counts, densities computed again where the final counts
/// differ) give the mesh of the reference path, which holds every piece's densities and
/// draws the nodes from them.
#[test]
fn summaries_equal_the_reference_densities() {
    let mut domains: Vec<(String, Domain)> = vec![
        ("lattice".into(), layouts::lattice().unwrap()),
        (
            "square lattice 16".into(),
            layouts::square_lattice(16).unwrap(),
        ),
        ("tiny holes".into(), tiny_holes()),
    ];
    for seed in 5..=8u64 {
        domains.push((
            format!("bubbles 50 seed {seed}"),
            layouts::bubbles(50, seed).unwrap(),
        ));
    }
    for seed in [7u64, 14924378680947049249] {
        domains.push((format!("poor seed {seed}"), random_layout(seed, 12, 0.003)));
    }
    let mut sets = option_sets();
    sets.push((
        "block-cells 16",
        Options {
            block_cells: Some(16),
            ..Options::default()
        },
    ));
    sets.push(("defaults", Options::default()));
    sets.push((
        "wall cells, relative first height",
        Options {
            wall_cells: vec![(0, 7), (-1, 3)],
            clustering: medial_blocks::exact_mode::Clustering {
                first: Some(medial_blocks::exact_mode::FirstCell::Relative(0.01)),
                growth: 1.15,
            },
            ..Options::default()
        },
    ));
    for (name, d) in &domains {
        for (oname, o) in &sets {
            // The coarsened tiny-hole meshes have millions of nodes with small cell counts.
            if name == "tiny holes" && o.cells < 16 && o.block_cells.is_none() {
                continue;
            }
            let what = format!("{name}, {oname}");
            let Ok(cb) = collapsed_blocking_excluding(d, o, &exact_sampling(), false, &[]) else {
                continue;
            };
            let s = single(&cb);
            let reference = build_collapsed_cached(&cb, o, &s, &mut PieceCache::reference())
                .map_err(|e| e.to_string());
            assert_same(&build(&cb, o, None), &reference, &what);
        }
    }
}
