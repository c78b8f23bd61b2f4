//! Fuzzing support for the whole mesher and the input parsers, shared by the cargo-fuzz
//! targets (`fuzz/fuzz_targets/{mesh,parse_json,parse_csv}.rs`) and the corpus replay tests
//! (`tests/fuzz_replay_*.rs`), so `cargo test` replays the committed corpora on stable.
//!
//! - [`decode_case`] / [`decode_layout`]: bytes to a circle layout from degenerate generators
//!   (lattices, regular polygons of holes around an empty circle, hexagonal packings,
//!   near-touching pairs, co-circular groups, ulp-nudged copies, random layouts), bounded
//!   domains; [`periodic`] has the periodic boxes;
//! - [`check_mesh`]: invariants of a finished mesh (counting identities that survive arc
//!   collapse, conformity by node coordinates, wall nodes on their circles, the signed-area
//!   identity, optionally no inverted cell);
//! - [`check_layout_bytes`], [`check_json_bytes`], [`check_csv_bytes`]: what each fuzz target
//!   runs on one input.
//!
//! Not a stable API.

use crate::domain::{Circle, CircleId, Domain};
use crate::geometry::Point;
use crate::layout::EdgeKind;
use crate::mesh::Mesh;
use crate::mesher::{mesh, MeshError, Options};
use std::collections::HashMap;
use std::f64::consts::PI;

pub mod periodic;
pub use periodic::{check_periodic_bytes, check_periodic_mesh, decode_periodic_case};

/// A little-endian byte reader that yields zeros when the input runs out.
struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }
    fn u16(&mut self) -> u16 {
        u16::from(self.u8()) | (u16::from(self.u8()) << 8)
    }
    /// A fraction in `[0, 1)` from two bytes.
    fn unit(&mut self) -> f64 {
        f64::from(self.u16()) / 65536.0
    }
    fn done(&self) -> bool {
        self.pos >= self.data.len()
    }
}

/// The most holes a decoded layout has (keeps one fuzz iteration in milliseconds).
pub const MAX_FUZZ_HOLES: usize = 48;

/// Power-of-two scales (exact) from tiny to huge.
fn scale_of(b: u8) -> f64 {
    const SCALES: [f64; 8] = [
        1.0,
        0.125,
        1024.0,
        1.0 / 1048576.0,
        1048576.0,
        1.0 / 1099511627776.0,
        1099511627776.0,
        2.0,
    ];
    SCALES[b as usize % SCALES.len()]
}

/// A gap factor: how close neighbours come, from comfortable down to a few tolerances.
fn closeness(b: u8) -> f64 {
    const F: [f64; 8] = [0.5, 0.25, 0.1, 1e-2, 1e-4, 1e-6, 4e-9, 1.5e-9];
    F[b as usize % F.len()]
}

fn nudge(v: f64, ulps: i64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    f64::from_bits((v.to_bits() as i64).wrapping_add(ulps) as u64)
}

/// The bounding circle centred at `c` enclosing every hole with a relative margin `margin`
/// (of the farthest extent).
fn enclose(holes: &[Circle], c: Point, margin: f64) -> Circle {
    let far = holes
        .iter()
        .map(|h| crate::domain::dist(h.center, c) + h.radius)
        .fold(0.0_f64, f64::max);
    let far = if far > 0.0 { far } else { 1.0 };
    Circle {
        center: c,
        radius: far * (1.0 + margin),
    }
}

/// Decode bytes into a bounded layout and mesh options (1 to 4 cells per block side), or
/// `None` when the decoded circles do not form a valid [`Domain`].
///
/// Byte 0 picks the generator, byte 1 the cells, byte 2 the post-processing (bit 0: nudge
/// every coordinate by a few ulps; bit 1: reverse the hole order; bit 2: swap x and y; bit 3:
/// move the layout far from the origin; bit 4, read by [`check_layout_bytes`]: mesh it
/// without keeping the nodes too), byte 3 the scale; the rest are generator parameters.
pub fn decode_case(data: &[u8]) -> Option<(Domain, Options)> {
    let mut b = Bytes { data, pos: 0 };
    let generator = b.u8();
    let cells = 1 + usize::from(b.u8() % 4);
    let post = b.u8();
    let scale = scale_of(b.u8());
    let (mut bounding, mut holes) = generate(generator, &mut b);
    holes.truncate(MAX_FUZZ_HOLES);
    if post & 1 != 0 {
        for h in holes.iter_mut() {
            let u = i64::from(b.u8() as i8 % 4);
            h.center[0] = nudge(h.center[0], u);
            h.center[1] = nudge(h.center[1], i64::from(b.u8() as i8 % 4));
            h.radius = nudge(h.radius, i64::from(b.u8() as i8 % 2));
        }
    }
    if post & 2 != 0 {
        holes.reverse();
    }
    let mut all: Vec<&mut Circle> = std::iter::once(&mut bounding)
        .chain(holes.iter_mut())
        .collect();
    let offset = if post & 8 != 0 {
        [f64::from(b.u16()) * 64.0, -f64::from(b.u16()) * 32.0]
    } else {
        [0.0, 0.0]
    };
    for c in all.iter_mut() {
        if post & 4 != 0 {
            c.center.swap(0, 1);
        }
        c.center = [
            (c.center[0] + offset[0]) * scale,
            (c.center[1] + offset[1]) * scale,
        ];
        c.radius *= scale;
    }
    let domain = Domain::bounded(bounding, holes).ok()?;
    Some((
        domain,
        Options {
            cells,
            ..Options::default()
        },
    ))
}

