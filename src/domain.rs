//! The fluid domain: a bounding circle with circular holes strictly inside it, pairwise apart.
//!
//! This is the input of Guoy & Erickson's Problem 1 ("Structured Meshes of Circles", paper
//! section 1). A [`Domain`] can only be obtained through validation ([`Domain::bounded`],
//! [`Domain::from_json_str`]), so every later stage may rely on these invariants:
//!
//! - every coordinate and radius is finite and at most [`Domain::MAX_MAGNITUDE`] in absolute
//!   value (so differences and squares of coordinates never overflow);
//! - every radius is `> 0`;
//! - every hole lies strictly inside the bounding circle: `R - |c - C| - r > tol`;
//! - holes are pairwise apart: `|c_i - c_j| - r_i - r_j > tol`, with
//!   `tol = GAP_TOLERANCE * R` (touching counts as overlapping);
//! - no two holes are identical, and there are at most the configured number of holes
//!   ([`Domain::MAX_HOLES`] by default).
//!
//! Overlap checks use [`HoleIndex`], a k-d tree over hole centres augmented with the largest
//! radius below each node, so validating `10^5` holes costs `O(n log n)`, not `O(n^2)`.

use crate::geometry::Point;
use rayon::prelude::*;
use serde::de::{IgnoredAny, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use std::borrow::Cow;
use std::collections::HashMap;
use std::fmt;
use std::sync::{Arc, OnceLock};

use crate::numfmt::Num;

/// Circle identifier used across the crate: `-1` is the bounding circle, `0..` the holes in
/// input order.
pub type CircleId = i32;

/// The id of the bounding circle.
pub const BOUNDING: CircleId = -1;

/// A circle given by its center and radius.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Circle {
    #[serde(deserialize_with = "deserialize_center")]
    pub center: Point,
    pub radius: f64,
}

impl Circle {
    /// A circle from its centre coordinates and radius.
    pub const fn new(x: f64, y: f64, radius: f64) -> Self {
        Circle {
            center: [x, y],
            radius,
        }
    }
}

/// A centre `[x, y]`: exactly two numbers, with a clear error for any other length (serde's
/// fixed-size arrays report a third element as "trailing characters").
fn deserialize_center<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Point, D::Error> {
    use serde::de::Error;
    struct V;
    impl<'de> Visitor<'de> for V {
        type Value = Point;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a centre [x, y] of two numbers")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Point, A::Error> {
            let x = seq
                .next_element::<f64>()?
                .ok_or_else(|| A::Error::invalid_length(0, &self))?;
            let y = seq
                .next_element::<f64>()?
                .ok_or_else(|| A::Error::invalid_length(1, &self))?;
            let mut n = 2usize;
            while seq.next_element::<IgnoredAny>()?.is_some() {
                n = n.saturating_add(1);
            }
            if n != 2 {
                return Err(A::Error::invalid_length(n, &self));
            }
            Ok([x, y])
        }
    }
    deserializer.deserialize_seq(V)
}

/// A human name for a circle id: `"hole 3"` or `"the bounding circle"`.
pub fn circle_name(id: CircleId) -> String {
    if id < 0 {
        "the bounding circle".to_string()
    } else {
        format!("hole {id}")
    }
}

/// `"holes 1 and 2"` or `"the bounding circle and hole 2"`.
fn pair_name(first: CircleId, second: usize) -> String {
    if first < 0 {
        format!("the bounding circle and hole {second}")
    } else {
        format!("holes {first} and {second}")
    }
}

/// Why a domain was refused. Holes are named by their 0-based index in the input; every
/// number in a message is printed by [`Num`] (`1e300`, not 301 digits).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DomainError {
    /// The JSON text is malformed, truncated, has wrong types, missing or unknown fields.
    /// Carries serde's message with line and column.
    #[error("invalid domain JSON: {0}")]
    Json(String),
    /// More holes than the configured limit (checked before any per-hole allocation).
    #[error("too many holes: {count} given, at most {max} allowed")]
    TooManyHoles { count: usize, max: usize },
    /// A coordinate or radius is NaN or infinite.
    #[error("{} has a non-finite {field}: {}", circle_name(*circle), Num(*value))]
    NonFinite {
        circle: CircleId,
        field: &'static str,
        value: f64,
    },
    /// A coordinate or radius exceeds [`Domain::MAX_MAGNITUDE`] in absolute value.
    #[error(
        "{} has {field} = {}, beyond the supported magnitude {}",
        circle_name(*circle),
        Num(*value),
        Num(*max)
    )]
    OutOfRange {
        circle: CircleId,
        field: &'static str,
        value: f64,
        max: f64,
    },
    /// A radius is zero or negative.
    #[error(
        "{} has radius {}, but a radius must be positive",
        circle_name(*circle),
        Num(*radius)
    )]
    NonPositiveRadius { circle: CircleId, radius: f64 },
    /// A hole is not strictly inside the bounding circle (touching within the tolerance
    /// counts as not inside). `gap = R - |c - C| - r`.
    #[error(
        "hole {hole} is not strictly inside the bounding circle: its gap to the bounding circle \
         is {}, it must exceed {}",
        Num(*gap),
        Num(*tolerance)
    )]
    HoleNotInside {
        hole: usize,
        gap: f64,
        tolerance: f64,
    },
    /// Two holes are identical (same centre and radius).
    #[error("hole {second} is a duplicate of hole {first} (same centre and radius)")]
    DuplicateHole { first: usize, second: usize },
    /// Two holes overlap or touch: `gap = |c_i - c_j + t| - r_i - r_j <= tolerance`, where
    /// `t = shift[0] Lx + shift[1] Ly` moves hole `second` to the image that meets hole
    /// `first` (`[0, 0]` in a bounded domain or inside the periodic box; non-zero when the
    /// holes meet only across the periodic boundary).
    #[error(
        "holes {first} and {second} overlap or touch{}: the gap between them is {}, it must \
         exceed {}",
        across_period(*second, *shift),
        Num(*gap),
        Num(*tolerance)
    )]
    HolesOverlap {
        first: usize,
        second: usize,
        shift: [i32; 2],
        gap: f64,
        tolerance: f64,
    },
    /// A circle too small for the magnitude of its coordinates: double precision cannot
    /// place enough distinct, convexly positioned samples on it. `magnitude` is
    /// [`Domain::coordinate_magnitude`] (for a periodic domain, the extent of the tiling the
    /// mesher samples, [`crate::periodic::PeriodicDomain::coordinate_magnitude`]) and
    /// `min_radius` is [`Domain::MIN_RADIUS_ULPS`] units of [`precision_unit`]`(magnitude)`.
    #[error(
        "{} has radius {}, which is too small for coordinates of magnitude {}: double \
         precision there needs a radius of at least {} ({ulps} units in the last place) to \
         sample the circle; translate the layout nearer the origin or scale it up",
        circle_name(*circle),
        Num(*radius),
        Num(*magnitude),
        Num(*min_radius),
        ulps = Domain::MIN_RADIUS_ULPS
    )]
    RadiusBelowPrecision {
        circle: CircleId,
        radius: f64,
        magnitude: f64,
        min_radius: f64,
    },
    /// Two circles closer than double precision can resolve at the magnitude of their
    /// coordinates (though farther apart than the relative tolerance): their boundary samples
    /// could not be told apart. `first` is [`BOUNDING`] for a hole's gap to the bounding
    /// circle; `min_gap` is [`Domain::MIN_GAP_ULPS`] units of
    /// [`precision_unit`]`(magnitude)`, `magnitude` is [`Domain::coordinate_magnitude`].
    #[error(
        "{} are only {} apart, which is too close for coordinates of magnitude {}: double \
         precision there needs a gap of at least {} ({ulps} units in the last place) to tell \
         the circles apart; translate the layout nearer the origin or scale it up",
        pair_name(*first, *second),
        Num(*gap),
        Num(*magnitude),
        Num(*min_gap),
        ulps = Domain::MIN_GAP_ULPS
    )]
    GapBelowPrecision {
        first: CircleId,
        second: usize,
        gap: f64,
        magnitude: f64,
        min_gap: f64,
    },
    /// The domain is smaller than [`Domain::MIN_SCALE`]: the bounding radius (`axis`
    /// `None`) or a period length (`axis` 0 is `Lx`, 1 is `Ly`) is below it, so squares of
    /// the distances the mesher compares (its gaps and tolerances) would underflow double
    /// precision.
    #[error(
        "{} is {}, below the smallest supported domain size {}: distances that small \
         underflow double precision when squared; scale the layout up",
        scale_name(*axis),
        Num(*value),
        Num(*min)
    )]
    DomainTooSmall {
        axis: Option<usize>,
        value: f64,
        min: f64,
    },
    /// A period length is not finite and positive, or beyond
    /// [`crate::periodic::PeriodicDomain::MAX_PERIOD`]; `axis` 0 is `Lx`, 1 is `Ly`.
    #[error(
        "the period {} is {}, but it must be finite, positive and at most {}",
        PERIOD_NAMES[(*axis).min(1)],
        Num(*value),
        Num(crate::periodic::PeriodicDomain::MAX_PERIOD)
    )]
    InvalidPeriod { axis: usize, value: f64 },
    /// A periodic domain without holes (nothing to mesh around).
    #[error("a periodic domain needs at least one hole")]
    NoPeriodicHoles,
    /// A hole of a periodic domain does not fit in the period along `axis` (0 is `Lx`, 1 is
    /// `Ly`): its diameter plus the tolerance is at least the period there, so it would meet
    /// its own image.
    #[error(
        "hole {hole} has diameter {}, which does not fit in the period {} = {}: a diameter \
         must be below each period minus the tolerance {} (the hole would touch its own \
         periodic image)",
        Num(*diameter),
        PERIOD_NAMES[(*axis).min(1)],
        Num(*period),
        Num(*tolerance)
    )]
    HoleWiderThanPeriod {
        hole: usize,
        axis: usize,
        diameter: f64,
        period: f64,
        tolerance: f64,
    },
}

