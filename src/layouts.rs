//! Ready-made domains users (and benches, tests) can start from, as written by
//! `medial-blocks example`: the paper's *Hexagon*, a faithful rebuild of its *Lattice*, random
//! *bubbles* from a seed, and a square lattice (the degenerate co-circular case).
//!
//! Everything is deterministic: the random layouts use [`SplitMix64`], implemented here, so the
//! same seed gives the same domain on every platform and with every dependency version.

use crate::domain::{Circle, Domain, DomainError};

/// Which ready-made layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// [`hexagon`].
    Hexagon,
    /// [`lattice`].
    Lattice,
    /// [`bubbles`].
    Bubbles,
    /// [`square_lattice`].
    SquareLattice,
}

/// Why a layout could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LayoutError {
    #[error("{0} has a fixed number of holes; --holes does not apply")]
    FixedCount(&'static str),
    #[error("the number of holes must be at least {min}, got {got}")]
    TooFew { min: usize, got: usize },
    #[error("the number of holes must be at most {max}, got {got}")]
    TooMany { max: usize, got: usize },
    #[error("could only place {placed} of {wanted} bubbles")]
    Placement { placed: usize, wanted: usize },
    #[error(transparent)]
    Domain(#[from] DomainError),
}

/// Largest number of holes the generators make (the domain's own limit).
pub const MAX_GENERATED: usize = Domain::MAX_HOLES;

/// Default number of bubbles.
pub const DEFAULT_BUBBLES: usize = 20;
/// Default number of holes of the square lattice (4 x 4).
pub const DEFAULT_SQUARE_LATTICE: usize = 16;

/// Make `layout` with `holes` holes (where the layout's count can vary) and `seed` (for
/// [`Layout::Bubbles`]).
pub fn generate(layout: Layout, holes: Option<usize>, seed: u64) -> Result<Domain, LayoutError> {
    match layout {
        Layout::Hexagon => match holes {
            None | Some(7) => Ok(hexagon()),
            Some(_) => Err(LayoutError::FixedCount("hexagon (7 holes)")),
        },
        Layout::Lattice => match holes {
            None | Some(21) => lattice(),
            Some(_) => Err(LayoutError::FixedCount("lattice (21 holes)")),
        },
        Layout::Bubbles => bubbles(holes.unwrap_or(DEFAULT_BUBBLES), seed),
        Layout::SquareLattice => square_lattice(holes.unwrap_or(DEFAULT_SQUARE_LATTICE)),
    }
}

/// `n` random non-overlapping bubbles in a periodic square box, as [`bubbles`] makes them
/// (radii uniform in `[0.3, 0.6]`, gaps at least 0.1 to every image of every bubble) at the
/// same density: the box's area is that of [`bubbles`]' disk without its rim,
/// `pi n 0.2575 / 0.35`. Centres are uniform in the box, so bubbles cross its edges.
///
/// Rejection sampling on a grid of cells at least as wide as the largest exclusion distance,
/// wrapped around the box: each try checks its cell and the eight around it (the distinct
/// ones, on a small box), with the nearest-image distance, so linear time in `n`.
///
/// ```
/// let pd = medial_blocks::layouts::periodic_bubbles(50, 7).unwrap();
/// assert_eq!(pd.hole_count(), 50);
/// ```
pub fn periodic_bubbles(
    n: usize,
    seed: u64,
) -> Result<crate::periodic::PeriodicDomain, LayoutError> {
    hole_count(n)?;
    let side = (std::f64::consts::PI * n as f64 * 0.2575 / 0.35).sqrt();
    let reach = 2.0 * BUBBLE_R[1] + BUBBLE_GAP;
    let cells = ((side / reach).floor() as usize).max(1);
    let width = side / cells as f64;
    let index = |v: f64| ((v / width).floor().max(0.0) as usize).min(cells - 1);
    let nearest = |d: f64| d - (d / side).round() * side;
    let holes = place_bubbles(
        n,
        seed,
        cells,
        |rng, _| {
            let (x, y) = (side * rng.next_f64(), side * rng.next_f64());
            ([x, y], [index(x), index(y)])
        },
        |[ci, cj]| {
            let mut around: Vec<[usize; 2]> = Vec::with_capacity(9);
            for dj in [cells - 1, 0, 1] {
                for di in [cells - 1, 0, 1] {
                    around.push([(ci + di) % cells, (cj + dj) % cells]);
                }
            }
            around.sort_unstable();
            around.dedup();
            around
        },
        |a, b| nearest(a[0] - b[0]).hypot(nearest(a[1] - b[1])),
    );
    all_placed(&holes, n)?;
    Ok(crate::periodic::PeriodicDomain::new([side, side], holes)?)
}

/// The rejection sampling of the bubble generators: at most `200 n + 10 000` tries, each a
/// radius uniform in [`BUBBLE_R`] and then a centre and its grid cell from `candidate`; a try
/// is kept when every bubble in the cells `around` its cell is at least [`BUBBLE_GAP`] away
/// (`dist` between centres). The grid has `cells x cells` cells at least as wide as the
/// largest exclusion distance, so the cells around a centre hold every bubble that could be
/// too close: linear time in `n`. Fewer than `n` bubbles when the tries run out.
fn place_bubbles(
    n: usize,
    seed: u64,
    cells: usize,
    mut candidate: impl FnMut(&mut SplitMix64, f64) -> ([f64; 2], [usize; 2]),
    around: impl Fn([usize; 2]) -> Vec<[usize; 2]>,
    dist: impl Fn([f64; 2], [f64; 2]) -> f64,
) -> Vec<Circle> {
    // Bubble ids per grid cell, row-major.
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); cells * cells];
    let mut holes: Vec<Circle> = Vec::with_capacity(n);
    let mut rng = SplitMix64(seed);
    let max_tries = 200 * n as u64 + 10_000;
    let mut tries = 0u64;
    while holes.len() < n && tries < max_tries {
        tries += 1;
        let r = BUBBLE_R[0] + (BUBBLE_R[1] - BUBBLE_R[0]) * rng.next_f64();
        let (c, [ci, cj]) = candidate(&mut rng, r);
        let free = around([ci, cj]).into_iter().all(|[gi, gj]| {
            grid[gi + gj * cells].iter().all(|&h| {
                let o = holes[h as usize];
                dist(o.center, c) >= o.radius + r + BUBBLE_GAP
            })
        });
        if free {
            grid[ci + cj * cells].push(holes.len() as u32);
            holes.push(Circle::new(c[0], c[1], r));
        }
    }
    holes
}

