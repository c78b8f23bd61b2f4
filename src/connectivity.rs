//! Block-to-block connectivity: for every block side its kind (wall, outer boundary,
//! interface) and, for interfaces, the partner block and side with the index orientation, also
//! in CGNS 1-to-1 terms (point range, donor range, transform).
//!
//! Periodic meshes ([`crate::periodic`]): a side on the period's boundary has kind
//! [`SideKind::Periodic`], its partner on the opposite boundary and the `translation` that
//! moves its nodes onto the partner's (the partner's orientation and CGNS terms are as for an
//! interface, with the periodic shift applied to coordinates).
//!
//! Everything here is derived from the [`BlockLayout`] topology (which edge each side uses and
//! in which direction) and the node counts of the grids; no coordinates are compared.

use crate::domain::CircleId;
use crate::layout::{BlockLayout, EdgeKind};
use crate::mesh::BlockGrid;
use rayon::prelude::*;
use serde::Serialize;

/// Names of the four sides in index terms, by side number (see [`crate::layout`]).
pub const SIDE_NAMES: [&str; 4] = ["j_min", "i_max", "j_max", "i_min"];

/// What lies across a block side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SideKind {
    /// The wall of hole `circle`.
    Wall,
    /// The bounding circle (the outer boundary of the body-fitted region).
    Outer,
    /// Another block.
    Interface,
    /// The copy of this side on the opposite boundary of a periodic mesh's period: the
    /// partner side's nodes are this side's plus `translation`.
    Periodic,
}

/// A block side's partner across an interface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Partner {
    pub block: usize,
    pub side: usize,
    /// True when the partner side's node order runs the same way along the shared edge as
    /// this side's (then node `p` of this side is node `p` of the partner side); false when
    /// opposite (node `p` is node `n - p`), the usual case for two counter-clockwise blocks.
    pub same_direction: bool,
}

/// CGNS 1-to-1 interface description, 1-based indices as in CGNS `GridConnectivity1to1_t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Cgns1to1 {
    /// `[[i_begin, j_begin], [i_end, j_end]]` in this block.
    pub point_range: [[usize; 2]; 2],
    /// The matching range in the donor block: `point_range[0]` is the same node as
    /// `point_range_donor[0]`, likewise for the ends.
    pub point_range_donor: [[usize; 2]; 2],
    /// CGNS transform: `transform[a] = ±(b + 1)` when a step `+1` along this block's index
    /// `a` (0 = i, 1 = j) is a step `±1` along the donor's index `b`.
    pub transform: [i32; 2],
}

/// Connectivity of one block side.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SideConnectivity {
    pub side: usize,
    pub name: &'static str,
    pub kind: SideKind,
    /// For walls and the outer boundary: the circle (`-1` the bounding circle).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub circle: Option<CircleId>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub partner: Option<Partner>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cgns: Option<Cgns1to1>,
    /// For periodic sides: the vector that moves this side's nodes onto the partner's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub translation: Option<[f64; 2]>,
}

/// Connectivity of one block.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlockConnectivity {
    pub block: usize,
    /// Node counts `[ni + 1, nj + 1]`.
    pub dims: [usize; 2],
    pub sides: [SideConnectivity; 4],
}

/// Why the layout's topology is not a valid multiblock connectivity.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ConnectivityError {
    #[error("edge {edge} is used by {count} block sides (a wall needs 1, an interface 2)")]
    EdgeUse { edge: usize, count: usize },
    #[error("the layout has {layout} blocks but {grids} grids were given")]
    GridCount { layout: usize, grids: usize },
    #[error("block side references edge {edge}, which does not exist")]
    MissingEdge { edge: usize },
}

/// (axis, sign) of the index direction along side `s` in the side's own direction.
fn along(s: usize) -> (usize, i32) {
    [(0, 1), (1, 1), (0, -1), (1, -1)][s]
}

/// (axis, sign) of the index direction pointing from side `s` into the block.
fn inward(s: usize) -> (usize, i32) {
    [(1, 1), (0, -1), (1, -1), (0, 1)][s]
}

/// 1-based `[i, j]` of node `p` (0-based, in the side's direction) along side `s`.
fn side_node(s: usize, p: usize, ni: usize, nj: usize) -> [usize; 2] {
    let (i, j) = match s {
        0 => (p, 0),
        1 => (ni, p),
        2 => (ni - p, nj),
        _ => (0, nj - p),
    };
    [i + 1, j + 1]
}

