//! The finished mesh: the layout, a structured grid per block, and what the pipeline learnt.

use crate::cocircular::CocircularGroup;
use crate::domain::Circle;
use crate::geometry::Point;
use crate::layout::BlockLayout;

/// The structured grid of one block: `(ni + 1) x (nj + 1)` nodes, node `(i, j)` at
/// `nodes[i + j * (ni + 1)]`. Side conventions are those of [`crate::layout`]. The default
/// is the empty grid (no cell, no node).
#[derive(Debug, Clone, PartialEq, Default)]
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

/// Which geometry a mesh's blocks were built on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Geometry {
    /// Paper geometry: circumcentre polylines, sampled walls, equally spaced transfinite
    /// interpolation (paper mode, the disk template, and exact mode's rare fallback, see
    /// [`crate::mesher::mesh`]).
    #[default]
    Paper,
    /// Exact geometry: Apollonius vertices, conic medial arcs, spoke-aligned grids
    /// ([`crate::exact_mode`]).
    Exact,
}

impl Geometry {
    /// The name used in `report.json` (`"geometry"`).
    pub fn name(self) -> &'static str {
        match self {
            Geometry::Paper => "paper",
            Geometry::Exact => "exact",
        }
    }
}

/// A multiblock structured mesh.
///
/// Counting identity (`h >= 2` input holes, `m` inserted holes): `medial_vertices =
/// 2(h + m - 1)`, `medial_arcs = 3(h + m - 1)` (the graph before collapse) and
/// `layout.blocks.len() = 6(h + m - 1) - 2 collapsed_arcs + 2 split_arcs + template_blocks`.
/// Build one with [`Mesh::new`] or a struct literal ending in `..Mesh::default()`, so that
/// fields added later do not break it.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub layout: BlockLayout,
    pub grids: Vec<BlockGrid>,
    /// Number of medial vertices and arcs of the final (refined) domain before arc collapse
    /// (0 for the template cases).
    pub medial_vertices: usize,
    pub medial_arcs: usize,
    /// Number of holes of the input domain (inserted holes not counted).
    pub holes: usize,
    /// Co-circular hole groups of the final domain (paper section 4.2), hole ids as in the
    /// input (`-1` the bounding circle; ids `>= holes` are inserted holes,
    /// `inserted_holes[id - holes]`).
    pub cocircular_groups: Vec<CocircularGroup>,
    /// Medial arcs collapsed (zero-length and short arcs, [`crate::collapse`]).
    pub collapsed_arcs: usize,
    /// Holes inserted by macro Delaunay refinement ([`crate::refine`]); they are fluid, filled
    /// by template blocks ([`crate::templates::fill_inserted_hole`]).
    pub inserted_holes: Vec<Circle>,
    /// Medial block pairs split in two to give an inserted hole an even number of sides; for
    /// one hole in exact mode, the pieces its closed medial loop is cut into
    /// ([`crate::exact_mode::annulus`]), so that blocks are `6(h - 1) + 2 split_arcs` there too.
    pub split_arcs: usize,
    /// Blocks inside inserted holes.
    pub template_blocks: usize,
    /// The geometry the blocks were built on (exact mode falls back to paper geometry only
    /// where the exact geometry disagrees with the sampled combinatorics).
    pub geometry: Geometry,
    /// Exact mode: `[default, used]` when the default target cell size (the median
    /// Apollonius radius over `cells`) would have given more nodes than
    /// [`crate::exact_mode::node_budget`] and was coarsened to `used`; `None` otherwise (also
    /// whenever the size was chosen: `cell_size`, `block_cells`, imposed counts).
    pub coarsened_cell_size: Option<[f64; 2]>,
    /// The report's figures of every block, measured as its grid was made, when the grids
    /// were made without keeping their nodes ([`crate::Options::keep_nodes`] false): then
    /// every grid has its `ni` and `nj` and no node, and
    /// [`crate::output::report::Report`] reads the figures from here. `None` whenever the
    /// grids hold their nodes.
    pub measured: Option<std::sync::Arc<crate::quality::Measured>>,
}

impl Mesh {
    /// A mesh of `layout` and `grids` for `holes` input holes, with no medial facts.
    pub fn new(layout: BlockLayout, grids: Vec<BlockGrid>, holes: usize) -> Mesh {
        Mesh {
            layout,
            grids,
            holes,
            ..Mesh::default()
        }
    }
}
