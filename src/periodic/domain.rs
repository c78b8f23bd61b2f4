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
    /// Each hole's smallest gap to another hole or image ([`PeriodicDomain::nearest_gaps`]),
    /// found once by the validation: a function of `size` and `holes` (issue 8: a periodic
    /// mesh asked for it once per layout and once per refinement round, about 0.15 s each at
    /// 1e5 holes).
    gaps: Vec<f64>,
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
    /// The same box with its holes (and their nearest gaps) in `order` (`order[k]` the hole
    /// that comes `k`-th; a permutation of the hole ids, [`crate::spatial_order`]): no check is
    /// made again.
    pub(crate) fn reordered(&self, order: &[u32]) -> PeriodicDomain {
        PeriodicDomain {
            size: self.size,
            holes: order.iter().map(|&i| self.holes[i as usize]).collect(),
            gaps: order.iter().map(|&i| self.gaps[i as usize]).collect(),
        }
    }

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
        // Overlaps with images: the nearest hole or image of each canonical copy over the
        // 3 x 3 tiling ([`nearest_images`]: tile (0, 0) first, then the tiles of `shifts`, so
        // tiling index `k h + j` is hole `j` moved by `shifts[k - 1]`).
        let h = holes.len();
        let shifts: Vec<(i32, i32)> = tile_offsets(1).filter(|&o| o != (0, 0)).collect();
        let mut worst: Option<(usize, usize, [i32; 2], f64)> = None;
        let nearest = nearest_images(size, &holes);
        for (i, nearest) in nearest.iter().enumerate() {
            if let Some((k, gap)) = *nearest {
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
        let gaps = nearest
            .into_iter()
            .map(|n| n.map_or(size[0].min(size[1]), |(_, g)| g))
            .collect();
        Ok(PeriodicDomain { size, holes, gaps })
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
    /// Found once, by the validation in [`PeriodicDomain::new`] (a hole with no other hole or
    /// image at a finite gap gets the shorter period).
    pub fn nearest_gaps(&self) -> Vec<f64> {
        self.gaps.clone()
    }
}

/// For each hole of `holes` (centres in the box of `size`), its nearest other hole or image
/// by gap, as the k-d tree ([`HoleIndex::nearest_gap`]) over the whole 3 x 3 tiling answers
/// it: `(k, gap)` with tiling index `k = t h + j` for hole `j` moved by the `t`-th shift
/// (`t = 0` the box itself, then [`tile_offsets`]`(1)` without `(0, 0)`), the exact
/// floating-point minimum gap, ties to the smaller `k`.
///
/// Only the images that can answer are put in the tree (issue 8: the nine copies of 100 000
/// holes, tree and queries built serially, took about a second per call, and a periodic mesh
/// calls it once per layout). A hole's nearest gap is at most `g_i`, its nearest gap among
/// the canonical holes alone, so its answer is within `g_i + r_i + r_max` of its centre: the
/// images whose centres lie within `max_i (g_i + r_i) + r_max` (widened by a relative 1e-9
/// for rounding) of the box are every candidate of every query. Kept in tiling order, their
/// indices in the smaller tree are in the same order as `k`: the same ties.
fn nearest_images(size: [f64; 2], holes: &[Circle]) -> Vec<Option<(usize, f64)>> {
    use rayon::prelude::*;
    let h = holes.len();
    let canonical = HoleIndex::new(holes).nearest_gap_each();
    let rmax = holes.iter().map(|c| c.radius).fold(0.0, f64::max);
    let reach = canonical
        .iter()
        .zip(holes)
        .map(|(n, c)| n.map_or(f64::INFINITY, |(_, g)| g) + c.radius)
        .fold(0.0, f64::max)
        + rmax;
    let (tiling, index_of) = images_near(size, holes, reach);
    let index = HoleIndex::new(&tiling);
    // A hole farther from the box's edges than its nearest canonical gap (plus the two radii
    // and a margin for rounding) has no image as near: every image's centre is outside the
    // box. Its answer over the tiling is then the canonical one (the same candidates, the same
    // gaps, ties to the smaller index either way), so only the holes near the edges are
    // searched again (issue 8: most holes of a large box are inside).
    let margin = 1e-9 * (size[0].max(size[1]) + reach.abs());
    (0..h)
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            let c = &holes[i];
            let to_edge = c.center[0]
                .min(size[0] - c.center[0])
                .min(c.center[1])
                .min(size[1] - c.center[1]);
            match canonical[i] {
                Some((j, g)) if to_edge - c.radius - rmax > g + margin => Some((j, g)),
                _ => index.nearest_gap(i).map(|(k, g)| (index_of[k], g)),
            }
        })
        .collect()
}