/// [`decode_case`] without the options.
pub fn decode_layout(data: &[u8]) -> Option<Domain> {
    decode_case(data).map(|(d, _)| d)
}

/// The circles of one generator (bounding circle, holes), before post-processing.
fn generate(generator: u8, b: &mut Bytes) -> (Circle, Vec<Circle>) {
    let origin = [0.0, 0.0];
    match generator % 8 {
        // Square or rectangular lattice, radius a fraction of the smaller spacing.
        0 => {
            let (nx, ny) = (1 + b.u8() % 6, 1 + b.u8() % 6);
            let sy: f64 = [1.0, 1.0, 1.5, 2.0, 0.75][b.u8() as usize % 5];
            let r = 0.5 * (1.0 - closeness(b.u8())) * sy.min(1.0);
            let margin = closeness(b.u8());
            let mut holes = Vec::new();
            for i in 0..nx {
                for j in 0..ny {
                    holes.push(Circle::new(f64::from(i), f64::from(j) * sy, r));
                }
            }
            let c = [f64::from(nx - 1) / 2.0, f64::from(ny - 1) * sy / 2.0];
            (enclose(&holes, c, margin), holes)
        }
        // A regular n-gon of equal holes around an empty circle (all co-circular).
        1 => {
            let n = 2 + b.u8() % 11;
            let d = 1.0;
            let max_r = d * (PI / f64::from(n)).sin();
            let r = max_r * (1.0 - closeness(b.u8()));
            let rot = b.unit() * 2.0 * PI;
            let holes: Vec<Circle> = (0..n)
                .map(|k| {
                    let a = rot + 2.0 * PI * f64::from(k) / f64::from(n);
                    Circle::new(d * a.cos(), d * a.sin(), r)
                })
                .collect();
            let margin = closeness(b.u8());
            (enclose(&holes, origin, margin), holes)
        }
        // Hexagonal packing: `rings` rings around a centre hole.
        2 => {
            let rings = 1 + i32::from(b.u8() % 3);
            let r = 0.5 * (1.0 - closeness(b.u8()));
            let s = 0.75_f64.sqrt();
            let mut holes = Vec::new();
            for q in -rings..=rings {
                for p in -rings..=rings {
                    if (p + q).abs() <= rings {
                        let x = f64::from(p) + 0.5 * f64::from(q);
                        let y = s * f64::from(q);
                        holes.push(Circle::new(x, y, r));
                    }
                }
            }
            let margin = closeness(b.u8());
            (enclose(&holes, origin, margin), holes)
        }
        // Near-touching pairs: `pairs` pairs along a line, each pair a few tolerances apart.
        3 => {
            let pairs = 1 + b.u8() % 4;
            let mut holes = Vec::new();
            for k in 0..pairs {
                let r1 = 0.2 + 0.2 * b.unit();
                let r2 = 0.2 + 0.2 * b.unit();
                let gap = (r1 + r2) * closeness(b.u8()) * (1.0 + 4.0 * b.unit());
                let a = b.unit() * 2.0 * PI;
                let c = [2.0 * f64::from(k), 0.0];
                let c2 = [
                    c[0] + (r1 + r2 + gap) * a.cos(),
                    c[1] + (r1 + r2 + gap) * a.sin(),
                ];
                holes.push(Circle::new(c[0], c[1], r1));
                holes.push(Circle::new(c2[0], c2[1], r2));
            }
            let margin = closeness(b.u8());
            let c = [f64::from(pairs - 1), 0.0];
            (enclose(&holes, c, margin), holes)
        }
        // Co-circular groups: holes of varied radii all tangent to one empty circle.
        4 => {
            let groups = 1 + b.u8() % 3;
            let mut holes = Vec::new();
            for g in 0..groups {
                let n = 3 + b.u8() % 6;
                let d = 1.0;
                let c = [3.0 * f64::from(g), 0.0];
                let rot = b.unit() * 2.0 * PI;
                // Radius r at distance d + r from c: tangent to the circle of radius d.
                // Keep neighbours apart: angular step 2 pi / n, radius below the chord.
                let step = 2.0 * PI / f64::from(n);
                let r_max = (d * (step / 2.0).sin() / (1.0 - (step / 2.0).sin())).min(0.9);
                for k in 0..n {
                    let r = r_max * (0.2 + 0.3 * b.unit());
                    let a = rot + step * f64::from(k);
                    holes.push(Circle::new(
                        c[0] + (d + r) * a.cos(),
                        c[1] + (d + r) * a.sin(),
                        r,
                    ));
                }
            }
            let margin = closeness(b.u8());
            let c = [1.5 * f64::from(groups - 1), 0.0];
            (enclose(&holes, c, margin), holes)
        }
        // Holes nearly touching the bounding circle.
        5 => {
            let n = 2 + b.u8() % 8;
            let big_r = 4.0;
            let gap = closeness(b.u8()) * 1e-3 * big_r;
            let holes: Vec<Circle> = (0..n)
                .map(|k| {
                    let r = 0.3 + 0.5 * b.unit();
                    let a = 2.0 * PI * f64::from(k) / f64::from(n);
                    let d = big_r - r - gap.max(2e-9 * big_r);
                    Circle::new(d * a.cos(), d * a.sin(), r)
                })
                .collect();
            (Circle::new(0.0, 0.0, big_r), holes)
        }
        // Copies of a small pattern shifted by a few ulps relative to each other.
        6 => {
            let n = 2 + b.u8() % 6;
            let mut holes = Vec::new();
            for k in 0..n {
                let x = f64::from(k) * 1.25;
                let y = nudge(0.0 + f64::from(k % 2) * 1.25, i64::from(b.u8() as i8 % 4));
                let x = nudge(x, i64::from(b.u8() as i8 % 4));
                holes.push(Circle::new(x, y, 0.5));
            }
            let margin = closeness(b.u8());
            (
                enclose(&holes, [f64::from(n - 1) * 0.625, 0.625], margin),
                holes,
            )
        }
        // Random layout with rejection of overlapping holes.
        _ => {
            let n = 2 + usize::from(b.u8()) % (MAX_FUZZ_HOLES - 1);
            let big_r = 10.0;
            let mut holes: Vec<Circle> = Vec::new();
            let mut tries = 0;
            while holes.len() < n && tries < 4 * n && !b.done() {
                tries += 1;
                let a = b.unit() * 2.0 * PI;
                let rho = b.unit().sqrt() * big_r;
                let r = 0.05 + 1.5 * b.unit() * b.unit();
                let c = Circle::new(rho * a.cos(), rho * a.sin(), r);
                let inside = big_r - rho - r > 1e-6 * big_r;
                if inside
                    && holes
                        .iter()
                        .all(|h| crate::domain::gap(h, &c) > 1e-6 * big_r)
                {
                    holes.push(c);
                }
            }
            (Circle::new(0.0, 0.0, big_r), holes)
        }
    }
}

