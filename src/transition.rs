//! Cartesian transition (tracker issue 6): a ring of blocks between the bounding circle and an
//! axis-aligned square whose boundary nodes are nodes of a Cartesian background grid of
//! spacing `s` (origin at 0: node `(i, j)` at `(i as f64 * s, j as f64 * s)`), so the
//! body-fitted mesh can be joined node to node to the carrier-phase grid.
//!
//! # Template
//! - The square `[i0 s, (i0 + N) s] x [j0 s, (j0 + N) s]` is the smallest lattice-aligned
//!   square enclosing the bounding circle grown by the margin `max(R / 4, 2 s)`.
//! - One transition block per bounding-circle wall edge `Q_a -> Q_b` (counter-clockwise):
//!   each end `Q` is projected radially from the circle's centre onto the square and snapped
//!   to a lattice node `P` along the perimeter (`assign_runs`: the nearest one, kept
//!   strictly increasing around the perimeter, so every block gets at least one lattice
//!   interval). The block has corners `[P_a, P_b, Q_b, Q_a]`: side 0 the run of lattice
//!   intervals from `P_a` to `P_b` (the new outer boundary, a polyline that may turn a
//!   corner of the square), side 1 and 3 the radial edges `Q -> P` (shared with the
//!   neighbouring transition blocks), side 2 the former wall edge, now an interface with the
//!   medial block behind it.
//! - Cell counts: the former wall edge gets as many cells as its lattice run has intervals,
//!   and so does its conformity class. Templates of inserted holes and collapsed vertices
//!   can tie several bounding-circle edges into one class: their runs get one count
//!   (`assign_runs`). The radial edges get `round(mean radial length / s)` (or a multiple,
//!   see below).
//! - The outer nodes are then set to the lattice points exactly (`i as f64 * s`), the same
//!   formula as the background grid's.
//! - The ring's grids (`ring_grids`): straight radial edges and transfinite interpolation
//!   where every cell is valid; else a polar interpolation that cannot fold where the wall
//!   nodes crowd (towards a hole near the bounding circle), with up to 8 times the radial
//!   cells. Every cell's orientation is checked exactly. Exact mode keeps its spoke-aligned
//!   grids only with a valid ring; otherwise the paper pipeline's interpolated mesh is used
//!   and labelled so ([`mesh_with_transition_rect`]).

use crate::domain::{Domain, BOUNDING};
use crate::exact_mode::imposed::{vertex_cycle, BlockKey, CircleTag, ImposedCounts};
use crate::geometry::predicates::orient2d;
use crate::geometry::Point;
use crate::grid::{build_grids_forced, tfi, MAX_CELLS_PER_SIDE};
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use crate::mesh::{BlockGrid, Geometry, Mesh};
use crate::mesher::{mesh, MeshError, Mode, Options};
use crate::numfmt::{Num, NumPair};
use std::cmp::Ordering;
use std::collections::BTreeMap;
use std::collections::HashMap;
use std::f64::consts::TAU;
use std::sync::Arc;

/// The background-aligned rectangle: lattice nodes `i0..=i0 + nx` by `j0..=j0 + ny`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub spacing: f64,
    pub i0: i64,
    pub j0: i64,
    pub nx: i64,
    pub ny: i64,
}

/// The earlier name: the default transition is a square [`Rect`].
pub type Square = Rect;

fn check_spacing(spacing: f64) -> Result<(), MeshError> {
    if spacing.is_finite() && spacing > 0.0 {
        Ok(())
    } else {
        Err(MeshError::Options(format!(
            "--transition: the background spacing must be finite and positive, got {}",
            Num(spacing)
        )))
    }
}

impl Rect {
    /// The smallest lattice-aligned square enclosing the circle `(center, r)` grown by the
    /// margin `max(r / 4, 2 spacing)`.
    pub fn around(center: Point, r: f64, spacing: f64) -> Result<Rect, MeshError> {
        check_spacing(spacing)?;
        let h = r + (0.25 * r).max(2.0 * spacing);
        let f = |x: f64| x / spacing;
        let (a0, a1) = (f(center[0] - h).floor(), f(center[0] + h).ceil());
        let (b0, b1) = (f(center[1] - h).floor(), f(center[1] + h).ceil());
        let n = (a1 - a0).max(b1 - b0);
        Rect::checked(spacing, a0, b0, n, n, r)
    }