/// The names of the two period lengths, by axis.
const PERIOD_NAMES: [&str; 2] = ["Lx", "Ly"];

/// `"the bounding circle's radius"` or `"the period Lx"` for [`DomainError::DomainTooSmall`].
fn scale_name(axis: Option<usize>) -> String {
    match axis {
        None => "the bounding circle's radius".to_string(),
        Some(a) => format!("the period {}", PERIOD_NAMES[a.min(1)]),
    }
}

/// `""` for holes that meet directly, else where across the periodic boundary they meet:
/// `" across the periodic boundary (hole 1 moved by -1 Lx)"`.
fn across_period(second: usize, shift: [i32; 2]) -> String {
    let moves: Vec<String> = shift
        .iter()
        .zip(PERIOD_NAMES)
        .filter(|(&k, _)| k != 0)
        .map(|(k, name)| format!("{k} {name}"))
        .collect();
    if moves.is_empty() {
        String::new()
    } else {
        format!(
            " across the periodic boundary (hole {second} moved by {})",
            moves.join(" and ")
        )
    }
}

/// A validated domain: a bounding circle and holes strictly inside it, pairwise apart
/// (see the module documentation for the exact invariants).
#[derive(Clone)]
pub struct Domain {
    bounding: Circle,
    holes: Vec<Circle>,
    /// The k-d tree over the holes and every hole's gap to its nearest other hole, each made
    /// once per domain ([`Domain::hole_index`], [`Domain::nearest_hole_gaps`]): the
    /// validation needs both, and so do the sampling and the refinement of the same domain
    /// (issue 8: at 1e5 holes the tree took 10-15 ms to build and the queries 25-35 ms, each
    /// made up to three times per domain). Shared by clones; a function of the holes, so not
    /// part of equality.
    index: Arc<DomainIndex>,
}

/// What [`Domain`] keeps of its [`HoleIndex`] and of its nearest-gap queries, made when first
/// needed (or by the validation, which needs both).
#[derive(Default)]
struct DomainIndex {
    tree: OnceLock<Tree>,
    /// Per hole, the gap of [`HoleIndex::nearest_gap`] (`None` for a lone hole).
    gaps: OnceLock<Vec<Option<f64>>>,
}

/// The parts of a [`HoleIndex`] it owns.
struct Tree {
    order: Vec<u32>,
    sorted: Vec<Circle>,
    nodes: Vec<Node>,
}

impl Tree {
    fn new(index: HoleIndex<'_>) -> Tree {
        Tree {
            order: index.order.into_owned(),
            sorted: index.sorted.into_owned(),
            nodes: index.nodes.into_owned(),
        }
    }
}

/// The gaps of [`HoleIndex::nearest_gap_each`]'s answers.
fn gaps_of(nearest: &[Option<(usize, f64)>]) -> Vec<Option<f64>> {
    nearest.iter().map(|n| n.map(|(_, g)| g)).collect()
}

impl PartialEq for Domain {
    fn eq(&self, other: &Domain) -> bool {
        self.bounding == other.bounding && self.holes == other.holes
    }
}

impl fmt::Debug for Domain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Domain")
            .field("bounding", &self.bounding)
            .field("holes", &self.holes)
            .finish()
    }
}

/// The JSON shape of a domain.
#[derive(Serialize)]
struct DomainJsonOut<'a> {
    bounding: Circle,
    holes: &'a [Circle],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DomainJsonIn {
    bounding: Circle,
    holes: LimitedHoles,
}

/// The `holes` array, read without allocating more than the limit: elements beyond it are
/// only counted (bounded and periodic JSON alike).
pub(crate) struct LimitedHoles {
    pub(crate) holes: Vec<Circle>,
    pub(crate) count: usize,
}

thread_local! {
    static JSON_HOLE_LIMIT: std::cell::Cell<usize> = const { std::cell::Cell::new(Domain::MAX_HOLES) };
}

impl<'de> Deserialize<'de> for LimitedHoles {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V(usize);
        impl<'de> Visitor<'de> for V {
            type Value = LimitedHoles;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an array of circles")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<LimitedHoles, A::Error> {
                let cap = seq.size_hint().unwrap_or(0).min(self.0).min(1 << 16);
                let mut holes = Vec::with_capacity(cap);
                let mut count = 0usize;
                loop {
                    if count < self.0 {
                        match seq.next_element::<Circle>()? {
                            Some(c) => holes.push(c),
                            None => break,
                        }
                    } else if seq.next_element::<IgnoredAny>()?.is_none() {
                        break;
                    }
                    count += 1;
                }
                Ok(LimitedHoles { holes, count })
            }
        }
        let limit = JSON_HOLE_LIMIT.with(|l| l.get());
        deserializer.deserialize_seq(V(limit))
    }
}

impl Domain {
    /// The same domain with its holes in `order` (`order[k]` the hole that comes `k`-th; a
    /// permutation of the hole ids, [`crate::spatial_order`]): no check is made again.
    pub(crate) fn reordered(&self, order: &[u32]) -> Domain {
        // A hole's nearest gap is the same value in any order of the holes (the minimum over
        // the others); the tree is built again for the new order when asked for.
        let gaps = match self.index.gaps.get() {
            Some(g) => OnceLock::from(order.iter().map(|&i| g[i as usize]).collect::<Vec<_>>()),
            None => OnceLock::new(),
        };
        Domain {
            bounding: self.bounding,
            holes: order.iter().map(|&i| self.holes[i as usize]).collect(),
            index: Arc::new(DomainIndex {
                tree: OnceLock::new(),
                gaps,
            }),
        }
    }

