//! Large layouts are meshed with their holes in a spatial order and given back in the
//! input's hole ids (`medial_blocks::spatial_order`, issue 8). The oracle: the same holes
//! in a shuffled order sort into the same order, so the two meshes must have the same nodes
//! bit for bit, and each block must name, in its own input's ids, the same circle; and
//! every wall block's wall nodes must lie on the circle it names (the input's geometry, not
//! the renaming's), every co-circular group's holes on its common circle, and a per-circle
//! option must reach the circle the caller named.

use crate::common;

use medial_blocks::domain::{Circle, CircleId, Domain};
use medial_blocks::layout::EdgeKind;
use medial_blocks::layouts::{self, SplitMix64};
use medial_blocks::spatial_order::{hole_order, SPATIAL_ORDER_MIN_HOLES};
use medial_blocks::{mesh, Mesh, Options};

/// A random permutation of `0..n` (Fisher-Yates from `seed`).
fn permutation(n: usize, seed: u64) -> Vec<usize> {
    let mut r = SplitMix64(seed);
    let mut from: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = (r.next_u64() % (i as u64 + 1)) as usize;
        from.swap(i, j);
    }
    from
}

/// `holes` in the order `from` (new hole `j` is old hole `from[j]`).
fn permuted(holes: &[Circle], from: &[usize]) -> Vec<Circle> {
    from.iter().map(|&i| holes[i]).collect()
}

/// `a` and `b`, the meshes of the same holes where `b`'s hole `j` is `a`'s hole `from[j]`, are
/// the same mesh: the same nodes bit for bit, and block by block and edge by edge the same
/// circle in each one's own ids (the bounding circle and inserted holes keep their ids).
fn assert_same_but_for_the_ids(a: &Mesh, b: &Mesh, from: &[usize]) {
    assert_eq!(common::node_bits(a), common::node_bits(b));
    assert_eq!(a.layout.blocks.len(), b.layout.blocks.len());
    let h = from.len() as CircleId;
    let to_a = |c: CircleId| {
        if (0..h).contains(&c) {
            from[c as usize] as CircleId
        } else {
            c
        }
    };
    for (x, y) in a.layout.blocks.iter().zip(&b.layout.blocks) {
        assert_eq!(x.wall, y.wall.map(to_a));
        assert_eq!(x.corners, y.corners);
    }
    for (x, y) in a.layout.edges.iter().zip(&b.layout.edges) {
        match (x.kind, y.kind) {
            (EdgeKind::Wall(p), EdgeKind::Wall(q)) => assert_eq!(p, to_a(q)),
            (p, q) => assert_eq!(p, q),
        }
    }
}

/// The circle `c` of `domain` (`-1` the bounding circle).
fn circle(domain: &Domain, m: &Mesh, c: CircleId) -> Circle {
    let h = domain.holes().len() as CircleId;
    if c >= h {
        m.inserted_holes[(c - h) as usize]
    } else {
        domain.circle(c)
    }
}

/// Every wall block's nodes on its wall side (`j = 0`) lie on the circle its `wall` names.
fn walls_on_their_circles(domain: &Domain, m: &Mesh) -> usize {
    let mut walls = 0;
    for (b, (block, g)) in m.layout.blocks.iter().zip(&m.grids).enumerate() {
        let Some(c) = block.wall else { continue };
        let k = circle(domain, m, c);
        for i in 0..=g.ni {
            let p = g.node(i, 0);
            let d = (p[0] - k.center[0]).hypot(p[1] - k.center[1]);
            assert!(
                (d - k.radius).abs() <= 1e-9 * k.radius.max(1.0),
                "block {b}: wall node {i} at {d} from circle {c} of radius {}",
                k.radius
            );
        }
        walls += 1;
    }
    walls
}