    /// The lattice rectangle `[xmin, xmax] x [ymin, ymax]` grown outwards to the nearest
    /// lattice lines (so its corners are lattice nodes). It must enclose the bounding circle
    /// `(center, r)` with at least one lattice interval to spare on every side.
    pub fn from_bounds(
        bounds: [f64; 4],
        spacing: f64,
        center: Point,
        r: f64,
    ) -> Result<Rect, MeshError> {
        check_spacing(spacing)?;
        let [x0, y0, x1, y1] = bounds;
        if !(bounds.iter().all(|v| v.is_finite()) && x0 < x1 && y0 < y1) {
            return Err(MeshError::Options(format!(
                "--transition-rect: expected XMIN,YMIN,XMAX,YMAX with XMIN < XMAX and YMIN < \
                 YMAX, got {}",
                bounds.map(|v| Num(v).to_string()).join(",")
            )));
        }
        let f = |x: f64| x / spacing;
        let (a0, a1) = (f(x0).floor(), f(x1).ceil());
        let (b0, b1) = (f(y0).floor(), f(y1).ceil());
        let rect = Rect::checked(spacing, a0, b0, a1 - a0, b1 - b0, r)?;
        let [lo_x, lo_y] = rect.point((rect.i0, rect.j0));
        let [hi_x, hi_y] = rect.point((rect.i0 + rect.nx, rect.j0 + rect.ny));
        let room = (center[0] - r - lo_x)
            .min(center[1] - r - lo_y)
            .min(hi_x - center[0] - r)
            .min(hi_y - center[1] - r);
        if room.is_nan() || room < spacing {
            return Err(MeshError::Options(format!(
                "--transition-rect: the rectangle [{}, {}] x [{}, {}] must enclose the bounding \
                 circle (centre {}, radius {}) with at least one background interval ({}) to \
                 spare on every side",
                Num(lo_x),
                Num(hi_x),
                Num(lo_y),
                Num(hi_y),
                NumPair(center),
                Num(r),
                Num(spacing)
            )));
        }
        Ok(rect)
    }

    fn checked(
        spacing: f64,
        a0: f64,
        b0: f64,
        nx: f64,
        ny: f64,
        r: f64,
    ) -> Result<Rect, MeshError> {
        let lim = 4.0 * MAX_CELLS_PER_SIDE as f64;
        let ok = |x: f64| x.is_finite() && x >= 1.0 && x <= lim;
        if !(ok(nx) && ok(ny) && a0.abs() < 1e15 && b0.abs() < 1e15) {
            return Err(MeshError::Options(format!(
                "--transition: a spacing of {} needs too many background intervals around a \
                 bounding circle of radius {}",
                Num(spacing),
                Num(r)
            )));
        }
        Ok(Rect {
            spacing,
            i0: a0 as i64,
            j0: b0 as i64,
            nx: nx as i64,
            ny: ny as i64,
        })
    }

    /// Lattice intervals around the perimeter.
    pub fn perimeter_len(&self) -> i64 {
        2 * (self.nx + self.ny)
    }

    /// Perimeter lattice node `p` (counter-clockwise from the lower-left corner, taken mod
    /// the perimeter), as `(i, j)`.
    pub fn node(&self, p: i64) -> (i64, i64) {
        let (nx, ny) = (self.nx, self.ny);
        let p = p.rem_euclid(self.perimeter_len());
        if p < nx {
            (self.i0 + p, self.j0)
        } else if p < nx + ny {
            (self.i0 + nx, self.j0 + (p - nx))
        } else if p < 2 * nx + ny {
            (self.i0 + nx - (p - nx - ny), self.j0 + ny)
        } else {
            (self.i0, self.j0 + ny - (p - 2 * nx - ny))
        }
    }

    /// The coordinates of lattice node `(i, j)`: `(i as f64 * s, j as f64 * s)`.
    pub fn point(&self, (i, j): (i64, i64)) -> Point {
        [i as f64 * self.spacing, j as f64 * self.spacing]
    }

    /// The ray from `c` (inside) at angle `theta`: its parameters where it meets the vertical
    /// and the horizontal side it heads for (infinite when parallel to them), and its unit
    /// direction.
    fn ray(&self, c: Point, theta: f64) -> (f64, f64, [f64; 2]) {
        let s = self.spacing;
        let (x0, y0) = (self.i0 as f64 * s, self.j0 as f64 * s);
        let (x1, y1) = (x0 + self.nx as f64 * s, y0 + self.ny as f64 * s);
        let (dx, dy) = (theta.cos(), theta.sin());
        let tx = if dx > 0.0 {
            (x1 - c[0]) / dx
        } else if dx < 0.0 {
            (x0 - c[0]) / dx
        } else {
            f64::INFINITY
        };
        let ty = if dy > 0.0 {
            (y1 - c[1]) / dy
        } else if dy < 0.0 {
            (y0 - c[1]) / dy
        } else {
            f64::INFINITY
        };
        (tx, ty, [dx, dy])
    }

    /// The distance from `c` (inside) to the rectangle's boundary in direction `theta`.
    fn reach(&self, c: Point, theta: f64) -> f64 {
        let (tx, ty, _) = self.ray(c, theta);
        tx.min(ty)
    }

    /// The distance from `c` (inside) to the nearest side of the rectangle.
    fn inner_reach(&self, c: Point) -> f64 {
        let s = self.spacing;
        let (x0, y0) = (self.i0 as f64 * s, self.j0 as f64 * s);
        let (x1, y1) = (x0 + self.nx as f64 * s, y0 + self.ny as f64 * s);
        (c[0] - x0).min(x1 - c[0]).min(c[1] - y0).min(y1 - c[1])
    }

    /// Continuous perimeter coordinate (in intervals, from the lower-left corner) of the ray
    /// from `c` (inside) at angle `theta`.
    fn perimeter(&self, c: Point, theta: f64) -> f64 {
        let s = self.spacing;
        let (nx, ny) = (self.nx as f64, self.ny as f64);
        let (x0, y0) = (self.i0 as f64 * s, self.j0 as f64 * s);
        let (x1, y1) = (x0 + nx * s, y0 + ny * s);
        let (tx, ty, [dx, dy]) = self.ray(c, theta);
        let t = tx.min(ty);
        let (x, y) = (c[0] + t * dx, c[1] + t * dy);
        if tx < ty {
            if dx > 0.0 {
                nx + (y - y0) / s
            } else {
                2.0 * nx + ny + (y1 - y) / s
            }
        } else if dy < 0.0 {
            (x - x0) / s
        } else {
            nx + ny + (x1 - x) / s
        }
    }
}

