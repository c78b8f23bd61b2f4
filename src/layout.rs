//! The block layout: the topology and geometry of the multiblock decomposition, before any grid.
//!
//! Conventions (used by every stage and writer):
//! - a block is a logically rectangular patch with corners `c0, c1, c2, c3` counter-clockwise;
//! - side `k` runs from corner `k` to corner `k+1 (mod 4)`;
//! - in the block's structured grid, side 0 is `j = 0` (i increasing), side 1 is `i = ni`
//!   (j increasing), side 2 is `j = nj` (traversed with i decreasing), side 3 is `i = 0`
//!   (traversed with j decreasing). So opposite sides 0/2 have `ni` cells, sides 1/3 have `nj`;
//! - for a medial block (paper Algorithm 2), side 0 is the wall (the paper's xi1 curve on a
//!   circle), side 2 is the medial arc (xi0) and sides 1 and 3 are spokes (eta curves); so `j`
//!   grows from the wall into the fluid, the usual structured-solver convention.
//!
//! Every geometric edge is stored once and referenced by the blocks that share it, so shared
//! sides get identical nodes by construction (the tests still check it independently).

use crate::domain::CircleId;
use crate::geometry::Point;

/// The geometry of one edge between two layout vertices. The discretisation always puts the
/// first and last node exactly on the edge's end vertices.
#[derive(Debug, Clone, PartialEq)]
pub enum Curve {
    /// A straight segment between the end vertices.
    Segment,
    /// An arc of a circle from the first end vertex to the second, sweeping `sweep` radians
    /// (positive = counter-clockwise), starting at angle `start` about `center`.
    Arc {
        center: Point,
        radius: f64,
        start: f64,
        sweep: f64,
    },
    /// A polyline through the given points, from the first end vertex to the second (the
    /// points include both ends).
    Polyline(Vec<Point>),
}

/// What an edge is, for connectivity and output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EdgeKind {
    /// On the wall of a circle (`-1` the bounding circle).
    Wall(CircleId),
    /// A medial arc (interface between two blocks).
    Medial,
    /// A spoke from a medial vertex to a circle (interface).
    Spoke,
    /// An interior edge of a template (interface).
    Interface,
    /// A side on the boundary of one period of a periodic mesh (the paper's zig-zag
    /// boundary), used by one block. Its copy on the opposite boundary is edge `partner`,
    /// used by another block: the partner's curve is this edge's curve moved by
    /// `translation`, in the same direction (so its nodes are this edge's nodes plus
    /// `translation`). The partner's own kind names this edge with the opposite translation.
    Periodic {
        partner: u32,
        translation: Translation,
    },
}

/// A translation vector (one period shift) of a periodic mesh. Compared bit for bit, so it
/// can live in the `Eq` type [`EdgeKind`].
#[derive(Debug, Clone, Copy)]
pub struct Translation(pub [f64; 2]);

impl PartialEq for Translation {
    fn eq(&self, other: &Self) -> bool {
        self.0[0].to_bits() == other.0[0].to_bits() && self.0[1].to_bits() == other.0[1].to_bits()
    }
}

impl Eq for Translation {}

/// An edge of the layout, shared by one (wall) or two (interface) blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    /// Layout vertex ids of its two ends, in the curve's direction.
    pub ends: [u32; 2],
    pub curve: Curve,
    pub kind: EdgeKind,
}

/// A reference from a block side to an edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SideRef {
    pub edge: u32,
    /// True when the side runs against the edge's direction.
    pub reversed: bool,
}

impl SideRef {
    /// The side running along `edge`'s direction.
    pub const fn along(edge: u32) -> SideRef {
        SideRef {
            edge,
            reversed: false,
        }
    }
    /// The side running against `edge`'s direction.
    pub const fn against(edge: u32) -> SideRef {
        SideRef {
            edge,
            reversed: true,
        }
    }
}

/// One block: four corners counter-clockwise and the edge of each side.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    pub corners: [u32; 4],
    pub sides: [SideRef; 4],
    /// The circle whose wall is side 0, if any.
    pub wall: Option<CircleId>,
}

/// The whole layout.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BlockLayout {
    pub vertices: Vec<Point>,
    pub edges: Vec<Edge>,
    pub blocks: Vec<Block>,
}

impl BlockLayout {
    /// The vertices a block side runs between, in the side's direction.
    pub fn side_ends(&self, block: usize, side: usize) -> [u32; 2] {
        let b = &self.blocks[block];
        [b.corners[side], b.corners[(side + 1) % 4]]
    }
}
