//! Exact circle geometry: the Apollonius circle of three circles and an exact tangency predicate
//! (DESIGN.md section 5).
//!
//! A [`Site`] is a circle with a tangency sense: `s = +r` for a hole (the sought circle is
//! *externally* tangent, `|p - c| = rho + r`) and `s = -R` for the bounding circle (*internally*
//! tangent, `|p - c| = R - rho`). In both cases the squared condition is
//! `|p - c|^2 = (rho + s)^2`, and the sense is the sign of `sigma = rho + s` (`>= 0` for a hole,
//! `<= 0` for the bounding circle).
//!
//! - [`apollonius_roots`] returns every valid circle tangent to three sites, exactly: centre and
//!   radius in `Q(sqrt D)` ([`exact::QSqrt`]), with correctly rounded `f64` copies.
//! - [`apollonius`] selects one root (orientation of the tangent points, then nearest to a hint)
//!   and rounds it with its tangent points: first by a certified double-double evaluation
//!   (`fast.rs`, `ball.rs`) that decides every sign, the choice and the correct roundings or
//!   gives up, then (rarely) by the exact solve; the exact root of a fast answer is built only
//!   when a query needs it.
//! - [`tangency`] decides exactly whether a fourth site is clear of, tangent to or cutting that
//!   circle; a floating-point interval filter answers all but near-degenerate calls.
//! - [`same_circle`] and [`cocircular`] compare circles exactly (co-circular group detection).
//!
//! Nothing here panics on finite input; non-finite input gives [`ApolloniusError::NonFinite`].
//!
//! ```
//! use medial_blocks::apollonius::{apollonius, tangency, Choice, Sign, Site};
//! use medial_blocks::Circle;
//!
//! // Four holes of radius 1/4 at the corners of the unit square.
//! let hole = |x: f64, y: f64| Site::hole(Circle { center: [x, y], radius: 0.25 });
//! let ap = apollonius([hole(0.0, 0.0), hole(1.0, 0.0), hole(1.0, 1.0)], Choice::ccw()).unwrap();
//! assert_eq!(ap.center, [0.5, 0.5]);
//! assert!((ap.radius - (0.5f64.sqrt() - 0.25)).abs() < 1e-15);
//! // The fourth corner touches the same empty circle: exactly, although rho is irrational.
//! assert_eq!(tangency(&ap.exact, &hole(0.0, 1.0)).unwrap(), Sign::Zero);
//! // A slightly smaller hole there is clear of it.
//! let smaller = Site::hole(Circle { center: [0.0, 1.0], radius: 0.2499999 });
//! assert_eq!(tangency(&ap.exact, &smaller).unwrap(), Sign::Positive);
//! ```

mod ball;
pub mod exact;
mod fast;
mod interval;
pub mod predicate;
pub mod solve;

use crate::domain::Circle;
use serde::{Deserialize, Serialize};

pub use exact::{QSqrt, Sign};
pub use predicate::{cocircular, is_tangent, same_circle, tangency};
#[doc(hidden)]
pub use predicate::{tangency_exact, tangency_filter, tangency_sign_filtered, Path};
pub use solve::{
    apollonius, apollonius_exact, apollonius_fast, apollonius_roots, choose, Apollonius,
    ApolloniusError, Choice, ExactApollonius,
};

/// A circle with a tangency sense: `s = +r` for a hole, `s = -R` for the bounding circle.
///
/// The sense is the sign bit of `s` (so `Site::bounding` of a zero-radius circle, `s = -0.0`, is
/// still a bounding site).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Site {
    pub center: [f64; 2],
    pub s: f64,
}

impl Site {
    /// A hole: tangent circles touch it from outside. `radius` should be `>= 0`.
    pub fn hole(c: Circle) -> Site {
        Site {
            center: c.center,
            s: c.radius,
        }
    }

    /// The bounding circle: tangent circles touch it from inside. `radius` should be `>= 0`.
    pub fn bounding(c: Circle) -> Site {
        Site {
            center: c.center,
            s: -c.radius,
        }
    }

    /// True for the bounding circle (negative `s`).
    pub fn is_bounding(&self) -> bool {
        self.s.is_sign_negative()
    }

    /// The radius `|s|`.
    pub fn radius(&self) -> f64 {
        self.s.abs()
    }

    /// The circle, forgetting the sense.
    pub fn circle(&self) -> Circle {
        Circle {
            center: self.center,
            radius: self.radius(),
        }
    }

    /// True when the centre and `s` are finite.
    pub fn is_finite(&self) -> bool {
        self.center[0].is_finite() && self.center[1].is_finite() && self.s.is_finite()
    }
}
