//! `medial-blocks mesh` on periodic input (JSON with "periodic", or CSV with --periodic).

use crate::common;
use common::{assert_spans_add_up, assert_stages_add_up, bin};

#[test]
fn periodic_json_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("p.json");
    std::fs::write(
        &json,
        r#"{"periodic": {"size": [2, 1]}, "holes": [{"center": [0.1, 0.1], "radius": 0.2},
            {"center": [1.2, 0.6], "radius": 0.25}]}"#,
    )
    .unwrap();
    let out = dir.path().join("o1");
    let r = bin()
        .args(["mesh", json.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(stdout.contains("12 blocks"), "{stdout}");
    let conn = std::fs::read_to_string(out.join("connectivity.json")).unwrap();
    assert!(conn.contains("\"periodic\"") && conn.contains("\"translation\""));
    let svg = std::fs::read_to_string(out.join("mesh.svg")).unwrap();
    assert!(
        svg.contains("stroke-dasharray"),
        "the period's box is drawn"
    );

    let csv = dir.path().join("p.csv");
    std::fs::write(&csv, "x,y,r\n0.1,0.1,0.2\n1.2,0.6,0.25\n").unwrap();
    let out2 = dir.path().join("o2");
    let r = bin()
        .args(["mesh", csv.to_str().unwrap(), "--periodic", "2,1", "-o"])
        .arg(&out2)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // Bad period: exit code 2 and a clear message.
    let r = bin()
        .args([
            "mesh",
            csv.to_str().unwrap(),
            "--periodic",
            "0.3,1",
            "-q",
            "-o",
        ])
        .arg(dir.path().join("o3"))
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("diameter"), "{err}");
    // --periodic with JSON input is refused.
    let r = bin()
        .args([
            "mesh",
            json.to_str().unwrap(),
            "--periodic",
            "2,1",
            "-q",
            "-o",
        ])
        .arg(dir.path().join("o4"))
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
}

/// `--timings` on a periodic domain attributes the work to the pipeline's stages (before,
/// everything but input and writing fell into `other`), in exact mode and in paper mode,
/// and the stages still add up to the total.
#[test]
fn periodic_timings_name_the_stages() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("p.json");
    std::fs::write(
        &json,
        r#"{"periodic": {"size": [2, 1]}, "holes": [{"center": [0.1, 0.1], "radius": 0.2},
            {"center": [1.2, 0.6], "radius": 0.25}, {"center": [0.9, 0.2], "radius": 0.1}]}"#,
    )
    .unwrap();
    for (mode, stages) in [
        (
            "exact",
            &[
                "sampling",
                "triangulation",
                "medial_graph",
                "blocking",
                "exact_geometry",
                "quality_check",
            ][..],
        ),
        (
            "paper",
            &[
                "sampling",
                "triangulation",
                "medial_graph",
                "blocking",
                "grids",
            ][..],
        ),
    ] {
        let out = dir.path().join(mode);
        let r = bin()
            .args(["--quiet", "mesh", json.to_str().unwrap(), "--timings"])
            .args(["--mode", mode, "--format", "json", "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let t: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("timings.json")).unwrap()).unwrap();
        for s in stages {
            assert!(
                t["calls"][*s].as_u64().is_some_and(|c| c >= 1),
                "{mode}: stage {s} never entered: {t}"
            );
        }
        assert_stages_add_up(&t);
        assert_spans_add_up(&t);
    }
}