/// Which optional checks [`check_mesh_with`] runs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Checks {
    /// Fail on any cell with a corner Jacobian `<= 0`. Paper mode can fold cells on extreme
    /// layouts (the paper's section 6 admits it); turn this on for a mode that guarantees
    /// valid cells.
    pub no_inverted_cells: bool,
}

/// What [`check_mesh_with`] measured on a mesh that passed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CheckReport {
    pub cells: usize,
    /// Cells with a corner Jacobian `<= 0` (reported, a failure only with
    /// [`Checks::no_inverted_cells`]).
    pub inverted_cells: usize,
}

/// [`check_mesh_with`] with the default checks (inverted cells reported, not refused).
pub fn check_mesh(domain: &Domain, m: &Mesh) -> Result<(), String> {
    check_mesh_with(domain, m, Checks::default()).map(|_| ())
}

type Key = (u64, u64);

fn key(p: Point) -> Key {
    ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits())
}

/// Invariants of a mesh of `domain`:
/// - one well-formed grid per block, every node finite, every block side of positive length;
/// - counting identities that survive the collapse of co-circular arcs (`h >= 2`): the medial
///   graph of the refined domain (h counting inserted holes) has `V = 2 (h - 1)`,
///   `E = 3 (h - 1)`, and there are `6 (h - 1) - 2 collapsed + 2 split + template` blocks; the
///   templates have 5 (disk) and 4 (annulus) blocks; exact mode's annulus
///   ([`crate::exact_mode::annulus`]) has no medial vertex or arc and
///   `2 split = 2 ANNULUS_ARCS` blocks;
/// - conformity by node coordinates: sides with the same set of nodes have the same nodes in
///   the same (or reversed) order, and they come in pairs; an unpaired side is a wall side;
///   and by topology: every edge is used by one wall side or two interface sides;
/// - every node of a wall side lies on its circle (relative tolerance `1e-9`);
/// - every circle has a wall, and the sum of the cells' signed areas equals the area between
///   the wall polygons (holds even for folded cells, fails on gaps or overlaps);
/// - the writers' merged numbering ([`crate::numbering::Numbering`]): its node count is
///   `V + sum over used edges (n_e - 1) + sum over blocks (ni - 1)(nj - 1)`, and every block
///   node but the corners has an id below it whose point is that node, bit for bit;
/// - with [`Checks::no_inverted_cells`], no cell with a corner Jacobian `<= 0`.
pub fn check_mesh_with(domain: &Domain, m: &Mesh, checks: Checks) -> Result<CheckReport, String> {
    let h = domain.hole_count();
    let blocks = m.layout.blocks.len();
    if m.grids.len() != blocks {
        return Err(format!("{} grids for {blocks} blocks", m.grids.len()));
    }
    if m.holes != h {
        return Err(format!("mesh says {} holes, the domain has {h}", m.holes));
    }
    for (b, g) in m.grids.iter().enumerate() {
        if g.ni == 0 || g.nj == 0 || g.nodes.len() != (g.ni + 1) * (g.nj + 1) {
            return Err(format!(
                "grid {b} is malformed: ni {}, nj {}, {} nodes",
                g.ni,
                g.nj,
                g.nodes.len()
            ));
        }
        if let Some(p) = g
            .nodes
            .iter()
            .find(|p| !p[0].is_finite() || !p[1].is_finite())
        {
            return Err(format!("grid {b} has a non-finite node {p:?}"));
        }
    }
    check_sides(m)?;
    check_counts(h, m)?;
    let wall_of = check_topology(m)?;
    check_conformity(m, &wall_of)?;
    check_numbering(m)?;
    let circles: Vec<Circle> = std::iter::once(domain.bounding())
        .chain(domain.holes().iter().copied())
        .collect();
    let center = domain.bounding().center;
    let rel = |p: Point| [p[0] - center[0], p[1] - center[1]];
    // Wall nodes on their circles; collected per circle for the area identity.
    let mut wall_nodes: Vec<Vec<Point>> = vec![Vec::new(); circles.len()];
    for (&(b, s), &id) in &wall_of {
        let k = (id + 1) as usize;
        let Some(c) = circles.get(k) else {
            return Err(format!(
                "block {b} side {s} is a wall of unknown circle {id}"
            ));
        };
        let scale = c.radius + c.center[0].abs() + c.center[1].abs();
        for p in m.grids[b].side(s) {
            let d = crate::domain::dist(p, c.center);
            if (d - c.radius).abs() > 1e-9 * scale {
                return Err(format!(
                    "block {b} side {s}: wall node {p:?} is {} off {}",
                    d - c.radius,
                    crate::domain::circle_name(id)
                ));
            }
            wall_nodes[k].push(rel(p));
        }
    }
    // Signed areas.
    let big_r = domain.bounding().radius;
    let (cell_area, abs_area, mut terms, report) = cell_sums(m, rel);
    let mut expected = 0.0;
    for (k, nodes) in wall_nodes.iter_mut().enumerate() {
        if nodes.is_empty() {
            return Err(format!(
                "{} has no wall side",
                crate::domain::circle_name(k as CircleId - 1)
            ));
        }
        let c = rel(circles[k].center);
        nodes.sort_by(|p, q| {
            let ap = (p[1] - c[1]).atan2(p[0] - c[0]);
            let aq = (q[1] - c[1]).atan2(q[0] - c[0]);
            ap.total_cmp(&aq).then(key(*p).cmp(&key(*q)))
        });
        nodes.dedup_by(|p, q| key(*p) == key(*q));
        terms += nodes.len();
        let a = shoelace(nodes);
        expected += if k == 0 { a } else { -a };
    }
    let tol = 1e-9 * abs_area + 64.0 * f64::EPSILON * big_r * big_r * terms as f64;
    let within = (cell_area - expected).abs() <= tol; // false on NaN too
    if !within {
        return Err(format!(
            "cells cover a signed area of {cell_area:e}, the region between the wall polygons \
             is {expected:e} (tolerance {tol:e})"
        ));
    }
    if checks.no_inverted_cells && report.inverted_cells > 0 {
        return Err(format!(
            "{} of {} cells are inverted",
            report.inverted_cells, report.cells
        ));
    }
    Ok(report)
}

