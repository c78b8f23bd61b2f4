//! Gmsh `.msh` 4.1, ASCII or binary ([`Encoding`]): one conforming quad mesh (shared nodes merged through
//! [`crate::numbering`]), one surface entity per block, one curve entity per layout edge with its
//! 2-node line elements, and physical groups:
//! - `fluid` (dimension 2, tag 1): every block;
//! - `outer` (dimension 1, tag 2): the bounding circle;
//! - `interfaces` (dimension 1, tag 3): every block-to-block interface;
//! - `wall_N` (dimension 1, tag 10 + N): the wall of hole `N` (0-based, input order).
//!
//! The binary file (`4.1 1 8`) has the same sections with the same numbers, in the binary
//! layout of the Gmsh reference manual: `int` tags and `size_t` (8-byte) counts, `double`
//! coordinates, all little-endian; `$PhysicalNames` stays text, as the format wants.

use super::binary::Encoding;
use super::text::{self, write_chunked};
use super::write_atomic;
use crate::layout::EdgeKind;
use crate::mesh::Mesh;
use crate::numbering::Numbering;
use std::collections::BTreeSet;
use std::io::{self, Write};
use std::path::Path;

/// Physical tag of the fluid surface group.
pub const PHYSICAL_FLUID: i32 = 1;
/// Physical tag of the bounding circle group.
pub const PHYSICAL_OUTER: i32 = 2;
/// Physical tag of the interfaces group.
pub const PHYSICAL_INTERFACES: i32 = 3;
/// Physical tag of hole `n`'s wall is `PHYSICAL_WALL_BASE + n`.
pub const PHYSICAL_WALL_BASE: i32 = 10;

fn physical_of(kind: EdgeKind) -> i32 {
    match kind {
        EdgeKind::Wall(c) if c < 0 => PHYSICAL_OUTER,
        EdgeKind::Wall(c) => PHYSICAL_WALL_BASE + c,
        _ => PHYSICAL_INTERFACES,
    }
}

/// ` xmin ymin 0 xmax ymax 0` of an entity's bounding box (`{:e}` floats).
fn entity_box(out: &mut Vec<u8>, b: [f64; 4]) {
    for (k, x) in [b[0], b[1], b[2], b[3]].into_iter().enumerate() {
        out.push(b' ');
        text::exp(out, x);
        if k % 2 == 1 {
            out.extend_from_slice(b" 0");
        }
    }
}

/// One line of integers separated by spaces.
fn line_of_ints(out: &mut Vec<u8>, values: &[usize]) {
    for (k, &v) in values.iter().enumerate() {
        if k > 0 {
            out.push(b' ');
        }
        text::int(out, v);
    }
    out.push(b'\n');
}

fn bbox(points: impl Iterator<Item = [f64; 2]>) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in points {
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
    }
    b
}

/// Write `mesh` as Gmsh 4.1 ASCII to `path`.
pub fn write_msh(mesh: &Mesh, path: &Path) -> io::Result<()> {
    write_msh_encoded(mesh, path, Encoding::Ascii)
}

/// Write `mesh` as Gmsh 4.1 to `path`, ASCII or binary.
pub fn write_msh_encoded(mesh: &Mesh, path: &Path, encoding: Encoding) -> io::Result<()> {
    super::check_mesh(mesh)?;
    let parts = Parts::new(mesh);
    write_atomic(path, |w| match encoding {
        Encoding::Ascii => write_ascii(w, mesh, &parts),
        Encoding::Binary => write_binary(w, mesh, &parts),
    })
}

/// What both encodings write: the numbering of the merged nodes (their coordinates and the
/// blocks' ids are formed as they are written, issue 8), the line chain of every layout edge
/// (from the first block side that uses it), the physical groups present, and the first
/// element tag of every edge's lines and of every block's quads.
struct Parts {
    nodes: Numbering,
    edge_lines: Vec<Option<Vec<u32>>>,
    walls: BTreeSet<i32>,
    has_outer: bool,
    has_interfaces: bool,
    /// `first_line[e]`: the tag of edge `e`'s first line; one more entry, the first quad's.
    first_line: Vec<usize>,
    /// `first_quad[b]`: the tag of block `b`'s first quad; one more entry, past the last.
    first_quad: Vec<usize>,
}

