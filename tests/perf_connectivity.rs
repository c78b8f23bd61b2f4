//! Issue #8: `connectivity::connectivity` records each edge's users in two flat arrays (a count
//! and the first two block sides) instead of one `Vec` per edge. Checked here against
//! independent facts on real meshes (bounded, refined, periodic, transition):
//! - every interface/periodic side's partner names it back, with the same orientation flag;
//! - counting identity: sides per edge kind (a wall or outer edge has one side, an interface
//!   two, a periodic edge one on each of its two partner edges) add up to `4 * blocks`;
//! - matching nodes: along an interface, node `p` of this side is node `p` or `n - p` of the
//!   partner side, bit for bit, as `same_direction` says;
//! - broken layouts give the same errors as the per-edge lists did: an edge used three times
//!   is `EdgeUse` with count 3 (of the first side in block order to meet it), a side naming a
//!   missing edge is `MissingEdge`, a grid count mismatch is `GridCount`;
//! - the compact form (`Connectivity`: 8 bytes of partner per side, each block's record formed
//!   on demand) answers every side's partner and every block's record as the records of
//!   `connectivity` do (which the checks above hold to the layout and the nodes), and `None`
//!   out of range.

use crate::common;

use medial_blocks::connectivity::{connectivity, Connectivity, ConnectivityError, SideKind};
use medial_blocks::layout::EdgeKind;
use medial_blocks::{layouts, mesh, Mesh, Options};

fn meshes() -> Vec<Mesh> {
    common::small_meshes(
        &layouts::bubbles(30, 2).unwrap(),
        &layouts::bubbles(40, 1).unwrap(),
    )
}

