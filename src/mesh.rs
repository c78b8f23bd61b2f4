//! The finished mesh: the layout, a structured grid per block, and what the pipeline learnt.

use crate::geometry::Point;
use crate::layout::BlockLayout;

/// The structured grid of one block: `(ni + 1) x (nj + 1)` nodes, node `(i, j)` at
/// `nodes[i + j * (ni + 1)]`. Side conventions are those of [`crate::layout`].
#[derive(Debug, Clone, PartialEq)]
pub struct BlockGrid {
    pub ni: usize,
    pub nj: usize,
    pub nodes: Vec<Point>,
}

impl BlockGrid {
    /// Node `(i, j)`.
    pub fn node(&self, i: usize, j: usize) -> Point {
        self.nodes[i + j * (self.ni + 1)]
    }
    /// The nodes of side `k` (0..4) in the side's direction (see [`crate::layout`]).
    pub fn side(&self, k: usize) -> Vec<Point> {
        match k {
            0 => (0..=self.ni).map(|i| self.node(i, 0)).collect(),
            1 => (0..=self.nj).map(|j| self.node(self.ni, j)).collect(),
            2 => (0..=self.ni).rev().map(|i| self.node(i, self.nj)).collect(),
            _ => (0..=self.nj).rev().map(|j| self.node(0, j)).collect(),
        }
    }
    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.ni * self.nj
    }
}

/// A multiblock structured mesh.
#[derive(Debug, Clone)]
pub struct Mesh {
    pub layout: BlockLayout,
    pub grids: Vec<BlockGrid>,
    /// Number of medial vertices and arcs (0 for the template cases).
    pub medial_vertices: usize,
    pub medial_arcs: usize,
    pub holes: usize,
}