impl Parts {
    fn new(mesh: &Mesh) -> Parts {
        let layout = &mesh.layout;
        let nodes = Numbering::new(layout, &mesh.grids);
        // Line elements of every edge, from the first block side that uses it.
        let mut chain = Vec::new();
        let edge_lines: Vec<Option<Vec<u32>>> = (0..layout.edges.len())
            .map(|e| {
                nodes.edge_chain(layout, &mesh.grids, e, &mut chain);
                (!chain.is_empty()).then(|| chain.iter().map(|&id| id as u32).collect())
            })
            .collect();
        let walls: BTreeSet<i32> = layout
            .edges
            .iter()
            .filter_map(|e| match e.kind {
                EdgeKind::Wall(c) if c >= 0 => Some(c),
                _ => None,
            })
            .collect();
        let has_outer = layout
            .edges
            .iter()
            .any(|e| matches!(e.kind, EdgeKind::Wall(c) if c < 0));
        let has_interfaces = layout
            .edges
            .iter()
            .any(|e| !matches!(e.kind, EdgeKind::Wall(_)));
        // Element tags run 1.. over the edges' lines, then the blocks' quads.
        let mut first_line = Vec::with_capacity(edge_lines.len() + 1);
        first_line.push(1usize);
        for c in &edge_lines {
            let k = c.as_ref().map_or(0, |c| c.len().saturating_sub(1));
            first_line.push(first_line.last().copied().unwrap_or(1) + k);
        }
        let mut first_quad = Vec::with_capacity(mesh.grids.len() + 1);
        first_quad.push(first_line.last().copied().unwrap_or(1));
        for g in &mesh.grids {
            first_quad.push(first_quad.last().copied().unwrap_or(1) + g.ni * g.nj);
        }
        Parts {
            nodes,
            edge_lines,
            walls,
            has_outer,
            has_interfaces,
            first_line,
            first_quad,
        }
    }

    /// The number of physical groups.
    fn physical_count(&self) -> usize {
        1 + usize::from(self.has_outer) + usize::from(self.has_interfaces) + self.walls.len()
    }

    /// The `$PhysicalNames` section (text in both encodings).
    fn physical_names<W: Write>(&self, w: &mut W) -> io::Result<()> {
        writeln!(w, "$PhysicalNames\n{}", self.physical_count())?;
        writeln!(w, "2 {PHYSICAL_FLUID} \"fluid\"")?;
        if self.has_outer {
            writeln!(w, "1 {PHYSICAL_OUTER} \"outer\"")?;
        }
        if self.has_interfaces {
            writeln!(w, "1 {PHYSICAL_INTERFACES} \"interfaces\"")?;
        }
        for c in &self.walls {
            writeln!(w, "1 {} \"wall_{c}\"", PHYSICAL_WALL_BASE + c)?;
        }
        writeln!(w, "$EndPhysicalNames")
    }

    /// The chain of edge `e`'s nodes (empty for an edge no block side uses).
    fn chain(&self, e: usize) -> &[u32] {
        self.edge_lines[e].as_deref().unwrap_or(&[])
    }

    /// The bounding box of edge `e`'s nodes (in the chain's order).
    fn edge_box(&self, mesh: &Mesh, e: usize) -> [f64; 4] {
        let mut points = Vec::new();
        self.nodes
            .edge_points(&mesh.layout, &mesh.grids, e, &mut points);
        bbox(points.into_iter())
    }

    /// The number of elements (lines and quads).
    fn elements(&self) -> usize {
        self.first_quad.last().copied().unwrap_or(1) - 1
    }
}

