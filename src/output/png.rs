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
//!
//! Speed: forming the text and parsing each part take longer than drawing it, so the calling
//! thread forms and parses the parts while a second thread draws them, in order, a few parts
//! behind at most (a channel of [`AHEAD`] parsed parts): the same pixels, drawn in the same
//! order. The drawing thread uses no thread pool, so the caller may be a pool worker that
//! waits for it (the text is formed on the rayon pool) without a deadlock, whatever the
//! number of workers. 1 000 bubbles (`--block-cells 16`): 0.60-0.64 -> 0.42-0.47 s.

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

/// Parsed parts that may wait for the drawing thread (see the module doc).
pub const AHEAD: usize = 2;

/// [`write_with_width`] drawing the SVG in parts of about `part_bytes` (at least one element
/// a part): the same file for every `part_bytes`.
pub fn write_in_parts(mesh: &Mesh, path: &Path, width: u32, part_bytes: usize) -> io::Result<()> {
    super::check_mesh(mesh)?;
    let width = width.max(1);
    let (tx, rx) = std::sync::mpsc::sync_channel::<resvg::usvg::Tree>(AHEAD);
    let pixmap = std::thread::scope(|scope| {
        // Draws the parsed parts in order. Drawing needs no thread pool, so this thread
        // always makes progress while the caller, which forms the text on the rayon pool
        // (`svg::write_checked`), waits for room in the channel.
        let drawer = scope.spawn(move || {
            run_anywhere();
            let mut canvas: Option<(resvg::tiny_skia::Pixmap, f32)> = None;
            for tree in &rx {
                // An error drops the receiver: the caller's next part fails and it stops.
                draw(&mut canvas, &tree, width)?;
            }
            canvas
                .map(|(pixmap, _)| pixmap)
                .ok_or_else(|| io::Error::other("the SVG picture was empty"))
        });
        let mut parts = Parts {
            part_bytes,
            head: Vec::new(),
            group: None,
            doc: Vec::new(),
            line: Vec::new(),
            parsed: tx,
            ended: false,
        };
        let formed = super::svg::write_checked(&mut parts, mesh).and_then(|()| {
            if parts.ended {
                Ok(())
            } else {
                Err(io::Error::other("the SVG picture did not end with </svg>"))
            }
        });
        // No more parts (the sender goes with them): the drawer finishes what it has.
        drop(parts);
        let drawn = drawer
            .join()
            .unwrap_or_else(|_| Err(io::Error::other("the PNG's drawing thread panicked")));
        // A drawing error stopped the forming: report the drawing's.
        match (formed, drawn) {
            (_, Err(e)) => Err(e),
            (Err(e), _) => Err(e),
            (Ok(()), Ok(pixmap)) => Ok(pixmap),
        }
    })?;
    let bytes = pixmap
        .encode_png()
        .map_err(|e| io::Error::other(format!("PNG encoding failed: {e}")))?;
    write_atomic(path, |w| w.write_all(&bytes))
}

/// Let the calling thread run on every CPU the process's main thread may: a spawned thread
/// inherits its parent's CPU set, and the command line pins each pool worker to one CPU
/// (`cli::affinity`), where the two threads of the picture would take turns. Best effort (a
/// refusal leaves the set as it was; Linux only).
fn run_anywhere() {
    #[cfg(target_os = "linux")]
    // SAFETY: `cpu_set_t` is plain data (all zero is the empty set); both calls only read
    // and write the set given with its size.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        let size = std::mem::size_of::<libc::cpu_set_t>();
        if libc::sched_getaffinity(libc::getpid(), size, &mut set) == 0 {
            libc::sched_setaffinity(0, size, &set);
        }
    }
}

/// Draw one parsed part onto the canvas, made `width` pixels wide from the first part's
/// size (white).
fn draw(
    canvas: &mut Option<(resvg::tiny_skia::Pixmap, f32)>,
    tree: &resvg::usvg::Tree,
    width: u32,
) -> io::Result<()> {
    if canvas.is_none() {
        let size = tree.size();
        let scale = width as f32 / size.width();
        let height = (size.height() * scale).ceil().max(1.0) as u32;
        let mut pixmap = resvg::tiny_skia::Pixmap::new(width, height)
            .ok_or_else(|| io::Error::other("PNG size out of range"))?;
        pixmap.fill(resvg::tiny_skia::Color::WHITE);
        *canvas = Some((pixmap, scale));
    }
    if let Some((pixmap, scale)) = canvas {
        resvg::render(
            tree,
            resvg::tiny_skia::Transform::from_scale(*scale, *scale),
            &mut pixmap.as_mut(),
        );
    }
    Ok(())
}

/// The sink that cuts the SVG text into parts and parses each (see the module doc).
struct Parts {
    part_bytes: usize,
    /// The document's first line (the `<svg>` opening).
    head: Vec<u8>,
    /// The line that opened the group the text is in, if any.
    group: Option<Vec<u8>>,
    /// The part being gathered (complete lines).
    doc: Vec<u8>,
    /// The line being received.
    line: Vec<u8>,
    /// Where the parsed parts go, in order, to be drawn.
    parsed: std::sync::mpsc::SyncSender<resvg::usvg::Tree>,
    /// `</svg>` was received and the last part parsed.
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
            self.parse()?;
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
            self.parse()?;
            self.doc.extend_from_slice(&self.head);
            if let Some(g) = &self.group {
                self.doc.extend_from_slice(g);
            }
        }
        self.doc.extend_from_slice(&line);
        Ok(())
    }

    /// Parse the part gathered (a whole SVG document), hand it to the drawing thread and
    /// empty it.
    fn parse(&mut self) -> io::Result<()> {
        let tree = resvg::usvg::Tree::from_data(&self.doc, &resvg::usvg::Options::default())
            .map_err(|e| io::Error::other(format!("SVG not readable for rasterising: {e}")))?;
        self.doc.clear();
        self.parsed
            .send(tree)
            .map_err(|_| io::Error::other("the PNG's drawing stopped"))
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
