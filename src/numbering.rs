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

/// Number the nodes of `grids` (one per layout block, same order) globally, every node's
/// coordinates and every block's ids held at once (the writers stream the same numbers
/// from a [`Numbering`] instead).
///
/// Corner `k` of a block is layout vertex `corners[k]`; node `p` of side `s` lies on the
/// side's edge at position `p` (or `n - p` when the side is reversed).
pub fn number_nodes(layout: &BlockLayout, grids: &[BlockGrid]) -> GlobalNodes {
    let numbering = Numbering::new(layout, grids);
    let mut coords: Vec<Point> = Vec::with_capacity(numbering.len());
    coords.extend_from_slice(&layout.vertices);
    let mut block_nodes = Vec::with_capacity(grids.len());
    let mut ids = Vec::new();
    for (b, g) in grids.iter().enumerate().take(layout.blocks.len()) {
        numbering.block_points(layout, b, g, &mut coords);
        numbering.block_ids(layout, b, g, &mut ids);
        block_nodes.push(ids.iter().map(|&id| id as u32).collect());
    }
    GlobalNodes {
        coords,
        block_nodes,
    }
}

/// The global node numbering of [`number_nodes`] in `O(edges + blocks)` memory: the first id
/// of every edge's interior nodes and of every block's interior, from which a block's ids and
/// the coordinates of the nodes it numbers first are formed on demand (issue 8: the
/// unstructured writers stream a 1e5-particle mesh without a second copy of its nodes).
///
/// The numbers: the layout vertices first (`0..vertices`), then block by block, the interior
/// nodes of each edge the block is the first to use (its sides in order, each edge's nodes in
/// the edge's direction), then the block's interior nodes (`i` fastest). So the ids a block
/// adds are consecutive, and [`Numbering::block_points`] of blocks `0, 1, ...` after the
/// vertices lists every node once, in id order.
///
/// ```
/// use medial_blocks::numbering::Numbering;
/// use medial_blocks::{layouts, mesh, Options};
///
/// let m = mesh(&layouts::hexagon(), &Options::default()).unwrap();
/// let n = Numbering::new(&m.layout, &m.grids);
/// // The merged points in id order: the vertices, then what each block adds.
/// let mut points = m.layout.vertices.clone();
/// for (b, g) in m.grids.iter().enumerate() {
///     n.block_points(&m.layout, b, g, &mut points);
/// }
/// assert_eq!(points.len(), n.len());
/// // Every node of a block but its corners (layout vertices) is the point of its id.
/// let mut ids = Vec::new();
/// let g = &m.grids[0];
/// n.block_ids(&m.layout, 0, g, &mut ids);
/// assert_eq!(points[ids[1]], g.node(1, 0));
/// assert_eq!(points[ids[g.ni + 2]], g.node(1, 1));
/// // Shared nodes are merged: fewer points than block nodes.
/// assert!(n.len() < m.grids.iter().map(|g| g.nodes.len()).sum::<usize>());
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Numbering {
    /// Id of edge `e`'s first interior node (`usize::MAX` for an edge no block uses).
    edge_base: Vec<usize>,
    /// The block side that numbers edge `e`: `4 block + side` of the first side using it
    /// (`usize::MAX` for none).
    edge_owner: Vec<usize>,
    /// `block_base[b]`: the first id block `b` adds; one more entry, the node count.
    block_base: Vec<usize>,
    /// Id of block `b`'s first interior node.
    interior_base: Vec<usize>,
}

impl Numbering {
    /// The numbering of `grids` (one per layout block, same order; extra grids or blocks are
    /// left out). Only the grids' `ni`, `nj` are read. The other methods expect what the
    /// writers check first (`output::check_mesh`): every block's corners and sides name
    /// vertices and edges of the layout, and every grid is well formed; they panic otherwise.
    pub fn new(layout: &BlockLayout, grids: &[BlockGrid]) -> Numbering {
        let vertices = layout.vertices.len();
        let mut edge_base = vec![usize::MAX; layout.edges.len()];
        let mut edge_owner = vec![usize::MAX; layout.edges.len()];
        let blocks = layout.blocks.len().min(grids.len());
        let mut block_base = Vec::with_capacity(blocks + 1);
        let mut interior_base = Vec::with_capacity(blocks);
        let mut next = vertices;
        for (b, (block, g)) in layout.blocks.iter().zip(grids).enumerate() {
            block_base.push(next);
            for (s, side) in block.sides.iter().enumerate() {
                let e = side.edge as usize;
                if let Some(base) = edge_base.get_mut(e).filter(|base| **base == usize::MAX) {
                    *base = next;
                    edge_owner[e] = 4 * b + s;
                    next += side_cells(g, s).saturating_sub(1);
                }
            }
            interior_base.push(next);
            next += g.ni.saturating_sub(1) * g.nj.saturating_sub(1);
        }
        block_base.push(next);
        Numbering {
            edge_base,
            edge_owner,
            block_base,
            interior_base,
        }
    }

    /// The number of global nodes (`block_base` always ends with it).
    pub fn len(&self) -> usize {
        self.block_base.last().copied().unwrap_or(0)
    }

    /// True when there is no node.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The ids block `b` adds: `block_base(b)..block_base(b + 1)`.
    pub fn block_range(&self, b: usize) -> std::ops::Range<usize> {
        self.block_base[b]..self.block_base[b + 1]
    }

