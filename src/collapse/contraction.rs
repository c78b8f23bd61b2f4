//! The contraction of [`super::contract`], indexed (issue 8): the block after each block end
//! is looked up in a table computed once per medial graph ([`successors`], kept by
//! [`super::Selection`] for every contraction of the local rebuilds) instead of a sort and a
//! binary search per block and call; clusters and sector extensions live in flat arrays
//! instead of one vector per cluster and two per block. Same result as the contraction as
//! first written ([`super::reference::contract`], the oracle of `tests/perf_blocking.rs`),
//! errors included.

use super::{find, internal, union_collapsed, Contracted};
use crate::medial::{MedialArc, MedialGraph, MedialVertex};
use crate::mesher::MeshError;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

/// No block starts at that corner.
pub(super) const NONE: u32 = u32::MAX;

/// The two corners `(medial vertex, sample)` of block `b` (`2e` on arc `e`'s C1, from
/// `(v0, c1[0])` to `(v1, c1.last)`; `2e + 1` on C2, from `(v1, c2.last)` to `(v0, c2[0])`).
/// The arc's chains must not be empty.
pub(super) fn corners(medial: &MedialGraph, b: usize) -> [(u32, u32); 2] {
    let arc = &medial.arcs[b / 2];
    let [v0, v1] = arc.ends;
    let (c1f, c1l) = (arc.c1[0], arc.c1[arc.c1.len() - 1]);
    let (c2f, c2l) = (arc.c2[0], arc.c2[arc.c2.len() - 1]);
    if b.is_multiple_of(2) {
        [(v0, c1f), (v1, c1l)]
    } else {
        [(v1, c2l), (v0, c2f)]
    }
}

/// The vertex of a cluster of `medial` vertices (`members`, in vertex order, not empty): its
/// first member, at the mean position of all members when there are several.
pub(super) fn merged_vertex(medial: &MedialGraph, members: &[u32]) -> MedialVertex {
    let mut v = medial.vertices[members[0] as usize].clone();
    if members.len() > 1 {
        let k = members.len() as f64;
        let sx: f64 = members
            .iter()
            .map(|&i| medial.vertices[i as usize].position[0])
            .sum();
        let sy: f64 = members
            .iter()
            .map(|&i| medial.vertices[i as usize].position[1])
            .sum();
        v.position = [sx / k, sy / k];
    }
    v
}

/// Kept arc `arc` of the sampled graph as an arc of the contraction: its ends the clusters
/// `ends`, its chains `c1` and `c2` (with the sector extensions), and each end of its polyline
/// moved to its cluster's merged position where that cluster has several vertices
/// (`merged`).
pub(super) fn kept_arc(
    arc: &MedialArc,
    ends: [u32; 2],
    merged: [bool; 2],
    vertices: &[MedialVertex],
    c1: Vec<u32>,
    c2: Vec<u32>,
) -> MedialArc {
    let mut polyline = arc.polyline.clone();
    let last = polyline.len() - 1;
    if merged[0] {
        polyline[0] = vertices[ends[0] as usize].position;
    }
    if merged[1] {
        polyline[last] = vertices[ends[1] as usize].position;
    }
    MedialArc {
        ends,
        end_slots: arc.end_slots,
        triangles: arc.triangles.clone(),
        polyline,
        circles: arc.circles,
        c1,
        c2,
    }
}

/// True when every arc has its ends in range and non-empty chains (what the contraction
/// checks first).
pub(super) fn well_formed(medial: &MedialGraph) -> bool {
    let n = medial.vertices.len();
    medial
        .arcs
        .iter()
        .all(|a| a.ends.iter().all(|&v| (v as usize) < n) && !a.c1.is_empty() && !a.c2.is_empty())
}