/// The ASCII file.
fn write_ascii<W: Write>(w: &mut W, mesh: &Mesh, parts: &Parts) -> io::Result<()> {
    let layout = &mesh.layout;
    let Parts {
        nodes, edge_lines, ..
    } = parts;
    writeln!(w, "$MeshFormat\n4.1 0 8\n$EndMeshFormat")?;
    parts.physical_names(w)?;

    // Entities: curves = layout edges (tag e + 1), surfaces = blocks (tag b + 1).
    writeln!(w, "$Entities")?;
    writeln!(w, "0 {} {} 0", layout.edges.len(), layout.blocks.len())?;
    write_chunked(w, layout.edges.len(), 1024, |r, out| {
        for e in r {
            text::int(out, e + 1);
            entity_box(out, parts.edge_box(mesh, e));
            out.extend_from_slice(b" 1 ");
            text::int(out, physical_of(layout.edges[e].kind));
            out.extend_from_slice(b" 0\n");
        }
    })?;
    write_chunked(w, layout.blocks.len(), 512, |r, out| {
        for b in r {
            let bb = bbox(mesh.grids[b].nodes.iter().copied());
            text::int(out, b + 1);
            entity_box(out, bb);
            out.extend_from_slice(b" 1 ");
            text::int(out, PHYSICAL_FLUID);
            out.extend_from_slice(b" 4");
            for side in &layout.blocks[b].sides {
                out.push(b' ');
                text::int(out, signed_curve(side));
            }
            out.push(b'\n');
        }
    })?;
    writeln!(w, "$EndEntities")?;

    let n = nodes.len();
    writeln!(w, "$Nodes\n1 {n} 1 {n}\n2 1 0 {n}")?;
    write_chunked(w, n, 8192, |r, out| {
        for k in r {
            text::int(out, k + 1);
            out.push(b'\n');
        }
    })?;
    super::write_merged_points(w, mesh, nodes, |points, out| {
        for p in points {
            text::exp(out, p[0]);
            out.push(b' ');
            text::exp(out, p[1]);
            out.extend_from_slice(b" 0\n");
        }
    })?;
    writeln!(w, "$EndNodes")?;

    let total = parts.elements();
    writeln!(w, "$Elements")?;
    writeln!(
        w,
        "{} {total} 1 {total}",
        layout.edges.len() + layout.blocks.len()
    )?;
    write_chunked(w, edge_lines.len(), 1024, |r, out| {
        for e in r {
            let chain = parts.chain(e);
            out.extend_from_slice(b"1 ");
            text::int(out, e + 1);
            out.extend_from_slice(b" 1 ");
            text::int(out, chain.len().saturating_sub(1));
            out.push(b'\n');
            for (k, pair) in chain.windows(2).enumerate() {
                line_of_ints(
                    out,
                    &[
                        parts.first_line[e] + k,
                        pair[0] as usize + 1,
                        pair[1] as usize + 1,
                    ],
                );
            }
        }
    })?;
    write_chunked(w, mesh.grids.len(), 16, |r, out| {
        for b in r {
            let g = &mesh.grids[b];
            line_of_ints(out, &[2, b + 1, 3, g.ni * g.nj]);
            quads(parts, mesh, b, |q| line_of_ints(out, &q));
        }
    })?;
    writeln!(w, "$EndElements")?;
    Ok(())
}

/// The curve tag of a block side, negative when the side runs against its edge.
fn signed_curve(side: &crate::layout::SideRef) -> i64 {
    let sign = if side.reversed { -1 } else { 1 };
    sign * (side.edge as i64 + 1)
}

/// Every quad of block `b` in file order: `[tag, n0, n1, n2, n3]` (1-based node tags,
/// counter-clockwise from `(i, j)`).
fn quads(parts: &Parts, mesh: &Mesh, b: usize, mut each: impl FnMut([usize; 5])) {
    let g = &mesh.grids[b];
    let mut ids = Vec::new();
    parts.nodes.block_ids(&mesh.layout, b, g, &mut ids);
    let at = |i: usize, j: usize| ids[i + j * (g.ni + 1)] + 1;
    let mut tag = parts.first_quad[b];
    for j in 0..g.nj {
        for i in 0..g.ni {
            each([tag, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            tag += 1;
        }
    }
}

/// Little-endian binary fields of the Gmsh binary layout.
struct Bin<'a>(&'a mut Vec<u8>);

impl Bin<'_> {
    /// An `int` (4 bytes).
    fn int(&mut self, v: i64) -> io::Result<()> {
        let v = i32::try_from(v).map_err(|_| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{v} does not fit a Gmsh binary int"),
            )
        })?;
        self.0.extend_from_slice(&v.to_le_bytes());
        Ok(())
    }
    /// An `int` known to fit (an entity tag or type, checked by [`check_int`] up front).
    fn small(&mut self, v: usize) {
        self.0.extend_from_slice(&(v as i32).to_le_bytes());
    }
    /// A `size_t` (8 bytes, the `data-size` of the header).
    fn size(&mut self, v: usize) {
        self.0.extend_from_slice(&(v as u64).to_le_bytes());
    }
    /// A `double`.
    fn double(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// An entity's bounding box `minX minY minZ maxX maxY maxZ` (z = 0).
    fn bbox(&mut self, b: [f64; 4]) {
        for v in [b[0], b[1], 0.0, b[2], b[3], 0.0] {
            self.double(v);
        }
    }
}

