//! `mesh.png`: the SVG picture rasterised (with `resvg`) for reports.
//!
//! Memory (issue 8): the SVG text is not held whole, nor parsed into one tree (at 1e4
//! bubbles with `--block-cells 16` that tree took 250 MB beside the mesh, about ten times the
//! text). The document is cut into parts of about [`PART_BYTES`] at element lines: each part
//! is the document's opening line, the group open at the cut (if any) and the next elements,
//! closed again, and the parts are drawn one after the other on the same pixmap. SVG paints
//! in document order and the picture's groups only pass attributes down
//! (`svg::write_checked` lists what this relies on), so the pixels are those of
//! drawing the whole document at once (`tests/perf_writer_memory.rs` compares the files).

use super::write_atomic;
use crate::mesh::Mesh;
use std::io::{self, Write};
use std::path::Path;

/// Width of the PNG in pixels (the height follows the picture's aspect ratio).
pub const WIDTH: u32 = 1200;

/// SVG bytes per part drawn at once (see the module doc).
pub const PART_BYTES: usize = 1 << 20;

/// Rasterise `mesh`'s SVG picture into a PNG at `path`, [`WIDTH`] pixels wide.
pub fn write(mesh: &Mesh, path: &Path) -> io::Result<()> {
    write_with_width(mesh, path, WIDTH)
}

/// Rasterise `mesh`'s SVG picture into a PNG at `path`, `width` pixels wide (at least 1).
pub fn write_with_width(mesh: &Mesh, path: &Path, width: u32) -> io::Result<()> {
    write_in_parts(mesh, path, width, PART_BYTES)
}

/// [`write_with_width`] drawing the SVG in parts of about `part_bytes` (at least one element
/// a part): the same file for every `part_bytes`.
pub fn write_in_parts(mesh: &Mesh, path: &Path, width: u32, part_bytes: usize) -> io::Result<()> {
    let mut parts = Parts {
        width: width.max(1),
        part_bytes,
        head: Vec::new(),
        group: None,
        doc: Vec::new(),
        line: Vec::new(),
        canvas: None,
        ended: false,
    };
    super::svg::write_checked(&mut parts, mesh)?;
    if !parts.ended {
        return Err(io::Error::other("the SVG picture did not end with </svg>"));
    }
    let (pixmap, _) = parts
        .canvas
        .ok_or_else(|| io::Error::other("the SVG picture was empty"))?;
    let bytes = pixmap
        .encode_png()
        .map_err(|e| io::Error::other(format!("PNG encoding failed: {e}")))?;
    write_atomic(path, |w| w.write_all(&bytes))
}

/// The sink that cuts the SVG text into parts and draws each (see the module doc).
struct Parts {
    width: u32,
    part_bytes: usize,
    /// The document's first line (the `<svg>` opening).
    head: Vec<u8>,
    /// The line that opened the group the text is in, if any.
    group: Option<Vec<u8>>,
    /// The part being gathered (complete lines).
    doc: Vec<u8>,
    /// The line being received.
    line: Vec<u8>,
    /// The pixmap and the scale, made from the first part's size.
    canvas: Option<(resvg::tiny_skia::Pixmap, f32)>,
    /// `</svg>` was received and the last part drawn.
    ended: bool,
}

impl Parts {
    /// Take one complete line (with its newline).
    fn take_line(&mut self) -> io::Result<()> {
        let line = std::mem::take(&mut self.line);
        let text = line.strip_suffix(b"\n").unwrap_or(&line);
        if self.head.is_empty() {
            self.head = line.clone();
        } else if text == b"</svg>" {
            self.doc.extend_from_slice(&line);
            self.draw()?;
            self.ended = true;
            return Ok(());
        } else if text.starts_with(b"  <g") {
            self.group = Some(line.clone());
        } else if text == b"  </g>" {
            self.group = None;
        } else if self.doc.len() >= self.part_bytes {
            // An element line: cut before it.
            if self.group.is_some() {
                self.doc.extend_from_slice(b"  </g>\n");
            }
            self.doc.extend_from_slice(b"</svg>\n");
            self.draw()?;
            self.doc.extend_from_slice(&self.head);
            if let Some(g) = &self.group {
                self.doc.extend_from_slice(g);
            }
        }
        self.doc.extend_from_slice(&line);
        Ok(())
    }

    /// Draw the part gathered (a whole SVG document) and empty it.
    fn draw(&mut self) -> io::Result<()> {
        let tree = resvg::usvg::Tree::from_data(&self.doc, &resvg::usvg::Options::default())
            .map_err(|e| io::Error::other(format!("SVG not readable for rasterising: {e}")))?;
        self.doc.clear();
        if self.canvas.is_none() {
            let size = tree.size();
            let scale = self.width as f32 / size.width();
            let height = (size.height() * scale).ceil().max(1.0) as u32;
            let mut pixmap = resvg::tiny_skia::Pixmap::new(self.width, height)
                .ok_or_else(|| io::Error::other("PNG size out of range"))?;
            pixmap.fill(resvg::tiny_skia::Color::WHITE);
            self.canvas = Some((pixmap, scale));
        }
        if let Some((pixmap, scale)) = &mut self.canvas {
            resvg::render(
                &tree,
                resvg::tiny_skia::Transform::from_scale(*scale, *scale),
                &mut pixmap.as_mut(),
            );
        }
        Ok(())
    }
}

impl Write for Parts {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let mut rest = buf;
        while let Some(k) = rest.iter().position(|&b| b == b'\n') {
            self.line.extend_from_slice(&rest[..=k]);
            self.take_line()?;
            rest = &rest[k + 1..];
        }
        self.line.extend_from_slice(rest);
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}
