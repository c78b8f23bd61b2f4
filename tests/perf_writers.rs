//! The hand-written `connectivity.json` writer and the shared connectivity of issue #8 against
//! independent references:
//! - `connectivity.json` is byte for byte the top level indented as serde_json's pretty printer
//!   does it, with every block on its own line as `serde_json::to_vec` writes it, and it parses
//!   back to the serde value of the same file, on real meshes (walls, outer boundary, interfaces, periodic sides
//!   with translations) and on synthetic blocks (odd floats, negative circles, a name that
//!   needs escaping, more blocks than one wave of parallel formatting);
//! - the report built from a shared connectivity equals the one that computes its own, and
//!   `write_files_prepared` with the shared connectivity writes the same files as
//!   `write_files`.

use crate::common;

use medial_blocks::connectivity::{
    connectivity, BlockConnectivity, Cgns1to1, Connectivity, Partner, SideConnectivity, SideKind,
};
use medial_blocks::output::connectivity::{
    write_json, write_json_from, File, CHUNK, CONVENTIONS, WAVE,
};
use medial_blocks::output::report::Report;
use medial_blocks::output::{write_files, write_files_prepared, Encoding, Format};
use medial_blocks::{layouts, Mesh};

/// The file serde_json writes for `blocks`: the pretty-printed top level, one block per line in
/// serde_json's compact format (plus the final newline).
fn serde_bytes(blocks: &[BlockConnectivity]) -> Vec<u8> {
    let mut v = b"{\n  \"conventions\": ".to_vec();
    v.extend(serde_json::to_vec(CONVENTIONS).unwrap());
    v.extend_from_slice(b",\n  \"blocks\": [");
    for (k, b) in blocks.iter().enumerate() {
        v.extend_from_slice(if k == 0 { b"\n    " } else { b",\n    " });
        v.extend(serde_json::to_vec(b).unwrap());
    }
    v.extend_from_slice(if blocks.is_empty() { b"]" } else { b"\n  ]" });
    v.extend_from_slice(b"\n}\n");
    // The same JSON value as the whole file written by serde (NaN and infinities read back as
    // null either way).
    let whole: serde_json::Value = serde_json::from_slice(
        &serde_json::to_vec_pretty(&File {
            conventions: CONVENTIONS,
            blocks,
        })
        .unwrap(),
    )
    .unwrap();
    assert_eq!(
        serde_json::from_slice::<serde_json::Value>(&v).unwrap(),
        whole
    );
    v
}

fn written(blocks: &[BlockConnectivity]) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("connectivity.json");
    write_json(blocks, &path).unwrap();
    std::fs::read(&path).unwrap()
}

/// The file [`write_json_from`] writes for the connectivity of `m`.
fn written_from(m: &Mesh) -> Vec<u8> {
    let conn = Connectivity::new(&m.layout, &m.grids).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("connectivity.json");
    write_json_from(&conn, &path).unwrap();
    std::fs::read(&path).unwrap()
}

fn meshes() -> Vec<Mesh> {
    let bubbles = layouts::bubbles(12, 3).unwrap();
    common::small_meshes(&bubbles, &bubbles)
}

#[test]
fn connectivity_json_is_serde_on_real_meshes() {
    let mut periodic = false;
    for m in meshes() {
        let conn = connectivity(&m.layout, &m.grids).unwrap();
        periodic |= conn
            .iter()
            .any(|b| b.sides.iter().any(|s| s.kind == SideKind::Periodic));
        let want = serde_bytes(&conn);
        assert_eq!(written(&conn), want);
        assert_eq!(written_from(&m), want);
    }
    assert!(periodic, "a periodic mesh with translations is covered");
}

/// The records formed wave by wave from the compact connectivity ([`write_json_from`]) are
/// serde_json's bytes of the records of `connectivity` on a mesh of more than one wave of
/// blocks, on one thread and on three.
#[test]
fn connectivity_json_from_the_compact_form_spans_waves() {
    let m = medial_blocks::mesh(
        &layouts::bubbles(400, 7).unwrap(),
        &medial_blocks::Options::default(),
    )
    .unwrap();
    let blocks = m.layout.blocks.len();
    assert!(blocks > CHUNK * WAVE, "{blocks} blocks: more than one wave");
    let want = serde_bytes(&connectivity(&m.layout, &m.grids).unwrap());
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert!(
            pool.install(|| written_from(&m)) == want,
            "{threads} threads"
        );
    }
}