/// A hole count the generators make: 1 to [`MAX_GENERATED`].
fn hole_count(n: usize) -> Result<(), LayoutError> {
    if n == 0 {
        return Err(LayoutError::TooFew { min: 1, got: 0 });
    }
    if n > MAX_GENERATED {
        return Err(LayoutError::TooMany {
            max: MAX_GENERATED,
            got: n,
        });
    }
    Ok(())
}

/// [`LayoutError::Placement`] when rejection sampling placed fewer than `n` bubbles.
fn all_placed(holes: &[Circle], n: usize) -> Result<(), LayoutError> {
    if holes.len() < n {
        return Err(LayoutError::Placement {
            placed: holes.len(),
            wanted: n,
        });
    }
    Ok(())
}

/// The paper's *Hexagon*: [`Domain::hexagon_example`] (7 holes, 36 blocks).
pub fn hexagon() -> Domain {
    Domain::hexagon_example()
}

/// The paper's *Lattice* (figure 14), rebuilt: 12 large holes (radius 0.6) interleaved with
/// 9 small ones (radius 0.3) on a square lattice of unit spacing. The small holes sit at
/// `(x, y)` with `x, y` in `{-2, 0, 2}`; the large ones at the odd positions `(±1, ±1)` (the
/// inner ring) and `(±3, ±1)`, `(±1, ±3)` (the outer ring); the bounding circle has radius 4.3
/// about the origin. As in the paper, each small hole has four hole neighbours, each inner
/// large hole eight, each outer large hole four and the bounding circle (so 4, 8 and 5
/// blocks), and Algorithm 2 gives `6 (21 - 1) = 120` blocks.
pub fn lattice() -> Result<Domain, LayoutError> {
    let mut holes = Vec::with_capacity(21);
    for y in [-2.0, 0.0, 2.0] {
        for x in [-2.0, 0.0, 2.0] {
            holes.push(Circle::new(x, y, 0.3));
        }
    }
    for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        holes.push(Circle::new(x, y, 0.6));
    }
    for (x, y) in [
        (1.0, -3.0),
        (3.0, -1.0),
        (3.0, 1.0),
        (1.0, 3.0),
        (-1.0, 3.0),
        (-3.0, 1.0),
        (-3.0, -1.0),
        (-1.0, -3.0),
    ] {
        holes.push(Circle::new(x, y, 0.6));
    }
    Ok(Domain::bounded(Circle::new(0.0, 0.0, 4.3), holes)?)
}

