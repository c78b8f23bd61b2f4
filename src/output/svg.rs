//! SVG picture of a mesh: blocks filled in alternating light colours (neighbours across an
//! interface differ, see [`block_colours`]), the circles (bounding circle unfilled, holes
//! filled light grey), light grid lines, block outlines, medial edges highlighted in red, and
//! block numbers; for a periodic mesh also the period's box `[0, Lx] x [0, Ly]` (dashed
//! green), with the zig-zag sides drawn as the medial edges they are.
//!
//! Lines at the picture's resolution: up to [`FULL_GRID_CELLS`] cells every grid line, block
//! outline and medial edge is drawn through every node; a larger mesh draws every `s`-th grid
//! line of each block through every `s`-th node (and each line's last node), and the block
//! fills, outlines and medial edges through every `s`-th node of each side (and its ends),
//! `s` = [`grid_line_stride`], so that lines stay about two pixels apart on average instead
//! of smearing into a solid fill (1 000 bubbles with default options, 3.8 M cells: a 151 MB
//! `mesh.svg` before, `s` = 4 now). Every block, edge, circle and block number is drawn.
//!
//! The y axis is flipped (mathematical orientation on screen). The picture is
//! [`WIDTH`] pixels wide with a fixed margin; its height follows the aspect ratio of the
//! mesh's bounding box. Coordinates are written with 3 decimals, so the file is deterministic.
//! The circles are recovered from the wall edges that are arcs (one `<circle>` per circle id).

use super::text::{self, write_chunked};
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

/// Most cells whose grid lines are all drawn: a picture [`WIDTH`] = 1 000 pixels wide then
/// has cells of at least about 2 x 2 pixels on average.
pub const FULL_GRID_CELLS: usize = 250_000;

/// Which grid lines a mesh of `cells` cells draws: every `s`-th line of each block through
/// every `s`-th node, `s = ceil(sqrt(cells / FULL_GRID_CELLS))` (1 up to [`FULL_GRID_CELLS`]).
pub fn grid_line_stride(cells: usize) -> usize {
    // The least s with s^2 >= ceil(cells / FULL_GRID_CELLS) (s^2 is an integer), at least 1.
    let q = cells.div_ceil(FULL_GRID_CELLS).max(1);
    let s = q.isqrt();
    if s * s < q {
        s + 1
    } else {
        s
    }
}

/// The node indices `0, s, 2s, ...` up to `n`, with `n` itself last.
fn strided(n: usize, s: usize) -> impl Iterator<Item = usize> {
    (0..n).step_by(s).chain(std::iter::once(n))
}

/// Every `s`-th node of a block side and its last one ([`strided`]).
fn thinned(nodes: &[Point], s: usize) -> impl Iterator<Item = Point> + '_ {
    strided(nodes.len().saturating_sub(1), s).filter_map(|i| nodes.get(i).copied())
}

/// Fill colours of the blocks, indexed by [`block_colours`].
pub const BLOCK_FILLS: [&str; 6] = [
    "#dbe9f6", "#fde7c8", "#d9f0d3", "#f3d9ec", "#fff6bf", "#e0e0f5",
];

/// A colour index (into [`BLOCK_FILLS`]) per block, by a greedy colouring of the block
/// adjacency in block order: blocks sharing an edge of the layout get different colours
/// whenever [`BLOCK_FILLS`] has enough colours (then indices wrap around).
pub fn block_colours(mesh: &Mesh) -> Vec<usize> {
    let layout = &mesh.layout;
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); layout.edges.len()];
    for (b, block) in layout.blocks.iter().enumerate() {
        for s in &block.sides {
            if let Some(u) = users.get_mut(s.edge as usize) {
                u.push(b);
            }
        }
    }
    let mut colour: Vec<Option<usize>> = vec![None; layout.blocks.len()];
    for (b, block) in layout.blocks.iter().enumerate() {
        let mut taken = [false; BLOCK_FILLS.len()];
        for s in &block.sides {
            for &n in users.get(s.edge as usize).map_or(&[][..], |u| &u[..]) {
                if let Some(Some(c)) = colour.get(n).filter(|_| n != b) {
                    taken[*c] = true;
                }
            }
        }
        let c = taken
            .iter()
            .position(|t| !t)
            .unwrap_or(b % BLOCK_FILLS.len());
        colour[b] = Some(c);
    }
    colour.into_iter().map(|c| c.unwrap_or(0)).collect()
}

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