/// `n` synthetic blocks: every optional field, odd floats and integers, an escaped name.
fn synthetic_blocks(n: usize) -> Vec<BlockConnectivity> {
    let floats = [
        0.0,
        -0.0,
        1e-7,
        -2.5e-300,
        1e16,
        123456789.125,
        f64::MAX,
        f64::NAN,
        f64::INFINITY,
        0.1,
    ];
    let side = |k: usize| {
        let i = k % floats.len();
        SideConnectivity {
            side: k % 4,
            name: if k.is_multiple_of(97) {
                "odd \"name\"\n"
            } else {
                "j_min"
            },
            kind: [
                SideKind::Wall,
                SideKind::Outer,
                SideKind::Interface,
                SideKind::Periodic,
            ][k % 4],
            circle: k.is_multiple_of(3).then_some(-(k as i32) + 7),
            partner: k.is_multiple_of(2).then_some(Partner {
                block: k * 31,
                side: k % 4,
                same_direction: k.is_multiple_of(5),
            }),
            cgns: (k % 5 != 1).then_some(Cgns1to1 {
                point_range: [[k, 1], [usize::MAX, 0]],
                point_range_donor: [[1, k + 10], [999, 1000]],
                transform: [-(k as i32 % 3) - 1, 2],
            }),
            translation: (k % 4 == 3).then_some([floats[i], floats[(i + 3) % floats.len()]]),
        }
    };
    (0..n)
        .map(|b| BlockConnectivity {
            block: b,
            dims: [b % 17 + 2, b * 7 + 2],
            sides: [
                side(4 * b),
                side(4 * b + 1),
                side(4 * b + 2),
                side(4 * b + 3),
            ],
        })
        .collect()
}

/// Synthetic blocks, enough for several waves of parallel formatting.
#[test]
fn connectivity_json_is_serde_on_synthetic_blocks() {
    assert_eq!(written(&[]), serde_bytes(&[]));
    let blocks = synthetic_blocks(9000);
    assert_eq!(written(&blocks[..1]), serde_bytes(&blocks[..1]));
    assert_eq!(written(&blocks), serde_bytes(&blocks));
}

/// Wave and chunk boundaries of the pipelined writer (a wave written while the next one is
/// formatted): one block short of, exactly at, and one past a wave; a partial last chunk after
/// two full waves. Same bytes as serde_json with one thread and with two.
#[test]
fn connectivity_json_at_wave_boundaries() {
    let wave = CHUNK * WAVE;
    let blocks = synthetic_blocks(2 * wave + CHUNK + 1);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for n in [
            CHUNK,
            CHUNK + 1,
            wave - 1,
            wave,
            wave + 1,
            2 * wave + CHUNK + 1,
        ] {
            let b = &blocks[..n];
            assert!(
                pool.install(|| written(b)) == serde_bytes(b),
                "{n} blocks, {threads} threads"
            );
        }
    }
}

/// The report from a shared connectivity is the report that computes its own, and the files
/// written with it are those of `write_files`.
#[test]
fn shared_connectivity_gives_the_same_report_and_files() {
    for m in meshes() {
        let conn = Connectivity::new(&m.layout, &m.grids).unwrap();
        let r = Report::from_mesh_with(&m, Some(&conn));
        assert_eq!(r, Report::from_mesh(&m));
        let a = tempfile::tempdir().unwrap();
        let b = tempfile::tempdir().unwrap();
        write_files(&m, a.path(), &[Format::Json]).unwrap();
        write_files_prepared(
            &m,
            b.path(),
            &[Format::Json],
            Encoding::Ascii,
            Some(&r),
            Some(&conn),
            |_| {},
        )
        .unwrap();
        for f in ["report.json", "connectivity.json"] {
            let x = std::fs::read(a.path().join(f)).unwrap();
            let y = std::fs::read(b.path().join(f)).unwrap();
            assert!(x == y, "{f} differs");
        }
    }
}
