//! Cartesian transition: outer nodes exactly on the background lattice, conformity, validity.

use medial_blocks::connectivity::{connectivity, SideKind};
use medial_blocks::quality::measure;
use medial_blocks::transition::mesh_with_transition;
use medial_blocks::{Circle, Domain, Options};

fn on_lattice(x: f64, s: f64) -> bool {
    let i = (x / s).round() as i64;
    i as f64 * s == x
}

fn check(domain: &Domain, spacing: f64, cells: usize) {
    let opts = Options {
        cells,
        ..Options::default()
    };
    let mesh = mesh_with_transition(domain, &opts, spacing).unwrap();
    let conn = connectivity(&mesh.layout, &mesh.grids).unwrap();
    let mut outer_nodes = 0;
    let (mut xmin, mut xmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for bc in &conn {
        for sc in &bc.sides {
            let nodes = mesh.grids[bc.block].side(sc.side);
            match sc.kind {
                SideKind::Outer => {
                    for p in &nodes {
                        assert!(
                            on_lattice(p[0], spacing) && on_lattice(p[1], spacing),
                            "outer node {p:?} is not a lattice node"
                        );
                        xmin = xmin.min(p[0]);
                        xmax = xmax.max(p[0]);
                    }
                    // Consecutive outer nodes are one lattice interval apart.
                    for w in nodes.windows(2) {
                        let d = ((w[1][0] - w[0][0]).abs() + (w[1][1] - w[0][1]).abs()) / spacing;
                        assert!((d - 1.0).abs() < 1e-9, "outer step {d}");
                    }
                    outer_nodes += nodes.len() - 1;
                }
                SideKind::Interface => {
                    let p = sc.partner.unwrap();
                    let mut other = mesh.grids[p.block].side(p.side);
                    if !p.same_direction {
                        other.reverse();
                    }
                    assert_eq!(nodes, other, "conforming interface");
                }
                _ => {}
            }
        }
    }
    let n = ((xmax - xmin) / spacing).round() as usize;
    assert_eq!(outer_nodes, 4 * n, "every lattice node of the square once");
    let b = domain.bounding();
    assert!(xmin < b.center[0] - b.radius && xmax > b.center[0] + b.radius);
    let q = measure(&mesh.grids);
    assert_eq!(q.inverted_cells, 0, "valid cells");
    eprintln!(
        "transition s={spacing}: {} blocks, angles {:.1}..{:.1}",
        mesh.layout.blocks.len(),
        q.min_angle_deg,
        q.max_angle_deg
    );
}

#[test]
fn hexagon_with_transition() {
    let d = Domain::hexagon_example();
    for s in [0.5, 0.3, 0.173] {
        check(&d, s, 8);
    }
}

#[test]
fn off_centre_domain_with_transition() {
    let d = Domain::bounded(
        Circle::new(3.3, -1.7, 4.0),
        vec![
            Circle::new(2.0, -1.0, 1.0),
            Circle::new(5.0, -2.0, 0.7),
            Circle::new(3.0, -3.6, 0.5),
        ],
    )
    .unwrap();
    check(&d, 0.37, 8);
    // The annulus template (one hole) too.
    let a = Domain::bounded(Circle::new(0.0, 0.0, 2.0), vec![Circle::new(0.1, 0.0, 0.5)]).unwrap();
    check(&a, 0.25, 8);
}

#[test]
fn bad_spacing_is_refused() {
    let d = Domain::hexagon_example();
    for s in [0.0, -1.0, f64::NAN, 1e-12] {
        assert!(mesh_with_transition(&d, &Options::default(), s).is_err());
    }
}

#[test]
fn cli_transition_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let r = std::process::Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args([
            "mesh",
            "--transition",
            "0.3",
            "--format",
            "json",
            "-q",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let conn = std::fs::read_to_string(out.join("connectivity.json")).unwrap();
    assert!(conn.contains("\"outer\""));
}
