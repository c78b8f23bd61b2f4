//! `connectivity.json`: the block connectivity of [`crate::connectivity`] as a documented JSON
//! file.
//!
//! ```text
//! {
//!   "conventions": "...",              // the index conventions, in words
//!   "blocks": [
//!     {"block": 0, "dims": [ni+1, nj+1],
//!      "sides": [
//!        {"side": 0, "name": "j_min", "kind": "wall", "circle": 3},
//!        {"side": 1, "name": "i_max", "kind": "interface",
//!         "partner": {"block": 5, "side": 3, "same_direction": false},
//!         "cgns": {"point_range": [[ni+1,1],[ni+1,nj+1]], "point_range_donor": [...],
//!                  "transform": [1, 2]}},
//!        ...]}]
//! }
//! ```
//! Kinds: `wall` (a hole, `circle` its 0-based input index), `outer` (the bounding circle,
//! `circle` -1), `interface` (another block), `periodic` (periodic meshes: the partner side on
//! the opposite boundary of the period, with `"translation": [tx, ty]`, the vector moving
//! this side's nodes onto the partner's). CGNS ranges are 1-based.

use super::write_atomic;
use crate::connectivity::BlockConnectivity;
use serde::Serialize;
use std::io::{self, Write};
use std::path::Path;

/// The conventions string written into the file.
pub const CONVENTIONS: &str = "Block node (i, j) for i in 0..=ni, j in 0..=nj; corners c0..c3 \
counter-clockwise; side 0 'j_min' runs c0->c1 (j = 0, i increasing), side 1 'i_max' c1->c2 \
(i = ni, j increasing), side 2 'j_max' c2->c3 (j = nj, i decreasing), side 3 'i_min' c3->c0 \
(i = 0, j decreasing). Medial blocks: side 0 on the wall, side 2 on the medial axis. Node p \
(0-based, in the side's direction) of a side is node p of the partner side when same_direction \
is true, else node n - p. CGNS ranges are 1-based (i, j); transform[a] = +-(b+1) maps this \
block's index a to the donor's index b. Kind 'periodic': the partner is on the opposite \
boundary of the period and its nodes are this side's plus 'translation'.";

#[derive(Serialize)]
struct File<'a> {
    conventions: &'static str,
    blocks: &'a [BlockConnectivity],
}

/// Write `connectivity.json`.
pub fn write_json(blocks: &[BlockConnectivity], path: &Path) -> io::Result<()> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(
            &mut *w,
            &File {
                conventions: CONVENTIONS,
                blocks,
            },
        )
        .map_err(io::Error::other)?;
        writeln!(w)
    })
}