/// A layout with its transition ring and what the grid stage must impose.
#[derive(Debug, Clone)]
pub struct Transition {
    pub layout: BlockLayout,
    pub square: Rect,
    /// `(edge, cells)` to impose: first a radial edge of the ring (every radial edge is in
    /// its class), then each bounding-circle wall edge with its lattice run's interval count.
    /// Edges of one conformity class of the input layout get one count (`assign_runs`).
    pub counts: Vec<(usize, usize)>,
    /// Per transition block: its id and the lattice nodes of its side 0, in order.
    pub outer: Vec<(usize, Vec<(i64, i64)>)>,
}

/// The bounding-circle wall edges of `layout` chained counter-clockwise (starting with the
/// one whose start projects first onto the rectangle's perimeter) and the perimeter node
/// `ps[i]` of each one's start: edge `chain[i]` gets the lattice run `ps[i]..ps[i + 1]`
/// (the last one up to `ps[0] + perimeter`), at least one interval each.
#[derive(Debug, Clone, PartialEq)]
struct Runs {
    chain: Vec<usize>,
    ps: Vec<i64>,
}

impl Runs {
    /// Lattice intervals of the run of chain edge `i`.
    fn cells(&self, i: usize, total: i64) -> i64 {
        let next = self.ps.get(i + 1).copied().unwrap_or(self.ps[0] + total);
        next - self.ps[i]
    }
}

