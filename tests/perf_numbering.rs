//! The compact global numbering (`numbering::Numbering`, issue 8: the unstructured writers
//! stream a mesh's merged nodes instead of holding a second copy of them) against the
//! materialising numbering it replaced, kept here as the reference, and against oracles that
//! trust neither: every id names a node with the block node's own coordinates (bit for bit,
//! or the layout vertex at a corner), two block nodes share an id exactly when they are the
//! same point, and the node count is the counting identity
//! `V + sum over used edges (n_e - 1) + sum over blocks (ni - 1)(nj - 1)`.

use crate::common;

use medial_blocks::geometry::Point;
use medial_blocks::layout::BlockLayout;
use medial_blocks::mesh::BlockGrid;
use medial_blocks::numbering::{number_nodes, GlobalNodes, Numbering};
use medial_blocks::{layouts, mesh, Mesh, Options};
use std::collections::HashMap;

/// The numbering as it was written before the compact form (copied unchanged).
fn reference(layout: &BlockLayout, grids: &[BlockGrid]) -> GlobalNodes {
    fn boundary_position(i: usize, j: usize, ni: usize, nj: usize) -> Option<(usize, usize)> {
        if j == 0 && i < ni {
            Some((0, i))
        } else if i == ni && j < nj {
            Some((1, j))
        } else if j == nj && i > 0 {
            Some((2, ni - i))
        } else if i == 0 && j > 0 {
            Some((3, nj - j))
        } else {
            None
        }
    }
    let mut coords: Vec<Point> = layout.vertices.clone();
    let mut edge_base: Vec<Option<u32>> = vec![None; layout.edges.len()];
    let mut block_nodes = Vec::with_capacity(grids.len());
    for (block, g) in layout.blocks.iter().zip(grids) {
        let (ni, nj) = (g.ni, g.nj);
        for (s, side) in block.sides.iter().enumerate() {
            let e = side.edge as usize;
            if edge_base[e].is_none() {
                let n = if s % 2 == 0 { ni } else { nj };
                edge_base[e] = Some(coords.len() as u32);
                let nodes = g.side(s);
                if side.reversed {
                    coords.extend(nodes[1..n].iter().rev());
                } else {
                    coords.extend(&nodes[1..n]);
                }
            }
        }
        let interior_base = coords.len() as u32;
        let mut ids = vec![0u32; (ni + 1) * (nj + 1)];
        for j in 0..=nj {
            for i in 0..=ni {
                let id = match boundary_position(i, j, ni, nj) {
                    Some((s, 0)) => block.corners[s],
                    Some((s, p)) => {
                        let n = if s % 2 == 0 { ni } else { nj };
                        let side = block.sides[s];
                        let pos = if side.reversed { n - p } else { p };
                        edge_base[side.edge as usize].unwrap_or(0) + pos as u32 - 1
                    }
                    None => interior_base + ((i - 1) + (j - 1) * (ni - 1)) as u32,
                };
                ids[i + j * (ni + 1)] = id;
            }
        }
        if ni > 1 && nj > 1 {
            for j in 1..nj {
                for i in 1..ni {
                    coords.push(g.node(i, j));
                }
            }
        }
        block_nodes.push(ids);
    }
    GlobalNodes {
        coords,
        block_nodes,
    }
}

fn meshes() -> Vec<(&'static str, Mesh)> {
    let paper = layouts::bubbles(12, 5).unwrap();
    let uniform = layouts::bubbles(9, 2).unwrap();
    let names = ["hexagon", "paper", "uniform 4", "periodic"];
    let mut out: Vec<(&str, Mesh)> = names
        .into_iter()
        .zip(common::small_meshes(&paper, &uniform))
        .collect();
    let opts = Options {
        block_cells: Some(7),
        ..Options::default()
    };
    out.push((
        "bubbles 60",
        mesh(&layouts::bubbles(60, 11).unwrap(), &opts).unwrap(),
    ));
    out.push((
        "lattice",
        mesh(&layouts::lattice().unwrap(), &Options::default()).unwrap(),
    ));
    out
}

/// The streamed numbering: the vertices, then every block's new points in block order.
fn streamed(m: &Mesh, n: &Numbering) -> (Vec<Point>, Vec<Vec<usize>>) {
    let mut points = m.layout.vertices.clone();
    let mut ids = Vec::new();
    let mut all = Vec::new();
    for (b, g) in m.grids.iter().enumerate() {
        let before = points.len();
        n.block_points(&m.layout, b, g, &mut points);
        assert_eq!(before..points.len(), n.block_range(b), "block {b}'s ids");
        n.block_ids(&m.layout, b, g, &mut ids);
        all.push(ids.clone());
    }
    (points, all)
}

