//! Holes meshed in a spatial order (issue 8): large bounded layouts are meshed with their
//! holes sorted along a Hilbert curve, and the mesh is given back in the input's hole ids.
//!
//! Every stage keeps its per-hole data in hole order (the samples circle by circle, the
//! triangles and medial arcs as the samples are met, the blocks as the arcs are). With the
//! holes in input order (a simulation's particles in particle-id order are scattered over the
//! domain) neighbouring holes lie far apart in those arrays, and at 1e5 holes each pass over
//! neighbours misses the caches: meshing 1e5 random bubbles in this order took the run from
//! 6.60 to 6.41 s (sampling 405 -> 283 ms, blocking 634 -> 580 ms). The blocks are then
//! numbered in a spatial order too (neighbouring blocks get nearby numbers, which a solver's
//! own passes over the blocks also like).
//!
//! The sorted layout is the same set of circles, so the same mesh up to the numbering of its
//! holes, blocks and vertices (bit for bit where no floating-point sum follows the order in
//! which triangles are met; `tests/perf_spatial_order.rs` checks the counts, the quality and
//! the walls); hole ids in the mesh ([`EdgeKind::Wall`], [`Block::wall`],
//! [`CocircularGroup::holes`]) and in the errors ([`MeshError::Sampling`]) are the input's,
//! and so are those of the options ([`Options::circle_clustering`],
//! [`Options::wall_cells`]). Inserted holes (ids from the hole count up) keep their ids.
//!
//! Periodic boxes likewise through [`crate::mesh_periodic`] (1e5 periodic bubbles: 15.9 ->
//! 14.3 s, 2 pairs), but not through
//! [`crate::periodic::mesh_periodic_frame`], which also gives the medial triples and block
//! keys in hole ids (normalised per image, for a sequence's comparisons).
//!
//! Below [`SPATIAL_ORDER_MIN_HOLES`] holes the working set fits in the caches and the input
//! order is kept, as it is with imposed counts ([`Options::imposed_counts`], a sequence's
//! later frames, whose keys and flags belong to the caller's options).
//!
//! [`Block::wall`]: crate::layout::Block::wall
//! [`CocircularGroup::holes`]: crate::cocircular::CocircularGroup::holes

use crate::domain::{Circle, CircleId};
use crate::layout::EdgeKind;
use crate::mesh::Mesh;
use crate::mesher::{MeshError, Options};
use rayon::prelude::*;

/// Layouts with at least this many holes are meshed in Hilbert order (1e5 random bubbles:
/// 6.60 -> 6.41 s; 1e4: the same time within the noise, 566 against 568 ms).
pub const SPATIAL_ORDER_MIN_HOLES: usize = 4096;

/// The order in which to mesh `holes` (a domain's, bounded or periodic; `order[k]` the input
/// id of the `k`-th hole meshed), or `None` to keep the input order: fewer than
/// [`SPATIAL_ORDER_MIN_HOLES`] holes, imposed counts, or holes already in that order.
pub fn hole_order(holes: &[Circle], options: &Options) -> Option<Vec<u32>> {
    if holes.len() < SPATIAL_ORDER_MIN_HOLES
        || holes.len() > u32::MAX as usize
        || options.imposed_counts.is_some()
    {
        return None;
    }
    let centres: Vec<crate::geometry::Point> = holes.iter().map(|h| h.center).collect();
    let order = crate::geometry::hilbert_order(&centres);
    let sorted = order.iter().enumerate().all(|(k, &i)| i as usize == k);
    (!sorted).then_some(order)
}

/// `mesh` of `domain` (whose holes are `holes`) with `options`, options checked: in
/// [`hole_order`] when there is one (the domain `reordered`, the options renamed to the
/// meshed ids, the mesh and its errors renamed back, [`Renaming`]), else as given. The one
/// round trip of [`crate::mesh()`] and [`crate::mesh_periodic`].
pub(crate) fn mesh_in_spatial_order<D>(
    domain: &D,
    holes: &[Circle],
    options: &Options,
    reordered: impl FnOnce(&D, &[u32]) -> D,
    mesh: impl Fn(&D, &Options) -> Result<Mesh, MeshError>,
) -> Result<Mesh, MeshError> {
    match hole_order(holes, options) {
        Some(order) => {
            let sorted = reordered(domain, &order);
            let renaming = Renaming::new(order);
            mesh(&sorted, &renaming.options(options))
                .map(|m| renaming.mesh(m))
                .map_err(|e| renaming.error(e))
        }
        None => mesh(domain, options),
    }
}

/// The input id of each meshed hole id: `input[k] = order[k]`, and the rank of each input id
/// (its meshed id), for renaming both ways.
pub struct Renaming {
    input: Vec<u32>,
    meshed: Vec<u32>,
}

impl Renaming {
    /// The renaming of [`hole_order`]'s `order`.
    pub fn new(order: Vec<u32>) -> Renaming {
        let mut meshed = vec![0; order.len()];
        for (k, &i) in order.iter().enumerate() {
            meshed[i as usize] = k as u32;
        }
        Renaming {
            input: order,
            meshed,
        }
    }

    /// The input id of meshed circle `c` (the bounding circle and inserted holes as they are).
    pub fn to_input(&self, c: CircleId) -> CircleId {
        self.rename(c, &self.input)
    }

    /// The meshed id of input circle `c`.
    pub fn to_meshed(&self, c: CircleId) -> CircleId {
        self.rename(c, &self.meshed)
    }

    fn rename(&self, c: CircleId, map: &[u32]) -> CircleId {
        match usize::try_from(c).ok().and_then(|i| map.get(i)) {
            Some(&j) => j as CircleId,
            None => c,
        }
    }

    /// `options` with its circle ids renamed to the meshed ones (the same entries in the same
    /// order, so that the same one wins where a circle is named twice).
    pub fn options(&self, options: &Options) -> Options {
        let mut o = options.clone();
        for (c, _) in &mut o.circle_clustering {
            *c = self.to_meshed(*c);
        }
        for (c, _) in &mut o.wall_cells {
            *c = self.to_meshed(*c);
        }
        o
    }

    /// `mesh`, made from the reordered domain, in the input's hole ids: the walls of its edges
    /// and blocks, and its co-circular groups (each group's holes sorted again, the groups in
    /// the order of their hole lists).
    pub fn mesh(&self, mut mesh: Mesh) -> Mesh {
        // In parallel: a million edges and half a million blocks at 1e5 holes.
        mesh.layout
            .edges
            .par_iter_mut()
            .with_min_len(4096)
            .for_each(|e| {
                if let EdgeKind::Wall(c) = &mut e.kind {
                    *c = self.to_input(*c);
                }
            });
        mesh.layout
            .blocks
            .par_iter_mut()
            .with_min_len(4096)
            .for_each(|b| {
                if let Some(c) = &mut b.wall {
                    *c = self.to_input(*c);
                }
            });
        for g in &mut mesh.cocircular_groups {
            for c in &mut g.holes {
                *c = self.to_input(*c);
            }
            g.holes.sort_unstable();
        }
        mesh.cocircular_groups.sort_by(|a, b| a.holes.cmp(&b.holes));
        mesh
    }

    /// `error` in the input's hole ids.
    pub fn error(&self, error: MeshError) -> MeshError {
        match error {
            MeshError::Sampling { circle, message } => MeshError::Sampling {
                circle: self.to_input(circle),
                message,
            },
            other => other,
        }
    }
}