/// Assign the lattice runs ([`Runs`]). Each chain vertex is projected radially from the
/// circle's centre onto the perimeter (continuous position `t_i`, in intervals). Edges that
/// share a conformity class of `layout` (templates of inserted holes and collapsed vertices
/// can tie two bounding arcs) must get one count: such a class gets the rounded mean of its
/// edges' ideal lengths (`t_{i+1} - t_i`, at least 1), lowered or raised one step at a time
/// (the class furthest from its mean first) until the other edges can close the perimeter;
/// the other edges share what is left in proportion to their ideal lengths. Positions are
/// then rounded in turn (a tied edge adds its class count), each edge at least one
/// interval, the last free edge closing the perimeter. Without tied edges this is the plain
/// rounding of every `t_i`, kept strictly increasing.
fn assign_runs(layout: &BlockLayout, domain: &Domain, sq: &Rect) -> Result<Runs, MeshError> {
    let spacing = sq.spacing;
    let b = domain.bounding();
    // The bounding wall edges, chained counter-clockwise.
    let walls: Vec<usize> = (0..layout.edges.len())
        .filter(|&e| layout.edges[e].kind == EdgeKind::Wall(BOUNDING))
        .collect();
    if walls.len() < 2 {
        return Err(MeshError::Options(
            "--transition needs a bounding circle split into at least two wall edges".into(),
        ));
    }
    let by_start: HashMap<u32, usize> = walls
        .iter()
        .map(|&e| (layout.edges[e].ends[0], e))
        .collect();
    let angle = |v: u32| {
        let p = layout.vertices[v as usize];
        (p[1] - b.center[1]).atan2(p[0] - b.center[0])
    };
    let first = walls
        .iter()
        .copied()
        .min_by(|&x, &y| {
            let (px, py) = (
                sq.perimeter(b.center, angle(layout.edges[x].ends[0])),
                sq.perimeter(b.center, angle(layout.edges[y].ends[0])),
            );
            px.total_cmp(&py).then(x.cmp(&y))
        })
        .ok_or_else(|| MeshError::Internal("no bounding wall".into()))?;
    let mut chain = vec![first];
    while chain.len() < walls.len() {
        let last = layout.edges[chain[chain.len() - 1]].ends[1];
        match by_start.get(&last) {
            Some(&e) if e != first => chain.push(e),
            _ => break,
        }
    }
    if chain.len() != walls.len()
        || layout.edges[chain[chain.len() - 1]].ends[1] != layout.edges[first].ends[0]
    {
        return Err(MeshError::Internal(
            "the bounding-circle walls do not form one closed chain".into(),
        ));
    }
    let total = sq.perimeter_len();
    let k = chain.len();
    let too_coarse = || {
        MeshError::Options(format!(
            "--transition: the background spacing {} is too coarse for the {k} bounding wall \
             edges (each needs at least one interval, edges tied by a conformity class the same \
             number)",
            Num(spacing)
        ))
    };
    // Continuous perimeter positions, increasing, t[k] = t[0] + total.
    let mut t: Vec<f64> = Vec::with_capacity(k + 1);
    for &e in &chain {
        let mut x = sq.perimeter(b.center, angle(layout.edges[e].ends[0]));
        while t.last().is_some_and(|&prev| x < prev) {
            x += total as f64;
        }
        t.push(x);
    }
    t.push(t[0] + total as f64);
    // Tied edges: classes holding two or more chain edges, with their count.
    let (class, _) = crate::grid::edge_classes(layout);
    let mut members: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (i, &e) in chain.iter().enumerate() {
        members.entry(class[e]).or_default().push(i);
    }
    let mut tied: Vec<(Vec<usize>, f64, i64)> = members
        .into_values()
        .filter(|m| m.len() >= 2)
        .map(|m| {
            let mean = m.iter().map(|&i| t[i + 1] - t[i]).sum::<f64>() / m.len() as f64;
            let n = (mean.round() as i64).max(1);
            (m, mean, n)
        })
        .collect();
    let mut fixed: Vec<Option<i64>> = vec![None; k];
    let free = k - tied.iter().map(|g| g.0.len()).sum::<usize>();
    if !tied.is_empty() {
        // What the tied edges take; the free edges need at least one interval each, and
        // without free edges the tied ones must close the perimeter alone.
        let taken = |tied: &[(Vec<usize>, f64, i64)]| -> i64 {
            tied.iter().map(|g| g.0.len() as i64 * g.2).sum()
        };
        let fits = |x: i64| {
            if free == 0 {
                x == total
            } else {
                x + free as i64 <= total
            }
        };
        let mut steps = 0;
        while !fits(taken(&tied)) {
            steps += 1;
            let x = taken(&tied);
            let lower = if free == 0 { x > total } else { true };
            // The class furthest from its mean in the direction of the step, that can take
            // it (one interval at least; without free edges, not past the perimeter).
            let pick = (0..tied.len())
                .filter(|&g| {
                    let (m, n) = (tied[g].0.len() as i64, tied[g].2);
                    if lower {
                        n > 1
                    } else {
                        x + m <= total
                    }
                })
                .max_by(|&a, &c| {
                    let d = |g: usize| {
                        let d = tied[g].2 as f64 - tied[g].1;
                        if lower {
                            d
                        } else {
                            -d
                        }
                    };
                    d(a).total_cmp(&d(c)).then(c.cmp(&a))
                });
            match pick {
                Some(g) if steps <= 4 * total => tied[g].2 += if lower { -1 } else { 1 },
                _ => return Err(too_coarse()),
            }
        }
        for (m, _, n) in &tied {
            for &i in m {
                fixed[i] = Some(*n);
            }
        }
    }
    if free == 0 {
        // Tied edges only: their counts close the perimeter (checked above).
        let mut ps = vec![t[0].round() as i64];
        for i in 0..k - 1 {
            let n = fixed[i].ok_or_else(|| MeshError::Internal("untied edge".into()))?;
            ps.push(ps[i] + n);
        }
        return Ok(Runs { chain, ps });
    }
    // The free edges share what the tied ones leave, in proportion to their ideal lengths;
    // positions are rounded from the first edge after the last free one, so that a free
    // edge closes the perimeter.
    let left = total - (0..k).filter_map(|i| fixed[i]).sum::<i64>();
    let free_len: f64 = (0..k)
        .filter(|&i| fixed[i].is_none())
        .map(|i| t[i + 1] - t[i])
        .sum();
    let scale = if free_len.is_finite() && free_len > 0.0 {
        left as f64 / free_len
    } else {
        1.0
    };
    let last_free = (0..k)
        .rev()
        .find(|&i| fixed[i].is_none())
        .ok_or_else(|| MeshError::Internal("no free edge".into()))?;
    let start = (last_free + 1) % k;
    let order: Vec<usize> = (0..k).map(|x| (start + x) % k).collect();
    // Target positions along `order`, from t[start] (without tied edges, the `t` themselves).
    let mut target = Vec::with_capacity(k);
    let mut acc = t[start];
    for &i in &order {
        target.push(if tied.is_empty() { t[i] } else { acc });
        acc += match fixed[i] {
            Some(n) => n as f64,
            None => (t[i + 1] - t[i]) * scale,
        };
    }
    // What the edges after each position need at least.
    let mut need = vec![0i64; k + 1];
    for x in (0..k).rev() {
        need[x] = need[x + 1] + fixed[order[x]].unwrap_or(1);
    }
    let mut pos = vec![target[0].round() as i64];
    for x in 1..k {
        let prev = pos[x - 1];
        // (Without tied edges the upper bound never binds where the perimeter closes.)
        let p = match fixed[order[x - 1]] {
            Some(n) => prev + n,
            None => (target[x].round() as i64)
                .max(prev + 1)
                .min(pos[0] + total - need[x]),
        };
        pos.push(p);
    }
    if pos[k - 1] + need[k - 1] > pos[0] + total || pos.windows(2).any(|w| w[1] <= w[0]) {
        return Err(too_coarse());
    }
    // Back to chain order, positions increasing from chain[0].
    let mut ps = vec![0i64; k];
    for (x, &i) in order.iter().enumerate() {
        ps[i] = pos[x] - if i < start { total } else { 0 };
    }
    Ok(Runs { chain, ps })
}

/// Add the transition ring to a layout whose outer boundary is the bounding circle of
/// `domain` (see the module documentation).
pub fn add_transition(
    layout: &BlockLayout,
    domain: &Domain,
    spacing: f64,
) -> Result<Transition, MeshError> {
    let b = domain.bounding();
    add_transition_rect(layout, domain, Rect::around(b.center, b.radius, spacing)?)
}

