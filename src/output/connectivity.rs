//! `connectivity.json`: the block connectivity of [`crate::connectivity`] as a documented JSON
//! file.
//!
//! One block per line (compact JSON inside a block, so the file stays readable line by line
//! and is about a third of the pretty-printed size: 4.6 MB instead of 13.8 MB for 5 904
//! blocks, issue 8):
//!
//! ```text
//! {
//!   "conventions": "...",              // the index conventions, in words
//!   "blocks": [
//!     {"block":0,"dims":[ni+1,nj+1],"sides":[{"side":0,"name":"j_min","kind":"wall","circle":3},{"side":1,"name":"i_max","kind":"interface","partner":{"block":5,"side":3,"same_direction":false},"cgns":{"point_range":[[ni+1,1],[ni+1,nj+1]],"point_range_donor":[...],"transform":[1,2]}},...]},
//!     ...
//!   ]
//! }
//! ```
//! Kinds: `wall` (a hole, `circle` its 0-based input index), `outer` (the bounding circle,
//! `circle` -1), `interface` (another block), `periodic` (periodic meshes: the partner side on
//! the opposite boundary of the period, with `"translation": [tx, ty]`, the vector moving
//! this side's nodes onto the partner's). CGNS ranges are 1-based.

use super::write_atomic;
use crate::connectivity::{BlockConnectivity, SideKind};
use rayon::prelude::*;
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

/// The file as serde sees it: [`write_json`] writes this value, with each element of
/// `blocks` exactly as `serde_json::to_writer` writes it, on a line of its own (the tests
/// check both).
#[derive(Serialize)]
pub struct File<'a> {
    pub conventions: &'static str,
    pub blocks: &'a [BlockConnectivity],
}

/// Blocks formatted per parallel task.
pub const CHUNK: usize = 64;
/// Chunks per wave: the blocks formatted together before they are written (bounds the memory
/// held: ~2 KB per block, two waves at a time, as much as one wave of 64 chunks before the
/// writing overlapped the formatting).
pub const WAVE: usize = 32;

/// Write `connectivity.json`: the top level indented, each block on one line in serde_json's
/// compact format, byte for byte, written by hand ([`write_block`]): blocks are formatted in parallel, in waves of [`WAVE`] chunks of
/// [`CHUNK`] blocks, and written in block order, so the file does not depend on the thread
/// count and at most two waves (a few MB) are held at once.
///
/// Wave `k` is written while wave `k + 1` is formatted ([`rayon::join`]): at 1e5 particles
/// the file is 1.4 GB and the kernel's copy into the page cache is as long as the
/// formatting, so the two overlap instead of alternating (issue 8).
pub fn write_json(blocks: &[BlockConnectivity], path: &Path) -> io::Result<()> {
    write_atomic(path, |w| {
        w.write_all(b"{\n  \"conventions\": ")?;
        serde_json::to_writer(&mut *w, CONVENTIONS).map_err(io::Error::other)?;
        w.write_all(b",\n  \"blocks\": ")?;
        if blocks.is_empty() {
            w.write_all(b"[]")?;
        } else {
            w.write_all(b"[")?;
            let mut waves = blocks.chunks(CHUNK * WAVE).enumerate();
            let mut pending = waves.next().map(|(wi, wave)| format_wave(wi, wave));
            while let Some(texts) = pending.take() {
                let next = waves.next();
                let (written, formatted) = rayon::join(
                    || texts.iter().try_for_each(|t| w.write_all(t)),
                    || next.map(|(wi, wave)| format_wave(wi, wave)),
                );
                written?;
                pending = formatted;
            }
            w.write_all(b"\n  ]")?;
        }
        w.write_all(b"\n}\n")
    })
}

/// The text of wave `wi` (`wave` its blocks), one buffer per chunk of [`CHUNK`] blocks: each
/// block preceded by its separator (none before the file's first block) and its indentation.
fn format_wave(wi: usize, wave: &[BlockConnectivity]) -> Vec<Vec<u8>> {
    wave.par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut out = Vec::with_capacity(chunk.len() * 1024);
            for (k, b) in chunk.iter().enumerate() {
                if wi > 0 || ci > 0 || k > 0 {
                    out.push(b',');
                }
                out.extend_from_slice(b"\n    ");
                write_block(&mut out, b);
            }
            out
        })
        .collect()
}

/// serde_json's compact printer, for the few shapes of this file: no whitespace, `,` between
/// entries, `"key":` before the values of objects.
struct Compact<'a> {
    out: &'a mut Vec<u8>,
    /// Whether the innermost open object or array has an entry yet.
    first: bool,
}