/// Compute the connectivity of every block: [`Connectivity::new`], then every block's record
/// ([`Connectivity::to_vec`]).
///
/// The blocks are visited in parallel (on the current rayon pool); each block's entry depends
/// only on the layout, the grids and the edge users, so the result, and the error (that of the
/// first failing block in block order), is the same for every thread count.
pub fn connectivity(
    layout: &BlockLayout,
    grids: &[BlockGrid],
) -> Result<Vec<BlockConnectivity>, ConnectivityError> {
    Connectivity::new(layout, grids).map(|c| c.to_vec())
}

/// The block connectivity of a mesh, checked, without the per-block records: the partner of
/// every block side (8 bytes a side, where a [`SideConnectivity`] takes about 170: at 1e5
/// particles 19 MB instead of 0.4 GB of fresh memory, issue 8). [`Connectivity::block`] forms
/// a block's [`BlockConnectivity`] when it is needed, equal to the entry of [`connectivity`].
///
/// ```
/// use medial_blocks::connectivity::{connectivity, Connectivity};
/// use medial_blocks::{mesh, Domain, Options};
///
/// let m = mesh(&Domain::hexagon_example(), &Options::default()).unwrap();
/// let conn = Connectivity::new(&m.layout, &m.grids).unwrap();
/// let records = connectivity(&m.layout, &m.grids).unwrap();
/// assert_eq!(conn.len(), records.len());
/// assert_eq!(conn.block(3), Some(records[3].clone()));
/// assert_eq!(conn.partner(3, 2), records[3].sides[2].partner);
/// ```
#[derive(Debug, Clone)]
pub struct Connectivity<'a> {
    layout: &'a BlockLayout,
    grids: &'a [BlockGrid],
    /// Per block, per side: [`pack`]ed partner, or [`NO_PARTNER`] for a wall.
    partners: Vec<[u64; 4]>,
}

/// [`Connectivity::partners`] entry of a side without a partner (a wall or the outer boundary).
const NO_PARTNER: u64 = u64::MAX;

/// A partner in 8 bytes: `(4 block + side) << 1 | same_direction`.
fn pack(p: Partner) -> u64 {
    ((4 * p.block as u64 + p.side as u64) << 1) | u64::from(p.same_direction)
}

/// The partner of a [`pack`]ed entry (`None` for [`NO_PARTNER`]).
fn unpack(x: u64) -> Option<Partner> {
    (x != NO_PARTNER).then_some(Partner {
        block: (x >> 3) as usize,
        side: ((x >> 1) & 3) as usize,
        same_direction: x & 1 == 1,
    })
}

impl<'a> Connectivity<'a> {
    /// Check the layout's topology against the grids and find every side's partner: the
    /// errors of [`connectivity`] (the first failing block in block order, and its first
    /// failing side), blocks in parallel on the current rayon pool.
    pub fn new(
        layout: &'a BlockLayout,
        grids: &'a [BlockGrid],
    ) -> Result<Connectivity<'a>, ConnectivityError> {
        if layout.blocks.len() != grids.len() {
            return Err(ConnectivityError::GridCount {
                layout: layout.blocks.len(),
                grids: grids.len(),
            });
        }
        let users = EdgeUsers::new(layout)?;
        // Blocks in parallel, written in place in block order; an error keeps the one of the
        // smallest block (the one a visit in block order meets first: each block's result
        // does not depend on the others).
        let first_error = std::sync::Mutex::new(None::<(usize, ConnectivityError)>);
        let mut partners = Vec::with_capacity(layout.blocks.len());
        (0..layout.blocks.len())
            .into_par_iter()
            .with_min_len(PARALLEL_BLOCKS)
            .with_max_len(4 * PARALLEL_BLOCKS)
            .map(|b| {
                if let Some(ahead) = layout.blocks.get(b + PREFETCH_BLOCKS) {
                    users.prefetch(layout, ahead);
                }
                let mut packed = [NO_PARTNER; 4];
                for (s, x) in packed.iter_mut().enumerate() {
                    match side_partner(layout, &users, b, s) {
                        Ok(p) => *x = p.map_or(NO_PARTNER, pack),
                        Err(e) => {
                            let mut first = first_error.lock().unwrap_or_else(|p| p.into_inner());
                            if first.as_ref().is_none_or(|(at, _)| b < *at) {
                                *first = Some((b, e));
                            }
                            break;
                        }
                    }
                }
                packed
            })
            .collect_into_vec(&mut partners);
        match first_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
            Some((_, e)) => Err(e),
            None => Ok(Connectivity {
                layout,
                grids,
                partners,
            }),
        }
    }

    /// Number of blocks.
    pub fn len(&self) -> usize {
        self.partners.len()
    }

    /// True when the mesh has no block.
    pub fn is_empty(&self) -> bool {
        self.partners.is_empty()
    }

    /// The partner of side `side` of block `block` (`None` for a wall, the outer boundary, or
    /// a block or side out of range).
    pub fn partner(&self, block: usize, side: usize) -> Option<Partner> {
        unpack(*self.partners.get(block)?.get(side)?)
    }

    /// The record of block `b`, as [`connectivity`] gives it (`None` when `b` is out of range).
    pub fn block(&self, b: usize) -> Option<BlockConnectivity> {
        let packed = self.partners.get(b)?;
        Some(BlockConnectivity {
            block: b,
            dims: self.dims(b)?,
            sides: [0, 1, 2, 3].map(|s| side_record(self.layout, self.grids, b, s, packed[s])),
        })
    }

    /// The node counts `[ni + 1, nj + 1]` of block `b` ([`BlockConnectivity::dims`]; `None`
    /// when `b` is out of range).
    pub fn dims(&self, b: usize) -> Option<[usize; 2]> {
        self.partners.get(b)?;
        let g = self.grids.get(b)?;
        Some([g.ni + 1, g.nj + 1])
    }

    /// The record of side `s` of block `b` (`self.block(b)?.sides[s]`), formed alone: a
    /// writer that takes the sides one at a time does not move whole block records (about 700
    /// bytes, copied by `memcpy` calls: issue 8).
    pub fn side(&self, b: usize, s: usize) -> Option<SideConnectivity> {
        let packed = *self.partners.get(b)?.get(s)?;
        Some(side_record(self.layout, self.grids, b, s, packed))
    }

    /// Every block's record, in block order (blocks in parallel on the current rayon pool).
    pub fn to_vec(&self) -> Vec<BlockConnectivity> {
        (0..self.len())
            .into_par_iter()
            .with_min_len(PARALLEL_BLOCKS)
            .with_max_len(4 * PARALLEL_BLOCKS)
            .map(|b| self.block(b))
            .collect::<Option<Vec<_>>>()
            .unwrap_or_default()
    }
}

