//! The fluid domain: a bounding circle with circular holes (STUB types; validation to come).

use crate::geometry::Point;
use serde::{Deserialize, Serialize};

/// Circle identifier used across the crate: `-1` is the bounding circle, `0..` the holes in
/// input order.
pub type CircleId = i32;

/// The id of the bounding circle.
pub const BOUNDING: CircleId = -1;

/// A circle given by its center and radius.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Circle {
    pub center: Point,
    pub radius: f64,
}

/// Why a domain was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DomainError {
    #[error("invalid domain: {0}")]
    Invalid(String),
}

/// A validated domain: a bounding circle and holes strictly inside it, pairwise apart.
#[derive(Debug, Clone, PartialEq)]
pub struct Domain {
    bounding: Circle,
    holes: Vec<Circle>,
}

impl Domain {
    /// Build and validate a bounded domain.
    pub fn bounded(bounding: Circle, holes: Vec<Circle>) -> Result<Self, DomainError> {
        Ok(Domain { bounding, holes })
    }
    pub fn bounding(&self) -> Circle {
        self.bounding
    }
    pub fn holes(&self) -> &[Circle] {
        &self.holes
    }
    /// Circle by id (`-1` the bounding circle).
    pub fn circle(&self, id: CircleId) -> Circle {
        if id < 0 {
            self.bounding
        } else {
            self.holes[id as usize]
        }
    }
}
