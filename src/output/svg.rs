//! SVG picture of a mesh: the circles (bounding circle unfilled, holes filled light grey),
//! light grid lines, block outlines, medial edges highlighted in red, and block numbers; for
//! a periodic mesh also the period's box `[0, Lx] x [0, Ly]` (dashed green), with the
//! zig-zag sides drawn as the medial edges they are.
//!
//! The y axis is flipped (mathematical orientation on screen). The picture is
//! [`WIDTH`] pixels wide with a fixed margin; its height follows the aspect ratio of the
//! mesh's bounding box. Coordinates are written with 3 decimals, so the file is deterministic.
//! The circles are recovered from the wall edges that are arcs (one `<circle>` per circle id).

use super::{check_mesh, write_atomic};
use crate::domain::CircleId;
use crate::geometry::Point;
use crate::layout::{Curve, EdgeKind};
use crate::mesh::Mesh;
use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::Path;

/// Width of the picture (the `viewBox` width), pixels.
pub const WIDTH: f64 = 1000.0;
/// Margin around the mesh, pixels.
pub const MARGIN: f64 = 20.0;

/// The circles of the mesh, by id, from its wall arcs (first arc of each id wins).
pub fn circles(mesh: &Mesh) -> BTreeMap<CircleId, (Point, f64)> {
    let mut out = BTreeMap::new();
    for e in &mesh.layout.edges {
        if let (EdgeKind::Wall(id), Curve::Arc { center, radius, .. }) = (e.kind, &e.curve) {
            out.entry(id).or_insert((*center, *radius));
        }
    }
    out
}

/// World to picture coordinates.
struct View {
    x0: f64,
    y1: f64,
    scale: f64,
    height: f64,
}

impl View {
    fn new(mesh: &Mesh, circles: &BTreeMap<CircleId, (Point, f64)>) -> View {
        let (mut x0, mut y0, mut x1, mut y1) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        let mut add = |p: Point| {
            if p[0].is_finite() && p[1].is_finite() {
                x0 = x0.min(p[0]);
                x1 = x1.max(p[0]);
                y0 = y0.min(p[1]);
                y1 = y1.max(p[1]);
            }
        };
        for g in &mesh.grids {
            for &p in &g.nodes {
                add(p);
            }
        }
        for &(c, r) in circles.values() {
            add([c[0] - r, c[1] - r]);
            add([c[0] + r, c[1] + r]);
        }
        if !(x0 <= x1 && y0 <= y1) {
            (x0, y0, x1, y1) = (0.0, 0.0, 1.0, 1.0);
        }
        let span = (x1 - x0).max(y1 - y0);
        let scale = if span > 0.0 && span.is_finite() {
            (WIDTH - 2.0 * MARGIN) / span
        } else {
            1.0
        };
        let height = ((y1 - y0) * scale + 2.0 * MARGIN).max(2.0 * MARGIN);
        View {
            x0,
            y1,
            scale,
            height,
        }
    }
    fn x(&self, x: f64) -> f64 {
        MARGIN + (x - self.x0) * self.scale
    }
    fn y(&self, y: f64) -> f64 {
        MARGIN + (self.y1 - y) * self.scale
    }
}

fn path<W: Write>(w: &mut W, v: &View, pts: impl Iterator<Item = Point>) -> io::Result<()> {
    write!(w, "    <path d=\"")?;
    for (k, p) in pts.enumerate() {
        let cmd = if k == 0 { "M" } else { " L" };
        write!(w, "{cmd}{:.3} {:.3}", v.x(p[0]), v.y(p[1]))?;
    }
    writeln!(w, "\"/>")
}

/// Write the SVG picture of `mesh` to `path` (atomically).
///
/// Errors: I/O failures, or a mesh whose grids do not match its blocks (`InvalidInput`).
pub fn write(mesh: &Mesh, path_out: &Path) -> io::Result<()> {
    check_mesh(mesh)?;
    write_atomic(path_out, |w| write_to(w, mesh))
}

/// The SVG document as a string (same checks as [`write`]).
pub fn to_string(mesh: &Mesh) -> io::Result<String> {
    check_mesh(mesh)?;
    let mut buf = Vec::new();
    write_to(&mut buf, mesh)?;
    String::from_utf8(buf).map_err(io::Error::other)
}

