//! Gmsh `.msh` 4.1 ASCII: one conforming quad mesh (shared nodes merged through
//! [`crate::numbering`]), one surface entity per block, one curve entity per layout edge with its
//! 2-node line elements, and physical groups:
//! - `fluid` (dimension 2, tag 1): every block;
//! - `outer` (dimension 1, tag 2): the bounding circle;
//! - `interfaces` (dimension 1, tag 3): every block-to-block interface;
//! - `wall_N` (dimension 1, tag 10 + N): the wall of hole `N` (0-based, input order).

use super::text::{self, write_chunked};
use super::write_atomic;
use crate::layout::EdgeKind;
use crate::mesh::Mesh;
use crate::numbering::number_nodes;
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
    let layout = &mesh.layout;
    let nodes = number_nodes(layout, &mesh.grids);
    // Line elements of every edge, from the first block side that uses it.
    let mut edge_lines: Vec<Option<Vec<u32>>> = vec![None; layout.edges.len()];
    for (b, block) in layout.blocks.iter().enumerate() {
        let g = &mesh.grids[b];
        let ids = &nodes.block_nodes[b];
        for (s, side) in block.sides.iter().enumerate() {
            let e = side.edge as usize;
            if edge_lines[e].is_some() {
                continue;
            }
            let mut chain: Vec<u32> = match s {
                0 => (0..=g.ni).map(|i| ids[i]).collect(),
                1 => (0..=g.nj).map(|j| ids[g.ni + j * (g.ni + 1)]).collect(),
                2 => (0..=g.ni)
                    .rev()
                    .map(|i| ids[i + g.nj * (g.ni + 1)])
                    .collect(),
                _ => (0..=g.nj).rev().map(|j| ids[j * (g.ni + 1)]).collect(),
            };
            if side.reversed {
                chain.reverse();
            }
            edge_lines[e] = Some(chain);
        }
    }
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

    write_atomic(path, |w| {
        writeln!(w, "$MeshFormat\n4.1 0 8\n$EndMeshFormat")?;
        let nphys = 1 + usize::from(has_outer) + usize::from(has_interfaces) + walls.len();
        writeln!(w, "$PhysicalNames\n{nphys}")?;
        writeln!(w, "2 {PHYSICAL_FLUID} \"fluid\"")?;
        if has_outer {
            writeln!(w, "1 {PHYSICAL_OUTER} \"outer\"")?;
        }
        if has_interfaces {
            writeln!(w, "1 {PHYSICAL_INTERFACES} \"interfaces\"")?;
        }
        for c in &walls {
            writeln!(w, "1 {} \"wall_{c}\"", PHYSICAL_WALL_BASE + c)?;
        }
        writeln!(w, "$EndPhysicalNames")?;

        // Entities: curves = layout edges (tag e + 1), surfaces = blocks (tag b + 1).
        writeln!(w, "$Entities")?;
        writeln!(w, "0 {} {} 0", layout.edges.len(), layout.blocks.len())?;
        write_chunked(w, layout.edges.len(), 1024, |r, out| {
            for e in r {
                let chain = edge_lines[e].as_deref().unwrap_or(&[]);
                let b = bbox(chain.iter().map(|&n| nodes.coords[n as usize]));
                text::int(out, e + 1);
                entity_box(out, b);
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
                    let sign = if side.reversed { -1 } else { 1 };
                    out.push(b' ');
                    text::int(out, sign * (side.edge as i64 + 1));
                }
                out.push(b'\n');
            }
        })?;
        writeln!(w, "$EndEntities")?;

        let n = nodes.coords.len();
        writeln!(w, "$Nodes\n1 {n} 1 {n}\n2 1 0 {n}")?;
        write_chunked(w, n, 8192, |r, out| {
            for k in r {
                text::int(out, k + 1);
                out.push(b'\n');
            }
        })?;
        write_chunked(w, n, 4096, |r, out| {
            for p in &nodes.coords[r] {
                text::exp(out, p[0]);
                out.push(b' ');
                text::exp(out, p[1]);
                out.extend_from_slice(b" 0\n");
            }
        })?;
        writeln!(w, "$EndNodes")?;

        let nlines: usize = edge_lines
            .iter()
            .map(|c| c.as_ref().map_or(0, |c| c.len().saturating_sub(1)))
            .sum();
        let nquads: usize = mesh.grids.iter().map(|g| g.ni * g.nj).sum();
        let total = nlines + nquads;
        writeln!(w, "$Elements")?;
        writeln!(
            w,
            "{} {total} 1 {total}",
            layout.edges.len() + layout.blocks.len()
        )?;
        // Element tags run 1.. over the edges' lines, then the blocks' quads: each chunk
        // starts from the tags of what precedes it.
        let mut first_line = Vec::with_capacity(edge_lines.len() + 1);
        first_line.push(1usize);
        for c in &edge_lines {
            let k = c.as_ref().map_or(0, |c| c.len().saturating_sub(1));
            first_line.push(first_line.last().copied().unwrap_or(1) + k);
        }
        write_chunked(w, edge_lines.len(), 1024, |r, out| {
            for e in r {
                let chain = edge_lines[e].as_deref().unwrap_or(&[]);
                out.extend_from_slice(b"1 ");
                text::int(out, e + 1);
                out.extend_from_slice(b" 1 ");
                text::int(out, chain.len().saturating_sub(1));
                out.push(b'\n');
                for (k, pair) in chain.windows(2).enumerate() {
                    line_of_ints(
                        out,
                        &[
                            first_line[e] + k,
                            pair[0] as usize + 1,
                            pair[1] as usize + 1,
                        ],
                    );
                }
            }
        })?;
        let mut first_quad = Vec::with_capacity(mesh.grids.len() + 1);
        first_quad.push(first_line.last().copied().unwrap_or(1));
        for g in &mesh.grids {
            first_quad.push(first_quad.last().copied().unwrap_or(1) + g.ni * g.nj);
        }
        write_chunked(w, mesh.grids.len(), 16, |r, out| {
            for b in r {
                let (g, ids) = (&mesh.grids[b], &nodes.block_nodes[b]);
                line_of_ints(out, &[2, b + 1, 3, g.ni * g.nj]);
                let at = |i: usize, j: usize| ids[i + j * (g.ni + 1)] as usize + 1;
                let mut tag = first_quad[b];
                for j in 0..g.nj {
                    for i in 0..g.ni {
                        line_of_ints(
                            out,
                            &[tag, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)],
                        );
                        tag += 1;
                    }
                }
            }
        })?;
        writeln!(w, "$EndElements")?;
        Ok(())
    })
}