/// Blocks per task of [`Connectivity`]'s parallel loops (each block is cheap: a task of this
/// many amortises the scheduling).
const PARALLEL_BLOCKS: usize = 512;

/// The record of a side on the wall of `circle` (the outer boundary for a negative id).
fn wall_side(circle: CircleId) -> impl Fn(usize) -> SideConnectivity {
    move |s| SideConnectivity {
        side: s,
        name: SIDE_NAMES[s],
        kind: if circle < 0 {
            SideKind::Outer
        } else {
            SideKind::Wall
        },
        circle: Some(circle),
        partner: None,
        cgns: None,
        translation: None,
    }
}

/// The partner of side `s` of block `b`, checked against its edge's users: `None` on a wall
/// (the edge has one user), the other user of an interface edge (two users), the one user of
/// a periodic edge's partner edge.
fn side_partner(
    layout: &BlockLayout,
    users: &EdgeUsers,
    b: usize,
    s: usize,
) -> Result<Option<Partner>, ConnectivityError> {
    let block = &layout.blocks[b];
    let e = block.sides[s].edge as usize;
    let u = users.of(e);
    let count_error = ConnectivityError::EdgeUse {
        edge: e,
        count: u.len(),
    };
    let (pb, ps) = match layout.edges[e].kind {
        EdgeKind::Wall(_) if u.len() == 1 => return Ok(None),
        EdgeKind::Wall(_) => return Err(count_error),
        EdgeKind::Periodic { partner, .. } => {
            let p = partner as usize;
            if p >= layout.edges.len() {
                return Err(ConnectivityError::MissingEdge { edge: p });
            }
            let pu = users.of(p);
            if u.len() != 1 || pu.len() != 1 {
                return Err(count_error);
            }
            pu.get(0)
        }
        _ if u.len() != 2 => return Err(count_error),
        _ if u.get(0) == (b, s) => u.get(1),
        _ => u.get(0),
    };
    Ok(Some(Partner {
        block: pb,
        side: ps,
        same_direction: layout.blocks[pb].sides[ps].reversed == block.sides[s].reversed,
    }))
}

