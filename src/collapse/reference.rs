//! The contraction as first written ([`contract`]): the oracle of the indexed one
//! ([`super::contract`]), kept for the tests (`tests/perf_blocking.rs`).

use super::contraction::{self, kept_arc, merged_vertex};
use super::{find, internal, union_collapsed, Contracted};
use crate::medial::{MedialGraph, MedialVertex};
use crate::mesher::MeshError;

/// Contract the arcs marked in `collapse` (one flag per arc; they must form a forest, as
/// [`super::select`] guarantees; a cycle or a kept arc with both ends in one cluster is an
/// [`MeshError::Internal`]).
pub fn contract(medial: &MedialGraph, collapse: &[bool]) -> Result<Contracted, MeshError> {
    let n = medial.vertices.len();
    let m = medial.arcs.len();
    let mut parent = union_collapsed(medial, collapse)?;
    let mut id_of_root = vec![u32::MAX; n];
    let mut cluster_of = vec![0u32; n];
    let mut members: Vec<Vec<u32>> = Vec::new();
    for (v, cluster) in cluster_of.iter_mut().enumerate() {
        let r = find(&mut parent, v as u32) as usize;
        if id_of_root[r] == u32::MAX {
            id_of_root[r] = members.len() as u32;
            members.push(Vec::new());
        }
        *cluster = id_of_root[r];
        members[id_of_root[r] as usize].push(v as u32);
    }
    let vertices: Vec<MedialVertex> = members.iter().map(|ms| merged_vertex(medial, ms)).collect();

    // Blocks: 2e on C1 (wall c1, from corner (v0, c1[0]) to (v1, c1.last)), 2e + 1 on C2
    // (wall c2 reversed, from (v1, c2.last) to (v0, c2[0])).
    let wall = |b: usize| -> Vec<u32> {
        let arc = &medial.arcs[b / 2];
        if b.is_multiple_of(2) {
            arc.c1.clone()
        } else {
            arc.c2.iter().rev().copied().collect()
        }
    };
    let corners = |b: usize| contraction::corners(medial, b);
    // The block starting at each corner: sorted by corner, found by binary search (no
    // hashing of 2m keys, issue 8).
    let mut start_block: Vec<((u32, u32), usize)> =
        (0..2 * m).map(|b| (corners(b)[0], b)).collect();
    start_block.sort_unstable();
    if start_block.windows(2).any(|w| w[0].0 == w[1].0) {
        return Err(internal("two blocks start at one corner"));
    }
    let block_at = |corner: (u32, u32)| -> Option<usize> {
        let i = start_block.binary_search_by(|x| x.0.cmp(&corner)).ok()?;
        Some(start_block[i].1)
    };
    let mut ext_end: Vec<Vec<u32>> = vec![Vec::new(); 2 * m];
    let mut ext_start: Vec<Vec<u32>> = vec![Vec::new(); 2 * m];
    for p in 0..2 * m {
        if collapse[p / 2] {
            continue;
        }
        let mut corner = corners(p)[1];
        let mut run = vec![corner.1];
        let mut steps = 0;
        let q = loop {
            let b = block_at(corner).ok_or_else(|| internal("no block starts at a corner"))?;
            if !collapse[b / 2] {
                break b;
            }
            steps += 1;
            if steps > 2 * m {
                return Err(internal("a sector does not end"));
            }
            run.extend_from_slice(&wall(b)[1..]);
            corner = corners(b)[1];
        };
        if run.len() > 1 {
            let mid = (run.len() - 1) / 2;
            ext_end[p] = run[1..=mid].to_vec();
            ext_start[q] = run[mid..run.len() - 1].to_vec();
        }
    }

    let mut arcs = Vec::with_capacity(m);
    let mut kept = Vec::with_capacity(m);
    for (e, arc) in medial.arcs.iter().enumerate() {
        if collapse[e] {
            continue;
        }
        let [v0, v1] = arc.ends.map(|v| cluster_of[v as usize]);
        if v0 == v1 {
            return Err(internal("a kept arc became a loop"));
        }
        let build = |b: usize| -> Vec<u32> {
            let mut w = ext_start[b].clone();
            w.extend(wall(b));
            w.extend_from_slice(&ext_end[b]);
            w
        };
        let c1 = build(2 * e);
        let mut c2 = build(2 * e + 1);
        c2.reverse();
        let merged = [v0, v1].map(|v| members[v as usize].len() > 1);
        arcs.push(kept_arc(arc, [v0, v1], merged, &vertices, c1, c2));
        kept.push(e as u32);
    }
    Ok(Contracted {
        graph: MedialGraph { vertices, arcs },
        cluster_of,
        kept,
        cluster_size: members.iter().map(|m| m.len() as u32).collect(),
    })
}