/// Over every cell of `m` (corners moved by `rel`): the sum of signed areas, the sum of their
/// absolute values, the number of shoelace terms, and the cell and inverted-cell counts (a
/// corner cross product `<= 0` or NaN).
fn cell_sums(m: &Mesh, rel: impl Fn(Point) -> Point) -> (f64, f64, usize, CheckReport) {
    let (mut area, mut abs_area, mut terms) = (0.0, 0.0, 0usize);
    let mut report = CheckReport::default();
    for g in &m.grids {
        for j in 0..g.nj {
            for i in 0..g.ni {
                let q = [
                    rel(g.node(i, j)),
                    rel(g.node(i + 1, j)),
                    rel(g.node(i + 1, j + 1)),
                    rel(g.node(i, j + 1)),
                ];
                let a = shoelace(&q);
                area += a;
                abs_area += a.abs();
                terms += 4;
                report.cells += 1;
                let inverted = (0..4).any(|k| {
                    let (p, x, y) = (q[k], q[(k + 1) % 4], q[(k + 3) % 4]);
                    let cross = (x[0] - p[0]) * (y[1] - p[1]) - (x[1] - p[1]) * (y[0] - p[0]);
                    cross.is_nan() || cross <= 0.0
                });
                if inverted {
                    report.inverted_cells += 1;
                }
            }
        }
    }
    (area, abs_area, terms, report)
}

