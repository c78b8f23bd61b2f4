//! The two readers agree: a layout written as JSON and as CSV (any correct decimal rendering
//! of the same doubles) parses to the same circles bit for bit, and the CLI meshes both to
//! byte-identical files. (Before serde_json's `float_roundtrip` the JSON reader could be an
//! ulp off the CSV reader, which is Rust's correctly rounded `f64::from_str`.)

use crate::common;

use common::tree;
use medial_blocks::input::{parse_holes_csv, parse_triple};
use medial_blocks::{Circle, Domain};
use proptest::prelude::*;
use std::process::Command;

/// Doubles of every magnitude the readers accept, including ones whose shortest decimal form
/// has 17 digits.
fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e6f64..1e6,
        (-1.0f64..1.0).prop_map(|x| x * 1e-200),
        (1u64..(1 << 52)).prop_map(|m| f64::from_bits((1023u64 << 52) | m) - 1.5),
    ]
}

/// Three renderings of `x` that all denote the same double: the shortest round trip, 17
/// significant digits in scientific form, and 25 digits (more than needed: the reader must
/// round correctly, not truncate).
fn renderings(x: f64) -> [String; 3] {
    [format!("{x:?}"), format!("{x:.16e}"), format!("{x:.24e}")]
}

fn bits(c: &Circle) -> [u64; 3] {
    [
        c.center[0].to_bits(),
        c.center[1].to_bits(),
        c.radius.to_bits(),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn json_and_csv_read_the_same_doubles(
        x in coordinate(), y in coordinate(), r in (1e-300f64..1e6), k in 0usize..3,
    ) {
        let (sx, sy, sr) = (&renderings(x)[k], &renderings(y)[k], &renderings(r)[k]);
        let csv = parse_holes_csv(&format!("x,y,r\n{sx},{sy},{sr}\n")).unwrap();
        let triple = parse_triple(&format!("{sx},{sy},{sr}")).unwrap();
        let json: serde_json::Value = serde_json::from_str(&format!(
            "{{\"center\": [{sx}, {sy}], \"radius\": {sr}}}"
        )).unwrap();
        let c: Circle = serde_json::from_value(json).unwrap();
        prop_assert_eq!(bits(&csv[0]), [x.to_bits(), y.to_bits(), r.to_bits()]);
        prop_assert_eq!(bits(&c), bits(&csv[0]));
        prop_assert_eq!(triple.map(f64::to_bits), bits(&csv[0]));
    }
}

/// The same layout as a domain JSON and as a CSV of holes with `--bounding` gives byte-identical
/// meshes.
#[test]
fn cli_meshes_json_and_csv_alike() {
    let d = medial_blocks::layouts::bubbles(12, 5).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("d.json");
    std::fs::write(&json, d.to_json_string()).unwrap();
    let mut csv = String::from("x,y,r\n");
    for h in d.holes() {
        // 17 significant digits, not the shortest form: a different text of the same doubles.
        csv.push_str(&format!(
            "{:.16e},{:.16e},{:.16e}\n",
            h.center[0], h.center[1], h.radius
        ));
    }
    let csv_path = dir.path().join("h.csv");
    std::fs::write(&csv_path, csv).unwrap();
    let b = d.bounding();
    let bounding = format!(
        "{:.16e},{:.16e},{:.16e}",
        b.center[0], b.center[1], b.radius
    );
    let bin = env!("CARGO_BIN_EXE_medial-blocks");
    let run = |input: &std::path::Path, out: &str, extra: &[&str]| {
        let o = dir.path().join(out);
        let status = Command::new(bin)
            .arg("mesh")
            .arg(input)
            .args(extra)
            .args(["--quiet", "--format", "vtk,json", "-o"])
            .arg(&o)
            .status()
            .unwrap();
        assert!(status.success());
        o
    };
    let a = run(&json, "a", &[]);
    let c = run(&csv_path, "c", &["--bounding", &bounding]);
    let (fa, fc) = (tree(&a), tree(&c));
    assert!(fa.len() >= 3, "files written: {}", fa.len());
    assert_eq!(
        fa.iter().map(|f| &f.0).collect::<Vec<_>>(),
        fc.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for ((n, x), (_, y)) in fa.iter().zip(&fc) {
        assert!(x == y, "{n:?} differs between the JSON and the CSV input");
    }
    let _ = Domain::from_json_str(&d.to_json_string()).unwrap();
}