/// The record of side `s` of block `b` whose [`pack`]ed partner is `packed` (from
/// [`side_partner`]): kind, circle and translation from the side's edge, the CGNS terms from
/// the two blocks' node counts.
fn side_record(
    layout: &BlockLayout,
    grids: &[BlockGrid],
    b: usize,
    s: usize,
    packed: u64,
) -> SideConnectivity {
    let kind = layout.edges[layout.blocks[b].sides[s].edge as usize].kind;
    let Some(Partner {
        block: pb,
        side: ps,
        same_direction: same,
    }) = unpack(packed)
    else {
        // No partner: a wall side ([`Connectivity::new`] checked the edge's kind and users).
        return wall_side(match kind {
            EdgeKind::Wall(c) => c,
            _ => 0,
        })(s);
    };
    let (g, pg) = (&grids[b], &grids[pb]);
    let n = if s.is_multiple_of(2) { g.ni } else { g.nj };
    let q = |p: usize| if same { p } else { n - p };
    let (aa, sa) = along(s);
    let (ab, sb) = along(ps);
    let (na, ia) = inward(s);
    let (nb, ib) = inward(ps);
    let dir = if same { 1 } else { -1 };
    let mut transform = [0i32; 2];
    transform[aa] = sa * sb * dir * (ab as i32 + 1);
    transform[na] = -ia * ib * (nb as i32 + 1);
    let translation = match kind {
        EdgeKind::Periodic { translation, .. } => Some(translation.0),
        _ => None,
    };
    SideConnectivity {
        side: s,
        name: SIDE_NAMES[s],
        kind: if translation.is_some() {
            SideKind::Periodic
        } else {
            SideKind::Interface
        },
        circle: None,
        partner: Some(Partner {
            block: pb,
            side: ps,
            same_direction: same,
        }),
        cgns: Some(Cgns1to1 {
            point_range: [side_node(s, 0, g.ni, g.nj), side_node(s, n, g.ni, g.nj)],
            point_range_donor: [
                side_node(ps, q(0), pg.ni, pg.nj),
                side_node(ps, q(n), pg.ni, pg.nj),
            ],
            transform,
        }),
        translation,
    }
}

/// How many blocks ahead [`connectivity`] asks for the edges of a block's sides: a side's
/// edge and its users are far apart in memory (a cache miss each at 1e4 particles, 40% of
/// the pass), the hint lets the misses of several blocks overlap.
const PREFETCH_BLOCKS: usize = 8;

/// The block sides using each edge, in block then side order: how many, and the first two
/// (all a valid layout has). Two flat arrays instead of one small `Vec` per edge (issue 8:
/// 1.2 M edges at 1e5 particles); [`EdgeUsers::of`] is the list the per-edge vectors held,
/// cut after two entries, so every check on it (its length, its entries) reads the same.
/// A side `(b, s)` is stored as `4 b + s` (`s < 4`): 16 bytes per edge instead of 32.
struct EdgeUsers {
    count: Vec<u32>,
    first: Vec<[u64; 2]>,
}

/// One edge's users: `len` (the full count) and the first `min(len, 2)` entries.
struct Users {
    count: usize,
    first: [u64; 2],
}

impl Users {
    fn len(&self) -> usize {
        self.count
    }

    /// User `k` (`k < min(len, 2)`) as `(block, side)`.
    fn get(&self, k: usize) -> (usize, usize) {
        assert!(
            k < self.count.min(2),
            "user {k} of an edge with {} users",
            self.count
        );
        let x = self.first[k];
        ((x >> 2) as usize, (x & 3) as usize)
    }
}

impl EdgeUsers {
    /// Count and record every block side's edge; a side naming a missing edge is an error
    /// (the first such side in block order, as before).
    fn new(layout: &BlockLayout) -> Result<EdgeUsers, ConnectivityError> {
        let ne = layout.edges.len();
        let mut count = vec![0u32; ne];
        let mut first = vec![[0u64; 2]; ne];
        for (b, block) in layout.blocks.iter().enumerate() {
            for (s, side) in block.sides.iter().enumerate() {
                let e = side.edge as usize;
                let c = count
                    .get_mut(e)
                    .ok_or(ConnectivityError::MissingEdge { edge: e })?;
                if *c < 2 {
                    first[e][*c as usize] = 4 * b as u64 + s as u64;
                }
                *c = c.saturating_add(1);
            }
        }
        Ok(EdgeUsers { count, first })
    }

    /// Ask for the edges of `block`'s sides and their users to be brought into the cache.
    fn prefetch(&self, layout: &BlockLayout, block: &crate::layout::Block) {
        for side in &block.sides {
            let e = side.edge as usize;
            crate::prefetch::read(layout.edges.as_ptr().wrapping_add(e));
            crate::prefetch::read(self.count.as_ptr().wrapping_add(e));
            crate::prefetch::read(self.first.as_ptr().wrapping_add(e));
        }
    }

    /// The users of edge `e` (`e` in range).
    fn of(&self, e: usize) -> Users {
        Users {
            count: self.count[e] as usize,
            first: self.first[e],
        }
    }
}