/// [`add_transition`] out to a given lattice rectangle (see [`Rect::from_bounds`]).
pub fn add_transition_rect(
    layout: &BlockLayout,
    domain: &Domain,
    sq: Rect,
) -> Result<Transition, MeshError> {
    let runs = assign_runs(layout, domain, &sq)?;
    Ok(ring_layout(layout, sq, &runs, 1))
}

/// The layout with one transition block per chain edge of `runs` (module documentation),
/// `rows` times as many radial cells as the mean radial length has intervals.
fn ring_layout(layout: &BlockLayout, sq: Rect, runs: &Runs, rows: usize) -> Transition {
    let (chain, ps) = (&runs.chain, &runs.ps);
    let total = sq.perimeter_len();
    let mut out = layout.clone();
    // New vertices and radial edges.
    let mut pv = Vec::with_capacity(chain.len());
    let mut radial = Vec::with_capacity(chain.len());
    let mut radial_len = 0.0;
    for (i, &e) in chain.iter().enumerate() {
        let q = layout.edges[e].ends[0];
        out.vertices.push(sq.point(sq.node(ps[i])));
        let v = (out.vertices.len() - 1) as u32;
        pv.push(v);
        let (a, c) = (out.vertices[q as usize], out.vertices[v as usize]);
        radial_len += (a[0] - c[0]).hypot(a[1] - c[1]);
        out.edges.push(Edge {
            ends: [q, v],
            curve: Curve::Segment,
            kind: EdgeKind::Interface,
        });
        radial.push((out.edges.len() - 1) as u32);
    }
    let radial_cells = ((radial_len / chain.len() as f64 / sq.spacing).round() as usize)
        .clamp(1, MAX_CELLS_PER_SIDE)
        .saturating_mul(rows)
        .min(MAX_CELLS_PER_SIDE);
    let mut counts = vec![(radial[0] as usize, radial_cells)];
    let mut outer = Vec::with_capacity(chain.len());
    let k = chain.len();
    for i in 0..k {
        let e = chain[i];
        let (pa, pb) = (ps[i], ps[i] + runs.cells(i, total));
        let nodes: Vec<(i64, i64)> = (pa..=pb).map(|p| sq.node(p)).collect();
        let pts: Vec<Point> = nodes.iter().map(|&n| sq.point(n)).collect();
        let (va, vb) = (pv[i], pv[(i + 1) % k]);
        out.edges.push(Edge {
            ends: [va, vb],
            curve: Curve::Polyline(pts),
            kind: EdgeKind::Wall(BOUNDING),
        });
        let outer_edge = (out.edges.len() - 1) as u32;
        out.edges[e].kind = EdgeKind::Interface;
        let [qa, qb] = layout.edges[e].ends;
        out.blocks.push(Block {
            corners: [va, vb, qb, qa],
            sides: [
                SideRef {
                    edge: outer_edge,
                    reversed: false,
                },
                SideRef {
                    edge: radial[(i + 1) % k],
                    reversed: true,
                },
                SideRef {
                    edge: e as u32,
                    reversed: true,
                },
                SideRef {
                    edge: radial[i],
                    reversed: false,
                },
            ],
            wall: None,
        });
        counts.push((e, (pb - pa) as usize));
        outer.push((out.blocks.len() - 1, nodes));
    }
    Transition {
        layout: out,
        square: sq,
        counts,
        outer,
    }
}

/// The ring's grids and the nodes of each radial edge ([`ring_grids`]).
type RingNodes = (Vec<BlockGrid>, HashMap<u32, Vec<Point>>);

/// How the ring's interior nodes are placed ([`ring_grids`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ring {
    /// Polar interpolation about the bounding circle's centre.
    Polar,
    /// Straight radial edges, equally spaced, and transfinite interpolation.
    Straight,
}

/// The angle of `p` about `c`, moved by a multiple of `2 pi` to within `pi` of `near`.
fn angle_near(c: Point, p: Point, near: f64) -> f64 {
    let a = (p[1] - c[1]).atan2(p[0] - c[0]);
    a + TAU * ((near - a) / TAU).round()
}