    /// This domain with the holes `added` after its own (their ids from the hole count up):
    /// what [`Domain::bounded`] of all the holes gives, its nearest gaps included, without
    /// checking the kept holes again (issue 8: the refinement adds a few holes to as many as
    /// 1e5 at a time, and `bounded` answered every hole's nearest-gap query anew).
    ///
    /// The kept holes were checked and stay valid among themselves, so only the added holes
    /// can make `bounded` fail: each gets `bounded`'s own checks (finite, inside the bounding
    /// circle, not below the precision of the coordinates), and every hole's nearest gap is
    /// the exact minimum over the others as `bounded` finds it (the same expression
    /// [`gap`]`(hole, other)`): a kept hole's is its known one or its gap to an added hole,
    /// whichever is smaller; an added hole's the least over the kept holes (from the tree,
    /// [`HoleIndex::nearest_gap_to`]) and the other added ones. When any check fails (or more
    /// than [`Domain::ADDED_AT_MOST`] holes are added, or the kept holes' gaps are not known)
    /// `bounded` of all the holes gives the answer, and so the same error.
    pub fn with_holes_added(&self, added: &[Circle]) -> Result<Domain, DomainError> {
        let full = || {
            let mut holes = self.holes.clone();
            holes.extend_from_slice(added);
            Domain::bounded(self.bounding, holes)
        };
        let Some(kept) = self.index.gaps.get() else {
            return full();
        };
        let (b, n) = (self.bounding, self.holes.len());
        if added.len() > Self::ADDED_AT_MOST || n + added.len() > Self::MAX_HOLES {
            return full();
        }
        // A gap `bounded` accepts, to the bounding circle or the nearest hole: above the
        // tolerance (else `HoleNotInside` or `HolesOverlap`), and at least the precision's
        // least gap where that is the larger (else `GapBelowPrecision`, `check_precision`).
        let (tol, min_gap) = (Self::tolerance_for(b.radius), Self::min_gap_for(&b));
        let fine = |g: f64| if min_gap > tol { g >= min_gap } else { g > tol };
        let min_radius = Self::min_radius_for(&b);
        let own = added.iter().enumerate().all(|(j, h)| {
            check_circle((n + j) as CircleId, h).is_ok()
                && h.radius >= min_radius
                && fine(b.radius - dist(h.center, b.center) - h.radius)
        });
        if !own {
            return full();
        }
        // The least of a known gap (if any) and one more.
        let least = |m: Option<f64>, x: f64| Some(m.map_or(x, |m: f64| m.min(x)));
        let index = self.hole_index();
        let mut gaps: Vec<Option<f64>> = kept
            .par_iter()
            .zip(self.holes.par_iter())
            .with_min_len(4096)
            .map(|(&g, h)| added.iter().map(|a| gap(h, a)).fold(g, least))
            .collect();
        gaps.extend(added.iter().enumerate().map(|(j, h)| {
            let others = added
                .iter()
                .enumerate()
                .filter(|&(k, _)| k != j)
                .map(|(_, a)| gap(h, a));
            others.fold(index.nearest_gap_to(h), least)
        }));
        if !gaps.iter().all(|g| g.is_none_or(fine)) {
            return full();
        }
        let mut holes = Vec::with_capacity(n + added.len());
        holes.extend_from_slice(&self.holes);
        holes.extend_from_slice(added);
        Ok(Domain {
            bounding: b,
            holes,
            index: Arc::new(DomainIndex {
                tree: OnceLock::new(),
                gaps: OnceLock::from(gaps),
            }),
        })
    }

    /// The most holes [`Domain::with_holes_added`] adds at once by itself (each kept hole's
    /// gap is compared with every added hole's); more go through [`Domain::bounded`].
    pub const ADDED_AT_MOST: usize = 64;

    /// A domain of these circles, not checked (the caller knows them valid); its index is
    /// built when first asked for.
    fn unchecked(bounding: Circle, holes: Vec<Circle>) -> Domain {
        Domain {
            bounding,
            holes,
            index: Arc::default(),
        }
    }

