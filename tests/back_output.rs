//! Back end end-to-end: template -> build_grids -> quality -> writers, read back by small
//! independent parsers; determinism of every file.

use crate::common;

use common::tree;
use medial_blocks::domain::Circle;
use medial_blocks::grid::build_grids;
use medial_blocks::layout::BlockLayout;
use medial_blocks::mesh::Mesh;
use medial_blocks::output::report::{write_json, Report};
use medial_blocks::output::{gmsh, svg, vtk, vtu, Encoding};
use medial_blocks::quality::measure;
use medial_blocks::templates::{annulus, disk};
use std::path::Path;

fn make_mesh(layout: BlockLayout, holes: usize, cells: usize) -> Mesh {
    let grids = build_grids(&layout, cells).unwrap();
    Mesh {
        layout,
        grids,
        medial_vertices: 0,
        medial_arcs: 0,
        holes,
        ..Mesh::default()
    }
}

fn meshes() -> Vec<(String, Mesh, usize)> {
    let big = Circle {
        center: [0.5, -0.25],
        radius: 2.0,
    };
    let mut out = vec![("disk".to_string(), make_mesh(disk(big), 0, 6), 1)];
    for (k, &(dx, dy, r)) in [
        (0.0, 0.0, 0.5),
        (1.2, 0.3, 0.4),
        (-0.3, -1.6, 0.2),
        (0.0, 1.97, 0.01),
    ]
    .iter()
    .enumerate()
    {
        let hole = Circle {
            center: [big.center[0] + dx, big.center[1] + dy],
            radius: r,
        };
        out.push((
            format!("annulus{k}"),
            make_mesh(annulus(big, hole), 1, 5),
            2,
        ));
    }
    out
}

/// The text between `<tag ...>` and `</tag>` of the first DataArray whose opening tag
/// contains `marker`.
fn data_array<'a>(xml: &'a str, marker: &str) -> &'a str {
    let start = xml.find(marker).unwrap_or_else(|| panic!("no {marker}"));
    let open_end = start + xml[start..].find('>').unwrap() + 1;
    let close = open_end + xml[open_end..].find("</DataArray>").unwrap();
    &xml[open_end..close]
}

fn numbers(s: &str) -> Vec<f64> {
    s.split_whitespace()
        .map(|t| t.parse::<f64>().unwrap())
        .collect()
}

fn attr<'a>(tag: &'a str, name: &str) -> &'a str {
    let key = format!("{name}=\"");
    let s = tag.find(&key).unwrap() + key.len();
    let e = s + tag[s..].find('"').unwrap();
    &tag[s..e]
}

fn check_vtk(mesh: &Mesh, dir: &Path) {
    let vtm = std::fs::read_to_string(dir.join("mesh.vtm")).unwrap();
    assert!(vtm.starts_with("<?xml"));
    assert!(vtm.contains("type=\"vtkMultiBlockDataSet\""));
    let files: Vec<&str> = vtm
        .match_indices("<DataSet ")
        .map(|(i, _)| attr(&vtm[i..], "file"))
        .collect();
    assert_eq!(files.len(), mesh.grids.len());
    for (b, (file, g)) in files.iter().zip(&mesh.grids).enumerate() {
        let vts = std::fs::read_to_string(dir.join(file)).unwrap();
        assert!(vts.trim_end().ends_with("</VTKFile>"));
        let ext = format!("0 {} 0 {} 0 0", g.ni, g.nj);
        assert_eq!(attr(&vts, "WholeExtent"), ext);
        let piece = &vts[vts.find("<Piece").unwrap()..];
        assert_eq!(attr(piece, "Extent"), ext);
        let pts = numbers(data_array(&vts, "NumberOfComponents=\"3\""));
        assert_eq!(pts.len(), 3 * g.nodes.len());
        for (k, p) in g.nodes.iter().enumerate() {
            // Round-trip formatting: exact equality.
            assert_eq!(pts[3 * k], p[0]);
            assert_eq!(pts[3 * k + 1], p[1]);
            assert_eq!(pts[3 * k + 2], 0.0);
        }
        let ids = numbers(data_array(&vts, "Name=\"block_id\""));
        assert_eq!(ids.len(), g.cells());
        assert!(ids.iter().all(|&x| x == b as f64));
        let mins = numbers(data_array(&vts, "Name=\"min_angle_deg\""));
        assert_eq!(mins.len(), g.cells());
        // Independent recomputation of cell 0's smallest angle.
        let at = |i: usize, j: usize| g.nodes[i + j * (g.ni + 1)];
        let p = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)];
        let mut lo = f64::INFINITY;
        for k in 0..4 {
            let (o, a, c) = (p[k], p[(k + 1) % 4], p[(k + 3) % 4]);
            let (u, v) = ([a[0] - o[0], a[1] - o[1]], [c[0] - o[0], c[1] - o[1]]);
            let cos = (u[0] * v[0] + u[1] * v[1]) / (u[0].hypot(u[1]) * v[0].hypot(v[1]));
            lo = lo.min(cos.clamp(-1.0, 1.0).acos().to_degrees());
        }
        assert!((mins[0] - lo).abs() < 1e-9, "{} vs {lo}", mins[0]);
    }
}

fn write_everything(mesh: &Mesh, dir: &Path) {
    vtk::write_multiblock(mesh, dir).unwrap();
    svg::write(mesh, &dir.join("mesh.svg")).unwrap();
    write_json(&Report::from_mesh(mesh), &dir.join("report.json")).unwrap();
}

