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
use crate::connectivity::{BlockConnectivity, Connectivity, SideConnectivity, SideKind};
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
/// compact format, byte for byte, written by hand ([`write_block`]): blocks are formatted in
/// parallel, in waves of [`WAVE`] chunks of [`CHUNK`] blocks, and written in block order, so
/// the file does not depend on the thread count and at most two waves (a few MB) are held at
/// once.
///
/// Wave `k` is written while wave `k + 1` is formatted ([`rayon::join`]): at 1e5 particles
/// the file is about 0.4 GB (411 MB for 1e5 bubbles) and the kernel's copy into the page
/// cache is as long as the formatting, so the two overlap instead of alternating (issue 8).
pub fn write_json(blocks: &[BlockConnectivity], path: &Path) -> io::Result<()> {
    write_blocks(blocks.len(), |out, b| write_block(out, &blocks[b]), path)
}

/// [`write_json`] of the records of `conn` ([`Connectivity::block`]), each formed as its
/// wave is formatted: the same bytes as `write_json(&conn.to_vec(), path)` without holding
/// every record (about 700 bytes a block).
pub fn write_json_from(conn: &Connectivity, path: &Path) -> io::Result<()> {
    write_blocks(
        conn.len(),
        |out, b| {
            // Side by side (`Connectivity::side`), not through a whole block record.
            if let Some(dims) = conn.dims(b) {
                write_block_with(out, b, dims, |s| conn.side(b, s));
            }
        },
        path,
    )
}

/// [`write_json`] of `n` blocks, block `b` written into a buffer by `block(out, b)`.
fn write_blocks(
    n: usize,
    block: impl Fn(&mut Vec<u8>, usize) + Sync,
    path: &Path,
) -> io::Result<()> {
    write_atomic(path, |w| {
        w.write_all(b"{\n  \"conventions\": ")?;
        serde_json::to_writer(&mut *w, CONVENTIONS).map_err(io::Error::other)?;
        w.write_all(b",\n  \"blocks\": ")?;
        if n == 0 {
            w.write_all(b"[]")?;
        } else {
            w.write_all(b"[")?;
            let wave = CHUNK * WAVE;
            let mut waves = (0..n.div_ceil(wave)).map(|wi| wi * wave..n.min((wi + 1) * wave));
            let format = |blocks| format_wave(blocks, &block);
            let mut pending = waves.next().map(format);
            while let Some(texts) = pending.take() {
                let next = waves.next();
                // The formatting (parallel) on this thread, the writing (serial) the part a
                // second worker takes: the other way round, each wave's formatting waited for
                // a worker to wake and steal it (about 120 ms of one-CPU time at 1e5).
                let (formatted, written) = rayon::join(
                    || next.map(format),
                    || texts.iter().try_for_each(|t| w.write_all(t)),
                );
                written?;
                pending = formatted;
            }
            w.write_all(b"\n  ]")?;
        }
        w.write_all(b"\n}\n")
    })
}

/// The text of the wave of blocks `blocks`, one buffer per chunk of [`CHUNK`] blocks: each
/// block preceded by its separator (none before the file's first block) and its indentation.
fn format_wave(
    blocks: std::ops::Range<usize>,
    block: &(impl Fn(&mut Vec<u8>, usize) + Sync),
) -> Vec<Vec<u8>> {
    (0..blocks.len().div_ceil(CHUNK))
        .into_par_iter()
        // One chunk per leaf: the wave's last leaf is what the other thread waits for, 289
        // times at 1e5 particles ([`crate::tasks`]).
        .with_max_len(1)
        .map(|ci| {
            let lo = blocks.start + ci * CHUNK;
            let hi = (lo + CHUNK).min(blocks.end);
            let mut out = Vec::with_capacity((hi - lo) * 1024);
            for b in lo..hi {
                if b > 0 {
                    out.push(b',');
                }
                out.extend_from_slice(b"\n    ");
                block(&mut out, b);
            }
            out
        })
        .collect()
}

/// Integers as serde_json writes them (decimal, `-` for negatives), two digits per step from
/// a table into a stack buffer, then one copy.
mod itoa_like {
    const PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

    pub fn unsigned(mut x: u64, out: &mut Vec<u8>) {
        let mut buf = [0u8; 20];
        let mut at = buf.len();
        while x >= 100 {
            let r = (x % 100) as usize;
            x /= 100;
            at -= 2;
            buf[at..at + 2].copy_from_slice(&PAIRS[2 * r..2 * r + 2]);
        }
        if x >= 10 {
            at -= 2;
            let r = x as usize;
            buf[at..at + 2].copy_from_slice(&PAIRS[2 * r..2 * r + 2]);
        } else {
            at -= 1;
            buf[at] = b'0' + x as u8;
        }
        // Pushed one by one: `extend_from_slice` of a length known only here called `memcpy`
        // for every number (some 300 000 numbers at 1e3 bubbles, most of a millisecond).
        out.reserve(buf.len() - at);
        for &d in &buf[at..] {
            out.push(d);
        }
    }

