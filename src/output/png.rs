//! `mesh.png`: the SVG picture rasterised (with `resvg`) for reports.

use super::write_atomic;
use crate::mesh::Mesh;
use std::io::{self, Write};
use std::path::Path;

/// Width of the PNG in pixels (the height follows the picture's aspect ratio).
pub const WIDTH: u32 = 1200;

/// Rasterise `mesh`'s SVG picture into a PNG at `path`, [`WIDTH`] pixels wide.
pub fn write(mesh: &Mesh, path: &Path) -> io::Result<()> {
    write_with_width(mesh, path, WIDTH)
}

/// Rasterise `mesh`'s SVG picture into a PNG at `path`, `width` pixels wide (at least 1).
pub fn write_with_width(mesh: &Mesh, path: &Path, width: u32) -> io::Result<()> {
    let width = width.max(1);
    let svg = super::svg::to_string(mesh)?;
    let tree = resvg::usvg::Tree::from_str(&svg, &resvg::usvg::Options::default())
        .map_err(|e| io::Error::other(format!("SVG not readable for rasterising: {e}")))?;
    let size = tree.size();
    let scale = width as f32 / size.width();
    let height = (size.height() * scale).ceil().max(1.0) as u32;
    let mut pixmap = resvg::tiny_skia::Pixmap::new(width, height)
        .ok_or_else(|| io::Error::other("PNG size out of range"))?;
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    let bytes = pixmap
        .encode_png()
        .map_err(|e| io::Error::other(format!("PNG encoding failed: {e}")))?;
    write_atomic(path, |w| w.write_all(&bytes))
}