#[test]
fn end_to_end_writers_read_back() {
    for (name, mesh, circles) in meshes() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join(&name);
        write_everything(&mesh, &dir);
        check_vtk(&mesh, &dir);

        // Report: every required key, right values.
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap())
                .unwrap();
        let q = measure(&mesh.grids);
        let cells: usize = mesh.grids.iter().map(|g| g.ni * g.nj).sum();
        let expect = [
            ("holes", serde_json::json!(mesh.holes)),
            ("blocks", serde_json::json!(mesh.layout.blocks.len())),
            ("cells", serde_json::json!(cells)),
            ("min_angle_deg", serde_json::json!(q.min_angle_deg)),
            ("max_angle_deg", serde_json::json!(q.max_angle_deg)),
            (
                "mean_min_angle_deg",
                serde_json::json!(q.mean_min_angle_deg),
            ),
            (
                "mean_max_angle_deg",
                serde_json::json!(q.mean_max_angle_deg),
            ),
            ("inverted_cells", serde_json::json!(0)),
            ("medial_vertices", serde_json::json!(0)),
            ("medial_arcs", serde_json::json!(0)),
        ];
        for (key, value) in expect {
            let got = json
                .get(key)
                .unwrap_or_else(|| panic!("{name}: no key {key}"));
            if value.is_u64() {
                assert_eq!(got, &value, "{name}: key {key}");
            } else {
                // serde_json's default float parsing may be off by an ulp.
                let (g, e) = (got.as_f64().unwrap(), value.as_f64().unwrap());
                assert!(
                    (g - e).abs() <= 1e-12 * e.abs(),
                    "{name}: key {key}: {g} vs {e}"
                );
            }
        }
        assert_eq!(json["blocks"], if name == "disk" { 5 } else { 4 });

        // SVG: well-formed-ish, one <circle per circle.
        let svg = std::fs::read_to_string(dir.join("mesh.svg")).unwrap();
        assert!(svg.starts_with("<svg"));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<circle").count(), circles, "{name}");
        assert_eq!(svg.matches("<g").count(), svg.matches("</g>").count());
        assert!(svg.contains("viewBox=\"0 0 1000 "));

        // No temporary files left behind.
        for (f, _) in tree(&dir) {
            assert!(!f.contains(".tmp"), "{f}");
        }
    }
}

#[test]
fn writing_twice_is_byte_identical() {
    for (name, mesh, _) in meshes() {
        let tmp = tempfile::tempdir().unwrap();
        let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
        write_everything(&mesh, &a);
        write_everything(&mesh, &b);
        let (fa, fb) = (tree(&a), tree(&b));
        assert_eq!(fa.len(), mesh.grids.len() + 3);
        assert_eq!(fa, fb, "{name}");
        // Rebuilding the mesh from scratch also gives the same bytes.
        write_everything(&meshes().into_iter().find(|m| m.0 == name).unwrap().1, &b);
        assert_eq!(fa, tree(&b), "{name}");
    }
}

#[test]
fn writers_refuse_inconsistent_meshes_without_panicking() {
    let (_, mut mesh, _) = meshes().remove(0);
    mesh.grids.pop();
    let tmp = tempfile::tempdir().unwrap();
    assert!(vtk::write_multiblock(&mesh, tmp.path()).is_err());
    assert!(svg::write(&mesh, &tmp.path().join("m.svg")).is_err());
    assert!(!tmp.path().join("m.svg").exists());
    let (_, mut mesh, _) = meshes().remove(0);
    mesh.grids[0].nodes.pop();
    assert!(vtk::write_multiblock(&mesh, tmp.path()).is_err());
    // The unstructured writers (merged nodes) check the mesh first too.
    assert!(vtu::write_vtu(&mesh, &tmp.path().join("m.vtu")).is_err());
    assert!(gmsh::write_msh(&mesh, &tmp.path().join("m.msh")).is_err());
    for corrupt in [
        |m: &mut Mesh| m.layout.blocks[1].sides[2].edge = m.layout.edges.len() as u32,
        |m: &mut Mesh| m.layout.blocks[0].corners[3] = m.layout.vertices.len() as u32 + 7,
    ] {
        let (_, mut mesh, _) = meshes().remove(0);
        corrupt(&mut mesh);
        for encoding in [Encoding::Ascii, Encoding::Binary] {
            let err = vtu::write_vtu_encoded(&mesh, &tmp.path().join("m.vtu"), encoding)
                .expect_err("a dangling edge or vertex");
            assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
            assert!(
                err.to_string().contains("the layout does not have"),
                "{err}"
            );
            assert!(gmsh::write_msh_encoded(&mesh, &tmp.path().join("m.msh"), encoding).is_err());
        }
        assert!(vtk::write_multiblock(&mesh, tmp.path()).is_err());
        assert!(svg::write(&mesh, &tmp.path().join("m.svg")).is_err());
    }
    assert!(!tmp.path().join("m.vtu").exists() && !tmp.path().join("m.msh").exists());
    // Report of a malformed mesh: no panic.
    let _ = Report::from_mesh(&mesh);
    // Unwritable target: an error, no panic.
    let (_, mesh, _) = meshes().remove(0);
    let file = tmp.path().join("plain");
    std::fs::write(&file, b"x").unwrap();
    assert!(vtk::write_multiblock(&mesh, &file.join("sub")).is_err());
    assert!(svg::write(&mesh, &file.join("m.svg")).is_err());
}