fn shoelace(p: &[Point]) -> f64 {
    (0..p.len())
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % p.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        * 0.5
}

fn check_counts(h: usize, m: &Mesh) -> Result<(), String> {
    let blocks = m.layout.blocks.len();
    let (v, e) = (m.medial_vertices, m.medial_arcs);
    match h {
        0 if blocks != 5 => Err(format!("disk: {blocks} blocks, expected 5")),
        // A lone hole with a seeded fluid hole (`mesher::lone_hole_seed`): the medial
        // identities of the refined domain below.
        1 if m.geometry == crate::mesh::Geometry::Exact && m.inserted_holes.is_empty() => {
            // The closed medial loop cut into `split_arcs` pieces, two blocks each.
            let arcs = crate::exact_mode::annulus::ANNULUS_ARCS;
            if m.split_arcs != arcs || blocks != 2 * arcs || v != 0 || e != 0 {
                Err(format!(
                    "exact annulus: {blocks} blocks, {} loop pieces, {v} vertices, {e} arcs; \
                     expected {} blocks, {arcs} pieces, no medial vertex or arc",
                    m.split_arcs,
                    2 * arcs
                ))
            } else {
                Ok(())
            }
        }
        1 if m.inserted_holes.is_empty() && blocks != 4 => {
            Err(format!("annulus: {blocks} blocks, expected 4"))
        }
        0 => Ok(()),
        1 if m.inserted_holes.is_empty() => Ok(()),
        _ => {
            // Counts of the refined domain (inserted holes count as holes) before collapse,
            // then the blocking identity of the degeneracy handling.
            let hr = h + m.inserted_holes.len();
            if v != 2 * (hr - 1) || e != 3 * (hr - 1) {
                return Err(format!(
                    "medial graph: {v} vertices, {e} arcs for {hr} holes (with inserted ones), \
                     expected V = 2(h-1), E = 3(h-1)"
                ));
            }
            let expected = (6 * (hr - 1) + 2 * m.split_arcs + m.template_blocks)
                .checked_sub(2 * m.collapsed_arcs);
            if expected != Some(blocks) {
                return Err(format!(
                    "{blocks} blocks, expected 6(h-1) - 2 collapsed + 2 split + template = \
                     {expected:?} (h = {hr}, collapsed {}, split {}, template {})",
                    m.collapsed_arcs, m.split_arcs, m.template_blocks
                ));
            }
            Ok(())
        }
    }
}

/// The merged numbering of the unstructured writers against the grids (see
/// [`check_mesh_with`]); the layout's references are checked already ([`check_topology`]).
fn check_numbering(m: &Mesh) -> Result<(), String> {
    let n = crate::numbering::Numbering::new(&m.layout, &m.grids);
    let mut first_side = vec![None; m.layout.edges.len()];
    let mut interiors = 0;
    for (block, g) in m.layout.blocks.iter().zip(&m.grids) {
        for (s, side) in block.sides.iter().enumerate() {
            let cells = if s % 2 == 0 { g.ni } else { g.nj };
            first_side[side.edge as usize].get_or_insert(cells - 1);
        }
        interiors += (g.ni - 1) * (g.nj - 1);
    }
    let want = m.layout.vertices.len() + first_side.iter().flatten().sum::<usize>() + interiors;
    if n.len() != want {
        return Err(format!(
            "the merged numbering has {} nodes, not {want}",
            n.len()
        ));
    }
    let mut points = m.layout.vertices.clone();
    let mut ids = Vec::new();
    for (b, g) in m.grids.iter().enumerate() {
        n.block_points(&m.layout, b, g, &mut points);
        n.block_ids(&m.layout, b, g, &mut ids);
        let corners = [0, g.ni, g.nj * (g.ni + 1), g.ni + g.nj * (g.ni + 1)];
        for (k, (&id, p)) in ids.iter().zip(&g.nodes).enumerate() {
            if corners.contains(&k) {
                continue;
            }
            match points.get(id) {
                Some(q) if q.map(f64::to_bits) == p.map(f64::to_bits) => {}
                other => {
                    return Err(format!(
                        "block {b} node {k}: merged id {id} holds {other:?}, not {p:?}"
                    ))
                }
            }
        }
    }
    Ok(())
}

/// Every block side has positive length (its nodes are not all one point): a zero-length
/// medial arc must have been collapsed, and no wall arc may have zero sweep.
fn check_sides(m: &Mesh) -> Result<(), String> {
    for (b, g) in m.grids.iter().enumerate() {
        for s in 0..4 {
            let side = g.side(s);
            if side.iter().all(|p| p == &side[0]) {
                return Err(format!(
                    "block {b} side {s} has zero length (an uncollapsed zero-length arc or a \
                     zero-sweep wall arc)"
                ));
            }
        }
    }
    Ok(())
}