    /// The k-d tree over the holes ([`HoleIndex::new`] of [`Domain::holes`]), built once per
    /// domain (by the validation, or on the first call) and borrowed from it.
    pub fn hole_index(&self) -> HoleIndex<'_> {
        let t = self
            .index
            .tree
            .get_or_init(|| Tree::new(HoleIndex::new(&self.holes)));
        HoleIndex {
            holes: &self.holes,
            order: Cow::Borrowed(&t.order),
            sorted: Cow::Borrowed(&t.sorted),
            nodes: Cow::Borrowed(&t.nodes),
        }
    }

    /// Every hole's gap to its nearest other hole (the gaps of
    /// [`HoleIndex::nearest_gap_each`] of [`Domain::hole_index`]; `None` for a lone hole),
    /// computed once per domain.
    pub fn nearest_hole_gaps(&self) -> &[Option<f64>] {
        self.index
            .gaps
            .get_or_init(|| gaps_of(&self.hole_index().nearest_gap_each()))
    }

    /// Default limit on the number of holes.
    pub const MAX_HOLES: usize = 1_000_000;
    /// Relative gap tolerance: two circles closer than `GAP_TOLERANCE * R` (R the bounding
    /// radius) are considered touching, and refused.
    pub const GAP_TOLERANCE: f64 = 1e-9;
    /// Largest accepted absolute value of a coordinate or radius (keeps squares finite).
    pub const MAX_MAGNITUDE: f64 = 1e100;
    /// Smallest accepted size of a domain: its bounding radius, or each period length of a
    /// periodic domain ([`DomainError::DomainTooSmall`]). The tolerance is `1e-9` of the size
    /// (periodic: `3.2e-8`) and distances are compared through their squares, which stay
    /// normal doubles above it (`1e-218` at the tolerance); the 7-hole hexagon meshes alike
    /// at any scale from `1e-150` to `1e99` but folds 5623 cells at `1e-160` and reports
    /// overlaps that are not there at `1e-200` (squares underflow), so the limit mirrors
    /// [`Domain::MAX_MAGNITUDE`] with margin.
    pub const MIN_SCALE: f64 = 1e-100;
    /// Smallest accepted radius, in units of [`precision_unit`] of the coordinates'
    /// magnitude ([`Domain::coordinate_magnitude`]). Below it the 32 coarse boundary samples of
    /// the circle (spacing `0.2 r`) come within the rounding of the coordinates of each other
    /// and coincide (the hexagon example moved to `1.6e14`, holes of 8.4 units, failed that
    /// way; at `8e13`, 17 units, it meshes, and still does). [`DomainError::RadiusBelowPrecision`].
    pub const MIN_RADIUS_ULPS: f64 = 16.0;
    /// Smallest accepted gap between two circles, in units of [`precision_unit`] of the
    /// coordinates' magnitude, on top of [`Domain::GAP_TOLERANCE`] (which is relative to the
    /// bounding radius and so can be below the resolution of the coordinates when the domain
    /// is small and far from the origin). Boundary sampling keeps every hole sample strictly
    /// inside the bounding polygon and the bounding samples convex for gaps above `2.84`
    /// units even when every rounding goes the wrong way (`crate::sampling`, the bounding
    /// circle's precision floor); a stress test of layouts far from the origin (gaps of 1 to 40
    /// units, about 40 000 meshes) found failures only below 1.5 units. Smaller gaps cannot be
    /// meshed in `f64` coordinates of that magnitude. [`DomainError::GapBelowPrecision`].
    pub const MIN_GAP_ULPS: f64 = 3.0;

    /// Build and validate a bounded domain with the default hole limit [`Self::MAX_HOLES`].
    pub fn bounded(bounding: Circle, holes: Vec<Circle>) -> Result<Self, DomainError> {
        Self::bounded_with_limit(bounding, holes, Self::MAX_HOLES)
    }

    /// Build and validate a bounded domain with at most `max_holes` holes.
    pub fn bounded_with_limit(
        bounding: Circle,
        holes: Vec<Circle>,
        max_holes: usize,
    ) -> Result<Self, DomainError> {
        if holes.len() > max_holes {
            return Err(DomainError::TooManyHoles {
                count: holes.len(),
                max: max_holes,
            });
        }
        check_circle(crate::domain::BOUNDING, &bounding)?;
        if bounding.radius < Self::MIN_SCALE {
            return Err(DomainError::DomainTooSmall {
                axis: None,
                value: bounding.radius,
                min: Self::MIN_SCALE,
            });
        }
        for (i, h) in holes.iter().enumerate() {
            check_circle(i as CircleId, h)?;
        }
        let tol = Self::tolerance_for(bounding.radius);
        for (i, h) in holes.iter().enumerate() {
            let gap = bounding.radius - dist(h.center, bounding.center) - h.radius;
            // Every value is finite here, so the gap is not NaN.
            if gap <= tol {
                return Err(DomainError::HoleNotInside {
                    hole: i,
                    gap,
                    tolerance: tol,
                });
            }
        }
        // Duplicates first, in O(n) with a hash map on the exact bits (-0.0 folded into 0.0).
        // Looked up, never iterated: a fixed fast hasher (the result does not depend on it).
        let mut seen: HashMap<[u64; 3], usize, foldhash::fast::FixedState> =
            HashMap::with_capacity_and_hasher(holes.len(), Default::default());
        for (i, h) in holes.iter().enumerate() {
            let key = [
                (h.center[0] + 0.0).to_bits(),
                (h.center[1] + 0.0).to_bits(),
                (h.radius + 0.0).to_bits(),
            ];
            if let Some(&first) = seen.get(&key) {
                return Err(DomainError::DuplicateHole { first, second: i });
            }
            seen.insert(key, i);
        }
        drop(seen);
        // Overlaps: for each hole in input order, its nearest neighbour by gap (the queries
        // answered together, on the thread pool for many holes: the same answers).
        let index = HoleIndex::new(&holes);
        let nearest = index.nearest_gap_each();
        let tree = Tree::new(index);
        for (i, &found) in nearest.iter().enumerate() {
            if let Some((j, gap)) = found {
                if gap <= tol {
                    return Err(DomainError::HolesOverlap {
                        first: i.min(j),
                        second: i.max(j),
                        shift: [0, 0],
                        gap,
                        tolerance: tol,
                    });
                }
            }
        }
        check_precision(&bounding, &holes, &nearest)?;
        Ok(Domain {
            bounding,
            holes,
            index: Arc::new(DomainIndex {
                tree: OnceLock::from(tree),
                gaps: OnceLock::from(gaps_of(&nearest)),
            }),
        })
    }

    /// The magnitude of the coordinates of a domain with this bounding circle:
    /// `max(|Cx|, |Cy|) + R`, an upper bound of every coordinate of every circle and sample
    /// (holes lie inside the bounding circle).
    pub fn coordinate_magnitude(bounding: &Circle) -> f64 {
        bounding.center[0].abs().max(bounding.center[1].abs()) + bounding.radius
    }

    /// The smallest radius a circle of a domain with this bounding circle may have
    /// ([`Domain::MIN_RADIUS_ULPS`]).
    pub fn min_radius_for(bounding: &Circle) -> f64 {
        Self::MIN_RADIUS_ULPS * precision_unit(Self::coordinate_magnitude(bounding))
    }

    /// The smallest gap two circles of a domain with this bounding circle may have:
    /// the larger of the tolerance ([`Domain::GAP_TOLERANCE`], where touching is refused as
    /// overlapping) and [`Domain::MIN_GAP_ULPS`] units of precision (where it is refused as
    /// too small for the coordinates).
    pub fn min_gap_for(bounding: &Circle) -> f64 {
        let precision = Self::MIN_GAP_ULPS * precision_unit(Self::coordinate_magnitude(bounding));
        Self::tolerance_for(bounding.radius).max(precision)
    }

    /// Parse and validate a domain from JSON of exactly this shape:
    /// `{"bounding": {"center": [x, y], "radius": R}, "holes": [{"center": [x, y], "radius": r}, ...]}`.
    /// Unknown fields are refused. Holes beyond [`Self::MAX_HOLES`] are counted, not stored.
    pub fn from_json_str(text: &str) -> Result<Self, DomainError> {
        Self::from_json_str_with_limit(text, Self::MAX_HOLES)
    }

    /// [`Self::from_json_str`] with a custom hole limit.
    pub fn from_json_str_with_limit(text: &str, max_holes: usize) -> Result<Self, DomainError> {
        let previous = JSON_HOLE_LIMIT.with(|l| l.replace(max_holes));
        let parsed = serde_json::from_str::<DomainJsonIn>(crate::input::without_bom(text));
        JSON_HOLE_LIMIT.with(|l| l.set(previous));
        let parsed = parsed.map_err(|e| DomainError::Json(e.to_string()))?;
        if parsed.holes.count > max_holes {
            return Err(DomainError::TooManyHoles {
                count: parsed.holes.count,
                max: max_holes,
            });
        }
        Self::bounded_with_limit(parsed.bounding, parsed.holes.holes, max_holes)
    }

    /// The domain as JSON, in the shape [`Self::from_json_str`] reads (round-trips exactly:
    /// serde_json prints shortest round-trip representations of f64).
    pub fn to_json_string(&self) -> String {
        serde_json::to_string(&DomainJsonOut {
            bounding: self.bounding,
            holes: &self.holes,
        })
        .unwrap_or_default()
    }

    /// The paper's *Hexagon* data (section 5, figure 12), rebuilt: 7 equal holes of radius
    /// `0.3` in hexagonal packing (one at the origin, six at distance `d = 1` at multiples of
    /// 60 degrees) inside a bounding circle of radius `sqrt(3) - 0.3` centred at the origin.
    /// Gaps: `0.4` between neighbouring holes, `sqrt(3) - 1.6 ~ 0.132` to the bounding circle.
    /// The bounding radius makes the packing's outer medial vertices like its inner ones: the
    /// empty circle tangent to two neighbouring outer holes and the bounding circle is centred at
    /// `2 / sqrt(3)` on their bisector (the inner vertices' distance `d / sqrt(3)` from each
    /// hole centre), and sees its three circles at 120 degrees, so the exact-mode corner limit is
    /// 60/120 degrees everywhere (issue #5). Algorithm 2 gives 36 blocks.
    pub fn hexagon_example() -> Domain {
        let d = 1.0_f64;
        let r = 0.3 * d;
        let s = 0.75_f64.sqrt() * d; // sin 60 degrees, the same bits for all four uses
        let h = 0.5 * d;
        let holes = vec![
            Circle::new(0.0, 0.0, r),
            Circle::new(d, 0.0, r),
            Circle::new(h, s, r),
            Circle::new(-h, s, r),
            Circle::new(-d, 0.0, r),
            Circle::new(-h, -s, r),
            Circle::new(h, -s, r),
        ];
        Domain::unchecked(Circle::new(0.0, 0.0, 3.0_f64.sqrt() * d - r), holes)
    }

    /// The absolute gap tolerance for a bounding radius `r`: `GAP_TOLERANCE * r`.
    pub fn tolerance_for(r: f64) -> f64 {
        Self::GAP_TOLERANCE * r
    }

    /// The absolute gap tolerance of this domain.
    pub fn tolerance(&self) -> f64 {
        Self::tolerance_for(self.bounding.radius)
    }

    /// The bounding circle.
    pub fn bounding(&self) -> Circle {
        self.bounding
    }
    /// The holes, in input order (hole `i` has [`CircleId`] `i`).
    pub fn holes(&self) -> &[Circle] {
        &self.holes
    }
    /// Number of holes.
    pub fn hole_count(&self) -> usize {
        self.holes.len()
    }
    /// Circle by id (`-1` the bounding circle). An id that is neither `-1` nor a hole index
    /// gives the bounding circle for negative ids; out-of-range hole ids are clamped away by
    /// returning the bounding circle too (never panics).
    pub fn circle(&self, id: CircleId) -> Circle {
        if id < 0 {
            self.bounding
        } else {
            self.holes
                .get(id as usize)
                .copied()
                .unwrap_or(self.bounding)
        }
    }
    /// All circle ids: `-1` then `0..h`.
    pub fn circle_ids(&self) -> impl Iterator<Item = CircleId> {
        std::iter::once(BOUNDING).chain(0..self.holes.len() as CircleId)
    }
    /// The gap of hole `i` to the bounding circle: `R - |c_i - C| - r_i` (`None` when there is
    /// no hole `i`).
    pub fn bounding_gap(&self, i: usize) -> Option<f64> {
        let h = self.holes.get(i)?;
        Some(self.bounding.radius - dist(h.center, self.bounding.center) - h.radius)
    }
}

/// The resolution of `f64` coordinates of magnitude at most `magnitude`: `eps * magnitude`
/// (at least one ulp of any such coordinate, so rounding moves a coordinate by at most half
/// of it), and never below the smallest subnormal.
pub fn precision_unit(magnitude: f64) -> f64 {
    (f64::EPSILON * magnitude.abs()).max(f64::from_bits(1))
}

