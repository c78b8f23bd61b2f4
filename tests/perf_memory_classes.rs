//! `grid::edge_classes` numbers classes without a per-root table (each root is its class's
//! smallest edge) and keeps `u32` parents (issue 8: half the fresh memory). Checked against a
//! plain reference: label propagation to a fixed point (every edge takes the smallest label
//! among the edges it is tied to), classes numbered in order of their smallest edge, on
//! random layouts (invalid side references included: ignored) and on real meshes.

use medial_blocks::grid::edge_classes;
use medial_blocks::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef, Translation};

use crate::common;
use common::XorShift;

fn reference(layout: &BlockLayout) -> (Vec<usize>, usize) {
    let ne = layout.edges.len();
    let mut ties: Vec<(usize, usize)> = Vec::new();
    for b in &layout.blocks {
        let e = b.sides.map(|s| s.edge as usize);
        if e.iter().all(|&x| x < ne) {
            ties.extend([(e[0], e[2]), (e[1], e[3])]);
        }
    }
    for (e, edge) in layout.edges.iter().enumerate() {
        if let EdgeKind::Periodic { partner, .. } = edge.kind {
            if (partner as usize) < ne {
                ties.push((e, partner as usize));
            }
        }
    }
    let mut label: Vec<usize> = (0..ne).collect();
    loop {
        let mut changed = false;
        for &(a, b) in &ties {
            let m = label[a].min(label[b]);
            for x in [a, b] {
                if label[x] != m {
                    label[x] = m;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    let mut id = vec![usize::MAX; ne];
    let mut classes = 0;
    let class = label
        .iter()
        .map(|&l| {
            if id[l] == usize::MAX {
                id[l] = classes;
                classes += 1;
            }
            id[l]
        })
        .collect();
    (class, classes)
}

fn random_layout(rng: &mut XorShift, ne: usize, nb: usize) -> BlockLayout {
    let edges = (0..ne)
        .map(|_| Edge {
            ends: [0, 0],
            curve: Curve::Segment,
            kind: if rng.below(10) == 0 {
                EdgeKind::Periodic {
                    // Now and then out of range: ignored.
                    partner: rng.below(ne as u64 + 2) as u32,
                    translation: Translation([1.0, 0.0]),
                }
            } else {
                EdgeKind::Interface
            },
        })
        .collect();
    let blocks = (0..nb)
        .map(|_| Block {
            corners: [0; 4],
            sides: [0; 4].map(|_| SideRef {
                edge: rng.below(ne as u64 + 1) as u32,
                reversed: false,
            }),
            wall: None,
        })
        .collect();
    BlockLayout {
        vertices: Vec::new(),
        edges,
        blocks,
    }
}

#[test]
fn edge_classes_match_label_propagation() {
    let mut rng = XorShift(0x5eed);
    for (ne, nb) in [
        (0, 0),
        (1, 0),
        (7, 3),
        (40, 10),
        (200, 30),
        (500, 200),
        (300, 600),
    ] {
        for _ in 0..4 {
            let layout = random_layout(&mut rng, ne, nb);
            assert_eq!(
                edge_classes(&layout),
                reference(&layout),
                "{ne} edges, {nb} blocks"
            );
        }
    }
    let bubbles = medial_blocks::layouts::bubbles(12, 3).unwrap();
    for m in common::small_meshes(&bubbles, &bubbles) {
        assert_eq!(edge_classes(&m.layout), reference(&m.layout));
    }
}