    pub fn signed(x: i32, out: &mut Vec<u8>) {
        if x < 0 {
            out.push(b'-');
        }
        unsigned(u64::from(x.unsigned_abs()), out);
    }
}

use itoa_like::{signed, unsigned};

/// A string value as serde_json writes it: plain names (ASCII letters, digits, `_`, all this
/// file's names) copied between quotes, anything else escaped by serde_json itself.
fn string(out: &mut Vec<u8>, s: &str) {
    if s.bytes().all(|c| c.is_ascii_alphanumeric() || c == b'_') {
        out.push(b'"');
        out.extend_from_slice(s.as_bytes());
        out.push(b'"');
    } else {
        let _ = serde_json::to_writer(&mut *out, s);
    }
}

/// `"key":[a,b]` entries and the like: `[a,b]` of two unsigned integers.
fn pair(out: &mut Vec<u8>, v: [usize; 2]) {
    out.push(b'[');
    unsigned(v[0] as u64, out);
    out.push(b',');
    unsigned(v[1] as u64, out);
    out.push(b']');
}

/// One element of `"blocks"`, exactly as `serde_json::to_writer` writes
/// [`BlockConnectivity`] (without the separator and the indentation before it): serde_json's
/// compact format (no whitespace, fields in declaration order, `None` fields skipped) with
/// every fixed run of keys and punctuation copied as one piece (issue 8: an entry at a time
/// was 7.8 k instructions per block).
pub fn write_block(out: &mut Vec<u8>, b: &BlockConnectivity) {
    write_block_with(out, b.block, b.dims, |k| b.sides.get(k).copied());
}

/// [`write_block`] of the block numbered `block` with node counts `dims` and the sides
/// `side(0)` to `side(3)` (a side that is `None` is left out; a block's record has all four).
#[inline]
fn write_block_with(
    out: &mut Vec<u8>,
    block: usize,
    dims: [usize; 2],
    side: impl Fn(usize) -> Option<SideConnectivity>,
) {
    out.reserve(1024);
    out.extend_from_slice(b"{\"block\":");
    unsigned(block as u64, out);
    out.extend_from_slice(b",\"dims\":");
    pair(out, dims);
    out.extend_from_slice(b",\"sides\":[");
    for (k, s) in (0..4).filter_map(side).enumerate() {
        out.extend_from_slice(if k == 0 {
            b"{\"side\":"
        } else {
            b",{\"side\":"
        });
        unsigned(s.side as u64, out);
        out.extend_from_slice(b",\"name\":");
        string(out, s.name);
        out.extend_from_slice(kind_entry(s.kind));
        if let Some(c) = s.circle {
            out.extend_from_slice(b",\"circle\":");
            signed(c, out);
        }
        if let Some(q) = s.partner {
            out.extend_from_slice(b",\"partner\":{\"block\":");
            unsigned(q.block as u64, out);
            out.extend_from_slice(b",\"side\":");
            unsigned(q.side as u64, out);
            out.extend_from_slice(if q.same_direction {
                b",\"same_direction\":true}"
            } else {
                b",\"same_direction\":false}"
            });
        }
        if let Some(c) = s.cgns {
            out.extend_from_slice(b",\"cgns\":{\"point_range\":[");
            pair(out, c.point_range[0]);
            out.push(b',');
            pair(out, c.point_range[1]);
            out.extend_from_slice(b"],\"point_range_donor\":[");
            pair(out, c.point_range_donor[0]);
            out.push(b',');
            pair(out, c.point_range_donor[1]);
            out.extend_from_slice(b"],\"transform\":[");
            signed(c.transform[0], out);
            out.push(b',');
            signed(c.transform[1], out);
            out.extend_from_slice(b"]}");
        }
        if let Some(t) = s.translation {
            out.extend_from_slice(b",\"translation\":[");
            // serde_json's own float format (null when not finite).
            let _ = serde_json::to_writer(&mut *out, &t[0]);
            out.push(b',');
            let _ = serde_json::to_writer(&mut *out, &t[1]);
            out.push(b']');
        }
        out.push(b'}');
    }
    out.extend_from_slice(b"]}");
}

/// The `,"kind":"..."` entry of a side kind (serde's `snake_case` of [`SideKind`]).
fn kind_entry(k: SideKind) -> &'static [u8] {
    match k {
        SideKind::Wall => b",\"kind\":\"wall\"",
        SideKind::Outer => b",\"kind\":\"outer\"",
        SideKind::Interface => b",\"kind\":\"interface\"",
        SideKind::Periodic => b",\"kind\":\"periodic\"",
    }
}
