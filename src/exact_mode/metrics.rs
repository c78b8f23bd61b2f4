//! Quality figures exact mode is judged by, beyond [`crate::quality`]: the scaled Jacobian of a
//! block, wall orthogonality and aspect ratio, and one row of the paper-vs-exact comparison.
//!
//! Definitions (cell corners `p0..p3` counter-clockwise as in [`crate::quality`]):
//! - scaled Jacobian at a corner: the cross product of its two edges over their lengths (the
//!   sine of the corner angle; `<= 0` inverted, `0` for a degenerate corner);
//! - wall orthogonality deviation at a wall node: the angle between the grid line leaving the
//!   wall there (to the next node inward) and the circle's normal at the node, degrees;
//! - aspect ratio of a cell: the larger over the smaller of the mean lengths of its two pairs
//!   of opposite edges (`1` for a square, infinite for a degenerate cell).

use crate::domain::Domain;
use crate::geometry::Point;
use crate::layout::{BlockLayout, EdgeKind};
use crate::mesh::{BlockGrid, Mesh};
use crate::quality::{measure, well_formed};
use serde::Serialize;

fn corners(g: &BlockGrid, i: usize, j: usize) -> [Point; 4] {
    [
        g.node(i, j),
        g.node(i + 1, j),
        g.node(i + 1, j + 1),
        g.node(i, j + 1),
    ]
}

fn len(a: Point, b: Point) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The smallest scaled Jacobian of the four corners of a quadrilateral (NaN-propagating).
pub fn cell_min_scaled_jacobian(p: [Point; 4]) -> f64 {
    let mut out = f64::INFINITY;
    for k in 0..4 {
        let (o, a, b) = (p[k], p[(k + 1) % 4], p[(k + 3) % 4]);
        let e1 = [a[0] - o[0], a[1] - o[1]];
        let e2 = [b[0] - o[0], b[1] - o[1]];
        let la = e1[0].hypot(e1[1]);
        let lb = e2[0].hypot(e2[1]);
        let s = if la > 0.0 && lb > 0.0 {
            (e1[0] * e2[1] - e1[1] * e2[0]) / (la * lb)
        } else {
            0.0
        };
        if s.is_nan() || s < out {
            out = s;
        }
    }
    out
}

/// The smallest scaled Jacobian over a block (`+inf` without cells, NaN propagates).
pub fn min_scaled_jacobian(g: &BlockGrid) -> f64 {
    let mut out = f64::INFINITY;
    if !well_formed(g) {
        return f64::NAN;
    }
    for j in 0..g.nj {
        for i in 0..g.ni {
            let s = cell_min_scaled_jacobian(corners(g, i, j));
            if s.is_nan() || s < out {
                out = s;
            }
        }
    }
    out
}

/// The aspect ratio of one cell (see the module docs).
pub fn aspect_ratio(p: [Point; 4]) -> f64 {
    let a = 0.5 * (len(p[0], p[1]) + len(p[3], p[2]));
    let b = 0.5 * (len(p[1], p[2]) + len(p[0], p[3]));
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    if lo > 0.0 {
        hi / lo
    } else {
        f64::INFINITY
    }
}

/// The largest aspect ratio over all cells (1 without cells).
pub fn max_aspect_ratio(grids: &[BlockGrid]) -> f64 {
    let mut out: f64 = 1.0;
    for g in grids.iter().filter(|g| well_formed(g)) {
        for j in 0..g.nj {
            for i in 0..g.ni {
                out = out.max(aspect_ratio(corners(g, i, j)));
            }
        }
    }
    out
}

/// Grid node `k` of side `s` and the next node inward along the grid line leaving it.
fn side_node_and_inward(g: &BlockGrid, s: usize, k: usize) -> (Point, Point) {
    match s {
        0 => (g.node(k, 0), g.node(k, 1)),
        1 => (g.node(g.ni, k), g.node(g.ni - 1, k)),
        2 => (g.node(k, g.nj), g.node(k, g.nj - 1)),
        _ => (g.node(0, k), g.node(1, k)),
    }
}