/// Write the SVG document to `w` (no checks beyond [`write`]'s; used by it).
fn write_to<W: Write>(w: &mut W, mesh: &Mesh) -> io::Result<()> {
    let circles = circles(mesh);
    let v = View::new(mesh, &circles);
    writeln!(
        w,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH:.0}\" height=\"{h:.3}\" viewBox=\"0 0 {WIDTH:.0} {h:.3}\">",
        h = v.height
    )?;
    writeln!(
        w,
        "  <title>medial-blocks: {} holes, {} blocks, {} cells</title>",
        mesh.holes,
        mesh.layout.blocks.len(),
        mesh.grids.iter().map(|g| g.cells()).sum::<usize>()
    )?;
    writeln!(w, "  <rect width=\"100%\" height=\"100%\" fill=\"white\"/>")?;
    writeln!(w, "  <g stroke=\"black\" stroke-width=\"1.5\">")?;
    for (&id, &(c, r)) in &circles {
        let fill = if id < 0 { "none" } else { "#dddddd" };
        writeln!(
            w,
            "    <circle cx=\"{:.3}\" cy=\"{:.3}\" r=\"{:.3}\" fill=\"{fill}\"/>",
            v.x(c[0]),
            v.y(c[1]),
            r * v.scale
        )?;
    }
    writeln!(w, "  </g>")?;

    writeln!(
        w,
        "  <g stroke=\"#b0b0b0\" stroke-width=\"0.4\" fill=\"none\">"
    )?;
    for g in &mesh.grids {
        for j in 1..g.nj {
            path(w, &v, (0..=g.ni).map(|i| g.node(i, j)))?;
        }
        for i in 1..g.ni {
            path(w, &v, (0..=g.nj).map(|j| g.node(i, j)))?;
        }
    }
    writeln!(w, "  </g>")?;

    // Each edge once, from the first block side that uses it.
    let mut drawn = vec![false; mesh.layout.edges.len()];
    let mut outlines = Vec::new();
    let mut medial = Vec::new();
    for (b, block) in mesh.layout.blocks.iter().enumerate() {
        for (k, s) in block.sides.iter().enumerate() {
            let e = s.edge as usize;
            if e < drawn.len() && !drawn[e] {
                drawn[e] = true;
                let nodes = mesh.grids[b].side(k);
                if matches!(
                    mesh.layout.edges[e].kind,
                    EdgeKind::Medial | EdgeKind::Periodic { .. }
                ) {
                    medial.push(nodes);
                } else {
                    outlines.push(nodes);
                }
            }
        }
    }
    writeln!(
        w,
        "  <g stroke=\"#303030\" stroke-width=\"1.2\" fill=\"none\">"
    )?;
    for nodes in &outlines {
        path(w, &v, nodes.iter().copied())?;
    }
    writeln!(w, "  </g>")?;
    writeln!(
        w,
        "  <g stroke=\"#d62728\" stroke-width=\"2.5\" fill=\"none\">"
    )?;
    for nodes in &medial {
        path(w, &v, nodes.iter().copied())?;
    }
    writeln!(w, "  </g>")?;

    // A periodic mesh: the period's box [0, Lx] x [0, Ly], dashed.
    if let Some([lx, ly]) = crate::periodic::period_of(&mesh.layout) {
        writeln!(
            w,
            "  <rect x=\"{:.3}\" y=\"{:.3}\" width=\"{:.3}\" height=\"{:.3}\" fill=\"none\" stroke=\"#2ca02c\" stroke-width=\"1.5\" stroke-dasharray=\"6 4\"/>",
            v.x(0.0),
            v.y(ly),
            lx * v.scale,
            ly * v.scale
        )?;
    }

    writeln!(
        w,
        "  <g font-family=\"sans-serif\" font-size=\"11\" fill=\"#1f4e9c\" text-anchor=\"middle\">"
    )?;
    for (b, g) in mesh.grids.iter().enumerate() {
        let p = g.node(g.ni / 2, g.nj / 2);
        writeln!(
            w,
            "    <text x=\"{:.3}\" y=\"{:.3}\">{b}</text>",
            v.x(p[0]),
            v.y(p[1])
        )?;
    }
    writeln!(w, "  </g>")?;
    writeln!(w, "</svg>")
}
