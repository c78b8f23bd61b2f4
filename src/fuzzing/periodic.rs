//! Periodic boxes for the fuzz targets: [`decode_periodic_case`] draws a periodic layout from
//! degenerate generators (square and rectangular lattices, which are co-circular everywhere,
//! hexagonal packings, holes centred on the box's edges and corners, near-touching images
//! across the boundary, a single hole, random layouts, ulp-nudged copies) and
//! [`check_periodic_mesh`] checks a finished mesh of one period from its coordinates and
//! connectivity alone.

use super::{closeness, nudge, scale_of, Bytes, CheckReport, Checks};
use crate::connectivity::{connectivity, SideKind};
use crate::domain::{Circle, CircleId};
use crate::geometry::Point;
use crate::mesh::Mesh;
use crate::mesher::{Mode, Options};
use crate::periodic::{mesh_periodic, PeriodicDomain};

/// The most holes a decoded periodic layout has (one period is meshed on a tiling of 3 x 3
/// copies or more, so this is smaller than [`super::MAX_FUZZ_HOLES`]).
pub const MAX_PERIODIC_FUZZ_HOLES: usize = 24;

/// Decode bytes into a periodic layout and mesh options (1 to 4 cells, exact or paper mode),
/// or `None` when the decoded circles do not form a valid [`PeriodicDomain`].
///
/// Byte 0 picks the generator, byte 1 the cells and the mode (bit 7), byte 2 the
/// post-processing (bit 0: nudge coordinates by a few ulps; bit 1: reverse the hole order;
/// bit 2: swap x and y; bit 3: shift every centre by whole periods and a fraction, so the
/// domain must wrap them; bit 4, read by [`check_periodic_bytes`]: mesh it without keeping
/// the nodes too), byte 3 the scale; the rest are generator parameters.
pub fn decode_periodic_case(data: &[u8]) -> Option<(PeriodicDomain, Options)> {
    let mut b = Bytes { data, pos: 0 };
    let generator = b.u8();
    let mode_cells = b.u8();
    let cells = 1 + usize::from(mode_cells % 4);
    let mode = if mode_cells & 0x80 != 0 {
        Mode::Paper
    } else {
        Mode::Exact
    };
    let post = b.u8();
    let scale = scale_of(b.u8());
    let (mut size, mut holes) = generate(generator, &mut b);
    holes.truncate(MAX_PERIODIC_FUZZ_HOLES);
    if post & 1 != 0 {
        for h in holes.iter_mut() {
            h.center[0] = nudge(h.center[0], i64::from(b.u8() as i8 % 4));
            h.center[1] = nudge(h.center[1], i64::from(b.u8() as i8 % 4));
            h.radius = nudge(h.radius, i64::from(b.u8() as i8 % 2));
        }
    }
    if post & 2 != 0 {
        holes.reverse();
    }
    if post & 4 != 0 {
        size.swap(0, 1);
        for h in holes.iter_mut() {
            h.center.swap(0, 1);
        }
    }
    if post & 8 != 0 {
        let shift = [
            f64::from(b.u8() % 5) - 2.0 + b.unit(),
            f64::from(b.u8() % 5) - 2.0 + b.unit(),
        ];
        for h in holes.iter_mut() {
            for d in 0..2 {
                h.center[d] += shift[d] * size[d];
            }
        }
    }
    for h in holes.iter_mut() {
        h.center = [h.center[0] * scale, h.center[1] * scale];
        h.radius *= scale;
    }
    let size = [size[0] * scale, size[1] * scale];
    let domain = PeriodicDomain::new(size, holes).ok()?;
    Some((
        domain,
        Options {
            cells,
            mode,
            ..Options::default()
        },
    ))
}