/// The blocks as filled polygons (their four sides' nodes), in alternating colours.
fn write_block_fills<W: Write>(w: &mut W, mesh: &Mesh, v: &View, s: usize) -> io::Result<()> {
    writeln!(w, "  <g stroke=\"none\">")?;
    let colours = block_colours(mesh);
    write_chunked(w, mesh.grids.len(), 64, |r, out| {
        for b in r {
            let g = &mesh.grids[b];
            out.extend_from_slice(b"    <path fill=\"");
            out.extend_from_slice(BLOCK_FILLS[colours[b]].as_bytes());
            out.extend_from_slice(b"\" d=\"");
            // Each side's nodes but its last (the next side's first), every s-th.
            let ring = (0..4).flat_map(|k| {
                let side = g.side(k);
                let n = side.len().saturating_sub(1);
                (0..n).step_by(s).map(move |i| side[i])
            });
            path_data(out, v, ring);
            out.extend_from_slice(b" Z\"/>\n");
        }
    })?;
    writeln!(w, "  </g>")
}

/// `M x y L x y ...` (three decimals) of `pts` in picture coordinates.
fn path_data(out: &mut Vec<u8>, v: &View, pts: impl Iterator<Item = Point>) {
    for (k, p) in pts.enumerate() {
        out.extend_from_slice(if k == 0 { b"M" } else { b" L" });
        text::fixed3(out, v.x(p[0]));
        out.push(b' ');
        text::fixed3(out, v.y(p[1]));
    }
}

/// One `<path>` element through `pts`.
fn path(out: &mut Vec<u8>, v: &View, pts: impl Iterator<Item = Point>) {
    out.extend_from_slice(b"    <path d=\"");
    path_data(out, v, pts);
    out.extend_from_slice(b"\"/>\n");
}

/// Write the SVG picture of `mesh` to `path` (atomically).
///
/// Errors: I/O failures, or a mesh whose grids do not match its blocks (`InvalidInput`).
pub fn write(mesh: &Mesh, path_out: &Path) -> io::Result<()> {
    check_mesh(mesh)?;
    write_atomic(path_out, |w| write_to(w, mesh))
}

/// The SVG document as a string (same checks as [`write()`]).
pub fn to_string(mesh: &Mesh) -> io::Result<String> {
    let mut buf = Vec::new();
    write_checked(&mut buf, mesh)?;
    String::from_utf8(buf).map_err(io::Error::other)
}

/// The SVG document into `w` (same checks as [`write()`]). Its lines, which
/// [`super::png`] relies on: the `<svg>` element's opening line first and `</svg>` last;
/// between them the top-level elements, each on its own line indented two spaces, and groups
/// (not nested) opened by a line `  <g ...>` and closed by `  </g>`, holding elements one per
/// line, indented four; no group sets opacity, a clip, a mask or a filter, so drawing the
/// elements in document order is drawing the picture.
pub(crate) fn write_checked<W: Write>(w: &mut W, mesh: &Mesh) -> io::Result<()> {
    check_mesh(mesh)?;
    write_to(w, mesh)
}