/// For each block of a well-formed `medial` ([`well_formed`]), the block starting at its end
/// corner ([`NONE`] when none does); an error when two blocks start at one corner. It does
/// not depend on which arcs are collapsed.
///
/// A corner's sample is one of the three samples of its medial vertex's triangle, so corners
/// are numbered `3 v + k` (`k` the sample's place in the triangle) and looked up in a table;
/// [`successors_by_search`] (sorting the corners) when a corner is not of that form.
pub(super) fn successors(medial: &MedialGraph) -> Result<Vec<u32>, MeshError> {
    let n = medial.vertices.len();
    let slot = |(v, s): (u32, u32)| -> Option<usize> {
        let k = medial
            .vertices
            .get(v as usize)?
            .samples
            .iter()
            .position(|&x| x == s)?;
        Some(3 * v as usize + k)
    };
    let m = medial.arcs.len();
    let mut start = vec![NONE; 3 * n];
    for b in 0..2 * m {
        let Some(at) = slot(corners(medial, b)[0]) else {
            return successors_by_search(medial);
        };
        if start[at] != NONE {
            return Err(internal("two blocks start at one corner"));
        }
        start[at] = b as u32;
    }
    Ok((0..2 * m)
        .map(|b| slot(corners(medial, b)[1]).map_or(NONE, |at| start[at]))
        .collect())
}

/// [`successors`] by sorting the start corners and searching every end corner.
pub(super) fn successors_by_search(medial: &MedialGraph) -> Result<Vec<u32>, MeshError> {
    let m = medial.arcs.len();
    let mut start_block: Vec<((u32, u32), u32)> = (0..2 * m)
        .map(|b| (corners(medial, b)[0], b as u32))
        .collect();
    start_block.sort_unstable();
    if start_block.windows(2).any(|w| w[0].0 == w[1].0) {
        return Err(internal("two blocks start at one corner"));
    }
    Ok((0..2 * m)
        .map(|b| {
            let corner = corners(medial, b)[1];
            start_block
                .binary_search_by(|x| x.0.cmp(&corner))
                .map_or(NONE, |i| start_block[i].1)
        })
        .collect())
}

/// The previous contraction of the same graph, whose arcs a new one may take over: its
/// collapse flags and the contraction itself (the arcs taken are left empty).
pub(crate) struct Previous<'a> {
    pub flags: &'a [bool],
    pub contracted: &'a mut Contracted,
}

/// The block ending a sector walk and the samples met ([`sector_run`]).
type SectorRun = (usize, Vec<u32>);

/// The sector walk from a block whose successor is `b` (its corner sample `first`): the
/// block `q` that ends it (the first one not collapsed) and the samples met, `first` and
/// then each collapsed block's wall without its first sample. It gives up (an error) once
/// `stop` is set, and sets it when it fails: a walk that does not end costs `2 m` steps, and
/// on the pool every walk into the same cycle would pay them.
fn sector_run(
    medial: &MedialGraph,
    collapse: &[bool],
    next: &[u32],
    first: u32,
    mut b: u32,
    stop: &AtomicBool,
) -> Result<SectorRun, MeshError> {
    let m = medial.arcs.len();
    let mut run = vec![first];
    let mut steps = 0;
    let fail = |message: &str| {
        stop.store(true, Relaxed);
        Err(internal(message))
    };
    let q = loop {
        if stop.load(Relaxed) {
            return Err(internal("a sector walk was given up"));
        }
        if b == NONE {
            return fail("no block starts at a corner");
        }
        let bu = b as usize;
        if !collapse[bu / 2] {
            break bu;
        }
        steps += 1;
        if steps > 2 * m {
            return fail("a sector does not end");
        }
        // The wall of block `bu` without its first sample.
        let arc = &medial.arcs[bu / 2];
        if bu.is_multiple_of(2) {
            run.extend_from_slice(&arc.c1[1..]);
        } else {
            run.extend(arc.c2.iter().rev().skip(1));
        }
        b = next[bu];
    };
    Ok((q, run))
}