/// The period and holes of one generator, before post-processing.
fn generate(generator: u8, b: &mut Bytes) -> ([f64; 2], Vec<Circle>) {
    match generator % 6 {
        // Square or rectangular lattice (every four neighbours share an empty circle),
        // optionally offset so that holes sit on the box's edges or corners.
        0 => {
            let (nx, ny) = (1 + b.u8() % 4, 1 + b.u8() % 4);
            let sy: f64 = [1.0, 1.0, 1.5, 2.0, 0.75][b.u8() as usize % 5];
            let r = 0.5 * (1.0 - closeness(b.u8())) * sy.min(1.0);
            let offset: [f64; 2] = match b.u8() % 4 {
                0 => [0.5, 0.5],
                1 => [0.0, 0.0],
                2 => [0.0, 0.5],
                _ => [b.unit(), b.unit()],
            };
            let mut holes = Vec::new();
            for i in 0..nx {
                for j in 0..ny {
                    holes.push(Circle::new(
                        f64::from(i) + offset[0],
                        (f64::from(j) + offset[1]) * sy,
                        r,
                    ));
                }
            }
            ([f64::from(nx), f64::from(ny) * sy], holes)
        }
        // Hexagonal packing: two holes per rectangular cell of 1 x sqrt(3).
        1 => {
            let (nx, ny) = (1 + b.u8() % 3, 1 + b.u8() % 3);
            let s = 3.0_f64.sqrt();
            let r = 0.5 * (1.0 - closeness(b.u8()));
            let (ox, oy) = (b.unit(), b.unit());
            let mut holes = Vec::new();
            for i in 0..nx {
                for j in 0..ny {
                    let (x, y) = (f64::from(i) + ox, f64::from(j) * s + oy);
                    holes.push(Circle::new(x, y, r));
                    holes.push(Circle::new(x + 0.5, y + 0.5 * s, r));
                }
            }
            ([f64::from(nx), f64::from(ny) * s], holes)
        }
        // A near-touching pair across the box's edge (the images nearly touch).
        2 => {
            let l = [1.0 + 2.0 * b.unit(), 1.0 + 2.0 * b.unit()];
            let r1 = 0.1 + 0.15 * b.unit();
            let r2 = 0.1 + 0.15 * b.unit();
            let gap = (r1 + r2) * closeness(b.u8());
            let y = b.unit() * l[1];
            let mut holes = vec![
                Circle::new(r1, y, r1),
                Circle::new(l[0] - r2 - gap, y + (b.unit() - 0.5) * 1e-3, r2),
            ];
            if b.u8() % 2 == 1 {
                holes.push(Circle::new(0.5 * l[0], 0.5 * l[1], 0.1 + 0.1 * b.unit()));
            }
            (l, holes)
        }
        // One hole, anywhere (centre possibly on a corner), in a box of any aspect.
        3 => {
            let l: [f64; 2] = [1.0, [1.0, 1.5, 3.0, 0.4][b.u8() as usize % 4]];
            let r = 0.5 * l[0].min(l[1]) * (1.0 - closeness(b.u8()));
            let c: [f64; 2] = match b.u8() % 3 {
                0 => [0.0, 0.0],
                1 => [0.5 * l[0], 0.0],
                _ => [b.unit() * l[0], b.unit() * l[1]],
            };
            (l, vec![Circle::new(c[0], c[1], r)])
        }
        // Copies of one hole shifted by a few ulps from a lattice (nearly co-circular).
        4 => {
            let n = 2 + b.u8() % 3;
            let mut holes = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    let x = nudge(f64::from(i) + 0.5, i64::from(b.u8() as i8 % 4));
                    let y = nudge(f64::from(j) + 0.5, i64::from(b.u8() as i8 % 4));
                    holes.push(Circle::new(x, y, 0.3));
                }
            }
            ([f64::from(n), f64::from(n)], holes)
        }
        // Random holes with rejection of overlapping images.
        _ => {
            let n = 1 + usize::from(b.u8()) % MAX_PERIODIC_FUZZ_HOLES;
            let l = [4.0, 4.0 * (0.5 + b.unit())];
            let mut holes: Vec<Circle> = Vec::new();
            let mut tries = 0;
            while holes.len() < n && tries < 4 * n && !b.done() {
                tries += 1;
                let c = Circle::new(
                    b.unit() * l[0],
                    b.unit() * l[1],
                    0.05 + 0.5 * b.unit() * b.unit(),
                );
                let apart = holes.iter().all(|h| {
                    let d = image_offset(c.center, h.center, l);
                    d[0].hypot(d[1]) - c.radius - h.radius > 1e-6 * l[0]
                });
                if apart && 2.0 * c.radius < 0.9 * l[0].min(l[1]) {
                    holes.push(c);
                }
            }
            (l, holes)
        }
    }
}

