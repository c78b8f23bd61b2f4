//! The writers hold nothing of the mesh's size beside it (issue 8: 1e5 particles must fit on
//! one ordinary machine). Oracle: the CLI's own peak memory (`timings.json`,
//! `peak_memory_bytes`, the kernel's `VmHWM`) with one writer, against the same run writing
//! only the SVG picture (the block outlines, a few bytes per block: it reads the nodes, so
//! the mesh holds them, as for every writer of grids; a run writing only `report.json` and
//! `connectivity.json` no longer holds them at all, `tests/perf_measured.rs`).
//! Before the writers streamed, `mesh.vtu` held every cell's seven figures and the merged
//! nodes again (about 80 bytes a cell) and `mesh.msh` the merged nodes and every block's ids
//! (about 20 bytes a cell); the bound allowed here is 12 bytes a cell, room for the chunks in
//! flight at one thread. `mesh.png` parsed the whole SVG text into one tree (1 000 bubbles:
//! 74 MB beside the mesh); now it draws the text in parts, the same pixels as the whole
//! document (checked here against the former writer, kept as the reference). Not a timing:
//! the peak of one process is the same from run to run up to allocator noise far below the
//! bounds.

use crate::common;

use medial_blocks::output::{png, svg};
use medial_blocks::{layouts, mesh, Options};

fn bubbles(holes: &str, dir: &std::path::Path) -> std::path::PathBuf {
    let input = dir.join(format!("b{holes}.json"));
    let o = common::run(&["example", "bubbles", "--holes", holes, "--seed", "4"]);
    assert!(o.status.success());
    std::fs::write(&input, &o.stdout).unwrap();
    input
}

fn peak(input: &std::path::Path, format: &str, extra: &[&str]) -> (u64, u64) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m");
    let mut args = vec![
        "--quiet",
        "--threads",
        "1",
        "mesh",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--block-cells",
        "16",
        "--timings",
        "--format",
        format,
    ];
    args.extend_from_slice(extra);
    let o = common::run(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let t: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("timings.json")).unwrap()).unwrap();
    let cells = t["cells"]
        .as_u64()
        .expect("timings.json names the cell count");
    (t["peak_memory_bytes"].as_u64().unwrap_or(0), cells)
}

#[test]
fn unstructured_writers_stream_beside_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let input = bubbles("300", dir.path());
    let (base, cells) = peak(&input, "svg", &[]);
    if base == 0 {
        eprintln!("no peak memory on this platform: nothing to compare");
        return;
    }
    assert!(cells > 400_000, "{cells} cells: too small a mesh to tell");
    for (format, extra) in [
        ("vtu", &[][..]),
        ("vtu", &["--binary"][..]),
        ("gmsh", &[][..]),
        ("gmsh", &["--binary"][..]),
    ] {
        let (p, c) = peak(&input, format, extra);
        assert_eq!(c, cells);
        let more = p.saturating_sub(base);
        assert!(
            more < 12 * cells,
            "{format} {extra:?}: peak {p} bytes, {more} more than the mesh's run ({base}): \
             {:.1} bytes a cell",
            more as f64 / cells as f64
        );
    }
}

#[test]
fn png_draws_in_parts_beside_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let input = bubbles("1000", dir.path());
    let (base, _) = peak(&input, "svg", &[]);
    if base == 0 {
        eprintln!("no peak memory on this platform: nothing to compare");
        return;
    }
    let (p, _) = peak(&input, "png", &[]);
    let more = p.saturating_sub(base);
    // The pixmap (about 6 MB) and a part's text and tree; the whole tree took 74 MB here.
    assert!(
        more < 40 << 20,
        "png: {more} bytes beside the mesh's run ({base})"
    );
}

/// The former writer: the whole SVG text, one tree, one drawing.
fn reference_png(m: &medial_blocks::Mesh, width: u32) -> Vec<u8> {
    let text = svg::to_string(m).unwrap();
    let tree = resvg::usvg::Tree::from_str(&text, &resvg::usvg::Options::default()).unwrap();
    let size = tree.size();
    let scale = width as f32 / size.width();
    let height = (size.height() * scale).ceil().max(1.0) as u32;
    let mut pixmap = resvg::tiny_skia::Pixmap::new(width, height).unwrap();
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().unwrap()
}

#[test]
fn png_in_parts_is_the_whole_picture() {
    let dir = tempfile::tempdir().unwrap();
    let periodic = medial_blocks::periodic::PeriodicDomain::new(
        [2.0, 1.0],
        vec![
            medial_blocks::Circle::new(0.1, 0.1, 0.2),
            medial_blocks::Circle::new(1.2, 0.6, 0.25),
        ],
    )
    .unwrap();
    let opts = Options {
        block_cells: Some(6),
        ..Options::default()
    };
    let meshes = [
        mesh(&layouts::bubbles(40, 3).unwrap(), &opts).unwrap(),
        mesh(&layouts::square_lattice(9).unwrap(), &Options::default()).unwrap(),
        medial_blocks::periodic::mesh_periodic(&periodic, &Options::default()).unwrap(),
    ];
    for (k, m) in meshes.iter().enumerate() {
        let want = reference_png(m, 320);
        for part in [1, 3000, 40_000, usize::MAX] {
            let path = dir.path().join(format!("{k}-{part}.png"));
            png::write_in_parts(m, &path, 320, part).unwrap();
            assert!(
                std::fs::read(&path).unwrap() == want,
                "mesh {k}, parts of {part} bytes"
            );
        }
    }
}

/// The picture is formed on the rayon pool by a caller that waits for its drawing thread:
/// from inside a pool of one worker (where a drawer that needed the pool, or a caller that
/// drew while the text needed the pool, would wait forever) and of three, with parts small
/// enough to fill the channel, the file is the whole picture's. A hang fails after a minute
/// instead of stalling the suite.
#[test]
fn png_from_a_pool_worker_is_the_whole_picture() {
    let opts = Options {
        block_cells: Some(6),
        ..Options::default()
    };
    let m = std::sync::Arc::new(mesh(&layouts::bubbles(60, 5).unwrap(), &opts).unwrap());
    let want = reference_png(&m, 320);
    for threads in [1, 3] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.png");
        let (tx, rx) = std::sync::mpsc::channel();
        let (m2, p2) = (m.clone(), path.clone());
        std::thread::spawn(move || {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let r = pool.install(|| png::write_in_parts(&m2, &p2, 320, 2000));
            let _ = tx.send(r.map_err(|e| e.to_string()));
        });
        let r = rx
            .recv_timeout(std::time::Duration::from_secs(60))
            .unwrap_or_else(|_| panic!("{threads} worker(s): no picture after a minute"));
        r.unwrap();
        assert!(std::fs::read(&path).unwrap() == want, "{threads} worker(s)");
    }
}