/// The holes (centres in the box of `size`) and those of their images in the 3 x 3 tiling
/// whose centres lie within `reach` of the box (widened by a relative 1e-9 for rounding; a
/// NaN or infinite `reach` keeps every image): the holes first, then the images tile by
/// tile ([`tile_offsets`]`(1)` without `(0, 0)`), each with its tiling index `t h + j` (hole
/// `j` moved by the `t`-th shift, `t = 0` the box itself).
pub(crate) fn images_near(
    size: [f64; 2],
    holes: &[Circle],
    reach: f64,
) -> (Vec<Circle>, Vec<usize>) {
    let h = holes.len();
    let m = reach + 1e-9 * (reach.abs() + size[0].max(size[1]));
    let near = |p: [f64; 2]| !m.is_finite() || (0..2).all(|a| p[a] >= -m && p[a] <= size[a] + m);
    let mut tiling = Vec::with_capacity(h);
    let mut index_of: Vec<usize> = Vec::with_capacity(h);
    tiling.extend_from_slice(holes);
    index_of.extend(0..h);
    for (t, (a, b)) in tile_offsets(1).filter(|&o| o != (0, 0)).enumerate() {
        for (j, c) in holes.iter().enumerate() {
            let center = [
                c.center[0] + a as f64 * size[0],
                c.center[1] + b as f64 * size[1],
            ];
            if near(center) {
                tiling.push(Circle {
                    center,
                    radius: c.radius,
                });
                index_of.push((t + 1) * h + j);
            }
        }
    }
    (tiling, index_of)
}

/// The tile offsets `(a, b)` with `|a|, |b| <= m`, in lexicographic order.
pub fn tile_offsets(m: i32) -> impl Iterator<Item = (i32, i32)> {
    tile_array([m, m])
}

/// The tile offsets `(a, b)` with `|a| <= m[0]` and `|b| <= m[1]`, in lexicographic order.
pub fn tile_array(m: [i32; 2]) -> impl Iterator<Item = (i32, i32)> {
    (-m[0]..=m[0]).flat_map(move |a| (-m[1]..=m[1]).map(move |b| (a, b)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The nearest hole or image of each canonical hole by brute force over the whole 3 x 3
    /// tiling: the exact floating-point minimum of [`crate::domain::gap`], ties to the
    /// smaller tiling index.
    fn brute_force(size: [f64; 2], holes: &[Circle]) -> Vec<Option<(usize, f64)>> {
        let h = holes.len();
        let mut tiling = holes.to_vec();
        for (a, b) in tile_offsets(1).filter(|&o| o != (0, 0)) {
            tiling.extend(holes.iter().map(|c| Circle {
                center: [
                    c.center[0] + a as f64 * size[0],
                    c.center[1] + b as f64 * size[1],
                ],
                radius: c.radius,
            }));
        }
        (0..h)
            .map(|i| {
                let mut best: Option<(usize, f64)> = None;
                for (k, c) in tiling.iter().enumerate().filter(|&(k, _)| k != i) {
                    let g = crate::domain::gap(&tiling[i], c);
                    if best.is_none_or(|(_, b)| g < b) {
                        best = Some((k, g));
                    }
                }
                best
            })
            .collect()
    }

    fn bits(v: &[Option<(usize, f64)>]) -> Vec<Option<(usize, u64)>> {
        v.iter().map(|n| n.map(|(k, g)| (k, g.to_bits()))).collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// [`nearest_images`] (a tree over the canonical holes and the images near the box)
        /// answers as the brute force over every image: random boxes dense and sparse, holes
        /// on a lattice (ties between images) and a single hole (only its own images).
        #[test]
        fn nearest_images_equal_the_brute_force_over_the_whole_tiling(
            size in (1.0..20.0f64, 1.0..20.0f64),
            raw in proptest::collection::vec((0.0..1.0f64, 0.0..1.0f64, 0.01..0.2f64), 1..60),
            lattice in 0usize..4,
        ) {
            let size = [size.0, size.1];
            let holes: Vec<Circle> = if lattice > 0 {
                // A k x k lattice of equal holes: every hole has its nearest at the same gap in
                // several directions.
                let k = lattice + 1;
                let r = 0.2 * size[0].min(size[1]) / k as f64;
                (0..k * k)
                    .map(|n| Circle {
                        center: [
                            (n % k) as f64 * size[0] / k as f64,
                            (n / k) as f64 * size[1] / k as f64,
                        ],
                        radius: r,
                    })
                    .collect()
            } else {
                let scale = size[0].min(size[1]) * 0.5;
                raw.iter()
                    .map(|&(x, y, r)| Circle {
                        center: [x * size[0], y * size[1]],
                        radius: r * scale,
                    })
                    .collect()
            };
            prop_assert_eq!(
                bits(&nearest_images(size, &holes)),
                bits(&brute_force(size, &holes))
            );
        }
    }
}