/// Write the SVG document to `w` (no checks beyond [`write()`]'s; used by it).
fn write_to<W: Write>(w: &mut W, mesh: &Mesh) -> io::Result<()> {
    let circles = circles(mesh);
    let v = View::new(mesh, &circles);
    writeln!(
        w,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH:.0}\" height=\"{h:.3}\" viewBox=\"0 0 {WIDTH:.0} {h:.3}\">",
        h = v.height
    )?;
    let cells: usize = mesh.grids.iter().map(|g| g.cells()).sum();
    writeln!(
        w,
        "  <title>medial-blocks: {} holes, {} blocks, {cells} cells</title>",
        mesh.holes,
        mesh.layout.blocks.len(),
    )?;
    writeln!(w, "  <rect width=\"100%\" height=\"100%\" fill=\"white\"/>")?;
    let s = grid_line_stride(cells);
    write_block_fills(w, mesh, &v, s)?;
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
    write_chunked(w, mesh.grids.len(), 64, |r, out| {
        for g in &mesh.grids[r] {
            for j in (1..g.nj).filter(|j| j % s == 0) {
                path(out, &v, strided(g.ni, s).map(|i| g.node(i, j)));
            }
            for i in (1..g.ni).filter(|i| i % s == 0) {
                path(out, &v, strided(g.nj, s).map(|j| g.node(i, j)));
            }
        }
    })?;
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
    write_chunked(w, outlines.len(), 256, |r, out| {
        for nodes in &outlines[r] {
            path(out, &v, thinned(nodes, s));
        }
    })?;
    writeln!(w, "  </g>")?;
    writeln!(
        w,
        "  <g stroke=\"#d62728\" stroke-width=\"2.5\" fill=\"none\">"
    )?;
    write_chunked(w, medial.len(), 256, |r, out| {
        for nodes in &medial[r] {
            path(out, &v, thinned(nodes, s));
        }
    })?;
    writeln!(w, "  </g>")?;

    write_degeneracy_marks(w, mesh, &v)?;
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
    write_chunked(w, mesh.grids.len(), 1024, |r, out| {
        for b in r {
            let g = &mesh.grids[b];
            let p = g.node(g.ni / 2, g.nj / 2);
            out.extend_from_slice(b"    <text x=\"");
            text::fixed3(out, v.x(p[0]));
            out.extend_from_slice(b"\" y=\"");
            text::fixed3(out, v.y(p[1]));
            out.extend_from_slice(b"\">");
            text::int(out, b);
            out.extend_from_slice(b"</text>\n");
        }
    })?;
    writeln!(w, "  </g>")?;
    writeln!(w, "</svg>")
}

/// Marks for paper section 4: each co-circular group's empty circle (dashed, green, class
/// `cocircular-group`) and each inserted hole (dashed, orange, class `inserted-hole`).
fn write_degeneracy_marks<W: Write>(w: &mut W, mesh: &Mesh, v: &View) -> io::Result<()> {
    if mesh.cocircular_groups.is_empty() && mesh.inserted_holes.is_empty() {
        return Ok(());
    }
    writeln!(
        w,
        "  <g fill=\"none\" stroke-width=\"1.5\" stroke-dasharray=\"4 3\">"
    )?;
    let finite = |c: [f64; 2], r: f64| c[0].is_finite() && c[1].is_finite() && r.is_finite();
    for g in &mesh.cocircular_groups {
        if finite(g.center, g.radius) {
            writeln!(
                w,
                "    <circle class=\"cocircular-group\" stroke=\"#2ca02c\" cx=\"{:.3}\" cy=\"{:.3}\" r=\"{:.3}\"/>",
                v.x(g.center[0]),
                v.y(g.center[1]),
                g.radius * v.scale
            )?;
        }
    }
    for h in &mesh.inserted_holes {
        if finite(h.center, h.radius) {
            writeln!(
                w,
                "    <circle class=\"inserted-hole\" stroke=\"#ff7f0e\" cx=\"{:.3}\" cy=\"{:.3}\" r=\"{:.3}\"/>",
                v.x(h.center[0]),
                v.y(h.center[1]),
                h.radius * v.scale
            )?;
        }
    }
    writeln!(w, "  </g>")
}
