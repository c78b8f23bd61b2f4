//! Bowyer–Watson Delaunay triangulation (STUB: the API the rest of the crate builds against).

use super::Point;

/// Why a point set could not be triangulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TriangulationError {
    #[error("point {index} has a non-finite coordinate")]
    NonFinite { index: usize },
    #[error("need at least 3 distinct points, got {distinct}")]
    TooFewPoints { distinct: usize },
    #[error("all {distinct} distinct points are collinear")]
    AllCollinear { distinct: usize },
}

/// A Delaunay triangulation of a point set (finite triangles only).
#[derive(Debug, Clone)]
pub struct Triangulation {
    points: Vec<Point>,
}

impl Triangulation {
    /// Triangulate `points`. Exact duplicates are removed and reported by [`Self::duplicates`].
    pub fn new(points: &[Point]) -> Result<Self, TriangulationError> {
        let _ = points;
        todo!("engine")
    }
    /// The input points, as given (indices in triangles refer to these).
    pub fn points(&self) -> &[Point] {
        &self.points
    }
    /// Number of finite triangles.
    pub fn len(&self) -> usize {
        todo!()
    }
    /// True when there is no triangle.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Triangle `t` as three input indices in counter-clockwise order.
    pub fn triangle(&self, t: usize) -> [u32; 3] {
        let _ = t;
        todo!()
    }
    /// All finite triangles, counter-clockwise, as input indices.
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        (0..self.len()).map(|t| self.triangle(t))
    }
    /// `neighbors(t)[k]` is the triangle across the edge opposite vertex `k` of triangle `t`,
    /// `None` on the convex hull.
    pub fn neighbors(&self, t: usize) -> [Option<u32>; 3] {
        let _ = t;
        todo!()
    }
    /// Exact duplicates as `(first, duplicate)` input index pairs, sorted.
    pub fn duplicates(&self) -> &[(u32, u32)] {
        todo!()
    }
    /// Maximal sets of input points whose triangles are joined across edges with exact
    /// incircle zero; each sorted, the list sorted.
    pub fn cocircular_groups(&self) -> Vec<Vec<u32>> {
        todo!()
    }
}