/// `k x k` equal holes (radius 0.3) at unit spacing centred on the origin, `k` the integer
/// nearest `sqrt(n)` (so `n` is rounded to `k²`, at least 1), in a bounding circle of radius
/// `(k - 1) / sqrt(2) + 0.9`. Every four neighbouring holes are co-circular: the degenerate
/// case of the medial axis.
pub fn square_lattice(n: usize) -> Result<Domain, LayoutError> {
    hole_count(n)?;
    let k = ((n as f64).sqrt().round() as usize).max(1);
    let half = (k as f64 - 1.0) / 2.0;
    let mut holes = Vec::with_capacity(k * k);
    for j in 0..k {
        for i in 0..k {
            holes.push(Circle::new(i as f64 - half, j as f64 - half, 0.3));
        }
    }
    let radius = half * std::f64::consts::SQRT_2 + 0.9;
    Ok(Domain::bounded(Circle::new(0.0, 0.0, radius), holes)?)
}

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, fast, fully specified generator, so seeds
/// give the same numbers everywhere.
#[derive(Debug, Clone)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// A uniform number in `[0, 1)` (53 random bits).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Smallest and largest bubble radius, and the smallest gap between two bubbles or a bubble
/// and the bounding circle.
const BUBBLE_R: [f64; 2] = [0.3, 0.6];
const BUBBLE_GAP: f64 = 0.1;

/// `n` random non-overlapping bubbles (radii uniform in `[0.3, 0.6]`, gaps at least 0.1) from
/// `seed`, inside a bounding circle about the origin sized for an area fraction of about 35%
/// (counting half a gap around each bubble): radius `sqrt(n * 0.2575 / 0.35) + 1`.
///
/// Rejection sampling with a uniform grid of cells as wide as the largest exclusion distance,
/// so each try checks a 3 x 3 block of cells: linear time in `n` (100 000 bubbles in well under
/// a second).
pub fn bubbles(n: usize, seed: u64) -> Result<Domain, LayoutError> {
    hole_count(n)?;
    let big_r = (n as f64 * 0.2575 / 0.35).sqrt() + 1.0;
    let cell = 2.0 * BUBBLE_R[1] + BUBBLE_GAP;
    let cells = ((2.0 * big_r / cell).ceil() as usize).max(1);
    let index = |v: f64| (((v + big_r) / cell).floor().max(0.0) as usize).min(cells - 1);
    let holes = place_bubbles(
        n,
        seed,
        cells,
        |rng, r| {
            // Uniform in the disk the centre may occupy.
            let reach = big_r - r - BUBBLE_GAP;
            let (u, t) = (rng.next_f64(), rng.next_f64());
            let rho = reach * u.sqrt();
            let phi = std::f64::consts::TAU * t;
            let (x, y) = (rho * phi.cos(), rho * phi.sin());
            ([x, y], [index(x), index(y)])
        },
        |[ci, cj]| {
            let rows = cj.saturating_sub(1)..=(cj + 1).min(cells - 1);
            rows.flat_map(|gj| {
                (ci.saturating_sub(1)..=(ci + 1).min(cells - 1)).map(move |gi| [gi, gj])
            })
            .collect()
        },
        |a, b| (a[0] - b[0]).hypot(a[1] - b[1]),
    );
    all_placed(&holes, n)?;
    Ok(Domain::bounded(Circle::new(0.0, 0.0, big_r), holes)?)
}