#[test]
fn shuffled_holes_give_the_same_mesh_in_their_own_ids() {
    let n = SPATIAL_ORDER_MIN_HOLES + 200;
    let domain = layouts::bubbles(n, 11).expect("layout");
    let options = Options {
        block_cells: Some(4),
        ..Options::default()
    };
    assert!(hole_order(domain.holes(), &options).is_some());
    let from = permutation(n, 5);
    let other = Domain::bounded(domain.bounding(), permuted(domain.holes(), &from))
        .expect("the same circles");
    let (a, b) = (
        mesh(&domain, &options).expect("mesh"),
        mesh(&other, &options).expect("mesh"),
    );
    assert_same_but_for_the_ids(&a, &b, &from);
    assert_eq!(
        walls_on_their_circles(&domain, &a),
        walls_on_their_circles(&other, &b)
    );
    assert!(walls_on_their_circles(&domain, &a) >= n);
}

/// A wall-normal count for one circle, named in the input's ids, reaches that circle.
#[test]
fn per_circle_options_name_the_callers_circles() {
    let domain = layouts::bubbles(SPATIAL_ORDER_MIN_HOLES + 10, 3).expect("layout");
    let named: CircleId = 17;
    let options = Options {
        wall_cells: vec![(named, 7)],
        ..Options::default()
    };
    assert!(hole_order(domain.holes(), &options).is_some());
    let m = mesh(&domain, &options).expect("mesh");
    let mut at_named = 0;
    for (block, g) in m.layout.blocks.iter().zip(&m.grids) {
        if block.wall == Some(named) {
            assert_eq!(g.nj, 7, "a block on circle {named}");
            at_named += 1;
        }
    }
    assert!(at_named >= 3, "{at_named} blocks on circle {named}");
    walls_on_their_circles(&domain, &m);
}

/// A square lattice of 64 x 64 holes (every four neighbours co-circular): each group's holes,
/// in the input's ids, are tangent to the group's circle.
#[test]
fn cocircular_groups_name_the_callers_holes() {
    let domain = layouts::square_lattice(64 * 64).expect("layout");
    assert_eq!(domain.holes().len(), SPATIAL_ORDER_MIN_HOLES);
    let options = Options {
        block_cells: Some(2),
        ..Options::default()
    };
    assert!(hole_order(domain.holes(), &options).is_some());
    let m = mesh(&domain, &options).expect("mesh");
    assert!(
        m.cocircular_groups.len() > 3000,
        "{}",
        m.cocircular_groups.len()
    );
    for g in &m.cocircular_groups {
        assert!(g.holes.windows(2).all(|w| w[0] < w[1]), "{:?}", g.holes);
        for &c in &g.holes {
            let k = circle(&domain, &m, c);
            let d = (g.center[0] - k.center[0]).hypot(g.center[1] - k.center[1]);
            let gap = if c < 0 { k.radius - d } else { d - k.radius };
            assert!(
                (gap - g.radius).abs() <= 1e-9,
                "group {:?}: circle {c}",
                g.holes
            );
        }
    }
    walls_on_their_circles(&domain, &m);
}

/// Small layouts and imposed counts keep the input order.
#[test]
fn small_layouts_keep_the_input_order() {
    let small = layouts::bubbles(SPATIAL_ORDER_MIN_HOLES - 1, 3).expect("layout");
    assert!(hole_order(small.holes(), &Options::default()).is_none());
    let large = layouts::bubbles(SPATIAL_ORDER_MIN_HOLES, 3).expect("layout");
    assert!(hole_order(large.holes(), &Options::default()).is_some());
    let imposed = Options {
        imposed_counts: Some(Default::default()),
        ..Options::default()
    };
    assert!(hole_order(large.holes(), &imposed).is_none());
    // Already in Hilbert order: nothing to do.
    let order = hole_order(large.holes(), &Options::default()).expect("an order");
    let holes: Vec<Circle> = order.iter().map(|&i| large.holes()[i as usize]).collect();
    let sorted = Domain::bounded(large.bounding(), holes).expect("the same circles");
    assert!(hole_order(sorted.holes(), &Options::default()).is_none());
}