/// `p - c` moved by whole periods to the image nearest `c`.
fn image_offset(p: Point, c: Point, size: [f64; 2]) -> [f64; 2] {
    let mut d = [p[0] - c[0], p[1] - c[1]];
    for k in 0..2 {
        d[k] -= (d[k] / size[k]).round() * size[k];
    }
    d
}

/// Invariants of a mesh of one period of `pd`, from coordinates and connectivity alone:
/// - one well-formed grid per block, every node finite, every block side of positive length
///   (a zero-length medial arc must have been collapsed);
/// - block counts on the torus (`V - E + F = 0`, one face per hole): with `h` holes
///   (inserted ones included) `V = 2h`, `E = 3h` and `6h - 2 collapsed + 2 split + template`
///   blocks;
/// - every side is a wall, an interface whose partner has the same nodes, or a periodic side
///   whose partner has its nodes plus the translation (a whole period shift) within
///   `1e-12 max(Lx, Ly)`, and the partner names it back;
/// - every wall node lies on an image of its hole (relative tolerance `1e-9`);
/// - the cells' signed areas add up to `Lx Ly` minus the areas of the wall polygons;
/// - with [`Checks::no_inverted_cells`], no cell with a corner Jacobian `<= 0`.
pub fn check_periodic_mesh(
    pd: &PeriodicDomain,
    m: &Mesh,
    checks: Checks,
) -> Result<CheckReport, String> {
    let size = pd.size();
    let big = size[0].max(size[1]);
    let blocks = m.layout.blocks.len();
    if m.grids.len() != blocks {
        return Err(format!("{} grids for {blocks} blocks", m.grids.len()));
    }
    for (b, g) in m.grids.iter().enumerate() {
        if g.ni == 0 || g.nj == 0 || g.nodes.len() != (g.ni + 1) * (g.nj + 1) {
            return Err(format!("grid {b} is malformed: ni {}, nj {}", g.ni, g.nj));
        }
        if let Some(p) = g
            .nodes
            .iter()
            .find(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(format!("grid {b} has a non-finite node {p:?}"));
        }
    }
    super::check_sides(m)?;
    let h = pd.hole_count() + m.inserted_holes.len();
    let (v, e) = (m.medial_vertices, m.medial_arcs);
    if v != 2 * h || e != 3 * h {
        return Err(format!(
            "medial graph on the torus: {v} vertices, {e} arcs for {h} holes, expected 2h, 3h"
        ));
    }
    let expected = (6 * h + 2 * m.split_arcs + m.template_blocks).checked_sub(2 * m.collapsed_arcs);
    if expected != Some(blocks) {
        return Err(format!(
            "{blocks} blocks, expected 6h - 2 collapsed + 2 split + template = {expected:?}"
        ));
    }
    let conn = connectivity(&m.layout, &m.grids).map_err(|e| e.to_string())?;
    let tol = 1e-12 * big;
    let mut wall_nodes: Vec<Vec<Point>> = vec![Vec::new(); pd.hole_count()];
    for bc in &conn {
        for sc in &bc.sides {
            let own = m.grids[bc.block].side(sc.side);
            match sc.kind {
                SideKind::Wall => {
                    let id: CircleId = sc.circle.ok_or("a wall without a circle")?;
                    let c = usize::try_from(id)
                        .ok()
                        .and_then(|k| pd.holes().get(k))
                        .ok_or_else(|| format!("wall of unknown hole {id}"))?;
                    for p in &own {
                        let d = image_offset(*p, c.center, size);
                        let r = d[0].hypot(d[1]);
                        if (r - c.radius).abs() > 1e-9 * (c.radius + big) {
                            return Err(format!(
                                "block {} side {}: wall node {p:?} is {} off hole {id}",
                                bc.block,
                                sc.side,
                                r - c.radius
                            ));
                        }
                        wall_nodes[id as usize].push(d);
                    }
                }
                SideKind::Outer => {
                    return Err(format!(
                        "block {} side {} lies on a bounding circle in a periodic mesh",
                        bc.block, sc.side
                    ))
                }
                SideKind::Interface | SideKind::Periodic => {
                    let p = sc.partner.ok_or("an interface without a partner")?;
                    let t = match sc.kind {
                        SideKind::Periodic => {
                            let t = sc
                                .translation
                                .ok_or("a periodic side without translation")?;
                            for d in 0..2 {
                                let k = t[d] / size[d];
                                if (k - k.round()).abs() > 1e-9 {
                                    return Err(format!("translation {t:?} is no period shift"));
                                }
                            }
                            t
                        }
                        _ => [0.0, 0.0],
                    };
                    let mut other = m.grids[p.block].side(p.side);
                    if !p.same_direction {
                        other.reverse();
                    }
                    if own.len() != other.len() {
                        return Err(format!(
                            "block {} side {}: {} nodes, its partner {}",
                            bc.block,
                            sc.side,
                            own.len(),
                            other.len()
                        ));
                    }
                    for (a, q) in own.iter().zip(&other) {
                        let d = (a[0] + t[0] - q[0]).hypot(a[1] + t[1] - q[1]);
                        let ok = if sc.kind == SideKind::Interface {
                            a == q
                        } else {
                            d <= tol
                        };
                        if !ok {
                            return Err(format!(
                                "block {} side {}: node {a:?} does not match partner {q:?} \
                                 (translation {t:?}, off by {d:e})",
                                bc.block, sc.side
                            ));
                        }
                    }
                    let back = conn[p.block].sides[p.side];
                    if back.kind != sc.kind
                        || back.partner.map(|q| (q.block, q.side)) != Some((bc.block, sc.side))
                    {
                        return Err(format!(
                            "block {} side {}: its partner does not name it back",
                            bc.block, sc.side
                        ));
                    }
                }
            }
        }
    }
    // Signed areas: the period minus the wall polygons.
    let (area, abs_area, mut terms, report) = super::cell_sums(m, |p| p);
    let mut expected_area = size[0] * size[1];
    for (k, nodes) in wall_nodes.iter_mut().enumerate() {
        if nodes.is_empty() {
            return Err(format!("hole {k} has no wall side"));
        }
        nodes.sort_by(|p, q| {
            p[1].atan2(p[0])
                .total_cmp(&q[1].atan2(q[0]))
                .then(super::key(*p).cmp(&super::key(*q)))
        });
        nodes.dedup_by(|p, q| super::key(*p) == super::key(*q));
        terms += nodes.len();
        expected_area -= super::shoelace(nodes);
    }
    // Cell corners are far from the origin (up to a period away), so the rounding of the
    // shoelace terms scales with the box, not with the cells.
    let far = pd
        .holes()
        .iter()
        .fold(big, |a, c| a.max(c.center[0].abs() + c.center[1].abs()))
        + big;
    let tol = 1e-9 * abs_area + 64.0 * f64::EPSILON * far * far * terms as f64;
    let within = (area - expected_area).abs() <= tol; // false on NaN too
    if !within {
        return Err(format!(
            "cells cover a signed area of {area:e}, the period minus the wall polygons is \
             {expected_area:e} (tolerance {tol:e})"
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

/// The `mesh_periodic` fuzz target: decode a periodic layout, mesh one period, check it.
/// `Ok(None)` when the bytes decode to no valid domain or the mesher refused within its
/// resource limits.
pub fn check_periodic_bytes(data: &[u8]) -> Result<Option<CheckReport>, String> {
    let Some((pd, options)) = decode_periodic_case(data) else {
        return Ok(None);
    };
    match mesh_periodic(&pd, &options) {
        Ok(m) => {
            // Byte 2's bit 4: also without keeping the nodes, which must give the same layout
            // and report (`Options::keep_nodes`).
            if data.get(2).is_some_and(|p| p & 16 != 0) {
                super::same_without_nodes(&m, |o| mesh_periodic(&pd, o), &options)
                    .map_err(|e| format!("{e}\nlayout: {}", pd.to_json_string()))?;
            }
            check_periodic_mesh(&pd, &m, Checks::default())
                .map(Some)
                .map_err(|e| format!("{e}\nlayout: {}", pd.to_json_string()))
        }
        Err(e) if accepted_periodic_refusal(&pd, &e) => Ok(None),
        Err(e) => Err(format!(
            "mesher failed on a valid periodic domain: {e}\nlayout: {}",
            pd.to_json_string()
        )),
    }
}

/// A resource limit, or sampling at its cap with a gap below
/// [`super::SAMPLING_REFUSAL_GAP`] of the period.
fn accepted_periodic_refusal(pd: &PeriodicDomain, e: &crate::mesher::MeshError) -> bool {
    super::within_limits(e, || {
        let size = pd.size();
        (pd.nearest_gaps(), size[0].max(size[1]))
    })
}
