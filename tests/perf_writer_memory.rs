//! The writers hold nothing of the mesh's size beside it (issue 8: 1e5 particles must fit on
//! one ordinary machine). Oracle: the CLI's own peak memory (`timings.json`,
//! `peak_memory_bytes`, the kernel's `VmHWM`) with one writer, against the same run writing
//! only `report.json` and `connectivity.json` (whose extra data is a few bytes per block).
//! Before the writers streamed, `mesh.vtu` held every cell's seven figures and the merged
//! nodes again (about 80 bytes a cell) and `mesh.msh` the merged nodes and every block's ids
//! (about 20 bytes a cell); the bound allowed here is 12 bytes a cell, room for the chunks in
//! flight at one thread. Not a timing: the peak of one process is the same from run to run up
//! to allocator noise far below the bound.

mod common;

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
    let input = dir.path().join("b.json");
    let o = common::run(&["example", "bubbles", "--holes", "300", "--seed", "4"]);
    assert!(o.status.success());
    std::fs::write(&input, &o.stdout).unwrap();
    let (base, cells) = peak(&input, "json", &[]);
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