/// The ring's grids by polar interpolation about the bounding circle's centre `c` (radius
/// `r`): node `(i, j)` of a ring block, `s = j / nj` from the lattice (`s = 0`) to the wall
/// (`s = 1`), is at angle `phi = beta_i + s (alpha_i - beta_i)` and distance
/// `rho(phi) + s (r - rho(phi))`, where `alpha_i` and `beta_i` are the angles of wall node
/// `i` and lattice node `i` (unwrapped along the block) and `rho(phi)` the distance from `c`
/// to the rectangle in direction `phi`. Both angle sequences increase with `i`, so every
/// grid line `j` has increasing angles and the ring cannot fold however the wall nodes
/// crowd (a straight-line interpolation folds where they crowd towards a hole near the
/// bounding circle while the lattice nodes are evenly spaced). The boundary nodes are the
/// given ones exactly; each radial edge's nodes are computed once and copied into both
/// blocks. `walls[k]` are the wall nodes of ring block `k` counter-clockwise (its side 2
/// reversed). Returns the grids and each radial edge's nodes (from the wall to the
/// lattice), or `None` when the counts do not fit or some cell is not strictly
/// counter-clockwise at all four corners (exact orientation, and the float test of
/// [`crate::quality`]).
fn ring_grids(
    t: &Transition,
    c: Point,
    r: f64,
    walls: &[Vec<Point>],
    shape: Ring,
) -> Option<RingNodes> {
    let nj = t.counts.first()?.1;
    let sq = &t.square;
    // Rows `0..=j2` run along the rays from the lattice nodes to the circle of radius `r2`;
    // rows `j2..=nj` turn from the lattice angles to the wall angles on circles.
    let j2 = if nj >= 2 { (nj / 3).max(1) } else { 0 };
    let r2 = r + (sq.inner_reach(c) - r) * (nj - j2) as f64 / nj as f64;
    let at = |alpha: f64, beta: f64, j: usize| -> Point {
        let (phi, d) = if j <= j2 && j2 > 0 {
            let rho = sq.reach(c, beta);
            (beta, rho + (j as f64 / j2 as f64) * (r2 - rho))
        } else {
            let u = (j - j2) as f64 / (nj - j2) as f64;
            (beta + u * (alpha - beta), r2 + u * (r - r2))
        };
        [c[0] + d * phi.cos(), c[1] + d * phi.sin()]
    };
    // Radial edge nodes, from the wall vertex (index 0) to the lattice vertex (index nj).
    let mut radial: HashMap<u32, Vec<Point>> = HashMap::new();
    for (k, (b, _)) in t.outer.iter().enumerate() {
        let block = t.layout.blocks.get(*b)?;
        let e = block.sides[3].edge;
        let [q, p] = t.layout.edges.get(e as usize)?.ends;
        let (q, p) = (
            *t.layout.vertices.get(q as usize)?,
            *t.layout.vertices.get(p as usize)?,
        );
        if walls.get(k)?.first() != Some(&q) {
            return None;
        }
        let alpha = (q[1] - c[1]).atan2(q[0] - c[0]);
        let beta = angle_near(c, p, alpha);
        let mut nodes: Vec<Point> = match shape {
            Ring::Polar => (0..=nj).map(|j| at(alpha, beta, nj - j)).collect(),
            Ring::Straight => (0..=nj)
                .map(|i| {
                    let s = i as f64 / nj as f64;
                    [q[0] + s * (p[0] - q[0]), q[1] + s * (p[1] - q[1])]
                })
                .collect(),
        };
        nodes[0] = q;
        nodes[nj] = p;
        radial.insert(e, nodes);
    }
    let mut grids = Vec::with_capacity(t.outer.len());
    for (k, (b, lattice)) in t.outer.iter().enumerate() {
        let block = t.layout.blocks.get(*b)?;
        let wall = walls.get(k)?;
        let ni = lattice.len().checked_sub(1)?;
        if wall.len() != ni + 1 || ni == 0 {
            return None;
        }
        let (left, right) = (
            radial.get(&block.sides[3].edge)?,
            radial.get(&block.sides[1].edge)?,
        );
        let outer: Vec<Point> = lattice.iter().map(|&n| sq.point(n)).collect();
        if left[nj] != outer[0] || right[nj] != outer[ni] || wall[ni] != right[0] {
            return None;
        }
        let mut alpha = Vec::with_capacity(ni + 1);
        let mut beta = Vec::with_capacity(ni + 1);
        alpha.push((wall[0][1] - c[1]).atan2(wall[0][0] - c[0]));
        beta.push(angle_near(c, outer[0], alpha[0]));
        for i in 1..=ni {
            alpha.push(angle_near(c, wall[i], alpha[i - 1]));
            beta.push(angle_near(c, outer[i], beta[i - 1]));
        }
        let g = match shape {
            Ring::Straight => tfi(
                &outer,
                &right.iter().rev().copied().collect::<Vec<_>>(),
                &wall.iter().rev().copied().collect::<Vec<_>>(),
                left,
            )?,
            Ring::Polar => {
                let mut nodes = Vec::with_capacity((ni + 1) * (nj + 1));
                for j in 0..=nj {
                    for i in 0..=ni {
                        nodes.push(if i == 0 {
                            left[nj - j]
                        } else if i == ni {
                            right[nj - j]
                        } else if j == 0 {
                            outer[i]
                        } else if j == nj {
                            wall[i]
                        } else {
                            at(alpha[i], beta[i], j)
                        });
                    }
                }
                BlockGrid { ni, nj, nodes }
            }
        };
        if !counter_clockwise(&g) {
            return None;
        }
        grids.push(g);
    }
    Some((grids, radial))
}

/// Radial cell counts tried for the polar ring, as multiples of the layout's (more rows
/// turn the grid lines more gently).
const POLAR_ROWS: [usize; 4] = [1, 2, 4, 8];

/// The ring of `t` (made by [`ring_layout`] on `inner`, the layout inside the ring, with
/// `runs`) with valid grids ([`ring_grids`]): the straight one (radial segments,
/// transfinite interpolation) where it is valid, else the polar one with the layout's radial
/// count or a multiple of it ([`POLAR_ROWS`]), whose radial edges become polylines of their
/// nodes. `walls` are the wall nodes of the ring blocks ([`ring_walls`]). `None` when none
/// is valid.
fn valid_ring(
    t: &Transition,
    inner: &BlockLayout,
    runs: &Runs,
    domain: &Domain,
    walls: &[Vec<Point>],
) -> Option<(Transition, Vec<BlockGrid>)> {
    let b = domain.bounding();
    if let Some((grids, _)) = ring_grids(t, b.center, b.radius, walls, Ring::Straight) {
        return Some((t.clone(), grids));
    }
    for rows in POLAR_ROWS {
        let t = ring_layout(inner, t.square, runs, rows);
        if let Some((grids, radial)) = ring_grids(&t, b.center, b.radius, walls, Ring::Polar) {
            let mut t = t;
            for (e, nodes) in radial {
                if let Some(edge) = t.layout.edges.get_mut(e as usize) {
                    edge.curve = Curve::Polyline(nodes);
                }
            }
            return Some((t, grids));
        }
    }
    None
}