/// The precision checks of [`Domain::bounded_with_limit`], run after every other check: each
/// radius at least [`Domain::min_radius_for`] and each gap (to the bounding circle and to the
/// nearest hole, `nearest[i]` for hole `i` as [`HoleIndex::nearest_gap`]) at least
/// [`Domain::MIN_GAP_ULPS`] units. Skipped entirely when the validation tolerance already
/// exceeds them (every layout within about `5e5 R` of the origin).
fn check_precision(
    bounding: &Circle,
    holes: &[Circle],
    nearest: &[Option<(usize, f64)>],
) -> Result<(), DomainError> {
    let magnitude = Domain::coordinate_magnitude(bounding);
    let unit = precision_unit(magnitude);
    let min_radius = Domain::MIN_RADIUS_ULPS * unit;
    let circles = std::iter::once((BOUNDING, bounding))
        .chain(holes.iter().enumerate().map(|(i, h)| (i as CircleId, h)));
    for (circle, c) in circles {
        if c.radius < min_radius {
            return Err(DomainError::RadiusBelowPrecision {
                circle,
                radius: c.radius,
                magnitude,
                min_radius,
            });
        }
    }
    let min_gap = Domain::MIN_GAP_ULPS * unit;
    if min_gap <= Domain::tolerance_for(bounding.radius) {
        return Ok(());
    }
    for (i, h) in holes.iter().enumerate() {
        let gap = bounding.radius - dist(h.center, bounding.center) - h.radius;
        if gap < min_gap {
            return Err(DomainError::GapBelowPrecision {
                first: BOUNDING,
                second: i,
                gap,
                magnitude,
                min_gap,
            });
        }
    }
    for (i, &found) in nearest.iter().enumerate() {
        if let Some((j, gap)) = found {
            if gap < min_gap {
                return Err(DomainError::GapBelowPrecision {
                    first: i.min(j) as CircleId,
                    second: i.max(j),
                    gap,
                    magnitude,
                    min_gap,
                });
            }
        }
    }
    Ok(())
}

/// Check one circle's numbers.
pub(crate) fn check_circle(id: CircleId, c: &Circle) -> Result<(), DomainError> {
    let fields = [
        ("center x", c.center[0]),
        ("center y", c.center[1]),
        ("radius", c.radius),
    ];
    for (field, value) in fields {
        if !value.is_finite() {
            return Err(DomainError::NonFinite {
                circle: id,
                field,
                value,
            });
        }
    }
    // Finite here, so `<=` is the complete test.
    if c.radius <= 0.0 {
        return Err(DomainError::NonPositiveRadius {
            circle: id,
            radius: c.radius,
        });
    }
    for (field, value) in fields {
        if value.abs() > Domain::MAX_MAGNITUDE {
            return Err(DomainError::OutOfRange {
                circle: id,
                field,
                value,
                max: Domain::MAX_MAGNITUDE,
            });
        }
    }
    Ok(())
}

/// Euclidean distance, symmetric in its arguments and under coordinate negation or swap
/// (bitwise), so mirror-symmetric layouts get bitwise-equal distances.
pub fn dist(a: Point, b: Point) -> f64 {
    let dx = a[0] - b[0];
    let dy = a[1] - b[1];
    (dx * dx + dy * dy).sqrt()
}

/// The gap between two disjoint circles, `|c_a - c_b| - r_a - r_b`.
pub fn gap(a: &Circle, b: &Circle) -> f64 {
    dist(a.center, b.center) - a.radius - b.radius
}

const LEAF: usize = 8;

/// Fewest holes whose nearest-gap queries are split between threads
/// ([`HoleIndex::nearest_gap_each`]; a query takes about a microsecond). Until the CLI pinned
/// its workers to CPUs (thirty-fifth session) 1e3 holes stayed on one thread: a hand-off to a
/// second core cost more than their 0.25 ms of queries (input stage 0.92 ms median split, 0.83
/// and 0.87 serial). Pinned, the split gains (thirty-sixth session, 1e3 bubbles, medians of
/// 10: input 0.79-0.82 -> 0.71-0.78 ms, sampling 2.11-2.47 -> 1.93-2.36 ms).
const PARALLEL_MIN_HOLES: usize = 512;

/// Fewest queries per task of [`HoleIndex::nearest_gap_each`] on the thread pool.
const QUERIES_PER_TASK: usize = 64;

/// A k-d tree over hole centres, each node augmented with the bounding box of its centres
/// and the largest radius below it, answering nearest-gap queries by branch and bound:
/// the gap from hole `i` to any hole of a node is at least
/// `dist(c_i, box) - r_i - max_radius`.
#[derive(Debug, Clone)]
pub struct HoleIndex<'a> {
    holes: &'a [Circle],
    /// Owned when built ([`HoleIndex::new`]), borrowed from a [`Domain`]'s
    /// ([`Domain::hole_index`]).
    order: Cow<'a, [u32]>,
    /// `holes[order[k]]` at `k`: a leaf's circles side by side (bitwise copies, so every gap
    /// is the one computed from `holes`), instead of one scattered cache line each.
    sorted: Cow<'a, [Circle]>,
    nodes: Cow<'a, [Node]>,
}

/// Most nodes pending in a query: the tree is at most 65 levels deep and a visit pushes two
/// children, so the pending nodes never exceed two per level.
const STACK: usize = 2 * 66;

/// A query's pending nodes, on the stack instead of a heap allocation per query.
struct Pending {
    nodes: [u32; STACK],
    len: usize,
}

impl Pending {
    fn root() -> Self {
        Pending {
            nodes: [0; STACK],
            len: 1,
        }
    }
    #[inline]
    fn push(&mut self, n: u32) {
        self.nodes[self.len] = n;
        self.len += 1;
    }
    #[inline]
    fn pop(&mut self) -> Option<u32> {
        self.len = self.len.checked_sub(1)?;
        Some(self.nodes[self.len])
    }
}

#[derive(Debug, Clone)]
struct Node {
    lo: Point,
    hi: Point,
    max_r: f64,
    start: u32,
    end: u32,
    children: Option<(u32, u32)>,
}

/// Subtrees of [`HoleIndex`] with more holes than this are built on two threads (issue 8: the
/// index is built for the validation, the sampling and every refinement round; 45 ms on one
/// thread at 1e5 holes).
const PARALLEL_BUILD: usize = 8192;

/// Build the subtree of the holes `order` (the index's order from position `start` on) into
/// `nodes`, in preorder (the node, its left subtree, its right subtree), splitting at the
/// median of the wider axis of the box; returns the subtree's root. A subtree of more than
/// `parallel_from` holes builds its two halves on two threads, each into a vector of its own
/// appended afterwards with its ids shifted: the same nodes, ids and order as one thread.
fn build_subtree(
    holes: &[Circle],
    order: &mut [u32],
    start: usize,
    depth: usize,
    nodes: &mut Vec<Node>,
    parallel_from: usize,
) -> u32 {
    let len = order.len();
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut max_r: f64 = 0.0;
    for &k in order.iter() {
        let c = holes[k as usize];
        for a in 0..2 {
            lo[a] = lo[a].min(c.center[a]);
            hi[a] = hi[a].max(c.center[a]);
        }
        max_r = max_r.max(c.radius);
    }
    let id = nodes.len() as u32;
    nodes.push(Node {
        lo,
        hi,
        max_r,
        start: start as u32,
        end: (start + len) as u32,
        children: None,
    });
    if len > LEAF && depth < 64 {
        let axis = if hi[0] - lo[0] >= hi[1] - lo[1] { 0 } else { 1 };
        let mid = len / 2;
        order.select_nth_unstable_by(mid, |&p, &q| {
            holes[p as usize].center[axis].total_cmp(&holes[q as usize].center[axis])
        });
        let (left, right) = order.split_at_mut(mid);
        let children = if len > parallel_from {
            let (mut ln, mut rn) = (Vec::new(), Vec::new());
            rayon::join(
                || build_subtree(holes, left, start, depth + 1, &mut ln, parallel_from),
                || build_subtree(holes, right, start + mid, depth + 1, &mut rn, parallel_from),
            );
            let mut place = |part: Vec<Node>| {
                let base = nodes.len() as u32;
                nodes.extend(part.into_iter().map(|mut n| {
                    n.children = n.children.map(|(a, b)| (a + base, b + base));
                    n
                }));
                base
            };
            (place(ln), place(rn))
        } else {
            let l = build_subtree(holes, left, start, depth + 1, nodes, parallel_from);
            let r = build_subtree(holes, right, start + mid, depth + 1, nodes, parallel_from);
            (l, r)
        };
        nodes[id as usize].children = Some(children);
    }
    id
}