/// A periodic box through `mesh_periodic`: shuffled holes give the same nodes bit for bit and
/// the same circle per block and edge in each input's own ids, and the mesh passes the
/// periodic checker (walls on their circles' images, partners translated) in the caller's
/// ids; `mesh_periodic_frame` (a sequence's, with medial triples in hole ids) keeps the
/// input order, so its mesh is the same up to the numbering.
#[test]
fn periodic_boxes_are_meshed_in_a_spatial_order_too() {
    use medial_blocks::fuzzing::{periodic::check_periodic_mesh, Checks};
    use medial_blocks::periodic::mesh_periodic_frame;
    use medial_blocks::{mesh_periodic, PeriodicDomain};
    let n = SPATIAL_ORDER_MIN_HOLES + 50;
    let pd = layouts::periodic_bubbles(n, 4).expect("layout");
    let options = Options {
        block_cells: Some(3),
        ..Options::default()
    };
    assert!(hole_order(pd.holes(), &options).is_some());
    let from = permutation(n, 8);
    let other =
        PeriodicDomain::new(pd.size(), permuted(pd.holes(), &from)).expect("the same circles");
    let (a, b) = (
        mesh_periodic(&pd, &options).expect("mesh"),
        mesh_periodic(&other, &options).expect("mesh"),
    );
    assert_same_but_for_the_ids(&a, &b, &from);
    let checks = Checks {
        no_inverted_cells: true,
    };
    check_periodic_mesh(&pd, &a, checks).expect("a valid periodic mesh");
    check_periodic_mesh(&other, &b, checks).expect("a valid periodic mesh");
    // The frame keeps the input order: the same counts, its own numbering.
    let f = mesh_periodic_frame(&pd, &options).expect("frame");
    assert_eq!(f.mesh.layout.blocks.len(), a.layout.blocks.len());
    check_periodic_mesh(&pd, &f.mesh, checks).expect("a valid periodic mesh");
}

/// A sequence of a large layout: its first frame is meshed in the spatial order, the later
/// ones with the first's counts imposed (in the input order, keyed by the input's hole ids);
/// small motions keep the combinatorics, the blocks and the node counts, frame after frame.
#[test]
fn sequences_of_large_layouts_keep_their_node_counts() {
    use medial_blocks::sequence::{parse_frames, run_sequence};
    let domain = layouts::bubbles(SPATIAL_ORDER_MIN_HOLES + 100, 9).expect("layout");
    let frames: Vec<String> = (0..3)
        .map(|k| {
            let holes: Vec<Circle> = domain
                .holes()
                .iter()
                .map(|h| Circle {
                    center: [h.center[0] + 1e-7 * k as f64, h.center[1]],
                    radius: h.radius,
                })
                .collect();
            let d = Domain::bounded(domain.bounding(), holes).expect("a frame");
            d.to_json_string()
        })
        .collect();
    let frames = parse_frames(&frames.join("\n"));
    let options = Options {
        cells: 4,
        ..Options::default()
    };
    let dir = tempfile::tempdir().expect("a scratch directory");
    let s = run_sequence(
        &frames,
        &options,
        &[medial_blocks::output::Format::Json],
        medial_blocks::output::Encoding::Ascii,
        dir.path(),
        2,
        &|| {},
    )
    .expect("the sequence");
    assert_eq!(s.failed, 0);
    for k in 1..3 {
        let f = &s.frames[k];
        assert!(f.same_combinatorics_as_previous, "frame {k}: {f:?}");
        assert!(f.same_block_structure_as_previous, "frame {k}: {f:?}");
        assert!(f.same_node_counts_as_previous, "frame {k}: {f:?}");
        assert_eq!(f.node_counts_from_frame, Some(0), "frame {k}");
    }
    // Frame 0's counts, by block key (hole ids: the input's), imposed on frame 2: the build
    // finds every key and applies them (it would not, were its keys in the sorted ids).
    use medial_blocks::exact_mode::imposed::ImposedCounts;
    use medial_blocks::sequence::mesh_frame;
    let f0 = mesh_frame(frames[0].as_ref().expect("frame 0"), &options).expect("frame 0");
    let want = f0.structure().expect("exact mode gives block keys");
    let counts = std::sync::Arc::new(ImposedCounts::new(want.iter().cloned().collect()));
    let imposed = Options {
        imposed_counts: Some(counts.clone()),
        ..options.clone()
    };
    let f2 = mesh_frame(frames[2].as_ref().expect("frame 2"), &imposed).expect("frame 2");
    assert!(
        counts.applied(),
        "frame 0's counts were not applied to frame 2"
    );
    assert_eq!(f2.structure().expect("keys"), want);
}