/// The largest deviation (degrees) from the wall normal of the grid lines leaving the walls,
/// over every block side whose edge is a wall (0 when there is none).
pub fn max_wall_orthogonality_deviation_deg(
    domain: &Domain,
    layout: &BlockLayout,
    grids: &[BlockGrid],
) -> f64 {
    let mut out: f64 = 0.0;
    for (block, g) in layout.blocks.iter().zip(grids) {
        if !well_formed(g) || g.ni == 0 || g.nj == 0 {
            continue;
        }
        for (s, side) in block.sides.iter().enumerate() {
            let Some(edge) = layout.edges.get(side.edge as usize) else {
                continue;
            };
            let EdgeKind::Wall(c) = edge.kind else {
                continue;
            };
            if c < -1 || c >= domain.hole_count() as crate::domain::CircleId {
                continue;
            }
            let center = domain.circle(c).center;
            let count = if s % 2 == 0 { g.ni } else { g.nj };
            for k in 0..=count {
                let (p, q) = side_node_and_inward(g, s, k);
                let n = [p[0] - center[0], p[1] - center[1]];
                let t = [q[0] - p[0], q[1] - p[1]];
                // The angle between the line p -> q and the normal line (either sense).
                let cross = (n[0] * t[1] - n[1] * t[0]).abs();
                let dot = (n[0] * t[0] + n[1] * t[1]).abs();
                let a = cross.atan2(dot).to_degrees();
                out = out.max(if a.is_nan() { 90.0 } else { a });
            }
        }
    }
    out
}

/// One row of the paper-vs-exact comparison.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Figures {
    pub blocks: usize,
    pub cells: usize,
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    pub mean_min_angle_deg: f64,
    pub mean_max_angle_deg: f64,
    pub min_scaled_jacobian: f64,
    pub max_wall_orthogonality_deviation_deg: f64,
    pub max_aspect_ratio: f64,
    pub inverted_cells: usize,
}

impl Figures {
    /// Measure a mesh of `domain`.
    pub fn of(domain: &Domain, mesh: &Mesh) -> Figures {
        let q = measure(&mesh.grids);
        Figures {
            blocks: mesh.layout.blocks.len(),
            cells: q.cells,
            min_angle_deg: q.min_angle_deg,
            max_angle_deg: q.max_angle_deg,
            mean_min_angle_deg: q.mean_min_angle_deg,
            mean_max_angle_deg: q.mean_max_angle_deg,
            min_scaled_jacobian: q.min_scaled_jacobian,
            max_wall_orthogonality_deviation_deg: max_wall_orthogonality_deviation_deg(
                domain,
                &mesh.layout,
                &mesh.grids,
            ),
            max_aspect_ratio: max_aspect_ratio(&mesh.grids),
            inverted_cells: q.inverted_cells,
        }
    }
}

/// The corner angles exact mode cannot beat: at a medial vertex the medial arc between two
/// circles bisects the angle between their spokes, so the block corners there are half the
/// angles between consecutive spokes (any number of spokes: collapsed vertices). Returns `(smallest corner angle, 180 - it)` in degrees
/// over all vertices (`(90, 90)` without vertices): the spoke-aligned grid's cells at those
/// corners have these angles as the cell count grows.
pub fn vertex_corner_limit(vertices: &[super::ExactVertex]) -> (f64, f64) {
    let mut lo: f64 = 90.0;
    for v in vertices {
        let mut a: Vec<f64> = v
            .tangent
            .iter()
            .map(|t| (t[1] - v.center[1]).atan2(t[0] - v.center[0]))
            .collect();
        a.sort_by(f64::total_cmp);
        for (k, &x) in a.iter().enumerate() {
            let next = a
                .get(k + 1)
                .copied()
                .unwrap_or(a[0] + std::f64::consts::TAU);
            if a.len() > 1 {
                lo = lo.min(0.5 * (next - x).to_degrees());
            }
        }
    }
    (lo, 180.0 - lo)
}