/// Every edge used by one wall side or two interface sides; returns the wall sides
/// `(block, side) -> circle`.
fn check_topology(m: &Mesh) -> Result<HashMap<(usize, usize), CircleId>, String> {
    let l = &m.layout;
    let mut users: Vec<Vec<(usize, usize)>> = vec![Vec::new(); l.edges.len()];
    for (b, block) in l.blocks.iter().enumerate() {
        for (s, side) in block.sides.iter().enumerate() {
            let u = users
                .get_mut(side.edge as usize)
                .ok_or_else(|| format!("block {b} side {s}: no edge {}", side.edge))?;
            u.push((b, s));
        }
    }
    let mut walls = HashMap::new();
    for (k, u) in users.iter().enumerate() {
        let edge = &l.edges[k];
        match (edge.kind, u.len()) {
            (_, 0) => {}
            (EdgeKind::Wall(id), 1) => {
                walls.insert(u[0], id);
            }
            (EdgeKind::Wall(_), n) => return Err(format!("wall edge {k} used by {n} sides")),
            (_, 2) => {
                let [(a, sa), (b, sb)] = [u[0], u[1]];
                let mut na = m.grids[a].side(sa);
                let nb = m.grids[b].side(sb);
                na.reverse();
                let (ka, kb): (Vec<Key>, Vec<Key>) = (
                    na.iter().map(|&p| key(p)).collect(),
                    nb.iter().map(|&p| key(p)).collect(),
                );
                if ka != kb {
                    return Err(format!(
                        "edge {k}: block {a} side {sa} and block {b} side {sb} do not match \
                         node for node"
                    ));
                }
            }
            (kind, n) => return Err(format!("{kind:?} edge {k} used by {n} sides")),
        }
    }
    Ok(walls)
}

/// Conformity from coordinates alone: sides keyed by their sorted node coordinates.
fn check_conformity(m: &Mesh, walls: &HashMap<(usize, usize), CircleId>) -> Result<(), String> {
    let mut groups: HashMap<Vec<Key>, Vec<(usize, usize)>> = HashMap::new();
    for (b, g) in m.grids.iter().enumerate() {
        for s in 0..4 {
            let mut k: Vec<Key> = g.side(s).into_iter().map(key).collect();
            k.sort_unstable();
            groups.entry(k).or_default().push((b, s));
        }
    }
    for users in groups.values() {
        if users.len() == 1 {
            if !walls.contains_key(&users[0]) {
                let (b, s) = users[0];
                return Err(format!(
                    "block {b} side {s} shares its nodes with no other side and is not a wall"
                ));
            }
            continue;
        }
        let interface = users.iter().filter(|u| !walls.contains_key(u)).count();
        if interface % 2 != 0 {
            let (b, s) = users[0];
            return Err(format!(
                "{} sides (block {b} side {s} among them) have the same nodes",
                users.len()
            ));
        }
        let (b0, s0) = users[0];
        let first: Vec<Key> = m.grids[b0].side(s0).into_iter().map(key).collect();
        for &(b, s) in &users[1..] {
            let mut k: Vec<Key> = m.grids[b].side(s).into_iter().map(key).collect();
            if k != first {
                k.reverse();
            }
            if k != first {
                return Err(format!(
                    "blocks {b0}/{b} have sides with the same nodes in a different order"
                ));
            }
        }
    }
    Ok(())
}

/// Gaps (to a neighbour hole or the bounding circle) below this fraction of the bounding radius
/// may be refused by boundary sampling. Adaptive sampling (bisection near close circles, with
/// a precision floor on the spacing) meshes holes down to the validation tolerance
/// (`tests/fuzz_replay_mesh.rs::near_touching_bounding_circle_is_meshed`: `1e-8 R` and
/// `2e-9 R` from the bounding circle), so this equals [`Domain::GAP_TOLERANCE`]: a sampling
/// refusal of any valid domain counts as a bug.
pub const SAMPLING_REFUSAL_GAP: f64 = Domain::GAP_TOLERANCE;

/// Whether a mesher error on a valid domain is an accepted refusal (a resource limit), not a
/// bug: too many cells or nodes, or sampling that reached its cap on a layout with a gap below
/// [`SAMPLING_REFUSAL_GAP`] times the bounding radius.
pub fn accepted_refusal(domain: &Domain, e: &MeshError) -> bool {
    within_limits(e, || {
        let gaps = crate::sampling::nearest_gaps(domain);
        (gaps, domain.bounding().radius)
    })
}

/// [`accepted_refusal`] for any domain: `gaps_and_scale` gives the nearest gaps and the length
/// [`SAMPLING_REFUSAL_GAP`] is relative to (asked only for a sampling error).
fn within_limits(e: &MeshError, gaps_and_scale: impl FnOnce() -> (Vec<f64>, f64)) -> bool {
    use crate::grid::GridError;
    match e {
        MeshError::Grid(GridError::TooManyNodes { .. } | GridError::TooManyCellsPerSide { .. })
        | MeshError::Tiling(_) => true,
        MeshError::Sampling { .. } => {
            let (gaps, scale) = gaps_and_scale();
            let min_gap = gaps.into_iter().fold(f64::INFINITY, f64::min);
            min_gap < SAMPLING_REFUSAL_GAP * scale
        }
        _ => false,
    }
}

