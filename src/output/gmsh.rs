//! Gmsh `.msh` 4.1 ASCII: one conforming quad mesh (shared nodes merged through
//! [`crate::numbering`]), one surface entity per block, one curve entity per layout edge with its
//! 2-node line elements, and physical groups:
//! - `fluid` (dimension 2, tag 1): every block;
//! - `outer` (dimension 1, tag 2): the bounding circle;
//! - `interfaces` (dimension 1, tag 3): every block-to-block interface;
//! - `wall_N` (dimension 1, tag 10 + N): the wall of hole `N` (0-based, input order).

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
        for (e, edge) in layout.edges.iter().enumerate() {
            let chain = edge_lines[e].as_deref().unwrap_or(&[]);
            let b = bbox(chain.iter().map(|&n| nodes.coords[n as usize]));
            writeln!(
                w,
                "{} {:e} {:e} 0 {:e} {:e} 0 1 {} 0",
                e + 1,
                b[0],
                b[1],
                b[2],
                b[3],
                physical_of(edge.kind)
            )?;
        }
        for (b, block) in layout.blocks.iter().enumerate() {
            let bb = bbox(mesh.grids[b].nodes.iter().copied());
            write!(
                w,
                "{} {:e} {:e} 0 {:e} {:e} 0 1 {PHYSICAL_FLUID} 4",
                b + 1,
                bb[0],
                bb[1],
                bb[2],
                bb[3]
            )?;
            for side in &block.sides {
                let sign = if side.reversed { -1 } else { 1 };
                write!(w, " {}", sign * (side.edge as i64 + 1))?;
            }
            writeln!(w)?;
        }
        writeln!(w, "$EndEntities")?;

        let n = nodes.coords.len();
        writeln!(w, "$Nodes\n1 {n} 1 {n}\n2 1 0 {n}")?;
        for k in 1..=n {
            writeln!(w, "{k}")?;
        }
        for p in &nodes.coords {
            writeln!(w, "{:e} {:e} 0", p[0], p[1])?;
        }
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
        let mut tag = 1usize;
        for (e, chain) in edge_lines.iter().enumerate() {
            let chain = chain.as_deref().unwrap_or(&[]);
            writeln!(w, "1 {} 1 {}", e + 1, chain.len().saturating_sub(1))?;
            for pair in chain.windows(2) {
                writeln!(w, "{tag} {} {}", pair[0] + 1, pair[1] + 1)?;
                tag += 1;
            }
        }
        for (b, g) in mesh.grids.iter().enumerate() {
            let ids = &nodes.block_nodes[b];
            writeln!(w, "2 {} 3 {}", b + 1, g.ni * g.nj)?;
            let at = |i: usize, j: usize| ids[i + j * (g.ni + 1)] + 1;
            for j in 0..g.nj {
                for i in 0..g.ni {
                    writeln!(
                        w,
                        "{tag} {} {} {} {}",
                        at(i, j),
                        at(i + 1, j),
                        at(i + 1, j + 1),
                        at(i, j + 1)
                    )?;
                    tag += 1;
                }
            }
        }
        writeln!(w, "$EndElements")?;
        Ok(())
    })
}
