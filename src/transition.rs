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
//!   to the nearest lattice node `P` along the perimeter (kept strictly increasing around
//!   the perimeter, so every block gets at least one lattice interval). The block has corners
//!   `[P_a, P_b, Q_b, Q_a]`: side 0 the run of lattice intervals from `P_a` to `P_b` (the
//!   new outer boundary, a polyline that may turn a corner of the square), side 1 and 3 the
//!   radial segments `Q -> P` (shared with the neighbouring transition blocks), side 2 the
//!   former wall edge, now an interface with the medial block behind it.
//! - Cell counts: the former wall edge gets as many cells as its lattice run has intervals
//!   (its conformity class follows: every class holds at most one bounding-circle edge, so
//!   this is always possible); the radial segments get `round(mean radial length / s)`.
//! - The outer nodes are then set to the lattice points exactly (`i as f64 * s`), the same
//!   formula as the background grid's.

use crate::domain::{Domain, BOUNDING};
use crate::exact_mode::imposed::{BlockKey, ImposedCounts};
use crate::geometry::Point;
use crate::grid::tfi;
use crate::grid::{build_grids_forced, MAX_CELLS_PER_SIDE};
use crate::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use crate::mesh::{Geometry, Mesh};
use crate::mesher::{mesh, MeshError, Mode, Options};
use crate::sequence::layout_keys;
use std::collections::BTreeMap;
use std::collections::HashMap;
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
            "--transition: the background spacing must be finite and positive, got {spacing}"
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
                 YMAX, got {bounds:?}"
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
                "--transition-rect: the rectangle [{lo_x}, {hi_x}] x [{lo_y}, {hi_y}] must \
                 enclose the bounding circle (centre {center:?}, radius {r}) with at least one \
                 background interval ({spacing}) to spare on every side"
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
                "--transition: a spacing of {spacing} needs too many background intervals \
                 around a bounding circle of radius {r}"
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

    /// Continuous perimeter coordinate (in intervals, from the lower-left corner) of the ray
    /// from `c` (inside) at angle `theta`.
    fn perimeter(&self, c: Point, theta: f64) -> f64 {
        let s = self.spacing;
        let (nx, ny) = (self.nx as f64, self.ny as f64);
        let (x0, y0) = (self.i0 as f64 * s, self.j0 as f64 * s);
        let (x1, y1) = (x0 + nx * s, y0 + ny * s);
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
    /// `(edge, cells)` to impose.
    pub counts: Vec<(usize, usize)>,
    /// Per transition block: its id and the lattice nodes of its side 0, in order.
    pub outer: Vec<(usize, Vec<(i64, i64)>)>,
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
    let spacing = sq.spacing;
    let b = domain.bounding();
    let mut out = layout.clone();
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
    // Snap the chain's vertices to perimeter nodes, strictly increasing.
    let total = sq.perimeter_len();
    let mut ps: Vec<i64> = Vec::with_capacity(chain.len());
    let mut prev_t = f64::NEG_INFINITY;
    for &e in &chain {
        let v = layout.edges[e].ends[0];
        let mut t = sq.perimeter(b.center, angle(v));
        while t < prev_t {
            t += total as f64;
        }
        prev_t = t;
        let mut p = t.round() as i64;
        if let Some(&q) = ps.last() {
            p = p.max(q + 1);
        }
        ps.push(p);
    }
    if ps[ps.len() - 1] + 1 > ps[0] + total {
        return Err(MeshError::Options(format!(
            "--transition: the background spacing {spacing} is too coarse for the {} bounding \
             wall edges (each needs at least one interval)",
            chain.len()
        )));
    }
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
    let radial_cells =
        ((radial_len / chain.len() as f64 / spacing).round() as usize).clamp(1, MAX_CELLS_PER_SIDE);
    let mut counts = vec![(radial[0] as usize, radial_cells)];
    let mut outer = Vec::with_capacity(chain.len());
    let k = chain.len();
    for i in 0..k {
        let e = chain[i];
        let (pa, pb) = (ps[i], if i + 1 < k { ps[i + 1] } else { ps[0] + total });
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
    Ok(Transition {
        layout: out,
        square: sq,
        counts,
        outer,
    })
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
/// Exact mode keeps its spoke-aligned grids when the lattice counts can be imposed on them
/// (`exact_transition`); otherwise every grid is interpolated and the mesh says
/// [`Geometry::Paper`].
pub fn mesh_with_transition_rect(
    domain: &Domain,
    options: &Options,
    rect: Rect,
) -> Result<Mesh, MeshError> {
    let base = mesh(domain, options)?;
    if options.mode == Mode::Exact && domain.hole_count() >= 2 {
        if let Some(m) = exact_transition(domain, options, rect, &base)? {
            return Ok(m);
        }
    }
    let t = add_transition_rect(&base.layout, domain, rect)?;
    let mut grids = build_grids_forced(&t.layout, options.cells, &t.counts)?;
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
    Ok(Mesh {
        layout: t.layout,
        grids,
        // Every grid is interpolated here, exact mode's spoke-aligned ones too.
        geometry: Geometry::Paper,
        ..base
    })
}

/// Exact mode: keep the spoke-aligned grids. The bounding-circle arcs get as many cells as
/// their lattice runs have intervals (imposed by block key, [`Options::imposed_counts`]; the
/// snapping only depends on the layout's vertices, which counts do not move), then only the
/// transition blocks are interpolated: side 2 is the medial block's wall nodes, side 0 the
/// lattice nodes, sides 1 and 3 equally spaced radial segments shared by neighbours.
/// `Ok(None)` when the counts could not be imposed (the caller interpolates everything).
fn exact_transition(
    domain: &Domain,
    options: &Options,
    rect: Rect,
    base: &Mesh,
) -> Result<Option<Mesh>, MeshError> {
    let t = add_transition_rect(&base.layout, domain, rect)?;
    let keys = layout_keys(&base.layout);
    let mut want: BTreeMap<BlockKey, [usize; 2]> = keys
        .iter()
        .cloned()
        .zip(base.grids.iter().map(|g| [g.ni, g.nj]))
        .collect();
    if want.len() != keys.len() || base.grids.len() != base.layout.blocks.len() {
        return Ok(None);
    }
    let wall_cells: HashMap<usize, usize> = t.counts.iter().skip(1).copied().collect();
    let blocks = &base.layout.blocks;
    for b in blocks {
        if let Some(&n) = wall_cells.get(&(b.sides[0].edge as usize)) {
            for (b2, other) in blocks.iter().enumerate() {
                if other.sides[2].edge == b.sides[2].edge {
                    if let Some(w) = want.get_mut(&keys[b2]) {
                        w[0] = n;
                    }
                }
            }
        }
    }
    let opts = Options {
        imposed_counts: Some(Arc::new(ImposedCounts(want.clone()))),
        ..options.clone()
    };
    let m = mesh(domain, &opts)?;
    let got: BTreeMap<BlockKey, [usize; 2]> = layout_keys(&m.layout)
        .into_iter()
        .zip(m.grids.iter().map(|g| [g.ni, g.nj]))
        .collect();
    if got != want {
        return Ok(None);
    }
    let t = add_transition_rect(&m.layout, domain, rect)?;
    let nbase = m.layout.blocks.len();
    let mut radial_nodes: HashMap<u32, Vec<Point>> = HashMap::new();
    let radial_cells = t.counts.first().map_or(1, |c| c.1);
    let mut grids = m.grids.clone();
    for (b, nodes) in &t.outer {
        let block = &t.layout.blocks[*b];
        let wall_edge = block.sides[2].edge;
        let Some(inner) = (0..nbase).find(|&k| m.layout.blocks[k].sides[0].edge == wall_edge)
        else {
            return Ok(None);
        };
        let mut s2 = m.grids[inner].side(0);
        s2.reverse();
        if s2.len() != nodes.len() {
            return Ok(None);
        }
        let s0: Vec<Point> = nodes.iter().map(|&n| t.square.point(n)).collect();
        let mut radial = |side: SideRef| -> Vec<Point> {
            let e = side.edge;
            let mut pts = radial_nodes
                .entry(e)
                .or_insert_with(|| {
                    let [a, c] = t.layout.edges[e as usize]
                        .ends
                        .map(|v| t.layout.vertices[v as usize]);
                    let mut v: Vec<Point> = (0..=radial_cells)
                        .map(|i| {
                            let s = i as f64 / radial_cells as f64;
                            [a[0] + s * (c[0] - a[0]), a[1] + s * (c[1] - a[1])]
                        })
                        .collect();
                    v[0] = a;
                    v[radial_cells] = c;
                    v
                })
                .clone();
            if side.reversed {
                pts.reverse();
            }
            pts
        };
        let (s1, s3) = (radial(block.sides[1]), radial(block.sides[3]));
        let g = tfi(&s0, &s1, &s2, &s3)
            .ok_or_else(|| MeshError::Internal("transition block side counts differ".into()))?;
        grids.push(g);
    }
    if grids.len() != t.layout.blocks.len() {
        return Ok(None);
    }
    Ok(Some(Mesh {
        layout: t.layout,
        grids,
        ..m
    }))
}
