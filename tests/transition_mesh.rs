//! Cartesian transition: outer nodes exactly on the background lattice, conformity, validity.

use medial_blocks::connectivity::{connectivity, SideKind};
use medial_blocks::quality::measure;
use medial_blocks::transition::{mesh_with_transition, mesh_with_transition_rect, Rect};
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

/// Every cell counter-clockwise at all four corners, from coordinates.
fn no_inverted_cells(mesh: &medial_blocks::Mesh) {
    for (b, g) in mesh.grids.iter().enumerate() {
        for j in 0..g.nj {
            for i in 0..g.ni {
                let q = [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ];
                for c in 0..4 {
                    let (o, a, bb) = (q[c], q[(c + 1) % 4], q[(c + 3) % 4]);
                    let z = (a[0] - o[0]) * (bb[1] - o[1]) - (a[1] - o[1]) * (bb[0] - o[0]);
                    assert!(z > 0.0, "block {b} cell ({i}, {j}) corner {c}: {z:e}");
                }
            }
        }
    }
}

/// A rectangle transition: the outer nodes are exactly `(i s, j s)` for integers on the
/// rectangle's lattice boundary, each lattice node of the boundary once, the four corners
/// included; conforming interfaces; no inverted cell.
fn check_rect(domain: &Domain, bounds: [f64; 4], spacing: f64, opts: &Options) {
    let b = domain.bounding();
    let rect = Rect::from_bounds(bounds, spacing, b.center, b.radius).unwrap();
    let (i0, j0, i1, j1) = (rect.i0, rect.j0, rect.i0 + rect.nx, rect.j0 + rect.ny);
    // Grown outwards to the lattice.
    assert!((i0 as f64) * spacing <= bounds[0] && (i1 as f64) * spacing >= bounds[2]);
    assert!((j0 as f64) * spacing <= bounds[1] && (j1 as f64) * spacing >= bounds[3]);
    let mesh = mesh_with_transition_rect(domain, opts, rect).unwrap();
    let conn = connectivity(&mesh.layout, &mesh.grids).unwrap();
    let mut seen = std::collections::BTreeSet::new();
    let mut steps = 0;
    for bc in &conn {
        for sc in &bc.sides {
            let nodes = mesh.grids[bc.block].side(sc.side);
            match sc.kind {
                SideKind::Outer => {
                    for p in &nodes {
                        let (i, j) = (
                            (p[0] / spacing).round() as i64,
                            (p[1] / spacing).round() as i64,
                        );
                        assert_eq!(p[0], i as f64 * spacing, "x is exactly a lattice value");
                        assert_eq!(p[1], j as f64 * spacing, "y is exactly a lattice value");
                        let on_boundary = ((i == i0 || i == i1) && (j0..=j1).contains(&j))
                            || ((j == j0 || j == j1) && (i0..=i1).contains(&i));
                        assert!(on_boundary, "({i}, {j}) is on the rectangle");
                        seen.insert((i, j));
                    }
                    for w in nodes.windows(2) {
                        let d = ((w[1][0] - w[0][0]).abs() + (w[1][1] - w[0][1]).abs()) / spacing;
                        assert!((d - 1.0).abs() < 1e-9, "outer step {d}");
                    }
                    steps += nodes.len() - 1;
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
    let perimeter = 2 * (rect.nx + rect.ny) as usize;
    assert_eq!(steps, perimeter, "each boundary interval once");
    assert_eq!(seen.len(), perimeter, "each boundary node once");
    for c in [(i0, j0), (i1, j0), (i1, j1), (i0, j1)] {
        assert!(seen.contains(&c), "corner {c:?} is a node");
    }
    no_inverted_cells(&mesh);
}

#[test]
fn rectangles_up_to_aspect_three() {
    let d = Domain::hexagon_example();
    for opts in [
        Options {
            cells: 8,
            ..Options::default()
        },
        Options {
            cells: 8,
            ..Options::paper()
        },
    ] {
        for (bounds, s) in [
            ([-3.0, -3.0, 3.0, 3.0], 0.25),
            ([-4.5, -2.6, 4.5, 2.6], 0.2),
            ([-7.5, -2.5, 7.5, 2.5], 0.25),
            ([-2.5, -7.3, 2.5, 7.1], 0.3),
            ([-2.9, -2.45, 8.1, 2.5], 0.1),
        ] {
            check_rect(&d, bounds, s, &opts);
        }
    }
    let off = Domain::bounded(
        Circle::new(3.3, -1.7, 4.0),
        vec![
            Circle::new(2.0, -1.0, 1.0),
            Circle::new(5.0, -2.0, 0.7),
            Circle::new(3.0, -3.6, 0.5),
        ],
    )
    .unwrap();
    check_rect(&off, [-8.0, -6.0, 15.0, 2.6], 0.37, &Options::default());
}

#[test]
fn bad_rectangles_are_refused() {
    let b = Domain::hexagon_example().bounding();
    for bounds in [
        [-1.0, -3.0, 3.0, 3.0],               // cuts the circle
        [-(b.radius + 0.01), -3.0, 3.0, 3.0], // grown to the lattice: less than one interval to spare
        [3.0, -3.0, -3.0, 3.0],               // empty
        [f64::NAN, -3.0, 3.0, 3.0],           // not a number
        [-1e30, -3.0, 3.0, 3.0],              // too many intervals
    ] {
        let r = Rect::from_bounds(bounds, 0.25, b.center, b.radius);
        assert!(r.is_err(), "{bounds:?} accepted");
    }
}

#[test]
fn cli_transition_rect_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let r = std::process::Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args([
            "mesh",
            "--transition",
            "0.25",
            "--transition-rect=-6,-3,6,3",
            "--format",
            "json",
            "-q",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
        .args([
            "mesh",
            "--transition",
            "0.25",
            "--transition-rect=1,2,3",
            "-q",
            "-o",
        ])
        .arg(dir.path().join("p"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("XMIN,YMIN,XMAX,YMAX"));
}

/// Exact mode keeps its spoke-aligned grids inside the transition ring: on every block whose
/// side 0 lies on a hole, the first grid line off the wall is normal to it (transfinite
/// interpolation of the whole layout would not give that).
#[test]
fn exact_mode_grids_are_kept_inside_the_ring() {
    let d = Domain::hexagon_example();
    let b = d.bounding();
    for (bounds, s) in [
        ([-3.0, -3.0, 3.0, 3.0], 0.25),
        ([-7.5, -2.5, 7.5, 2.5], 0.25),
    ] {
        let rect = Rect::from_bounds(bounds, s, b.center, b.radius).unwrap();
        let mesh = mesh_with_transition_rect(&d, &Options::default(), rect).unwrap();
        let mut walls = 0;
        for g in &mesh.grids {
            let side = g.side(0);
            let Some(c) = d.holes().iter().find(|c| {
                side.iter().all(|p| {
                    ((p[0] - c.center[0]).hypot(p[1] - c.center[1]) - c.radius).abs() < 1e-9
                })
            }) else {
                continue;
            };
            walls += 1;
            for i in 0..=g.ni {
                let (p, q) = (g.node(i, 0), g.node(i, 1));
                let u = [p[0] - c.center[0], p[1] - c.center[1]];
                let v = [q[0] - p[0], q[1] - p[1]];
                let ang = (u[0] * v[1] - u[1] * v[0])
                    .atan2(u[0] * v[0] + u[1] * v[1])
                    .to_degrees()
                    .abs();
                assert!(ang < 0.5, "wall angle off by {ang} deg");
            }
        }
        assert!(walls >= 6 * 5, "the hole blocks are there");
        check_rect(&d, bounds, s, &Options::default());
    }
}

/// When exact mode's transition cannot keep the spoke-aligned grids (the exact mesher does not
/// honour the lattice counts imposed on the bounding-circle arcs), every grid is interpolated,
/// and the mesh says `Geometry::Paper`: exact geometry is never reported for interpolated
/// grids. Two holes near the bounding circle, spacing 0.07 (from the robustness sweep): the
/// interpolated mesh has inverted cells and was labelled exact. The hexagon keeps its exact
/// grids.
#[test]
fn interpolated_transition_is_not_labelled_exact() {
    use medial_blocks::mesh::Geometry;
    let d = Domain::bounded(
        Circle::new(0.0, 0.0, 1.0),
        vec![
            Circle::new(
                0.9413840504912407,
                -0.004767127675588344,
                0.05860257788639028,
            ),
            Circle::new(0.7322512631258415, -0.5563126007602222, 0.08039363288774218),
        ],
    )
    .unwrap();
    let m = mesh_with_transition(&d, &Options::default(), 0.07).unwrap();
    let inverted = measure(&m.grids).inverted_cells;
    assert!(
        m.geometry == Geometry::Paper || inverted == 0,
        "{:?} geometry with {inverted} inverted cells",
        m.geometry
    );
    let m = mesh_with_transition(&Domain::hexagon_example(), &Options::default(), 0.2).unwrap();
    assert_eq!(m.geometry, Geometry::Exact);
    assert_eq!(measure(&m.grids).inverted_cells, 0);
}