    /// The block side that numbers edge `e` (the first side using it), as `(block, side)`.
    pub fn edge_owner(&self, e: usize) -> Option<(usize, usize)> {
        let o = *self.edge_owner.get(e)?;
        (o != usize::MAX).then_some((o / 4, o % 4))
    }

    /// The ids of block `b`'s nodes into `out` (cleared first): node `(i, j)` at
    /// `out[i + j * (ni + 1)]`, `grid` being block `b`'s grid.
    pub fn block_ids(
        &self,
        layout: &BlockLayout,
        b: usize,
        grid: &BlockGrid,
        out: &mut Vec<usize>,
    ) {
        let block = &layout.blocks[b];
        let (ni, nj) = (grid.ni, grid.nj);
        out.clear();
        out.reserve((ni + 1) * (nj + 1));
        let interior = self.interior_base[b];
        for j in 0..=nj {
            for i in 0..=ni {
                out.push(match boundary_position(i, j, ni, nj) {
                    Some((s, 0)) => block.corners[s] as usize,
                    Some((s, p)) => {
                        let side = block.sides[s];
                        let n = side_cells(grid, s);
                        let pos = if side.reversed { n - p } else { p };
                        self.edge_base[side.edge as usize] + pos - 1
                    }
                    None => interior + (i - 1) + (j - 1) * (ni - 1),
                });
            }
        }
    }

    /// Append the coordinates of the nodes block `b` adds (ids [`Self::block_range`], in
    /// order) to `out`; `grid` is block `b`'s grid, well formed
    /// ([`crate::quality::well_formed`]).
    pub fn block_points(
        &self,
        layout: &BlockLayout,
        b: usize,
        grid: &BlockGrid,
        out: &mut Vec<Point>,
    ) {
        let block = &layout.blocks[b];
        let (ni, nj) = (grid.ni, grid.nj);
        out.reserve(self.block_range(b).len());
        for (s, side) in block.sides.iter().enumerate() {
            if self.edge_owner[side.edge as usize] == 4 * b + s {
                let nodes = side_interior(grid, s);
                if side.reversed {
                    out.extend(nodes.rev());
                } else {
                    out.extend(nodes);
                }
            }
        }
        if ni > 1 && nj > 1 {
            for j in 1..nj {
                let row = j * (ni + 1);
                out.extend_from_slice(&grid.nodes[row + 1..row + ni]);
            }
        }
    }

    /// The side that numbers edge `e` (`block`, `side`) and the layout vertices the edge runs
    /// between, in its direction.
    fn edge_ends(&self, layout: &BlockLayout, e: usize) -> Option<(usize, usize, [usize; 2])> {
        let (b, s) = self.edge_owner(e)?;
        let block = &layout.blocks[b];
        let [from, to] = [block.corners[s], block.corners[(s + 1) % 4]].map(|v| v as usize);
        Some((
            b,
            s,
            if block.sides[s].reversed {
                [to, from]
            } else {
                [from, to]
            },
        ))
    }

    /// The ids of edge `e`'s nodes in the edge's direction (its two layout vertices and the
    /// interior nodes between them) into `out` (cleared first; left empty for an edge no block
    /// uses): the chain of the side that numbers it.
    pub fn edge_chain(
        &self,
        layout: &BlockLayout,
        grids: &[BlockGrid],
        e: usize,
        out: &mut Vec<usize>,
    ) {
        out.clear();
        let Some((b, s, [start, end])) = self.edge_ends(layout, e) else {
            return;
        };
        let inner = side_cells(&grids[b], s).saturating_sub(1);
        let base = self.edge_base[e];
        out.push(start);
        out.extend(base..base + inner);
        out.push(end);
    }

    /// The points of [`Self::edge_chain`] (the two layout vertices, the interior nodes of the
    /// side that numbers the edge between them) into `out` (cleared first).
    pub fn edge_points(
        &self,
        layout: &BlockLayout,
        grids: &[BlockGrid],
        e: usize,
        out: &mut Vec<Point>,
    ) {
        out.clear();
        let Some((b, s, [start, end])) = self.edge_ends(layout, e) else {
            return;
        };
        out.push(layout.vertices[start]);
        let nodes = side_interior(&grids[b], s);
        if layout.blocks[b].sides[s].reversed {
            out.extend(nodes.rev());
        } else {
            out.extend(nodes);
        }
        out.push(layout.vertices[end]);
    }
}

/// The number of cells along side `s` of `grid`.
fn side_cells(grid: &BlockGrid, s: usize) -> usize {
    if s.is_multiple_of(2) {
        grid.ni
    } else {
        grid.nj
    }
}

/// The interior nodes of side `s` of `grid` (positions `1..n`, in the side's direction), as
/// `grid.side(s)[1..n]` without allocating.
fn side_interior(grid: &BlockGrid, s: usize) -> impl DoubleEndedIterator<Item = Point> + '_ {
    let (ni, nj) = (grid.ni, grid.nj);
    let n = side_cells(grid, s);
    (1..n.max(1)).map(move |p| match s {
        0 => grid.node(p, 0),
        1 => grid.node(ni, p),
        2 => grid.node(ni - p, nj),
        _ => grid.node(0, nj - p),
    })
}
