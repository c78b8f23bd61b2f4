//! Periodic boxes at scale (issue 8): what the periodic pipeline does to stay fast, checked
//! with oracles that do not trust it: cell orientation recomputed from the nodes
//! (`common::count_inverted_cells`), stage call counts from [`timings::Recording`].

use crate::common;

use medial_blocks::domain::AnyDomain;
use medial_blocks::mesh::Geometry;
use medial_blocks::periodic::{mesh_periodic, PeriodicDomain};
use medial_blocks::{timings, Options};

fn calls(t: &timings::Timings, stage: &str) -> u64 {
    t.calls
        .iter()
        .find(|(s, _)| s == stage)
        .map_or(0, |&(_, n)| n)
}

fn domain(json: &str) -> PeriodicDomain {
    match AnyDomain::from_json_str(json).unwrap() {
        AnyDomain::Periodic(pd) => pd,
        other => panic!("not a periodic domain: {other:?}"),
    }
}

/// The periodic domain of `json` meshed in exact mode (4 x 4 cells a block), with its
/// stage timings.
fn mesh_recorded(json: &str) -> (PeriodicDomain, medial_blocks::Mesh, timings::Timings) {
    let pd = domain(json);
    let options = Options {
        block_cells: Some(4),
        ..Options::default()
    };
    let rec = timings::Recording::start();
    let mesh = mesh_periodic(&pd, &options).unwrap();
    (pd, mesh, rec.finish())
}

/// 60 random holes whose first sampling disagrees with the exact geometry: the exact attempt
/// is repeated on a finer sampling around the disagreement (exact mode's local resampling),
/// and the mesh is exact with no inverted cell.
#[test]
fn a_disagreeing_periodic_box_is_resampled_and_exact() {
    let _turn = common::turn();
    let (pd, mesh, t) = mesh_recorded(include_str!("data/periodic_resampled_60.json"));
    assert!(calls(&t, "triangulation") >= 2, "{:?}", t.calls);
    assert_eq!(mesh.geometry, Geometry::Exact);
    assert_eq!(common::count_inverted_cells(&mesh.grids), 0);
    // On the torus: 2E = 6h blocks around the h holes (inserted ones included), fewer two per
    // collapsed arc orbit and more two per arc orbit split for a template, then the templates
    // inside the inserted holes.
    let h = pd.hole_count() + mesh.inserted_holes.len();
    assert_eq!(
        mesh.layout.blocks.len() - mesh.template_blocks,
        6 * h - 2 * mesh.collapsed_arcs + 2 * mesh.split_arcs
    );
}

/// 100 random holes whose first layout has a short arc collapsed and arcs running backwards:
/// exact mode fixes them on the same sampling (their orbits collapsed in every copy, the
/// layout extracted again: no second sampling, triangulation or medial graph, and no
/// zero-only layout), and one exact build: the first extraction finds the backwards arcs
/// itself, before numbering its layout, so no build is started and stopped there; the mesh is
/// exact, with more collapsed arc orbits than the first layout's one, and the block count of
/// the torus identity.
#[test]
fn backwards_arcs_are_fixed_on_the_same_sampling() {
    let _turn = common::turn();
    let (pd, mesh, t) = mesh_recorded(include_str!("data/periodic_backwards_100.json"));
    let calls3 = (
        calls(&t, "triangulation"),
        calls(&t, "blocking"),
        calls(&t, "exact_geometry"),
    );
    assert_eq!(calls3, (1, 2, 1), "{:?}", t.calls);
    assert!(mesh.collapsed_arcs >= 2, "{}", mesh.collapsed_arcs);
    assert_eq!(mesh.geometry, Geometry::Exact);
    assert_eq!(common::count_inverted_cells(&mesh.grids), 0);
    let h = pd.hole_count() + mesh.inserted_holes.len();
    assert_eq!(
        mesh.layout.blocks.len() - mesh.template_blocks,
        6 * h - 2 * mesh.collapsed_arcs + 2 * mesh.split_arcs
    );
}