/// Every cell of `g` strictly counter-clockwise at its four corners: exactly
/// ([`orient2d`]) and by the float test that [`crate::quality`] reports inverted cells with.
fn counter_clockwise(g: &BlockGrid) -> bool {
    for j in 0..g.nj {
        for i in 0..g.ni {
            let q = [
                g.node(i, j),
                g.node(i + 1, j),
                g.node(i + 1, j + 1),
                g.node(i, j + 1),
            ];
            for k in 0..4 {
                if orient2d(q[k], q[(k + 1) % 4], q[(k + 3) % 4]) != Ordering::Greater {
                    return false;
                }
            }
        }
    }
    crate::quality::inverted_cells(std::slice::from_ref(g)) == 0
}

/// The wall nodes of each transition block of `t` (counter-clockwise), from the grids of
/// the blocks inside the ring (`grids[b]` for block `b` of the layout before the ring).
fn ring_walls(t: &Transition, grids: &[BlockGrid], inner: usize) -> Option<Vec<Vec<Point>>> {
    let mut by_wall: HashMap<u32, usize> = HashMap::new();
    for (b, block) in t.layout.blocks.iter().enumerate().take(inner) {
        by_wall.entry(block.sides[0].edge).or_insert(b);
    }
    t.outer
        .iter()
        .map(|(b, _)| {
            let edge = t.layout.blocks.get(*b)?.sides[2].edge;
            let g = grids.get(*by_wall.get(&edge)?)?;
            Some(g.side(0))
        })
        .collect()
}

/// Mesh `domain` ([`mesh`]) and add the transition ring to a Cartesian background of
/// `spacing`; the outer nodes are exactly the background's lattice nodes.
pub fn mesh_with_transition(
    domain: &Domain,
    options: &Options,
    spacing: f64,
) -> Result<Mesh, MeshError> {
    let b = domain.bounding();
    mesh_with_transition_rect(domain, options, Rect::around(b.center, b.radius, spacing)?)
}

/// [`mesh_with_transition`] out to the lattice rectangle `rect` ([`Rect::from_bounds`]).
///
/// Exact mode keeps its spoke-aligned grids when the exact mesher honours the lattice counts
/// imposed on the bounding-circle arcs and the ring is valid (`exact_transition`): such a
/// mesh has no inverted cell. Otherwise the domain is meshed by the paper pipeline (paper
/// mode, [`Geometry::Paper`]) with those counts imposed on its conformity classes, every
/// grid interpolated, the ring as in `valid_ring` (its straight interpolation when no
/// ring is valid: the inverted cells are then reported by the quality measures).
pub fn mesh_with_transition_rect(
    domain: &Domain,
    options: &Options,
    rect: Rect,
) -> Result<Mesh, MeshError> {
    // The ring joins the blocks' nodes: they are kept.
    let options = &*options.keeping_nodes();
    let mut base = mesh(domain, options)?;
    if options.mode == Mode::Exact && domain.hole_count() >= 1 {
        if base.geometry == Geometry::Exact {
            if let Some(m) = exact_transition(domain, options, rect, &base)? {
                return Ok(m);
            }
        }
        base = mesh(
            domain,
            &Options {
                mode: Mode::Paper,
                ..options.clone()
            },
        )?;
    }
    let runs = assign_runs(&base.layout, domain, &rect)?;
    let t = ring_layout(&base.layout, rect, &runs, 1);
    let mut grids = build_grids_forced(&t.layout, options.cells, &t.counts)?;
    let nbase = base.layout.blocks.len();
    for (b, nodes) in &t.outer {
        let g = grids
            .get_mut(*b)
            .ok_or_else(|| MeshError::Internal("transition block without a grid".into()))?;
        if g.ni + 1 != nodes.len() {
            return Err(MeshError::Internal(
                "transition block side 0 has the wrong node count".into(),
            ));
        }
        for (i, &n) in nodes.iter().enumerate() {
            g.nodes[i] = t.square.point(n);
        }
    }
    // The forced grids' ring is the straight one: kept where no ring is valid.
    let mut layout = t.layout.clone();
    if let Some((valid, ring)) =
        ring_walls(&t, &grids, nbase).and_then(|w| valid_ring(&t, &base.layout, &runs, domain, &w))
    {
        for ((b, _), g) in valid.outer.iter().zip(ring) {
            grids[*b] = g;
        }
        layout = valid.layout;
    }
    Ok(Mesh {
        layout,
        grids,
        // Every grid is interpolated here.
        geometry: Geometry::Paper,
        ..base
    })
}

