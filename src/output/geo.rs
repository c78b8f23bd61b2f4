//! A Gmsh `.geo` script of the block layout, so a user can re-mesh, refine or export through
//! Gmsh's own writers: points (layout vertices), curves (straight spokes as `Line`, circle arcs
//! as `Circle`, medial polylines as `Spline`), one `Plane Surface` per block, `Transfinite
//! Curve` with the node counts of the mesh, `Transfinite Surface` on the block corners,
//! `Recombine`, and the same physical groups as the `.msh` writer.
//!
//! Gmsh's `Circle` needs an arc of less than pi; a wall arc of pi or more is written as a
//! `Spline` through points on the exact circle (every 1/32 of a turn).

use super::gmsh::{PHYSICAL_FLUID, PHYSICAL_INTERFACES, PHYSICAL_OUTER, PHYSICAL_WALL_BASE};
use super::text;
use super::write_atomic;
use crate::layout::{Curve, EdgeKind};
use crate::mesh::Mesh;
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::io::{self, Write};
use std::path::Path;

fn list(tags: &[i64]) -> String {
    tags.iter()
        .map(|t| t.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// `Point(tag) = {x, y, 0};` (`{:e}` floats) and a newline.
fn point_line(w: &mut dyn Write, tag: usize, p: [f64; 2]) -> io::Result<()> {
    let mut out = Vec::with_capacity(64);
    out.extend_from_slice(b"Point(");
    text::int(&mut out, tag);
    out.extend_from_slice(b") = {");
    text::exp(&mut out, p[0]);
    out.extend_from_slice(b", ");
    text::exp(&mut out, p[1]);
    out.extend_from_slice(b", 0};\n");
    w.write_all(&out)
}

/// Write the `.geo` script of `mesh`'s layout to `path`.
pub fn write_geo(mesh: &Mesh, path: &Path) -> io::Result<()> {
    let layout = &mesh.layout;
    // Cell count of each edge, from the first block side that uses it.
    let mut cells = vec![0usize; layout.edges.len()];
    for (block, g) in layout.blocks.iter().zip(&mesh.grids) {
        for (s, side) in block.sides.iter().enumerate() {
            cells[side.edge as usize] = if s % 2 == 0 { g.ni } else { g.nj };
        }
    }
    write_atomic(path, |w| {
        writeln!(w, "// Block layout written by medial-blocks.")?;
        writeln!(
            w,
            "// gmsh mesh.geo -2 -format msh41 re-meshes it with the same node counts."
        )?;
        writeln!(w, "SetFactory(\"Built-in\");")?;
        for (v, p) in layout.vertices.iter().enumerate() {
            point_line(w, v + 1, *p)?;
        }
        let mut next_point = layout.vertices.len() + 1;
        let mut extra_point = |w: &mut dyn Write, p: [f64; 2]| -> io::Result<usize> {
            let tag = next_point;
            next_point += 1;
            point_line(w, tag, p)?;
            Ok(tag)
        };
        for (e, edge) in layout.edges.iter().enumerate() {
            let (a, b) = (edge.ends[0] as usize + 1, edge.ends[1] as usize + 1);
            let tag = e + 1;
            match &edge.curve {
                Curve::Segment => writeln!(w, "Line({tag}) = {{{a}, {b}}};")?,
                Curve::Arc {
                    center,
                    radius,
                    start,
                    sweep,
                } => {
                    if sweep.abs() < PI * 0.999 {
                        let c = extra_point(w, *center)?;
                        writeln!(w, "Circle({tag}) = {{{a}, {c}, {b}}};")?;
                    } else {
                        let steps = ((sweep.abs() / (2.0 * PI) * 32.0).ceil() as usize).max(2);
                        let mut pts = vec![a as i64];
                        for k in 1..steps {
                            let t = start + sweep * k as f64 / steps as f64;
                            let p = [center[0] + radius * t.cos(), center[1] + radius * t.sin()];
                            pts.push(extra_point(w, p)? as i64);
                        }
                        pts.push(b as i64);
                        writeln!(w, "Spline({tag}) = {{{}}};", list(&pts))?;
                    }
                }
                Curve::Polyline(points) => {
                    let mut pts = vec![a as i64];
                    for p in points.iter().skip(1).take(points.len().saturating_sub(2)) {
                        pts.push(extra_point(w, *p)? as i64);
                    }
                    pts.push(b as i64);
                    if pts.len() == 2 {
                        writeln!(w, "Line({tag}) = {{{a}, {b}}};")?;
                    } else {
                        writeln!(w, "Spline({tag}) = {{{}}};", list(&pts))?;
                    }
                }
            }
            writeln!(w, "Transfinite Curve{{{tag}}} = {};", cells[e] + 1)?;
        }
        for (b, block) in layout.blocks.iter().enumerate() {
            let tag = b + 1;
            let loop_: Vec<i64> = block
                .sides
                .iter()
                .map(|s| {
                    let t = s.edge as i64 + 1;
                    if s.reversed {
                        -t
                    } else {
                        t
                    }
                })
                .collect();
            writeln!(w, "Curve Loop({tag}) = {{{}}};", list(&loop_))?;
            writeln!(w, "Plane Surface({tag}) = {{{tag}}};")?;
            let corners: Vec<i64> = block.corners.iter().map(|&c| c as i64 + 1).collect();
            writeln!(w, "Transfinite Surface{{{tag}}} = {{{}}};", list(&corners))?;
            writeln!(w, "Recombine Surface{{{tag}}};")?;
        }
        let mut groups: BTreeMap<(i32, String), Vec<i64>> = BTreeMap::new();
        for (e, edge) in layout.edges.iter().enumerate() {
            let key = match edge.kind {
                EdgeKind::Wall(c) if c < 0 => (PHYSICAL_OUTER, "outer".to_string()),
                EdgeKind::Wall(c) => (PHYSICAL_WALL_BASE + c, format!("wall_{c}")),
                _ => (PHYSICAL_INTERFACES, "interfaces".to_string()),
            };
            groups.entry(key).or_default().push(e as i64 + 1);
        }
        for ((tag, name), curves) in &groups {
            writeln!(
                w,
                "Physical Curve(\"{name}\", {tag}) = {{{}}};",
                list(curves)
            )?;
        }
        let all: Vec<i64> = (1..=layout.blocks.len() as i64).collect();
        writeln!(
            w,
            "Physical Surface(\"fluid\", {PHYSICAL_FLUID}) = {{{}}};",
            list(&all)
        )?;
        Ok(())
    })
}
