//! Cell quality: interior angles and corner Jacobians of every quadrilateral cell.
//!
//! A cell `(i, j)` of a [`BlockGrid`] has corners `p0 = (i, j)`, `p1 = (i + 1, j)`,
//! `p2 = (i + 1, j + 1)`, `p3 = (i, j + 1)`, counter-clockwise for a valid cell. The Jacobian
//! at corner `k` is the cross product `(p[k+1] - p[k]) x (p[k-1] - p[k])`: positive for a
//! valid (counter-clockwise, convex at that corner) corner. The interior angle at corner `k`
//! is the angle swept counter-clockwise from `p[k+1] - p[k]` to `p[k-1] - p[k]`, in
//! `[0, 360)` degrees: below 180 where the Jacobian is positive, above 180 at a reflex corner
//! (so the four angles of a simple counter-clockwise cell sum to 360). A cell is *inverted*
//! when any corner Jacobian is `<= 0` or not a number.

use crate::geometry::Point;
use crate::mesh::BlockGrid;
use serde::Serialize;

/// Angles (degrees) and Jacobians of the four corners of one quadrilateral `[p0, p1, p2, p3]`
/// (see the module doc for the conventions).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellCorners {
    pub angle_deg: [f64; 4],
    pub jacobian: [f64; 4],
}

/// Measure one quadrilateral's corners.
pub fn cell_corners(p: [Point; 4]) -> CellCorners {
    let mut angle_deg = [0.0; 4];
    let mut jacobian = [0.0; 4];
    for k in 0..4 {
        let o = p[k];
        let a = p[(k + 1) % 4];
        let b = p[(k + 3) % 4];
        let e1 = [a[0] - o[0], a[1] - o[1]];
        let e2 = [b[0] - o[0], b[1] - o[1]];
        let cross = e1[0] * e2[1] - e1[1] * e2[0];
        let dot = e1[0] * e2[0] + e1[1] * e2[1];
        let mut ang = cross.atan2(dot).to_degrees();
        if ang < 0.0 {
            ang += 360.0;
        }
        angle_deg[k] = ang;
        jacobian[k] = cross;
    }
    CellCorners {
        angle_deg,
        jacobian,
    }
}

/// Per-cell figures of one block, cells in the order `i + j * ni` (VTK's cell order).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CellFields {
    pub min_angle_deg: Vec<f64>,
    pub max_angle_deg: Vec<f64>,
    /// The smallest of the four corner Jacobians (cross products, in squared length units).
    pub min_jacobian: Vec<f64>,
}

/// True when `grid.nodes` has exactly `(ni + 1) * (nj + 1)` nodes.
pub fn well_formed(grid: &BlockGrid) -> bool {
    grid.ni
        .checked_add(1)
        .and_then(|a| grid.nj.checked_add(1).and_then(|b| a.checked_mul(b)))
        == Some(grid.nodes.len())
}

/// The four corners of cell `(i, j)`; requires a well-formed grid and `i < ni`, `j < nj`.
fn corners(grid: &BlockGrid, i: usize, j: usize) -> [Point; 4] {
    [
        grid.node(i, j),
        grid.node(i + 1, j),
        grid.node(i + 1, j + 1),
        grid.node(i, j + 1),
    ]
}

/// Per-cell figures of one block (empty for a malformed grid, see [`well_formed`]).
pub fn cell_fields(grid: &BlockGrid) -> CellFields {
    let mut f = CellFields::default();
    if !well_formed(grid) {
        return f;
    }
    let n = grid.ni * grid.nj;
    f.min_angle_deg.reserve(n);
    f.max_angle_deg.reserve(n);
    f.min_jacobian.reserve(n);
    for j in 0..grid.nj {
        for i in 0..grid.ni {
            let c = cell_corners(corners(grid, i, j));
            f.min_angle_deg.push(fold(c.angle_deg, f64::min));
            f.max_angle_deg.push(fold(c.angle_deg, f64::max));
            // NaN-propagating minimum: a NaN Jacobian must not look valid.
            let mut mj = c.jacobian[0];
            for &x in &c.jacobian[1..] {
                if x.is_nan() || x < mj {
                    mj = x;
                }
            }
            f.min_jacobian.push(mj);
        }
    }
    f
}

fn fold(v: [f64; 4], op: fn(f64, f64) -> f64) -> f64 {
    op(op(v[0], v[1]), op(v[2], v[3]))
}

/// Quality figures of a whole mesh.
///
/// With no cells, every angle figure is 0. Malformed grids (see [`well_formed`]) contribute
/// no cells and are counted in `malformed_grids`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quality {
    /// Number of cells measured.
    pub cells: usize,
    /// Smallest and largest interior angle over all cells, degrees.
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    /// Mean over cells of each cell's smallest / largest interior angle, degrees (the
    /// paper's "average smallest / largest angle").
    pub mean_min_angle_deg: f64,
    pub mean_max_angle_deg: f64,
    /// Cells with a corner Jacobian `<= 0` (or not a number).
    pub inverted_cells: usize,
    /// Smallest corner Jacobian divided by the lengths of its two edges (the sine of the
    /// corner angle; 1 for a rectangle, `<= 0` for an inverted cell).
    pub min_scaled_jacobian: f64,
    /// Grids whose node count does not match `ni`, `nj`.
    pub malformed_grids: usize,
}

/// Measure every cell of every grid.
pub fn measure(grids: &[BlockGrid]) -> Quality {
    let mut q = Quality {
        cells: 0,
        min_angle_deg: f64::INFINITY,
        max_angle_deg: f64::NEG_INFINITY,
        mean_min_angle_deg: 0.0,
        mean_max_angle_deg: 0.0,
        inverted_cells: 0,
        min_scaled_jacobian: f64::INFINITY,
        malformed_grids: 0,
    };
    let (mut sum_min, mut sum_max) = (0.0, 0.0);
    for grid in grids {
        if !well_formed(grid) {
            q.malformed_grids += 1;
            continue;
        }
        for j in 0..grid.nj {
            for i in 0..grid.ni {
                let p = corners(grid, i, j);
                let c = cell_corners(p);
                let lo = fold(c.angle_deg, f64::min);
                let hi = fold(c.angle_deg, f64::max);
                q.cells += 1;
                sum_min += lo;
                sum_max += hi;
                q.min_angle_deg = q.min_angle_deg.min(lo);
                q.max_angle_deg = q.max_angle_deg.max(hi);
                if c.jacobian.iter().any(|&x| x.is_nan() || x <= 0.0) {
                    q.inverted_cells += 1;
                }
                for k in 0..4 {
                    let o = p[k];
                    let a = p[(k + 1) % 4];
                    let b = p[(k + 3) % 4];
                    let la = (a[0] - o[0]).hypot(a[1] - o[1]);
                    let lb = (b[0] - o[0]).hypot(b[1] - o[1]);
                    let s = if la > 0.0 && lb > 0.0 {
                        c.jacobian[k] / (la * lb)
                    } else {
                        0.0
                    };
                    if s.is_nan() || s < q.min_scaled_jacobian {
                        q.min_scaled_jacobian = s;
                    }
                }
            }
        }
    }
    if q.cells == 0 {
        q.min_angle_deg = 0.0;
        q.max_angle_deg = 0.0;
        q.min_scaled_jacobian = 0.0;
    } else {
        q.mean_min_angle_deg = sum_min / q.cells as f64;
        q.mean_max_angle_deg = sum_max / q.cells as f64;
    }
    q
}
