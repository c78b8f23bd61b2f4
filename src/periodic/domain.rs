//! The periodic domain: a rectangle `[0, Lx) x [0, Ly)` repeated over the plane, with circular
//! holes that may cross the rectangle's edges (they wrap).
//!
//! A [`PeriodicDomain`] can only be obtained through validation ([`PeriodicDomain::new`],
//! [`PeriodicDomain::from_json_str`]), which guarantees:
//!
//! - `Lx`, `Ly` are finite and in [`Domain::MIN_SCALE`]`..=`[`PeriodicDomain::MAX_PERIOD`];
//! - every hole centre and radius is finite (magnitudes as for [`Domain`]), every radius `> 0`;
//! - every hole centre is wrapped into `[0, Lx) x [0, Ly)` (its *canonical copy*);
//! - every hole's diameter plus the tolerance is below `min(Lx, Ly)`, so a hole never meets
//!   its own images;
//! - holes are pairwise apart *including periodic images*: for holes `i`, `j` (also `i = j`
//!   with a non-zero shift) and every period shift `t`, `|c_i - c_j - t| - r_i - r_j > tol`
//!   with `tol = `[`PeriodicDomain::tolerance`].
//!
//! The overlap check runs a k-d tree ([`HoleIndex`]) over the 3 x 3 tiling of the canonical
//! copies, `O(h log h)`: with every diameter below the period, the nearest image of a hole is
//! always in a neighbouring tile.

use crate::domain::{
    check_circle, precision_unit, Circle, CircleId, Domain, DomainError, HoleIndex, LimitedHoles,
};
use serde::{Deserialize, Serialize};