#[test]
fn compact_numbering_gives_the_reference_numbers() {
    for (name, m) in meshes() {
        let want = reference(&m.layout, &m.grids);
        let n = Numbering::new(&m.layout, &m.grids);
        assert_eq!(n.len(), want.coords.len(), "{name}: node count");
        let (points, ids) = streamed(&m, &n);
        let bits = |p: &[Point]| p.iter().map(|q| q.map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&points), bits(&want.coords), "{name}: coordinates");
        for (b, (got, want)) in ids.iter().zip(&want.block_nodes).enumerate() {
            let want: Vec<usize> = want.iter().map(|&x| x as usize).collect();
            assert_eq!(got, &want, "{name}: ids of block {b}");
        }
        // `number_nodes` (now built on the compact form) still gives the same.
        assert_eq!(
            number_nodes(&m.layout, &m.grids),
            want,
            "{name}: number_nodes"
        );
    }
}

#[test]
fn every_id_names_its_nodes_point_and_the_count_is_the_identity() {
    for (name, m) in meshes() {
        let n = Numbering::new(&m.layout, &m.grids);
        let (points, ids) = streamed(&m, &n);
        // Counting identity, from the layout alone.
        let mut used = vec![None; m.layout.edges.len()];
        for (block, g) in m.layout.blocks.iter().zip(&m.grids) {
            for (s, side) in block.sides.iter().enumerate() {
                let cells = if s % 2 == 0 { g.ni } else { g.nj };
                used[side.edge as usize].get_or_insert(cells - 1);
            }
        }
        let interiors: usize = m.grids.iter().map(|g| (g.ni - 1) * (g.nj - 1)).sum();
        let edges: usize = used.iter().flatten().sum();
        assert_eq!(
            n.len(),
            m.layout.vertices.len() + edges + interiors,
            "{name}"
        );
        // Every block node's id holds that node (a layout vertex at a corner).
        let mut by_point: HashMap<[u64; 2], usize> = HashMap::new();
        for (b, (g, ids)) in m.grids.iter().zip(&ids).enumerate() {
            let corners = m.layout.blocks[b].corners;
            for j in 0..=g.nj {
                for i in 0..=g.ni {
                    let id = ids[i + j * (g.ni + 1)];
                    let corner = [(0, 0), (g.ni, 0), (g.ni, g.nj), (0, g.nj)]
                        .iter()
                        .position(|&c| c == (i, j));
                    let node = g.node(i, j);
                    match corner {
                        Some(k) => assert_eq!(id, corners[k] as usize, "{name}: corner"),
                        None => assert_eq!(
                            points[id].map(f64::to_bits),
                            node.map(f64::to_bits),
                            "{name}: block {b} node ({i}, {j})"
                        ),
                    }
                    // Two nodes share an id exactly when they are the same point (these
                    // meshes have no two distinct nodes at one point).
                    if corner.is_none() {
                        let key = node.map(f64::to_bits);
                        assert_eq!(*by_point.entry(key).or_insert(id), id, "{name}: merged");
                    }
                }
            }
        }
        let distinct: std::collections::HashSet<usize> = by_point.values().copied().collect();
        assert_eq!(distinct.len(), by_point.len(), "{name}: one id per point");
    }
}

#[test]
fn edge_chains_run_along_their_edges() {
    for (name, m) in meshes() {
        let n = Numbering::new(&m.layout, &m.grids);
        let (_, ids) = streamed(&m, &n);
        let mut chain = Vec::new();
        for (e, edge) in m.layout.edges.iter().enumerate() {
            n.edge_chain(&m.layout, &m.grids, e, &mut chain);
            let Some((b, s)) = n.edge_owner(e) else {
                assert!(chain.is_empty());
                continue;
            };
            assert_eq!(m.layout.blocks[b].sides[s].edge as usize, e);
            assert_eq!(
                chain.first(),
                Some(&(edge.ends[0] as usize)),
                "{name}: edge {e}"
            );
            assert_eq!(
                chain.last(),
                Some(&(edge.ends[1] as usize)),
                "{name}: edge {e}"
            );
            // Every block side on the edge has these ids, in its own direction.
            for (bb, block) in m.layout.blocks.iter().enumerate() {
                for (ss, side) in block.sides.iter().enumerate() {
                    if side.edge as usize != e {
                        continue;
                    }
                    let g = &m.grids[bb];
                    let w = g.ni + 1;
                    let at = |i: usize, j: usize| ids[bb][i + j * w];
                    let mut along: Vec<usize> = match ss {
                        0 => (0..=g.ni).map(|i| at(i, 0)).collect(),
                        1 => (0..=g.nj).map(|j| at(g.ni, j)).collect(),
                        2 => (0..=g.ni).rev().map(|i| at(i, g.nj)).collect(),
                        _ => (0..=g.nj).rev().map(|j| at(0, j)).collect(),
                    };
                    if side.reversed {
                        along.reverse();
                    }
                    assert_eq!(along, chain, "{name}: edge {e}, block {bb} side {ss}");
                }
            }
        }
    }
}