/// `layouts::periodic_bubbles`: `n` bubbles, radii in `[0.3, 0.6]`, centres in the box, the
/// box's area `pi n 0.2575 / 0.35`, and every pair at least 0.1 apart at their nearest images
/// (brute force over the nine images, not the generator's grid); the same seed gives the
/// same layout, another seed another one.
#[test]
fn periodic_bubbles_keep_their_gaps_across_the_box() {
    let _turn = common::turn();
    use medial_blocks::layouts::periodic_bubbles;
    for (n, seed) in [(1, 1), (2, 5), (7, 2), (300, 3)] {
        let pd = periodic_bubbles(n, seed).unwrap();
        let [lx, ly] = pd.size();
        assert_eq!(lx, ly);
        let area = std::f64::consts::PI * n as f64 * 0.2575 / 0.35;
        assert!((lx * ly - area).abs() <= 1e-9 * area, "{lx} for {n}");
        let holes = pd.holes();
        assert_eq!(holes.len(), n);
        for h in holes {
            assert!((0.3..=0.6).contains(&h.radius));
            assert!((0.0..lx).contains(&h.center[0]) && (0.0..ly).contains(&h.center[1]));
        }
        for (i, a) in holes.iter().enumerate() {
            for b in &holes[i + 1..] {
                let gap = (-1..=1)
                    .flat_map(|dx| (-1..=1).map(move |dy| (dx, dy)))
                    .map(|(dx, dy)| {
                        let x = a.center[0] - b.center[0] + dx as f64 * lx;
                        let y = a.center[1] - b.center[1] + dy as f64 * ly;
                        x.hypot(y) - a.radius - b.radius
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!(gap >= 0.1 - 1e-12, "{n} bubbles, seed {seed}: gap {gap}");
            }
        }
        assert_eq!(periodic_bubbles(n, seed).unwrap(), pd);
        if n > 1 {
            assert_ne!(periodic_bubbles(n, seed + 1).unwrap(), pd);
        }
    }
    assert!(periodic_bubbles(0, 1).is_err());
}

/// `medial-blocks example periodic-bubbles` writes the library's layout as a periodic domain
/// (read back through the `mesh` input parser, bit for bit), and meshes in exact mode.
#[test]
fn the_cli_writes_periodic_bubbles() {
    let _turn = common::turn();
    let o = common::run(&[
        "example",
        "periodic-bubbles",
        "--holes",
        "30",
        "--seed",
        "2",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pd = domain(&String::from_utf8(o.stdout).unwrap());
    assert_eq!(pd, medial_blocks::layouts::periodic_bubbles(30, 2).unwrap());
    let mesh = mesh_periodic(&pd, &Options::default()).unwrap();
    assert_eq!(mesh.geometry, Geometry::Exact);
    assert_eq!(common::count_inverted_cells(&mesh.grids), 0);
    let o = common::run(&["example", "periodic-bubbles", "--holes", "0"]);
    assert_eq!(o.status.code(), Some(2));
}

/// The medial polylines of the layout are the medial sides of the block grids, node for
/// node and bit for bit (side 2, `j = nj`, traversed with `i` decreasing; the polyline in
/// the side's direction), on a box whose refinement inserts holes (their templates' layout
/// is made without the arcs' nodes and given them before the grids, issue 8) and on one
/// without.
#[test]
fn medial_polylines_are_the_grids_medial_sides() {
    let _turn = common::turn();
    use medial_blocks::layout::Curve;
    let mut checked_templates = false;
    for (n, seed) in [(60, 3), (40, 5)] {
        let pd = medial_blocks::layouts::periodic_bubbles(n, seed).unwrap();
        let options = Options {
            block_cells: Some(4),
            refine_ratio: Some(1.0),
            ..Options::default()
        };
        let mesh = mesh_periodic(&pd, &options).unwrap();
        assert_eq!(mesh.geometry, Geometry::Exact);
        checked_templates |= mesh.template_blocks > 0;
        let medial = mesh.layout.blocks.len() - mesh.template_blocks;
        for (b, block) in mesh.layout.blocks[..medial].iter().enumerate() {
            let side = block.sides[2];
            let Curve::Polyline(pts) = &mesh.layout.edges[side.edge as usize].curve else {
                panic!("block {b}: side 2 is not a polyline");
            };
            let mut along: Vec<[f64; 2]> = pts.clone();
            if side.reversed {
                along.reverse();
            }
            let g = &mesh.grids[b];
            let top: Vec<[f64; 2]> = (0..=g.ni)
                .rev()
                .map(|i| g.nodes[i + g.nj * (g.ni + 1)])
                .collect();
            let bits = |v: &[[f64; 2]]| -> Vec<[u64; 2]> {
                v.iter().map(|p| p.map(f64::to_bits)).collect()
            };
            assert_eq!(bits(&along), bits(&top), "block {b}");
        }
    }
    assert!(checked_templates, "no box with inserted holes");
}