impl<'a> HoleIndex<'a> {
    /// Build the index over `holes` (finite values assumed; NaN only weakens the pruning).
    pub fn new(holes: &'a [Circle]) -> Self {
        Self::new_with(holes, PARALLEL_BUILD)
    }

    /// [`HoleIndex::new`] with every subtree of more than `parallel_from` holes built on two
    /// threads (the tests compare the trees built with and without threads).
    fn new_with(holes: &'a [Circle], parallel_from: usize) -> Self {
        let mut order: Vec<u32> = (0..holes.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * holes.len() / LEAF + 1);
        if !holes.is_empty() {
            build_subtree(holes, &mut order, 0, 0, &mut nodes, parallel_from);
        }
        let sorted = order.iter().map(|&k| holes[k as usize]).collect();
        HoleIndex {
            holes,
            order: Cow::Owned(order),
            sorted: Cow::Owned(sorted),
            nodes: Cow::Owned(nodes),
        }
    }

    /// The hole nearest to hole `i` by gap (`|c_i - c_j| - r_i - r_j`, negative when they
    /// overlap), as `(j, gap)`; ties go to the smaller `j`. `None` when there is no other
    /// hole. The returned gap is the exact floating-point minimum over all `j != i`.
    pub fn nearest_gap(&self, i: usize) -> Option<(usize, f64)> {
        if self.holes.len() < 2 {
            return None;
        }
        self.nearest_of(&self.holes[i], Some(i))
    }

    /// The least gap [`gap`]`(q, hole)` over every hole of the index (`q` need not be one of
    /// them): the exact floating-point minimum, as [`HoleIndex::nearest_gap`] finds it for a
    /// hole of the index. `None` when the index is empty.
    pub fn nearest_gap_to(&self, q: &Circle) -> Option<f64> {
        self.nearest_of(q, None).map(|(_, g)| g)
    }

    /// The hole nearest to `q` by gap, hole `skip` left out (ties to the smaller index).
    fn nearest_of(&self, q: &Circle, skip: Option<usize>) -> Option<(usize, f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        let q = *q;
        let mut best: Option<(usize, f64)> = None;
        // Safety margin on the lower bound, so floating-point rounding never prunes the
        // true minimum.
        let slack = |v: f64| v.abs() * 1e-12;
        let mut stack = Pending::root();
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            let dx = (node.lo[0] - q.center[0])
                .max(q.center[0] - node.hi[0])
                .max(0.0);
            let dy = (node.lo[1] - q.center[1])
                .max(q.center[1] - node.hi[1])
                .max(0.0);
            let lb = (dx * dx + dy * dy).sqrt() - q.radius - node.max_r;
            let lb = lb - slack(q.radius + node.max_r) - slack(lb);
            if let Some((_, g)) = best {
                if lb > g {
                    continue;
                }
            }
            match node.children {
                None => {
                    let (s, e) = (node.start as usize, node.end as usize);
                    for (&k, c) in self.order[s..e].iter().zip(&self.sorted[s..e]) {
                        let j = k as usize;
                        if Some(j) == skip {
                            continue;
                        }
                        let g = gap(&q, c);
                        let better = match best {
                            None => true,
                            Some((bj, bg)) => g < bg || (g == bg && j < bj),
                        };
                        if better {
                            best = Some((j, g));
                        }
                    }
                }
                Some((l, r)) => {
                    // Visit the nearer child first (pushed last).
                    let dl = box_dist2(&self.nodes[l as usize], q.center);
                    let dr = box_dist2(&self.nodes[r as usize], q.center);
                    if dl <= dr {
                        stack.push(r);
                        stack.push(l);
                    } else {
                        stack.push(l);
                        stack.push(r);
                    }
                }
            }
        }
        best
    }
}

impl HoleIndex<'_> {
    /// [`HoleIndex::nearest_gap`] of every hole, indexed by hole. The queries run in the
    /// tree's order (neighbouring holes one after the other, so that they find the same nodes
    /// in cache); each answer is that of its own query, so the queries are split between the
    /// threads of the pool when it has several and there are enough holes to pay for it (the
    /// same answers, [`HoleIndex::nearest_gap_each_on`]).
    pub fn nearest_gap_each(&self) -> Vec<Option<(usize, f64)>> {
        self.nearest_gap_each_on(
            self.holes.len() >= PARALLEL_MIN_HOLES && rayon::current_num_threads() > 1,
        )
    }

    /// [`HoleIndex::nearest_gap_each`], on the thread pool when `parallel` (ranges of the
    /// tree's order, answers collected in that order) and on this thread otherwise.
    #[doc(hidden)]
    pub fn nearest_gap_each_on(&self, parallel: bool) -> Vec<Option<(usize, f64)>> {
        let mut out = vec![None; self.holes.len()];
        if parallel {
            let found: Vec<Option<(usize, f64)>> = self
                .order
                .par_iter()
                .with_min_len(QUERIES_PER_TASK)
                .map(|&k| self.nearest_gap(k as usize))
                .collect();
            for (&k, f) in self.order.iter().zip(found) {
                out[k as usize] = f;
            }
        } else {
            for &k in self.order.iter() {
                out[k as usize] = self.nearest_gap(k as usize);
            }
        }
        out
    }
}

impl HoleIndex<'_> {
    /// Every hole `j != i` whose gap to hole `i` is below `max_gap`, in increasing order of
    /// `j` (range query with the same branch and bound as [`HoleIndex::nearest_gap`]).
    pub fn within_gap(&self, i: usize, max_gap: f64) -> Vec<usize> {
        let mut out = Vec::new();
        let Some(&q) = self.holes.get(i) else {
            return out;
        };
        if self.nodes.is_empty() || max_gap.is_nan() {
            return out;
        }
        let mut stack = Pending::root();
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            let lb = box_dist2(node, q.center).sqrt() - q.radius - node.max_r;
            if lb - (q.radius + node.max_r + lb.abs()) * 1e-12 >= max_gap {
                continue;
            }
            match node.children {
                None => {
                    let (s, e) = (node.start as usize, node.end as usize);
                    out.extend(
                        self.order[s..e]
                            .iter()
                            .zip(&self.sorted[s..e])
                            .filter(|&(&k, c)| k as usize != i && gap(&q, c) < max_gap)
                            .map(|(&k, _)| k as usize),
                    );
                }
                Some((l, r)) => {
                    stack.push(l);
                    stack.push(r);
                }
            }
        }
        out.sort_unstable();
        out
    }
}

impl HoleIndex<'_> {
    /// Visit the leaves of the tree that may hold a hole `c` with `gap(c, q) < max_gap`
    /// (the conservative bound of [`HoleIndex::within_gap`]), as (input indices, holes),
    /// until `visit` returns true; whether it did. `q` and `max_gap` finite.
    fn visit_near(
        &self,
        q: &Circle,
        max_gap: f64,
        mut visit: impl FnMut(&[u32], &[Circle]) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = Pending::root();
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            let lb = box_dist2(node, q.center).sqrt() - q.radius - node.max_r;
            if lb - (q.radius.abs() + node.max_r.abs() + lb.abs()) * 1e-12 >= max_gap {
                continue;
            }
            match node.children {
                None => {
                    let (s, e) = (node.start as usize, node.end as usize);
                    if visit(&self.order[s..e], &self.sorted[s..e]) {
                        return true;
                    }
                }
                Some((l, r)) => {
                    stack.push(l);
                    stack.push(r);
                }
            }
        }
        false
    }

    /// Every hole `k` with `gap(c_k, q) < max_gap` (`q` any circle, not necessarily a hole),
    /// in increasing order of `k`: the range query of [`HoleIndex::within_gap`] around a
    /// query circle (tested against the scan). Empty for a non-finite `q` or `max_gap`.
    pub fn within_gap_of(&self, q: &Circle, max_gap: f64) -> Vec<usize> {
        let mut out = Vec::new();
        let finite = q.center[0].is_finite()
            && q.center[1].is_finite()
            && q.radius.is_finite()
            && max_gap.is_finite();
        if finite {
            self.visit_near(q, max_gap, |order, sorted| {
                out.extend(
                    order
                        .iter()
                        .zip(sorted)
                        .filter(|&(_, c)| gap(c, q) < max_gap)
                        .map(|(&k, _)| k as usize),
                );
                false
            });
        }
        out.sort_unstable();
        out
    }

    /// True when some hole `c` has `gap(c, q) < max_gap` (`q` any circle, not necessarily a
    /// hole), i.e. exactly `!holes.iter().all(|c| gap(c, q) >= max_gap)` for finite `q` and
    /// `max_gap`: candidates are pruned by the same conservative bound as
    /// [`HoleIndex::within_gap`] and decided by the same expression `gap(c, q)`, so the answer
    /// is bitwise that of the scan (tested against it). A non-finite `q` or `max_gap` falls
    /// back to the scan. O(log n) for a small query instead of O(n).
    pub fn any_closer(&self, q: &Circle, max_gap: f64) -> bool {
        let finite = q.center[0].is_finite()
            && q.center[1].is_finite()
            && q.radius.is_finite()
            && max_gap.is_finite();
        if !finite {
            return !self.holes.iter().all(|c| gap(c, q) >= max_gap);
        }
        self.visit_near(q, max_gap, |_, leaf| {
            leaf.iter().any(|c| {
                // `!(gap >= max_gap)`: a NaN gap counts as closer, as in the scan.
                matches!(
                    gap(c, q).partial_cmp(&max_gap),
                    None | Some(std::cmp::Ordering::Less)
                )
            })
        })
    }
}