/// The block keys exact mode gives the medial blocks of the exact mesh `m` (the blocks
/// before its templates), as [`crate::exact_mode::imposed`] computes them from its vertices:
/// the wall circle (a block around an inserted hole has no `wall`: its circle is the
/// inserted hole whose arc its side 0 is) and the circles around its two medial corners,
/// from the touching points of the blocks there. `None` when a wall is not found.
fn exact_keys(m: &Mesh) -> Option<Vec<BlockKey>> {
    let layout = &m.layout;
    let nmed = layout.blocks.len().checked_sub(m.template_blocks)?;
    let walls: Vec<i64> = layout.blocks[..nmed]
        .iter()
        .map(|b| {
            if let Some(w) = b.wall {
                return Some(w as i64);
            }
            match &layout.edges.get(b.sides[0].edge as usize)?.curve {
                Curve::Arc { center, radius, .. } => m
                    .inserted_holes
                    .iter()
                    .position(|h| h.center == *center && h.radius == *radius)
                    .map(|k| (m.holes + k) as i64),
                _ => None,
            }
        })
        .collect::<Option<_>>()?;
    let mut touching: Vec<Vec<(CircleTag, Point)>> = vec![Vec::new(); layout.vertices.len()];
    for (b, &w) in layout.blocks[..nmed].iter().zip(&walls) {
        for (corner, wall_corner) in [(3, 0), (2, 1)] {
            let p = *layout.vertices.get(b.corners[wall_corner] as usize)?;
            touching
                .get_mut(b.corners[corner] as usize)?
                .push(((w, 0, 0), p));
        }
    }
    let cycle = |v: u32| vertex_cycle(layout.vertices[v as usize], &touching[v as usize]);
    let mut keys: Vec<BlockKey> = layout.blocks[..nmed]
        .iter()
        .zip(&walls)
        .map(|(b, &w)| ((w, 0, 0), cycle(b.corners[3]), cycle(b.corners[2])))
        .collect();
    // One hole's loop pieces, numbered as the exact mesher numbers them.
    crate::exact_mode::imposed::number_loop_pieces(&mut keys);
    Some(keys)
}

/// The most exact meshes made to honour the lattice counts: the counts are imposed on the
/// combinatorics of the previous mesh; a rebuild that changes them (an inverted block given
/// up) gets its own counts imposed in turn.
const EXACT_ATTEMPTS: usize = 3;

/// Exact mode: keep the spoke-aligned grids. The bounding-circle arcs get as many cells as
/// their lattice runs have intervals, and so does every arc in their conformity classes
/// (imposed by block key, [`Options::imposed_counts`], on the medial blocks; the templates
/// of inserted holes follow their classes); then only the ring is interpolated
/// ([`ring_grids`]). `Ok(None)` when the exact mesher did not honour the counts, the mesh
/// is not exact, or the ring is not valid (the caller interpolates everything).
fn exact_transition(
    domain: &Domain,
    options: &Options,
    rect: Rect,
    base: &Mesh,
) -> Result<Option<Mesh>, MeshError> {
    let mut current = base.clone();
    for _ in 0..EXACT_ATTEMPTS {
        let m = &current;
        if m.geometry != Geometry::Exact || m.grids.len() != m.layout.blocks.len() {
            return Ok(None);
        }
        let Ok(runs) = assign_runs(&m.layout, domain, &rect) else {
            return Ok(None);
        };
        let total = rect.perimeter_len();
        // The lattice count of each class holding a chain edge.
        let (class, _) = crate::grid::edge_classes(&m.layout);
        let mut class_cells: HashMap<usize, usize> = HashMap::new();
        for (i, &e) in runs.chain.iter().enumerate() {
            class_cells.insert(class[e], runs.cells(i, total) as usize);
        }
        let nmed = m.layout.blocks.len().saturating_sub(m.template_blocks);
        let honoured = m.layout.blocks[..nmed].iter().zip(&m.grids).all(|(b, g)| {
            class_cells
                .get(&class[b.sides[0].edge as usize])
                .is_none_or(|&n| n == g.ni)
        });
        if honoured {
            let t = ring_layout(&m.layout, rect, &runs, 1);
            let Some((valid, ring)) = ring_walls(&t, &m.grids, m.layout.blocks.len())
                .and_then(|w| valid_ring(&t, &m.layout, &runs, domain, &w))
            else {
                return Ok(None);
            };
            let mut grids = current.grids;
            grids.extend(ring);
            return Ok(Some(Mesh {
                layout: valid.layout,
                grids,
                ..current
            }));
        }
        let Some(keys) = exact_keys(m) else {
            return Ok(None);
        };
        let mut want: BTreeMap<BlockKey, [usize; 2]> = BTreeMap::new();
        for ((key, b), g) in keys.into_iter().zip(&m.layout.blocks).zip(&m.grids) {
            let ni = class_cells
                .get(&class[b.sides[0].edge as usize])
                .copied()
                .unwrap_or(g.ni);
            if want.insert(key, [ni, g.nj]).is_some() {
                return Ok(None);
            }
        }
        let opts = Options {
            imposed_counts: Some(Arc::new(ImposedCounts::new(want))),
            ..options.clone()
        };
        // An error of the rebuild (the imposed counts exceed a limit) leaves the paper
        // pipeline to try.
        match mesh(domain, &opts) {
            Ok(m) => current = m,
            Err(_) => return Ok(None),
        }
    }
    Ok(None)
}
