//! A global node numbering shared across blocks, derived from the layout's topology: nodes on a
//! shared corner or edge get one number, whichever blocks touch them. Unstructured writers
//! (Gmsh `.msh`, VTK `.vtu`) use it to merge the blocks into one conforming mesh.

use crate::geometry::Point;
use crate::layout::BlockLayout;
use crate::mesh::BlockGrid;

/// Global nodes: coordinates, and for every block the global id of its node `(i, j)` at
/// `block_nodes[b][i + j * (ni + 1)]`.
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalNodes {
    pub coords: Vec<Point>,
    pub block_nodes: Vec<Vec<u32>>,
}

/// Side number and position along the side (in the side's direction) of boundary node
/// `(i, j)`; `None` for an interior node. Corners report the side that starts there.
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

/// Number the nodes of `grids` (one per layout block, same order) globally.
///
/// Corner `k` of a block is layout vertex `corners[k]`; node `p` of side `s` lies on the
/// side's edge at position `p` (or `n - p` when the side is reversed).
pub fn number_nodes(layout: &BlockLayout, grids: &[BlockGrid]) -> GlobalNodes {
    let nv = layout.vertices.len();
    let mut coords: Vec<Point> = layout.vertices.clone();
    // First node id of each edge's interior nodes, assigned on first use.
    let mut edge_base: Vec<Option<u32>> = vec![None; layout.edges.len()];
    let mut block_nodes = Vec::with_capacity(grids.len());
    for (block, g) in layout.blocks.iter().zip(grids) {
        let (ni, nj) = (g.ni, g.nj);
        // Edge interiors first, in side order, so numbering is deterministic.
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
    debug_assert!(coords.len() >= nv);
    GlobalNodes {
        coords,
        block_nodes,
    }
}