#[test]
fn partners_counts_and_nodes_agree() {
    for m in meshes() {
        let conn = connectivity(&m.layout, &m.grids).unwrap();
        assert_eq!(conn.len(), m.layout.blocks.len());
        let mut per_edge = vec![0usize; m.layout.edges.len()];
        for b in &m.layout.blocks {
            for s in &b.sides {
                per_edge[s.edge as usize] += 1;
            }
        }
        for (e, edge) in m.layout.edges.iter().enumerate() {
            let want = match edge.kind {
                EdgeKind::Wall(_) | EdgeKind::Periodic { .. } => 1,
                _ => 2,
            };
            assert!(per_edge[e] == want || per_edge[e] == 0, "edge {e}");
        }
        let mut sides = 0;
        for (b, bc) in conn.iter().enumerate() {
            assert_eq!(bc.block, b);
            for (s, sc) in bc.sides.iter().enumerate() {
                sides += 1;
                assert_eq!(sc.side, s);
                let e = m.layout.blocks[b].sides[s].edge as usize;
                match sc.kind {
                    SideKind::Wall | SideKind::Outer => {
                        assert!(matches!(m.layout.edges[e].kind, EdgeKind::Wall(_)));
                        assert!(sc.partner.is_none());
                    }
                    SideKind::Interface | SideKind::Periodic => {
                        let p = sc.partner.unwrap();
                        let back = conn[p.block].sides[p.side].partner.unwrap();
                        assert_eq!((back.block, back.side), (b, s));
                        assert_eq!(back.same_direction, p.same_direction);
                        let (g, pg) = (&m.grids[b], &m.grids[p.block]);
                        let (mine, theirs) = (g.side(s), pg.side(p.side));
                        assert_eq!(mine.len(), theirs.len());
                        if sc.kind == SideKind::Interface {
                            let n = mine.len() - 1;
                            for (k, x) in mine.iter().enumerate() {
                                let q = if p.same_direction { k } else { n - k };
                                assert_eq!(x, &theirs[q], "block {b} side {s} node {k}");
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(sides, 4 * m.layout.blocks.len());
    }
}

#[test]
fn compact_form_answers_as_the_records() {
    for m in meshes() {
        let records = connectivity(&m.layout, &m.grids).unwrap();
        let conn = Connectivity::new(&m.layout, &m.grids).unwrap();
        let n = records.len();
        assert_eq!((conn.len(), conn.is_empty()), (n, n == 0));
        let mut partners = 0;
        for (b, bc) in records.iter().enumerate() {
            assert_eq!(conn.block(b).as_ref(), Some(bc));
            assert_eq!(conn.dims(b), Some(bc.dims));
            for (s, sc) in bc.sides.iter().enumerate() {
                assert_eq!(conn.partner(b, s), sc.partner, "block {b} side {s}");
                // The side formed alone is the record's (what the writer takes).
                assert_eq!(conn.side(b, s).as_ref(), Some(sc), "block {b} side {s}");
                partners += usize::from(sc.partner.is_some());
            }
            assert_eq!(conn.partner(b, 4), None);
            assert_eq!(conn.side(b, 4), None);
        }
        assert!(partners > 0);
        assert_eq!(conn.block(n), None);
        assert_eq!(conn.partner(n, 0), None);
        assert_eq!((conn.dims(n), conn.side(n, 0)), (None, None));
        assert_eq!(conn.to_vec(), records);
    }
}

#[test]
fn broken_layouts_give_the_same_errors() {
    let m = mesh(&layouts::hexagon(), &Options::default()).unwrap();
    // An interface edge used by a third side: the first side (in block order) that meets it.
    let conn = connectivity(&m.layout, &m.grids).unwrap();
    let (b, s) = (0..conn.len())
        .flat_map(|b| (0..4).map(move |s| (b, s)))
        .find(|&(b, s)| conn[b].sides[s].kind == SideKind::Interface)
        .unwrap();
    let e = m.layout.blocks[b].sides[s].edge;
    let wall = (0..conn.len())
        .flat_map(|b| (0..4).map(move |s| (b, s)))
        .find(|&(b, s)| conn[b].sides[s].kind == SideKind::Wall)
        .unwrap();
    let mut layout = m.layout.clone();
    layout.blocks[wall.0].sides[wall.1].edge = e;
    let err = connectivity(&layout, &m.grids).unwrap_err();
    // The wall edge left behind has no user; the edge now has three.
    let first_user = (0..layout.blocks.len())
        .flat_map(|b| (0..4).map(move |s| (b, s)))
        .find(|&(b, s)| layout.blocks[b].sides[s].edge == e)
        .unwrap();
    assert!(first_user <= (b, s));
    assert_eq!(
        err,
        ConnectivityError::EdgeUse {
            edge: e as usize,
            count: 3
        }
    );
    // A side naming a missing edge.
    let mut layout = m.layout.clone();
    let ne = layout.edges.len() as u32;
    layout.blocks[3].sides[2].edge = ne + 5;
    assert_eq!(
        connectivity(&layout, &m.grids).unwrap_err(),
        ConnectivityError::MissingEdge {
            edge: ne as usize + 5
        }
    );
    assert_eq!(
        connectivity(&m.layout, &m.grids[1..]).unwrap_err(),
        ConnectivityError::GridCount {
            layout: m.layout.blocks.len(),
            grids: m.grids.len() - 1
        }
    );
}

/// The blocks are visited in parallel: with several broken blocks far apart (in different
/// tasks), the error is still that of the first side in block order with a wrong user count
/// (found here by a plain sequential count), on 1, 2 and 3 threads.
#[test]
fn parallel_visit_reports_the_first_error_in_block_order() {
    let m = mesh(&layouts::bubbles(300, 4).unwrap(), &Options::default()).unwrap();
    let nb = m.layout.blocks.len();
    assert!(nb > 1500, "{nb} blocks");
    let conn = connectivity(&m.layout, &m.grids).unwrap();
    let sides = |from: usize, kind: SideKind| {
        (from..nb)
            .flat_map(|b| (0..4).map(move |s| (b, s)))
            .find(|&(b, s)| conn[b].sides[s].kind == kind)
            .unwrap()
    };
    let run = |layout: &medial_blocks::BlockLayout, threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| connectivity(layout, &m.grids).unwrap_err())
    };
    for (early, late) in [(nb / 3, nb - 5), (10, nb / 2), (nb - 40, nb - 2)] {
        let mut layout = m.layout.clone();
        for at in [late, early] {
            let i = sides(at, SideKind::Interface);
            let w = sides(at, SideKind::Wall);
            layout.blocks[w.0].sides[w.1].edge = layout.blocks[i.0].sides[i.1].edge;
        }
        let mut users = vec![0usize; layout.edges.len()];
        for b in &layout.blocks {
            for s in &b.sides {
                users[s.edge as usize] += 1;
            }
        }
        let e = layout
            .blocks
            .iter()
            .flat_map(|b| b.sides.iter().map(|s| s.edge as usize))
            .find(|&e| {
                let want = if matches!(layout.edges[e].kind, EdgeKind::Wall(_)) {
                    1
                } else {
                    2
                };
                users[e] != want
            })
            .unwrap();
        let want = ConnectivityError::EdgeUse {
            edge: e,
            count: users[e],
        };
        for threads in [1, 2, 3] {
            assert_eq!(run(&layout, threads), want, "{threads} threads");
        }
    }
}