/// The `mesh` fuzz target: decode a layout, mesh it, check the mesh. `Ok(None)` when the
/// bytes decode to no valid domain or the mesher refused within its resource limits.
pub fn check_layout_bytes(data: &[u8]) -> Result<Option<CheckReport>, String> {
    let Some((domain, options)) = decode_case(data) else {
        return Ok(None);
    };
    match mesh(&domain, &options) {
        Ok(m) => {
            // Byte 2's bit 4: also without keeping the nodes (the grids measured as they are
            // made, `Options::keep_nodes`), which must give the same layout and report.
            if data.get(2).is_some_and(|p| p & 16 != 0) {
                same_without_nodes(&m, |o| mesh(&domain, o), &options)
                    .map_err(|e| format!("{e}\nlayout: {}", domain.to_json_string()))?;
            }
            check_mesh_with(&domain, &m, Checks::default())
                .map(Some)
                .map_err(|e| format!("{e}\nlayout: {}", domain.to_json_string()))
        }
        Err(e) if accepted_refusal(&domain, &e) => Ok(None),
        Err(e) => Err(format!(
            "mesher failed on a valid domain: {e}\nlayout: {}",
            domain.to_json_string()
        )),
    }
}

/// The layout meshed by `remesh` with `options` but without keeping the nodes has the
/// layout, block dimensions and report of `kept` (meshed with them).
pub(crate) fn same_without_nodes(
    kept: &Mesh,
    remesh: impl FnOnce(&Options) -> Result<Mesh, MeshError>,
    options: &Options,
) -> Result<(), String> {
    use crate::output::report::Report;
    let o = Options {
        keep_nodes: false,
        ..options.clone()
    };
    let m = remesh(&o).map_err(|e| format!("meshed with its nodes, not without: {e}"))?;
    let dims = |m: &Mesh| m.grids.iter().map(|g| (g.ni, g.nj)).collect::<Vec<_>>();
    if m.layout != kept.layout || dims(&m) != dims(kept) {
        return Err("without its nodes: another layout or other block dimensions".into());
    }
    let json = |m: &Mesh| serde_json::to_string(&Report::from_mesh(m)).unwrap_or_default();
    let (a, b) = (json(&m), json(kept));
    if a != b {
        return Err(format!(
            "without its nodes another report:\n{a}\nagainst\n{b}"
        ));
    }
    Ok(())
}

/// The `parse_json` fuzz target: [`Domain::from_json_str`] on the bytes (as UTF-8, lossily)
/// must not panic; on success the domain re-serialises and re-parses to the same domain, bit
/// for bit.
pub fn check_json_bytes(data: &[u8]) -> Result<(), String> {
    let text = String::from_utf8_lossy(data);
    let limit = 1 + usize::from(data.first().copied().unwrap_or(0) % 64);
    for result in [
        Domain::from_json_str(&text),
        Domain::from_json_str_with_limit(&text, limit),
    ] {
        let Ok(d) = result else { continue };
        let json = d.to_json_string();
        let again =
            Domain::from_json_str(&json).map_err(|e| format!("re-parse of {json} failed: {e}"))?;
        if circle_bits(&d) != circle_bits(&again) {
            return Err(format!("re-parse of {json} differs: {again:?} vs {d:?}"));
        }
    }
    Ok(())
}