impl Compact<'_> {
    /// Start the next entry of the innermost object (`"key":`) or array (`key == None`).
    fn entry(&mut self, key: Option<&str>) {
        if !self.first {
            self.out.push(b',');
        }
        self.first = false;
        if let Some(k) = key {
            self.out.push(b'"');
            self.out.extend_from_slice(k.as_bytes());
            self.out.extend_from_slice(b"\":");
        }
    }
    fn open(&mut self, bracket: u8) {
        self.out.push(bracket);
        self.first = true;
    }
    /// Close an object or array.
    fn close(&mut self, bracket: u8) {
        self.out.push(bracket);
        self.first = false;
    }
    fn int(&mut self, key: Option<&str>, x: impl itoa_like::Int) {
        self.entry(key);
        x.write(self.out);
    }
    fn string(&mut self, key: &str, s: &str) {
        self.entry(Some(key));
        if s.bytes().all(|c| c.is_ascii_alphanumeric() || c == b'_') {
            self.out.push(b'"');
            self.out.extend_from_slice(s.as_bytes());
            self.out.push(b'"');
        } else {
            // Escapes as serde_json writes them.
            let _ = serde_json::to_writer(&mut *self.out, s);
        }
    }
    fn pair(&mut self, key: Option<&str>, v: [usize; 2]) {
        self.entry(key);
        self.open(b'[');
        self.int(None, v[0]);
        self.int(None, v[1]);
        self.close(b']');
    }
}

/// Integers as serde_json writes them (decimal, `-` for negatives).
mod itoa_like {
    pub trait Int {
        fn write(self, out: &mut Vec<u8>);
    }
    fn unsigned(mut x: u64, out: &mut Vec<u8>) {
        let mut buf = [0u8; 20];
        let mut at = buf.len();
        loop {
            at -= 1;
            buf[at] = b'0' + (x % 10) as u8;
            x /= 10;
            if x == 0 {
                break;
            }
        }
        out.extend_from_slice(&buf[at..]);
    }
    impl Int for usize {
        fn write(self, out: &mut Vec<u8>) {
            unsigned(self as u64, out);
        }
    }
    impl Int for i32 {
        fn write(self, out: &mut Vec<u8>) {
            if self < 0 {
                out.push(b'-');
            }
            unsigned(u64::from(self.unsigned_abs()), out);
        }
    }
}

/// One element of `"blocks"`, exactly as `serde_json::to_writer` writes
/// [`BlockConnectivity`] (without the separator and the indentation before it).
pub fn write_block(out: &mut Vec<u8>, b: &BlockConnectivity) {
    let mut p = Compact { out, first: true };
    p.open(b'{');
    p.int(Some("block"), b.block);
    p.pair(Some("dims"), b.dims);
    p.entry(Some("sides"));
    p.open(b'[');
    for s in &b.sides {
        p.entry(None);
        p.open(b'{');
        p.int(Some("side"), s.side);
        p.string("name", s.name);
        p.string("kind", kind_name(s.kind));
        if let Some(c) = s.circle {
            p.int(Some("circle"), c);
        }
        if let Some(q) = s.partner {
            p.entry(Some("partner"));
            p.open(b'{');
            p.int(Some("block"), q.block);
            p.int(Some("side"), q.side);
            p.entry(Some("same_direction"));
            p.out
                .extend_from_slice(if q.same_direction { b"true" } else { b"false" });
            p.close(b'}');
        }
        if let Some(c) = s.cgns {
            p.entry(Some("cgns"));
            p.open(b'{');
            for (key, range) in [
                ("point_range", c.point_range),
                ("point_range_donor", c.point_range_donor),
            ] {
                p.entry(Some(key));
                p.open(b'[');
                p.pair(None, range[0]);
                p.pair(None, range[1]);
                p.close(b']');
            }
            p.entry(Some("transform"));
            p.open(b'[');
            p.int(None, c.transform[0]);
            p.int(None, c.transform[1]);
            p.close(b']');
            p.close(b'}');
        }
        if let Some(t) = s.translation {
            p.entry(Some("translation"));
            p.open(b'[');
            for x in t {
                p.entry(None);
                // serde_json's own float format (null when not finite).
                let _ = serde_json::to_writer(&mut *p.out, &x);
            }
            p.close(b']');
        }
        p.close(b'}');
    }
    p.close(b']');
    p.close(b'}');
}

/// The JSON name of a side kind (serde's `snake_case` of [`SideKind`]).
fn kind_name(k: SideKind) -> &'static str {
    match k {
        SideKind::Wall => "wall",
        SideKind::Outer => "outer",
        SideKind::Interface => "interface",
        SideKind::Periodic => "periodic",
    }
}