/// A validated periodic domain (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicDomain {
    size: [f64; 2],
    holes: Vec<Circle>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PeriodJson {
    size: [f64; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PeriodicJsonIn {
    periodic: PeriodJson,
    holes: LimitedHoles,
}

#[derive(Serialize)]
struct PeriodicJsonOut<'a> {
    periodic: PeriodJson,
    holes: &'a [Circle],
}

/// `x` wrapped into `[0, l)` (never returns `l` itself, even after rounding).
pub fn wrap(x: f64, l: f64) -> f64 {
    let w = x.rem_euclid(l);
    if w >= l || w < 0.0 {
        0.0
    } else {
        w
    }
}

impl PeriodicDomain {
    /// Relative gap tolerance: two circles (or a circle and an image) closer than
    /// `GAP_TOLERANCE * max(Lx, Ly)` count as touching and are refused. It is larger than
    /// [`Domain::GAP_TOLERANCE`] because the mesher validates an auxiliary bounded domain of
    /// copies (at most 7 `max(Lx, Ly)` a side) whose bounding radius is below 32 `max(Lx, Ly)`.
    pub const GAP_TOLERANCE: f64 = 32.0 * Domain::GAP_TOLERANCE;
    /// The largest period length, `Domain::MAX_MAGNITUDE / 8`: the mesher samples a tiling
    /// whose coordinates reach [`Self::coordinate_magnitude`] `= 8 max(Lx, Ly)`, and that
    /// tiling is validated as a bounded [`Domain`] (a box of `1e100` was accepted and then
    /// failed there with an internal error).
    pub const MAX_PERIOD: f64 = Domain::MAX_MAGNITUDE / 8.0;

    /// Validate a periodic domain of period `size = [Lx, Ly]` with `holes` (centres anywhere;
    /// they are wrapped into the box). Holes are named by their 0-based input index.
    pub fn new(size: [f64; 2], holes: Vec<Circle>) -> Result<Self, DomainError> {
        Self::with_limit(size, holes, Domain::MAX_HOLES)
    }

    /// [`Self::new`] with a custom hole limit.
    pub fn with_limit(
        size: [f64; 2],
        mut holes: Vec<Circle>,
        max_holes: usize,
    ) -> Result<Self, DomainError> {
        if holes.len() > max_holes {
            return Err(DomainError::TooManyHoles {
                count: holes.len(),
                max: max_holes,
            });
        }
        for (axis, &l) in size.iter().enumerate() {
            if !(l.is_finite() && l > 0.0 && l <= Self::MAX_PERIOD) {
                return Err(DomainError::InvalidPeriod { axis, value: l });
            }
            if l < Domain::MIN_SCALE {
                return Err(DomainError::DomainTooSmall {
                    axis: Some(axis),
                    value: l,
                    min: Domain::MIN_SCALE,
                });
            }
        }
        if holes.is_empty() {
            return Err(DomainError::NoPeriodicHoles);
        }
        for (i, h) in holes.iter().enumerate() {
            check_circle(i as CircleId, h)?;
        }
        let magnitude = Self::coordinate_magnitude(size);
        let min_radius = Domain::MIN_RADIUS_ULPS * precision_unit(magnitude);
        for (i, h) in holes.iter().enumerate() {
            if h.radius < min_radius {
                return Err(DomainError::RadiusBelowPrecision {
                    circle: i as CircleId,
                    radius: h.radius,
                    magnitude,
                    min_radius,
                });
            }
        }
        let tol = Self::tolerance_for(size);
        for (i, h) in holes.iter_mut().enumerate() {
            if let Some(axis) = (0..2).find(|&a| 2.0 * h.radius + tol >= size[a]) {
                return Err(DomainError::HoleWiderThanPeriod {
                    hole: i,
                    axis,
                    diameter: 2.0 * h.radius,
                    period: size[axis],
                    tolerance: tol,
                });
            }
            h.center = [wrap(h.center[0], size[0]), wrap(h.center[1], size[1])];
        }
        // Overlaps with images: a k-d tree over the 3 x 3 tiling, queried for the canonical
        // copies (tile (0, 0) is stored first, then the tiles of `shifts`, so tiling index
        // `k h + j` is hole `j` moved by `shifts[k - 1]`).
        let h = holes.len();
        let shifts: Vec<(i32, i32)> = tile_offsets(1).filter(|&o| o != (0, 0)).collect();
        let mut tiling = Vec::with_capacity(9 * h);
        tiling.extend_from_slice(&holes);
        for &(a, b) in &shifts {
            for c in &holes {
                tiling.push(Circle {
                    center: [
                        c.center[0] + a as f64 * size[0],
                        c.center[1] + b as f64 * size[1],
                    ],
                    radius: c.radius,
                });
            }
        }
        let index = HoleIndex::new(&tiling);
        let mut worst: Option<(usize, usize, [i32; 2], f64)> = None;
        for i in 0..h {
            if let Some((k, gap)) = index.nearest_gap(i) {
                if gap <= tol {
                    let (j, shift) = match (k / h).checked_sub(1) {
                        None => (k, [0, 0]),
                        Some(s) => (k % h, [shifts[s].0, shifts[s].1]),
                    };
                    // As `first`, `second`: the image of `second` that meets `first`.
                    let pair = if i <= j {
                        (i, j, shift, gap)
                    } else {
                        (j, i, [-shift[0], -shift[1]], gap)
                    };
                    if worst.is_none_or(|w| (pair.0, pair.1) < (w.0, w.1)) {
                        worst = Some(pair);
                    }
                }
            }
        }
        if let Some((first, second, shift, gap)) = worst {
            if first == second {
                // A hole against its own image: it does not fit in the period along the
                // shift (the diameter test above passed only by rounding of the shifted
                // centre).
                let axis = usize::from(shift[0] == 0);
                return Err(DomainError::HoleWiderThanPeriod {
                    hole: first,
                    axis,
                    diameter: 2.0 * holes[first].radius,
                    period: size[axis],
                    tolerance: tol,
                });
            }
            return Err(DomainError::HolesOverlap {
                first,
                second,
                shift,
                gap,
                tolerance: tol,
            });
        }
        Ok(PeriodicDomain { size, holes })
    }

    /// Parse and validate `{"periodic": {"size": [Lx, Ly]}, "holes": [{"center": [x, y],
    /// "radius": r}, ...]}` (unknown fields refused).
    pub fn from_json_str(text: &str) -> Result<Self, DomainError> {
        let raw: PeriodicJsonIn = serde_json::from_str(crate::input::without_bom(text))
            .map_err(|e| DomainError::Json(e.to_string()))?;
        if raw.holes.count > Domain::MAX_HOLES {
            return Err(DomainError::TooManyHoles {
                count: raw.holes.count,
                max: Domain::MAX_HOLES,
            });
        }
        Self::new(raw.periodic.size, raw.holes.holes)
    }

    /// The JSON form read by [`Self::from_json_str`] (canonical, wrapped centres).
    pub fn to_json_string(&self) -> String {
        serde_json::to_string(&PeriodicJsonOut {
            periodic: PeriodJson { size: self.size },
            holes: &self.holes,
        })
        .unwrap_or_default()
    }

    /// A bound of the coordinates the mesher samples for a period `size`: `8 max(Lx, Ly)`.
    /// The largest tiling (each side of the array of copies at most
    /// [`crate::periodic::MAX_ARRAY_SIDE`] `= 7 max(Lx, Ly)` long) has its bounding circle
    /// centred at `(Lx / 2, Ly / 2)` with radius at most `3.5 sqrt(2) max(Lx, Ly) + max(Lx,
    /// Ly)`, so every coordinate is below `6.5 max(Lx, Ly)`. Holes with a radius below
    /// [`Domain::MIN_RADIUS_ULPS`] units of precision at this magnitude are refused
    /// ([`DomainError::RadiusBelowPrecision`]), so the tiled bounded domain always validates.
    /// Gaps need no such rule: [`Self::GAP_TOLERANCE`] is far above the precision there.
    pub fn coordinate_magnitude(size: [f64; 2]) -> f64 {
        8.0 * size[0].max(size[1])
    }

    /// The tolerance for a period `size`.
    pub fn tolerance_for(size: [f64; 2]) -> f64 {
        Self::GAP_TOLERANCE * size[0].max(size[1])
    }

    /// The gap tolerance of this domain.
    pub fn tolerance(&self) -> f64 {
        Self::tolerance_for(self.size)
    }

    /// The period `[Lx, Ly]`.
    pub fn size(&self) -> [f64; 2] {
        self.size
    }

    /// The holes, centres wrapped into `[0, Lx) x [0, Ly)`, in input order.
    pub fn holes(&self) -> &[Circle] {
        &self.holes
    }

    /// Number of holes.
    pub fn hole_count(&self) -> usize {
        self.holes.len()
    }

    /// Each hole's smallest gap to another hole or to an image (of itself or another hole).
    pub fn nearest_gaps(&self) -> Vec<f64> {
        let h = self.holes.len();
        let mut tiling = self.holes.clone();
        for (a, b) in tile_offsets(1).filter(|&o| o != (0, 0)) {
            for c in &self.holes {
                tiling.push(Circle {
                    center: [
                        c.center[0] + a as f64 * self.size[0],
                        c.center[1] + b as f64 * self.size[1],
                    ],
                    radius: c.radius,
                });
            }
        }
        let index = HoleIndex::new(&tiling);
        (0..h)
            .map(|i| {
                index
                    .nearest_gap(i)
                    .map_or(self.size[0].min(self.size[1]), |(_, g)| g)
            })
            .collect()
    }
}

/// The tile offsets `(a, b)` with `|a|, |b| <= m`, in lexicographic order.
pub fn tile_offsets(m: i32) -> impl Iterator<Item = (i32, i32)> {
    tile_array([m, m])
}

/// The tile offsets `(a, b)` with `|a| <= m[0]` and `|b| <= m[1]`, in lexicographic order.
pub fn tile_array(m: [i32; 2]) -> impl Iterator<Item = (i32, i32)> {
    (-m[0]..=m[0]).flat_map(move |a| (-m[1]..=m[1]).map(move |b| (a, b)))
}