/// The binary file (`4.1 1 8`): the sections and numbers of [`write_ascii`] in Gmsh's binary
/// layout.
fn write_binary<W: Write>(w: &mut W, mesh: &Mesh, parts: &Parts) -> io::Result<()> {
    let layout = &mesh.layout;
    let nodes = &parts.nodes;
    w.write_all(b"$MeshFormat\n4.1 1 8\n")?;
    w.write_all(&1i32.to_le_bytes())?;
    w.write_all(b"\n$EndMeshFormat\n")?;
    parts.physical_names(w)?;

    let mut out = Vec::new();
    let mut bin = Bin(&mut out);
    for count in [0, layout.edges.len(), layout.blocks.len(), 0] {
        bin.size(count);
    }
    for (e, edge) in layout.edges.iter().enumerate() {
        bin.int(e as i64 + 1)?;
        bin.bbox(parts.edge_box(mesh, e));
        bin.size(1);
        bin.int(physical_of(edge.kind).into())?;
        bin.size(0);
    }
    for (b, block) in layout.blocks.iter().enumerate() {
        bin.int(b as i64 + 1)?;
        bin.bbox(bbox(mesh.grids[b].nodes.iter().copied()));
        bin.size(1);
        bin.int(PHYSICAL_FLUID.into())?;
        bin.size(block.sides.len());
        for side in &block.sides {
            bin.int(signed_curve(side))?;
        }
    }
    w.write_all(b"$Entities\n")?;
    w.write_all(&out)?;
    w.write_all(b"\n$EndEntities\n")?;

    let n = nodes.len();
    let mut head = Vec::new();
    let mut bin = Bin(&mut head);
    for v in [1, n, 1, n] {
        bin.size(v);
    }
    bin.int(2)?;
    bin.int(1)?;
    bin.int(0)?;
    bin.size(n);
    w.write_all(b"$Nodes\n")?;
    w.write_all(&head)?;
    write_chunked(w, n, 1 << 16, |r, out| {
        for k in r {
            Bin(out).size(k + 1);
        }
    })?;
    super::write_merged_points(w, mesh, nodes, |points, out| {
        for p in points {
            let mut bin = Bin(out);
            bin.double(p[0]);
            bin.double(p[1]);
            bin.double(0.0);
        }
    })?;
    w.write_all(b"\n$EndNodes\n")?;

    let total = parts.elements();
    let mut head = Vec::new();
    let mut bin = Bin(&mut head);
    for v in [layout.edges.len() + layout.blocks.len(), total, 1, total] {
        bin.size(v);
    }
    w.write_all(b"$Elements\n")?;
    w.write_all(&head)?;
    // The ints of the element blocks are entity tags, below this count.
    check_int(layout.edges.len() + layout.blocks.len())?;
    write_chunked(w, parts.edge_lines.len(), 1024, |r, out| {
        for e in r {
            let chain = parts.chain(e);
            let mut bin = Bin(out);
            bin.small(1);
            bin.small(e + 1);
            bin.small(1);
            bin.size(chain.len().saturating_sub(1));
            for (k, pair) in chain.windows(2).enumerate() {
                bin.size(parts.first_line[e] + k);
                bin.size(pair[0] as usize + 1);
                bin.size(pair[1] as usize + 1);
            }
        }
    })?;
    write_chunked(w, mesh.grids.len(), 16, |r, out| {
        for b in r {
            let g = &mesh.grids[b];
            let mut bin = Bin(out);
            bin.small(2);
            bin.small(b + 1);
            bin.small(3);
            bin.size(g.ni * g.nj);
            quads(parts, mesh, b, |q| {
                for v in q {
                    Bin(out).size(v);
                }
            });
        }
    })?;
    w.write_all(b"\n$EndElements\n")
}

/// `Ok` when `v` fits a Gmsh binary `int`.
fn check_int(v: usize) -> io::Result<()> {
    Bin(&mut Vec::new()).int(v as i64)
}
