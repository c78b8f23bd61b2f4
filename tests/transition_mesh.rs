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
    let one_hole = Domain::bounded(
        Circle::new(0.0, 0.0, 2.0),
        vec![Circle::new(0.4, -0.3, 0.5)],
    )
    .unwrap();
    for (d, bounds, s, min_walls) in [
        (
            Domain::hexagon_example(),
            [-3.0, -3.0, 3.0, 3.0],
            0.25,
            6 * 5,
        ),
        (
            Domain::hexagon_example(),
            [-7.5, -2.5, 7.5, 2.5],
            0.25,
            6 * 5,
        ),
        // One hole: exact mode's annulus (4 blocks on the hole) keeps its grids too.
        (one_hole, [-3.0, -3.0, 3.0, 3.0], 0.25, 4),
    ] {
        let b = d.bounding();
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
        assert!(walls >= min_walls, "the hole blocks are there");
        assert_eq!(mesh.geometry, medial_blocks::mesh::Geometry::Exact);
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

/// What a transition mesh must satisfy on every layout, checked from coordinates: the outer
/// sides' nodes are exactly lattice nodes of the rectangle's boundary, one lattice interval
/// apart, each boundary node once with the four corners; every interface side's partner has
/// the same node count and the same nodes; no inverted cell (every cell strictly
/// counter-clockwise at its four corners) whenever the geometry is labelled exact. Returns
/// the geometry and the inverted cells.
fn check_any(
    domain: &Domain,
    rect: Rect,
    opts: &Options,
) -> (medial_blocks::mesh::Geometry, usize) {
    use medial_blocks::mesh::Geometry;
    let spacing = rect.spacing;
    let (i0, j0, i1, j1) = (rect.i0, rect.j0, rect.i0 + rect.nx, rect.j0 + rect.ny);
    let mesh = mesh_with_transition_rect(domain, opts, rect)
        .unwrap_or_else(|e| panic!("{domain:?} spacing {spacing}: {e}"));
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
                    assert_eq!(nodes.len(), other.len(), "partner node count");
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
    if mesh.geometry == Geometry::Exact {
        no_inverted_cells(&mesh);
    }
    (mesh.geometry, measure(&mesh.grids).inverted_cells)
}

fn bounded(holes: &[(f64, f64, f64)]) -> Domain {
    Domain::bounded(
        Circle::new(0.0, 0.0, 1.0),
        holes
            .iter()
            .map(|&(x, y, r)| Circle::new(x, y, r))
            .collect(),
    )
    .unwrap()
}

/// Robustness sweep reproduction 1: a hole 0.01 from the bounding circle. The wall nodes of
/// the bounding arc facing it crowd towards the gap while the lattice nodes are evenly
/// spaced: the straight ring folded (8 inverted cells labelled exact). The polar ring keeps
/// the exact grids with no inverted cell.
#[test]
fn hole_near_the_bounding_circle_keeps_a_valid_exact_ring() {
    use medial_blocks::mesh::Geometry;
    let d = bounded(&[(0.0, -0.69, 0.3), (0.0, 0.4, 0.2)]);
    let b = d.bounding();
    for s in [0.1, 0.07, 0.05] {
        let rect = Rect::around(b.center, b.radius, s).unwrap();
        let (geometry, inverted) = check_any(&d, rect, &Options::default());
        assert_eq!(geometry, Geometry::Exact, "spacing {s}");
        assert_eq!(inverted, 0, "spacing {s}");
    }
}

/// Robustness sweep reproduction 2: four equal holes of a square (a k-gon of the stress
/// sweep); refinement inserts a hole whose template ties two bounding-circle arcs into one
/// conformity class, which the lattice runs gave 6 and 26 cells (exit 2: `edge ... must
/// have 6 cells, but its conformity class must have 26`). The runs of tied arcs now get one
/// count, in exact and in paper mode.
#[test]
fn bounding_arcs_tied_by_a_template_get_one_lattice_count() {
    let d = bounded(&[
        (
            0.009446535856663968,
            0.19293100912102235,
            0.05962542605942259,
        ),
        (
            -0.12750743599574926,
            0.32988498097343555,
            0.05962542605942259,
        ),
        (
            -0.2644614078481625,
            0.19293100912102237,
            0.05962542605942259,
        ),
        (
            -0.1275074359957493,
            0.055977037268609114,
            0.05962542605942259,
        ),
    ]);
    let b = d.bounding();
    for s in [0.07, 0.1, 0.05] {
        let rect = Rect::around(b.center, b.radius, s).unwrap();
        check_any(&d, rect, &Options::default());
        check_any(&d, rect, &Options::paper());
    }
    // Three holes of the sweep (a tiny one between two others), the same failure.
    let d = bounded(&[
        (0.3656049481636551, 0.5081597091631754, 0.14046137813394693),
        (0.541987477801507, 0.6161728312402284, 0.06623195609226751),
        (0.29421855184464035, 0.6300510697956857, 0.00079535309850294),
    ]);
    let rect = Rect::around(b.center, b.radius, 0.07).unwrap();
    check_any(&d, rect, &Options::default());
}

/// Robustness sweep reproduction 3: inserted holes (here around a near-touching pair) made
/// the block keys of the imposed counts ambiguous, so every grid was interpolated. The
/// exact grids are kept.
#[test]
fn inserted_holes_keep_the_exact_grids() {
    use medial_blocks::mesh::Geometry;
    let d = bounded(&[
        (0.08739588229724349, 0.4209111728772229, 0.09567980352601023),
        (-0.1291030299574446, 0.3780248773340127, 0.12502478429138764),
        (0.2830494928550108, 0.49587835616678144, 0.11383287855476072),
        (
            0.20257794027871398,
            0.5799068617466937,
            0.002357519698353887,
        ),
        (
            -0.5951513260608847,
            -0.20727843895705889,
            0.10272005289417385,
        ),
        (
            -0.4180936624365045,
            -0.08969334320568736,
            0.10982191951233189,
        ),
        (
            -0.43174920189386484,
            -0.19952892428511623,
            0.0008590963559601647,
        ),
        (
            -0.26457625287416786,
            0.23232921510934576,
            0.07392293258621899,
        ),
        (
            0.14380150162305294,
            -0.5718707105920642,
            0.13726523546792976,
        ),
        (0.1713590083267636, 0.2795506638855025, 0.0686645004533415),
        (0.27139678127306066, 0.6631288715769333, 0.05382303911741289),
        (
            -0.48323626761207034,
            -0.3332211852133584,
            0.06484207533758087,
        ),
        (0.49138879020693094, 0.6127212307064667, 0.12474704485182816),
    ]);
    let plain = medial_blocks::mesh(&d, &Options::default()).unwrap();
    assert!(
        !plain.inserted_holes.is_empty(),
        "the layout has inserted holes"
    );
    let b = d.bounding();
    let rect = Rect::around(b.center, b.radius, 0.07).unwrap();
    let (geometry, inverted) = check_any(&d, rect, &Options::default());
    assert_eq!(geometry, Geometry::Exact);
    assert_eq!(inverted, 0);
}

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

/// Layout `seed` of the sweep: random bubbles, holes near the bounding circle (gaps from
/// 1e-2 to 1e-6 of the radius), a regular k-gon (with a centre hole or not) or a lattice of
/// equal holes, in the unit circle.
fn sweep_layout(seed: u64) -> Vec<(f64, f64, f64)> {
    let mut rng = Rng(seed.wrapping_mul(7919).wrapping_add(17));
    let mut holes: Vec<(f64, f64, f64)> = Vec::new();
    let fits = |holes: &[(f64, f64, f64)], x: f64, y: f64, r: f64| {
        x.hypot(y) + r < 1.0 - 1e-9
            && holes
                .iter()
                .all(|&(a, b, s)| (x - a).hypot(y - b) > r + s + 1e-3)
    };
    match seed % 4 {
        0 => {
            let n = 2 + (rng.next() * 12.0) as usize;
            for _ in 0..400 {
                if holes.len() >= n {
                    break;
                }
                let r = rng.range(0.03, 0.25 / (n as f64).sqrt() + 0.03);
                let (rho, t) = (rng.range(0.0, 1.0 - r - 0.01), rng.range(0.0, 6.3));
                let (x, y) = (rho * t.cos(), rho * t.sin());
                if fits(&holes, x, y, r) {
                    holes.push((x, y, r));
                }
            }
        }
        1 => {
            let n = 2 + (rng.next() * 5.0) as usize;
            for _ in 0..400 {
                if holes.len() >= n {
                    break;
                }
                let r = rng.range(0.05, 0.3);
                let gap = 10f64.powf(rng.range(-6.0, -2.0));
                let t = rng.range(0.0, 6.3);
                let d = 1.0 - r - gap;
                if fits(&holes, d * t.cos(), d * t.sin(), r) {
                    holes.push((d * t.cos(), d * t.sin(), r));
                }
            }
        }
        2 => {
            let k = 3 + (rng.next() * 8.0) as usize;
            let r = rng.range(0.03, 0.12);
            let ring = rng.range(r * 1.3 / (std::f64::consts::PI / k as f64).sin(), 0.8);
            let ph = rng.range(0.0, 1.0);
            for i in 0..k {
                let t = ph + std::f64::consts::TAU * i as f64 / k as f64;
                if fits(&holes, ring * t.cos(), ring * t.sin(), r) {
                    holes.push((ring * t.cos(), ring * t.sin(), r));
                }
            }
            if seed % 8 == 2 && fits(&holes, 0.0, 0.0, 0.5 * (ring - r)) {
                holes.push((0.0, 0.0, 0.5 * (ring - r)));
            }
        }
        _ => {
            let k = 2 + (rng.next() * 3.0) as usize;
            let sp = 1.2 / k as f64;
            let r = sp * rng.range(0.2, 0.45);
            for i in 0..k {
                for j in 0..k {
                    let (x, y) = (
                        (i as f64 - (k - 1) as f64 / 2.0) * sp,
                        (j as f64 - (k - 1) as f64 / 2.0) * sp,
                    );
                    if fits(&holes, x, y, r) {
                        holes.push((x, y, r));
                    }
                }
            }
        }
    }
    if holes.len() < 2 {
        holes = vec![(-0.4, 0.1, 0.2), (0.4, -0.1, 0.25)];
    }
    holes
}

/// Many layouts, spacings from coarse to fine and rectangles up to aspect 3: every mesh is
/// made (`Ok`) and satisfies [`check_any`]; and the exact grids are kept in most of the
/// exact-mode runs. The floor: on these cases the exact path was kept in 36 of 40 runs when
/// this test was written (the others have arcs split twice around an inserted hole, whose
/// block keys are ambiguous, or a ring no interpolation could make valid); the mesher
/// before this change kept it in about half of the runs of the stress sweep. Set
/// `TRANSITION_SWEEP=N` for `N` layouts instead of 20 (each in two spacings).
#[test]
fn transition_sweep_over_many_layouts() {
    use medial_blocks::mesh::Geometry;
    let n: u64 = std::env::var("TRANSITION_SWEEP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    let (mut runs, mut exact) = (0usize, 0usize);
    for seed in 0..n {
        let d = bounded(&sweep_layout(seed));
        let b = d.bounding();
        let spacings = [0.3, 0.12, 0.07, 0.04];
        let s = spacings[(seed % 4) as usize];
        let s2 = spacings[((seed + 2) % 4) as usize];
        let rect = Rect::around(b.center, b.radius, s).unwrap();
        let (g, _) = check_any(&d, rect, &Options::default());
        runs += 1;
        exact += usize::from(g == Geometry::Exact);
        // A rectangle of aspect up to 3, off-centre.
        let a = 1.0 + 2.0 * (seed % 3) as f64 / 2.0;
        let m = 1.1 + s2;
        let bounds = if seed % 2 == 0 {
            [-1.1 * m * a, -m, m * a, 1.05 * m]
        } else {
            [-m, -1.1 * m * a, 1.05 * m, m * a]
        };
        let rect = Rect::from_bounds(bounds, s2, b.center, b.radius).unwrap();
        let (g, _) = check_any(&d, rect, &Options::default());
        runs += 1;
        exact += usize::from(g == Geometry::Exact);
        if seed % 5 == 0 {
            let (g, _) = check_any(&d, rect, &Options::paper());
            assert_eq!(g, Geometry::Paper);
        }
    }
    eprintln!("transition sweep: exact grids kept in {exact} of {runs} runs");
    assert!(
        exact * 10 >= runs * 7,
        "exact grids kept in only {exact} of {runs} runs"
    );
}