/// Random bytes through a fuzz check on the stable toolchain (the `*_exploration` tests):
/// for `MESH_FUZZ_SECONDS` seconds (default 10) from seed `MESH_FUZZ_SEED` (default 1), inputs
/// of 4 to 203 bytes whose first byte cycles through `generators`. Returns the inputs run, how
/// many meshed, and each failure as `hex: message`.
pub fn explore_random_bytes(
    generators: u8,
    check: impl Fn(&[u8]) -> Result<Option<CheckReport>, String>,
) -> (u64, u64, Vec<String>) {
    let env = |name: &str, default: u64| -> u64 {
        std::env::var(name)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let seconds = env("MESH_FUZZ_SECONDS", 10);
    let mut rng = crate::layouts::SplitMix64(env("MESH_FUZZ_SEED", 1));
    let start = std::time::Instant::now();
    let (mut runs, mut meshed, mut failures) = (0u64, 0u64, Vec::new());
    while start.elapsed().as_secs() < seconds {
        let len = 4 + (rng.next_u64() % 200) as usize;
        let mut data: Vec<u8> = (0..len).map(|_| rng.next_u64() as u8).collect();
        data[0] = (runs % u64::from(generators.max(1))) as u8;
        runs += 1;
        match check(&data) {
            Ok(Some(_)) => meshed += 1,
            Ok(None) => {}
            Err(e) => {
                let hex: String = data.iter().map(|b| format!("{b:02x}")).collect();
                failures.push(format!("{hex}: {e}"));
            }
        }
    }
    (runs, meshed, failures)
}

fn circle_bits(d: &Domain) -> Vec<[u64; 3]> {
    std::iter::once(d.bounding())
        .chain(d.holes().iter().copied())
        .map(|c| {
            [
                c.center[0].to_bits(),
                c.center[1].to_bits(),
                c.radius.to_bits(),
            ]
        })
        .collect()
}

/// A parsed CSV number written back so that it parses to the same bits: `{:?}` for every
/// number but a NaN with its sign bit set, which `{:?}` writes as `NaN` (the parser reads
/// `-NaN` as that NaN: found by the `parse_csv` fuzz target,
/// `fuzz/corpus/parse_csv/regress_negative_nan`).
fn csv_number(x: f64) -> String {
    if x.is_nan() && x.is_sign_negative() {
        "-NaN".to_string()
    } else {
        format!("{x:?}")
    }
}

/// The `parse_csv` fuzz target: the CSV parsers of [`crate::input`] on the bytes must not
/// panic; on success the rows, written back as CSV, parse to the same numbers bit for bit,
/// with increasing line numbers; the holes then go through [`Domain::bounded`] (must not
/// panic).
pub fn check_csv_bytes(data: &[u8]) -> Result<(), String> {
    use crate::input::{parse_holes_csv_with_limit, parse_points_csv_with_limit, parse_triple};
    let text = String::from_utf8_lossy(data);
    let _ = parse_triple(&text);
    if let Ok(holes) = parse_holes_csv_with_limit(&text, 10_000) {
        let mut csv = String::from("x,y,r\n");
        for c in &holes {
            csv.push_str(&format!(
                "{},{},{}\n",
                csv_number(c.center[0]),
                csv_number(c.center[1]),
                csv_number(c.radius)
            ));
        }
        let again = parse_holes_csv_with_limit(&csv, 10_000)
            .map_err(|e| format!("re-parse of holes failed: {e}\n{csv}"))?;
        let bits = |v: &[Circle]| -> Vec<[u64; 3]> {
            v.iter()
                .map(|c| {
                    [
                        c.center[0].to_bits(),
                        c.center[1].to_bits(),
                        c.radius.to_bits(),
                    ]
                })
                .collect()
        };
        if bits(&holes) != bits(&again) {
            return Err(format!("holes re-parse differently:\n{csv}"));
        }
        let _ = Domain::bounded(Circle::new(0.0, 0.0, 1e6), holes);
    }
    if let Ok((points, lines)) = parse_points_csv_with_limit(&text, 10_000) {
        if points.len() != lines.len() || lines.windows(2).any(|w| w[0] >= w[1]) {
            return Err(format!(
                "line numbers {lines:?} for {} points",
                points.len()
            ));
        }
        let mut csv = String::new();
        for p in &points {
            csv.push_str(&format!("{},{}\n", csv_number(p[0]), csv_number(p[1])));
        }
        let (again, _) = parse_points_csv_with_limit(&csv, 10_000)
            .map_err(|e| format!("re-parse of points failed: {e}\n{csv}"))?;
        let bits = |v: &[Point]| -> Vec<[u64; 2]> {
            v.iter().map(|p| [p[0].to_bits(), p[1].to_bits()]).collect()
        };
        if bits(&points) != bits(&again) {
            return Err(format!("points re-parse differently:\n{csv}"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_generator_gives_some_valid_layout() {
        for g in 0..8u8 {
            let mut found = false;
            for seed in 0..64u8 {
                let data = [
                    g,
                    1,
                    0,
                    0,
                    seed,
                    seed.wrapping_mul(7),
                    3,
                    seed,
                    9,
                    seed,
                    200,
                    17,
                    seed,
                    5,
                    99,
                    seed,
                ];
                if let Some(d) = decode_layout(&data) {
                    found = true;
                    assert!(d.hole_count() <= MAX_FUZZ_HOLES);
                }
            }
            assert!(found, "generator {g} never gives a valid layout");
        }
    }

    #[test]
    fn hexagon_passes_and_inverted_flag_works() {
        let d = Domain::hexagon_example();
        let m = mesh(&d, &Options::default()).unwrap();
        let r = check_mesh_with(
            &d,
            &m,
            Checks {
                no_inverted_cells: true,
            },
        )
        .unwrap();
        assert_eq!(r.inverted_cells, 0);
        // A moved node of a shared side breaks conformity.
        let mut bad = m.clone();
        let g = &mut bad.grids[0];
        let k = g.ni + 1; // node (0, 1), on side 3
        g.nodes[k][0] += 1e-3;
        assert!(check_mesh(&d, &bad).is_err());
        let mut bad = m.clone();
        bad.grids[0].nodes[1][0] += 1e-3; // a wall node off its circle
        assert!(check_mesh(&d, &bad).is_err());
        let mut bad = m;
        bad.grids.pop();
        assert!(check_mesh(&d, &bad).is_err());
    }
}