fn box_dist2(node: &Node, p: Point) -> f64 {
    let dx = (node.lo[0] - p[0]).max(p[0] - node.hi[0]).max(0.0);
    let dy = (node.lo[1] - p[1]).max(p[1] - node.hi[1]).max(0.0);
    dx * dx + dy * dy
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`AnyDomain::from_json_str`] skips its probe when the text cannot name `periodic`:
    /// the same answers as with it, for a key spelled with an escape and for texts the
    /// bounded parser refuses.
    #[test]
    fn any_domain_without_the_periodic_key_skips_the_probe() {
        let escaped =
            r#"{"\u0070eriodic": {"size": [4, 4]}, "holes": [{"center": [1, 1], "radius": 0.3}]}"#;
        assert!(matches!(
            AnyDomain::from_json_str(escaped),
            Ok(AnyDomain::Periodic(_))
        ));
        let texts = [
            r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [{"center": [1, 1], "radius": 0.5}]}"#,
            r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [{"center": [1, 1], "radius": }]}"#,
            r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [{"center": [1, 1], "radius": 0.5}, {"center": [1, 1], "radius": 0.5}]}"#,
            "{",
            "{}",
            r#"{"bounding": 3}"#,
            r#"{"holes": []}"#,
        ];
        for t in texts {
            let any = AnyDomain::from_json_str(t).map_err(|e| e.to_string());
            let bounded = Domain::from_json_str(t).map_err(|e| e.to_string());
            match (any, bounded) {
                (Ok(AnyDomain::Bounded(a)), Ok(b)) => assert_eq!(a, b, "{t}"),
                (Err(a), Err(b)) => assert_eq!(a, b, "{t}"),
                (a, b) => panic!("{t}: {:?} against {:?}", a.is_ok(), b.is_ok()),
            }
        }
    }

    /// The index built with subtrees on two threads is the one-thread index: the same nodes
    /// (boxes, radii, ranges, children ids) and the same order, on random holes with repeated
    /// coordinates (ties in the median split) and on a lattice; and the nearest gaps agree.
    #[test]
    fn hole_index_built_on_threads_equals_the_serial_one() {
        let mut r = crate::layouts::SplitMix64(8);
        for (round, n) in [1usize, 9, 17, 100, 1000, 5000, 20000]
            .into_iter()
            .enumerate()
        {
            let holes: Vec<Circle> = (0..n)
                .map(|i| {
                    let (x, y) = if round % 2 == 0 {
                        ((r.next_f64() * 50.0).floor(), r.next_f64())
                    } else {
                        ((i % 97) as f64, (i / 97) as f64)
                    };
                    Circle {
                        center: [x, y],
                        radius: 0.01 + 0.1 * r.next_f64(),
                    }
                })
                .collect();
            let serial = HoleIndex::new_with(&holes, usize::MAX);
            for parallel_from in [16, 1000, PARALLEL_BUILD] {
                let split = HoleIndex::new_with(&holes, parallel_from);
                assert_eq!(split.order, serial.order, "{n} holes");
                assert_eq!(format!("{:?}", split.nodes), format!("{:?}", serial.nodes));
            }
            let fast = HoleIndex::new(&holes);
            assert_eq!(
                fast.nearest_gap_each_on(false),
                serial.nearest_gap_each_on(false)
            );
            assert!(serial.nodes.len() >= n / LEAF);
        }
    }

    #[test]
    fn domain_index_and_gaps_equal_fresh_ones() {
        // The validated domain's (made by the validation), a reordered copy's (gaps carried
        // over, tree built on demand), a clone's (shared) and an unchecked domain's (both on
        // demand): the index answers and the nearest gaps of a fresh index, bit for bit,
        // brute force included.
        let d = crate::layouts::bubbles(700, 4).expect("bubbles");
        let n = d.holes().len();
        let order: Vec<u32> = (0..n as u32)
            .rev()
            .step_by(2)
            .chain((0..n as u32).rev().skip(1).step_by(2))
            .collect();
        let r = d.reordered(&order);
        let domains = [
            d.clone(),
            r.clone(),
            Domain::unchecked(r.bounding(), r.holes().to_vec()),
            Domain::hexagon_example(),
        ];
        for (k, d) in domains.iter().enumerate() {
            let fresh = HoleIndex::new(d.holes());
            let want = fresh.nearest_gap_each();
            assert_eq!(d.nearest_hole_gaps(), &gaps_of(&want)[..], "domain {k}");
            for (i, w) in want.iter().enumerate() {
                let brute = (0..d.holes().len())
                    .filter(|&j| j != i)
                    .map(|j| gap(&d.holes()[i], &d.holes()[j]))
                    .fold(None, |m: Option<f64>, g| Some(m.map_or(g, |m| m.min(g))));
                assert_eq!(
                    brute.map(f64::to_bits),
                    w.map(|w| w.1.to_bits()),
                    "domain {k} hole {i}"
                );
            }
            let idx = d.hole_index();
            assert_eq!(idx.nearest_gap_each(), want, "domain {k}");
            for i in (0..d.holes().len()).step_by(37) {
                assert_eq!(idx.within_gap(i, 0.5), fresh.within_gap(i, 0.5));
            }
        }
        // The reordered copy carried its gaps over, and a clone shares the built index.
        assert!(r.index.gaps.get().is_some() && r.index.tree.get().is_some());
        let c = d.clone();
        assert!(Arc::ptr_eq(&c.index, &d.index));
        assert_eq!(c, d);
        assert!(!format!("{c:?}").contains("index"));
    }

    #[test]
    fn nearest_gap_matches_brute_force() {
        let mut holes = Vec::new();
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..500 {
            holes.push(Circle::new(rnd() * 10.0, rnd() * 10.0, rnd() * 0.3));
        }
        holes.push(Circle::new(5.0, 5.0, 3.0));
        // Exact ties of the gap (the smaller index wins).
        holes.push(Circle::new(20.0, 0.0, 1.0));
        holes.push(Circle::new(23.0, 0.0, 1.0));
        holes.push(Circle::new(17.0, 0.0, 1.0));
        let idx = HoleIndex::new(&holes);
        let each = idx.nearest_gap_each();
        for i in 0..holes.len() {
            assert_eq!(each[i], idx.nearest_gap(i), "hole {i}");
            let mut best = (usize::MAX, f64::INFINITY);
            for j in 0..holes.len() {
                if j != i {
                    let g = gap(&holes[i], &holes[j]);
                    if g < best.1 || (g == best.1 && j < best.0) {
                        best = (j, g);
                    }
                }
            }
            assert_eq!(idx.nearest_gap(i), Some(best), "hole {i}");
            for g in [0.0, 0.05, 0.5] {
                let want: Vec<usize> = (0..holes.len())
                    .filter(|&j| j != i && gap(&holes[i], &holes[j]) < g)
                    .collect();
                assert_eq!(idx.within_gap(i, g), want, "hole {i} gap {g}");
            }
        }
    }

    /// [`Domain::with_holes_added`] against [`Domain::bounded`] of all the holes: the same
    /// result (holes, every nearest gap bit for bit, against brute force too) for valid
    /// additions (near and far, one and many, to an empty and a one-hole domain), and the
    /// same error for each kind of bad addition (overlapping a kept or an added hole, a
    /// duplicate, outside, touching the bounding circle, NaN, negative or tiny radius, too
    /// many at once: those through `bounded` itself).
    #[test]
    fn holes_added_give_the_domain_of_all_the_holes() {
        let check = |d: &Domain, added: &[Circle]| {
            let mut all = d.holes().to_vec();
            all.extend_from_slice(added);
            let want = Domain::bounded(d.bounding(), all);
            let got = d.with_holes_added(added);
            match (&got, &want) {
                (Ok(g), Ok(w)) => {
                    assert_eq!(g, w);
                    // The incremental path when it applies (`bounded` builds the tree).
                    let fast = d.index.gaps.get().is_some() && added.len() <= Domain::ADDED_AT_MOST;
                    assert_eq!(g.index.tree.get().is_none(), fast);
                    let bits = |x: &[Option<f64>]| -> Vec<Option<u64>> {
                        x.iter().map(|g| g.map(f64::to_bits)).collect()
                    };
                    assert_eq!(bits(g.nearest_hole_gaps()), bits(w.nearest_hole_gaps()));
                    let h = g.holes();
                    for i in (0..h.len()).step_by(1 + h.len() / 50) {
                        let brute = (0..h.len())
                            .filter(|&j| j != i)
                            .map(|j| gap(&h[i], &h[j]))
                            .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.min(x))));
                        assert_eq!(
                            brute.map(f64::to_bits),
                            g.nearest_hole_gaps()[i].map(f64::to_bits)
                        );
                    }
                    for i in h.len().saturating_sub(added.len())..h.len() {
                        assert_eq!(g.hole_index().nearest_gap(i), w.hole_index().nearest_gap(i));
                    }
                }
                // As text: a NaN in an error is not `==` itself.
                (Err(g), Err(w)) => assert_eq!(format!("{g:?}"), format!("{w:?}")),
                _ => panic!("{got:?} against {want:?}"),
            }
            got.is_ok()
        };
        let d = crate::layouts::bubbles(300, 9).expect("bubbles");
        let b = d.bounding();
        let mut rng = crate::layouts::SplitMix64(5);
        let mut valid = 0;
        for round in 0..60 {
            // Holes dropped at random, tiny to large: many overlap, some fit.
            let k = 1 + round % 7;
            let added: Vec<Circle> = (0..k)
                .map(|_| {
                    let a = std::f64::consts::TAU * rng.next_f64();
                    let r = b.radius * rng.next_f64();
                    let c = [b.center[0] + r * a.cos(), b.center[1] + r * a.sin()];
                    Circle::new(c[0], c[1], 1e-3 * b.radius * (1.0 + 20.0 * rng.next_f64()))
                })
                .collect();
            valid += usize::from(check(&d, &added));
            // One of them alone, when the batch failed.
            valid += usize::from(check(&d, &added[..1]));
        }
        assert!(valid > 10, "{valid}");
        // A hole in the widest gap of the layout is valid, close to its neighbours.
        let h = d.holes()[0];
        let near = Circle::new(h.center[0], h.center[1] + h.radius + 1e-4, 1e-5);
        assert!(check(&d, &[near]));
        // Bad additions: each the error `bounded` gives.
        let bad = [
            Circle::new(h.center[0], h.center[1], h.radius),
            Circle::new(h.center[0] + 0.5 * h.radius, h.center[1], h.radius),
            Circle::new(b.center[0] + b.radius, b.center[1], 0.01),
            Circle::new(b.center[0] + b.radius - 0.01, b.center[1], 0.01),
            Circle::new(f64::NAN, 0.0, 0.1),
            Circle::new(0.0, 0.0, -0.1),
            Circle::new(near.center[0], near.center[1], 1e-300),
        ];
        for c in bad {
            assert!(!check(&d, &[c]), "{c:?}");
            assert!(!check(&d, &[near, c]), "{c:?}");
        }
        // Two added holes overlapping each other; more than ADDED_AT_MOST at once.
        let twin = Circle::new(near.center[0] + 1e-6, near.center[1], 1e-5);
        assert!(!check(&d, &[near, twin]));
        let many: Vec<Circle> = (0..Domain::ADDED_AT_MOST + 1)
            .map(|i| {
                Circle::new(
                    h.center[0],
                    h.center[1] + h.radius + 1e-4 * (1.0 + i as f64),
                    1e-6,
                )
            })
            .collect();
        check(&d, &many);
        // To a domain with no hole, and with one.
        let empty = Domain::bounded(b, Vec::new()).unwrap();
        assert!(check(&empty, &[near]));
        assert!(check(
            &empty,
            &[near, Circle::new(0.5 * b.radius, 0.0, 0.01)]
        ));
        let one = Domain::bounded(b, vec![h]).unwrap();
        assert!(check(&one, &[near]));
        // Gaps not known (a domain never validated): through `bounded`.
        let unchecked = Domain::unchecked(b, d.holes().to_vec());
        assert!(check(&unchecked, &[near]));
    }

    #[test]
    fn hexagon_is_valid() {
        let d = Domain::hexagon_example();
        let again = Domain::bounded(d.bounding(), d.holes().to_vec()).unwrap();
        assert_eq!(d, again);
        assert_eq!(Domain::from_json_str(&d.to_json_string()).unwrap(), d);
    }
}