/// [`super::contract`] with the [`successors`] of `medial` when known (`None`: computed here),
/// taking over from `previous` the arcs its flags cannot have changed. Besides the
/// contraction, for each of its arcs the index of the previous contraction's arc taken over
/// ([`NONE`] for an arc built afresh; empty without `previous`).
///
/// A *dirty* vertex is an end of an arc whose flag differs from the previous one; a cluster
/// without a dirty vertex has exactly its previous members (every collapsed arc at its
/// vertices is unchanged), hence the same merged position and the same sector walks at its
/// corners. A kept arc with both ends in such clusters is therefore the previous arc with its
/// ends renumbered: its chains, polyline and triangles are moved over, not rebuilt.
pub(super) fn contract_with(
    medial: &MedialGraph,
    collapse: &[bool],
    next: Option<&[u32]>,
    previous: Option<Previous<'_>>,
) -> Result<(Contracted, Vec<u32>), MeshError> {
    let n = medial.vertices.len();
    let m = medial.arcs.len();
    let mut parent = union_collapsed(medial, collapse)?;
    // Clusters numbered in order of their smallest vertex; members in vertex order, as one
    // array cut by `start`.
    let mut id_of_root = vec![u32::MAX; n];
    let mut cluster_of = vec![0u32; n];
    let mut cluster_size: Vec<u32> = Vec::new();
    for (v, cluster) in cluster_of.iter_mut().enumerate() {
        let r = find(&mut parent, v as u32) as usize;
        if id_of_root[r] == u32::MAX {
            id_of_root[r] = cluster_size.len() as u32;
            cluster_size.push(0);
        }
        *cluster = id_of_root[r];
        cluster_size[*cluster as usize] += 1;
    }
    drop((parent, id_of_root));
    let k = cluster_size.len();
    let mut start = Vec::with_capacity(k + 1);
    start.push(0u32);
    for &s in &cluster_size {
        start.push(start[start.len() - 1] + s);
    }
    let mut fill: Vec<u32> = start[..k].to_vec();
    let mut member = vec![0u32; n];
    for (v, &c) in cluster_of.iter().enumerate() {
        member[fill[c as usize] as usize] = v as u32;
        fill[c as usize] += 1;
    }
    drop(fill);
    let members = |c: usize| &member[start[c] as usize..start[c + 1] as usize];
    let vertices: Vec<MedialVertex> = (0..k).map(|c| merged_vertex(medial, members(c))).collect();

    let owned;
    let next = match next {
        Some(next) if next.len() == 2 * m => next,
        _ => {
            owned = successors(medial)?;
            &owned[..]
        }
    };
    // Sector extensions: per block, `(offset, len)` into `pool` of the samples added before
    // its wall (`ext_start`) and after it (`ext_end`), in wall direction.
    let mut ext_end: Vec<(u32, u32)> = vec![(0, 0); 2 * m];
    let mut ext_start: Vec<(u32, u32)> = vec![(0, 0); 2 * m];
    let mut pool: Vec<u32> = Vec::new();
    // The sector walks on the pool (issue 8: this loop over every block took 13-20 ms on one
    // CPU at 1e5 particles): only a block whose successor is collapsed has a run longer than
    // its corner sample, and those come back in block order, so the pool is that of the loop
    // over the blocks. A failed walk stops the others, and the walks are then taken again in
    // block order for the loop's first error.
    let walk_from = |p: usize, stop: &AtomicBool| {
        if collapse[p / 2] {
            return None;
        }
        let first = corners(medial, p)[1].1;
        let b = next[p];
        if b != NONE && !collapse[b as usize / 2] {
            return None;
        }
        Some((p, sector_run(medial, collapse, next, first, b, stop)))
    };
    let stop = AtomicBool::new(false);
    let walks: Vec<(usize, Result<SectorRun, MeshError>)> = {
        use rayon::prelude::*;
        (0..2 * m)
            .into_par_iter()
            .with_min_len(1024)
            .filter_map(|p| walk_from(p, &stop))
            .collect()
    };
    if stop.load(Relaxed) {
        let stop = AtomicBool::new(false);
        for p in 0..2 * m {
            if let Some((_, Err(e))) = walk_from(p, &stop) {
                return Err(e);
            }
        }
        return Err(internal("a sector walk failed on the pool only"));
    }
    for (p, walk) in walks {
        let (q, run) = walk?;
        if run.len() > 1 {
            let mid = (run.len() - 1) / 2;
            ext_end[p] = (pool.len() as u32, mid as u32);
            pool.extend_from_slice(&run[1..=mid]);
            ext_start[q] = (pool.len() as u32, (run.len() - 1 - mid) as u32);
            pool.extend_from_slice(&run[mid..run.len() - 1]);
        }
    }
    let ext = |(at, len): (u32, u32)| &pool[at as usize..(at + len) as usize];

    // Per sampled arc, the previous contraction's arc to take over (NONE: build it).
    let mut previous = previous.filter(|p| {
        p.flags.len() == m
            && p.contracted.kept.len() == p.contracted.graph.arcs.len()
            && p.contracted.kept.iter().all(|&e| (e as usize) < m)
    });
    let mut take_from: Vec<u32> = Vec::new();
    if let Some(p) = previous.as_ref() {
        let mut dirty = vec![false; k];
        for (e, arc) in medial.arcs.iter().enumerate() {
            if p.flags[e] != collapse[e] {
                for v in arc.ends {
                    dirty[cluster_of[v as usize] as usize] = true;
                }
            }
        }
        take_from = vec![NONE; m];
        for (at, &e) in p.contracted.kept.iter().enumerate() {
            let [v0, v1] = medial.arcs[e as usize].ends.map(|v| cluster_of[v as usize]);
            if !collapse[e as usize] && !dirty[v0 as usize] && !dirty[v1 as usize] {
                take_from[e as usize] = at as u32;
            }
        }
    }

    // The kept arcs in arc order: loops checked and previous arcs taken over one after the
    // other (the first loop's error, the takes in arc order, as the one-by-one construction),
    // then the others built in parallel (each a function of its arc, the clusters and the
    // extensions alone) into their places.
    let mut kept: Vec<u32> = Vec::with_capacity(collapse.iter().filter(|&&c| !c).count());
    kept.extend((0..m as u32).filter(|&e| !collapse[e as usize]));
    // A kept arc built afresh: a function of its arc, the clusters and the extensions alone.
    let build_arc = |e: u32| {
        let (e, arc) = (e as usize, &medial.arcs[e as usize]);
        let [v0, v1] = arc.ends.map(|v| cluster_of[v as usize]);
        // Block 2e: extension before, C1, extension after.
        let (before, after) = (ext(ext_start[2 * e]), ext(ext_end[2 * e]));
        let mut c1 = Vec::with_capacity(before.len() + arc.c1.len() + after.len());
        c1.extend_from_slice(before);
        c1.extend_from_slice(&arc.c1);
        c1.extend_from_slice(after);
        // Block 2e + 1 runs along C2 backwards: C2 is its wall reversed, with the
        // reversed extensions swapped.
        let (before, after) = (ext(ext_start[2 * e + 1]), ext(ext_end[2 * e + 1]));
        let mut c2 = Vec::with_capacity(before.len() + arc.c2.len() + after.len());
        c2.extend(after.iter().rev());
        c2.extend_from_slice(&arc.c2);
        c2.extend(before.iter().rev());
        let merged = [v0, v1].map(|v| cluster_size[v as usize] > 1);
        kept_arc(arc, [v0, v1], merged, &vertices, c1, c2)
    };
    let mut arcs: Vec<MedialArc> = Vec::with_capacity(kept.len());
    if previous.is_none() {
        // Nothing to take over: every kept arc built on the pool straight into its place
        // (issue 8: the serial pass that reserved the places took 10-12 ms at 1e5).
        use rayon::prelude::*;
        let is_loop = |&e: &u32| {
            let [v0, v1] = medial.arcs[e as usize].ends.map(|v| cluster_of[v as usize]);
            v0 == v1
        };
        if kept.par_iter().any(is_loop) {
            return Err(internal("a kept arc became a loop"));
        }
        kept.par_iter()
            .with_min_len(256)
            .map(|&e| build_arc(e))
            .collect_into_vec(&mut arcs);
    } else {
        let mut build = vec![false; kept.len()];
        for (at_kept, &e) in kept.iter().enumerate() {
            let arc = &medial.arcs[e as usize];
            let [v0, v1] = arc.ends.map(|v| cluster_of[v as usize]);
            if v0 == v1 {
                return Err(internal("a kept arc became a loop"));
            }
            if let (Some(p), Some(&at)) = (previous.as_mut(), take_from.get(e as usize)) {
                let old = p.contracted.graph.arcs.get_mut(at as usize);
                if let Some(old) = old.filter(|o| !o.c1.is_empty() && !o.c2.is_empty()) {
                    arcs.push(MedialArc {
                        ends: [v0, v1],
                        end_slots: arc.end_slots,
                        triangles: std::mem::take(&mut old.triangles),
                        polyline: std::mem::take(&mut old.polyline),
                        circles: arc.circles,
                        c1: std::mem::take(&mut old.c1),
                        c2: std::mem::take(&mut old.c2),
                    });
                    continue;
                }
            }
            arcs.push(MedialArc::default());
            build[at_kept] = true;
        }
        use rayon::prelude::*;
        arcs.par_iter_mut()
            .zip(kept.par_iter().zip(build.par_iter()))
            .with_min_len(256)
            .filter(|(_, (_, &b))| b)
            .for_each(|(slot, (&e, _))| *slot = build_arc(e));
    }
    // Per arc of the result, the previous arc taken over.
    let taken: Vec<u32> = if take_from.is_empty() {
        Vec::new()
    } else {
        kept.iter().map(|&e| take_from[e as usize]).collect()
    };
    Ok((
        Contracted {
            graph: MedialGraph { vertices, arcs },
            cluster_of,
            kept,
            cluster_size,
        },
        taken,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sector walks that never end (a successor table tampered into a cycle of collapsed
    /// blocks, entered from every kept block) fail with the error of the first block in
    /// order, as the walk block by block did, and stop early on the pool (each walk would
    /// otherwise take `2 m` steps).
    #[test]
    fn endless_sector_walks_fail_with_the_first_error() {
        let d = crate::layouts::bubbles(60, 4).unwrap();
        let s = crate::sampling::sample_and_triangulate(&d, &Default::default()).unwrap();
        let g = &s.medial;
        let m = g.arcs.len();
        assert!(m > 10);
        let mut collapse = vec![false; m];
        collapse[0] = true;
        collapse[1] = true;
        let mut next = successors(g).unwrap();
        // Blocks 0 -> 2 -> 0 (both collapsed) and every kept block's successor into it.
        next[0] = 2;
        next[2] = 0;
        next[4..].fill(0);
        let e = contract_with(g, &collapse, Some(&next), None).unwrap_err();
        assert!(e.to_string().contains("a sector does not end"), "{e}");
        // A missing successor met first (block 4's, the first kept block in order) is the
        // error, whatever the later walks give.
        next[4] = NONE;
        let e = contract_with(g, &collapse, Some(&next), None).unwrap_err();
        assert!(e.to_string().contains("no block starts at a corner"), "{e}");
        // Block 4 fine again (its successor kept): the cycle's error once more.
        next[4] = 6;
        let e = contract_with(g, &collapse, Some(&next), None).unwrap_err();
        assert!(e.to_string().contains("a sector does not end"), "{e}");
    }

    /// The corner table gives what the sorted search gives, on bubbles and on graphs whose
    /// corners were tampered with (a sample not of the vertex, two blocks at one corner).
    #[test]
    fn corner_table_equals_the_sorted_search() {
        let mut checked = 0;
        for (n, seed) in [(20, 1), (100, 2), (300, 3)] {
            let d = crate::layouts::bubbles(n, seed).unwrap();
            let s = crate::sampling::sample_and_triangulate(&d, &Default::default()).unwrap();
            let mut g = s.medial.clone();
            let mut variants = vec![g.clone()];
            g.arcs[0].c1[0] = g.arcs[1].c1[0];
            variants.push(g.clone());
            let mut g = s.medial.clone();
            let (e, f) = (3, 4);
            g.arcs[e].ends[0] = g.arcs[f].ends[0];
            g.arcs[e].c1[0] = g.arcs[f].c1[0];
            variants.push(g);
            for g in variants {
                let (a, b) = (successors(&g), successors_by_search(&g));
                match (a, b) {
                    (Ok(a), Ok(b)) => assert_eq!(a, b),
                    (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                    (a, b) => panic!("{:?} / {:?}", a.err(), b.err()),
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 9);
    }
}