/// Either kind of domain: bounded (a bounding circle) or periodic (a rectangle repeated over
/// the plane, [`crate::periodic::PeriodicDomain`]).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyDomain {
    Bounded(Domain),
    Periodic(crate::periodic::PeriodicDomain),
}

impl AnyDomain {
    /// Parse either JSON form: `{"bounding": ..., "holes": [...]}` or
    /// `{"periodic": {"size": [Lx, Ly]}, "holes": [...]}` (told apart by the top-level
    /// `periodic` key).
    pub fn from_json_str(text: &str) -> Result<Self, DomainError> {
        #[derive(Deserialize)]
        struct Probe {
            periodic: Option<IgnoredAny>,
            bounding: Option<IgnoredAny>,
        }
        let text = crate::input::without_bom(text);
        // Only an object is a domain: serde reads a struct from an array too, so `[1, 2]` was
        // taken for a domain with both "periodic" and "bounding".
        let found = match text.trim_start().chars().next() {
            Some('{') | None => None,
            Some('[') => Some("an array"),
            Some('"') => Some("a string"),
            Some(_) => Some("a number or literal"),
        };
        if let Some(found) = found {
            return Err(DomainError::Json(format!(
                "a domain is a JSON object ({{\"bounding\": ..., \"holes\": [...]}} or \
                 {{\"periodic\": ..., \"holes\": [...]}}), not {found}"
            )));
        }
        // Without the key `periodic` (spelled out: an escape could spell it otherwise) the
        // probe can only answer "bounded": its pass over the text is skipped (issue 8: 8 ms
        // of the 1e5 input stage, one thread).
        let may_be_periodic = text.contains("periodic") || text.contains('\\');
        let probe = may_be_periodic
            .then(|| serde_json::from_str::<Probe>(text).ok())
            .flatten();
        match probe {
            Some(Probe {
                periodic: Some(_),
                bounding: Some(_),
            }) => Err(DomainError::Json(
                "a domain has either \"bounding\" (a bounding circle) or \"periodic\" (a \
                 periodic box), not both: unknown field `periodic` next to `bounding`"
                    .into(),
            )),
            Some(Probe {
                periodic: Some(_), ..
            }) => crate::periodic::PeriodicDomain::from_json_str(text).map(AnyDomain::Periodic),
            _ => Domain::from_json_str(text).map(AnyDomain::Bounded),
        }
    }

    /// Number of holes.
    pub fn hole_count(&self) -> usize {
        match self {
            AnyDomain::Bounded(d) => d.hole_count(),
            AnyDomain::Periodic(d) => d.hole_count(),
        }
    }
}
