//! The Plot3D, Gmsh and connectivity writers, each checked by an independent reader written
//! here, on a hand-made layout whose blocks start at different corners (so every side pairing
//! and orientation occurs) and whose nodes are exact integers.

use medial_blocks::connectivity::{connectivity, SideKind};
use medial_blocks::layout::{Block, BlockLayout, Curve, Edge, EdgeKind, SideRef};
use medial_blocks::mesh::{BlockGrid, Mesh};
use medial_blocks::output::{connectivity as conn_out, geo, gmsh, plot3d};
use std::collections::{BTreeSet, HashMap};

const CELLS_X: usize = 3;
const CELLS_Y: usize = 5;

/// A 3x2 arrangement of square cells of size 30; block k's corners start at a rotating corner.
fn layout_and_grids() -> (BlockLayout, Vec<BlockGrid>) {
    let (cols, rows) = (3usize, 2usize);
    let vid = |r: usize, c: usize| (r * (cols + 1) + c) as u32;
    let mut layout = BlockLayout::default();
    for r in 0..=rows {
        for c in 0..=cols {
            layout.vertices.push([30.0 * c as f64, 30.0 * r as f64]);
        }
    }
    let mut edge_of: HashMap<(u32, u32), u32> = HashMap::new();
    let mut grids = Vec::new();
    let mut k = 0;
    for r in 0..rows {
        for c in 0..cols {
            let ccw = [vid(r, c), vid(r, c + 1), vid(r + 1, c + 1), vid(r + 1, c)];
            let rot = k % 4;
            k += 1;
            let corners = [
                ccw[rot],
                ccw[(rot + 1) % 4],
                ccw[(rot + 2) % 4],
                ccw[(rot + 3) % 4],
            ];
            let mut sides = [SideRef {
                edge: 0,
                reversed: false,
            }; 4];
            for s in 0..4 {
                let (a, b) = (corners[s], corners[(s + 1) % 4]);
                let key = (a.min(b), a.max(b));
                let pa = layout.vertices[a as usize];
                let pb = layout.vertices[b as usize];
                let on_border = |p: [f64; 2], q: [f64; 2]| {
                    (p[0] == q[0] && (p[0] == 0.0 || p[0] == 90.0))
                        || (p[1] == q[1] && (p[1] == 0.0 || p[1] == 60.0))
                };
                let e = *edge_of.entry(key).or_insert_with(|| {
                    layout.edges.push(Edge {
                        ends: [a, b],
                        curve: Curve::Segment,
                        kind: if on_border(pa, pb) {
                            if pa[1] == 0.0 && pb[1] == 0.0 {
                                EdgeKind::Wall(-1)
                            } else {
                                EdgeKind::Wall(2)
                            }
                        } else {
                            EdgeKind::Interface
                        },
                    });
                    layout.edges.len() as u32 - 1
                });
                sides[s] = SideRef {
                    edge: e,
                    reversed: layout.edges[e as usize].ends[0] != a,
                };
            }
            layout.blocks.push(Block {
                corners,
                sides,
                wall: None,
            });
            // Side 0 horizontal -> ni = CELLS_X, else CELLS_Y.
            let p0 = layout.vertices[corners[0] as usize];
            let p1 = layout.vertices[corners[1] as usize];
            let (ni, nj) = if p0[1] == p1[1] {
                (CELLS_X, CELLS_Y)
            } else {
                (CELLS_Y, CELLS_X)
            };
            let q: Vec<[f64; 2]> = corners
                .iter()
                .map(|&v| layout.vertices[v as usize])
                .collect();
            let mut nodes = Vec::new();
            for j in 0..=nj {
                for i in 0..=ni {
                    let mut p = [0.0; 2];
                    for (axis, v) in p.iter_mut().enumerate() {
                        // Exact integer bilinear map: all values are multiples of 30 / 15.
                        let num = q[0][axis] * ((ni - i) * (nj - j)) as f64
                            + q[1][axis] * (i * (nj - j)) as f64
                            + q[2][axis] * (i * j) as f64
                            + q[3][axis] * ((ni - i) * j) as f64;
                        *v = num / (ni * nj) as f64;
                    }
                    nodes.push(p);
                }
            }
            grids.push(BlockGrid { ni, nj, nodes });
        }
    }
    (layout, grids)
}

fn mesh() -> Mesh {
    let (layout, grids) = layout_and_grids();
    Mesh {
        layout,
        grids,
        medial_vertices: 0,
        medial_arcs: 0,
        holes: 1,
        ..Mesh::default()
    }
}

/// 0-based (i, j) of node p along side s (independent restatement of the conventions).
fn node_on_side(g: &BlockGrid, s: usize, p: usize) -> (usize, usize) {
    match s {
        0 => (p, 0),
        1 => (g.ni, p),
        2 => (g.ni - p, g.nj),
        _ => (0, g.nj - p),
    }
}

/// The hand-made layout plus the disk and annulus templates gridded by `build_grids`.
fn meshes() -> Vec<Mesh> {
    use medial_blocks::domain::Circle;
    use medial_blocks::grid::build_grids;
    use medial_blocks::templates::{annulus, disk};
    let bounding = Circle {
        center: [0.5, -1.0],
        radius: 2.0,
    };
    let hole = Circle {
        center: [1.1, -0.7],
        radius: 0.4,
    };
    let mut out = vec![mesh()];
    for (layout, holes) in [(disk(bounding), 0), (annulus(bounding, hole), 1)] {
        let grids = build_grids(&layout, 7).expect("template grids");
        out.push(Mesh {
            layout,
            grids,
            medial_vertices: 0,
            medial_arcs: 0,
            holes,
            ..Mesh::default()
        });
    }
    out
}

#[test]
fn connectivity_partners_and_cgns_ranges_match_coordinates() {
    for m in meshes() {
        check_connectivity(&m);
    }
}

fn check_connectivity(m: &Mesh) {
    let conn = connectivity(&m.layout, &m.grids).expect("valid layout");
    let mut interfaces = 0;
    for bc in &conn {
        let g = &m.grids[bc.block];
        assert_eq!(bc.dims, [g.ni + 1, g.nj + 1]);
        for sc in &bc.sides {
            let n = if sc.side % 2 == 0 { g.ni } else { g.nj };
            match sc.kind {
                SideKind::Interface => {
                    interfaces += 1;
                    let p = sc.partner.expect("interface has a partner");
                    let pg = &m.grids[p.block];
                    // Partner relation is symmetric.
                    let back = conn[p.block].sides[p.side].partner.expect("symmetric");
                    assert_eq!((back.block, back.side), (bc.block, sc.side));
                    for k in 0..=n {
                        let (i, j) = node_on_side(g, sc.side, k);
                        let kk = if p.same_direction { k } else { n - k };
                        let (pi, pj) = node_on_side(pg, p.side, kk);
                        assert_eq!(g.node(i, j), pg.node(pi, pj));
                    }
                    // CGNS: walk the range with the transform and compare coordinates.
                    let c = sc.cgns.expect("cgns");
                    let [b0, b1] = c.point_range;
                    let d0 = c.point_range_donor[0];
                    let steps =
                        (b1[0] as i64 - b0[0] as i64).abs() + (b1[1] as i64 - b0[1] as i64).abs();
                    assert_eq!(steps as usize, n);
                    for t in 0..=steps {
                        let di = (b1[0] as i64 - b0[0] as i64).signum() * t;
                        let dj = (b1[1] as i64 - b0[1] as i64).signum() * t;
                        let here = [b0[0] as i64 + di, b0[1] as i64 + dj];
                        let delta = [di, dj];
                        let mut donor = [d0[0] as i64, d0[1] as i64];
                        for (tr, d) in c.transform.iter().zip(delta) {
                            donor[(tr.unsigned_abs() - 1) as usize] += tr.signum() as i64 * d;
                        }
                        let x = g.node(here[0] as usize - 1, here[1] as usize - 1);
                        let y = pg.node(donor[0] as usize - 1, donor[1] as usize - 1);
                        assert_eq!(x, y, "block {} side {} step {t}", bc.block, sc.side);
                    }
                    assert_eq!(c.point_range_donor[1].map(|v| v as i64), {
                        let mut donor = [d0[0] as i64, d0[1] as i64];
                        let delta = [b1[0] as i64 - b0[0] as i64, b1[1] as i64 - b0[1] as i64];
                        for (tr, d) in c.transform.iter().zip(delta) {
                            donor[(tr.unsigned_abs() - 1) as usize] += tr.signum() as i64 * d;
                        }
                        donor
                    });
                    // Both blocks are counter-clockwise, so the transform is a rotation:
                    // det(T) = +1 (a reflection would mean a flipped block).
                    let mut t = [[0i64; 2]; 2];
                    for (a, tr) in c.transform.iter().enumerate() {
                        t[(tr.unsigned_abs() - 1) as usize][a] = tr.signum() as i64;
                    }
                    assert_eq!(t[0][0] * t[1][1] - t[0][1] * t[1][0], 1);
                }
                SideKind::Periodic => panic!("a bounded mesh has no periodic side"),
                SideKind::Wall | SideKind::Outer => {
                    assert!(sc.partner.is_none());
                    assert_eq!(sc.kind == SideKind::Outer, sc.circle == Some(-1));
                }
            }
        }
    }
    // Every non-wall edge is seen from both sides.
    let interface_edges = m
        .layout
        .edges
        .iter()
        .filter(|e| !matches!(e.kind, EdgeKind::Wall(_)))
        .count();
    assert_eq!(interfaces, 2 * interface_edges);
}

#[test]
fn connectivity_json_parses_and_names_every_side() {
    let m = mesh();
    let conn = connectivity(&m.layout, &m.grids).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("connectivity.json");
    conn_out::write_json(&conn, &path).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let blocks = v["blocks"].as_array().unwrap();
    assert_eq!(blocks.len(), m.grids.len());
    for b in blocks {
        let sides = b["sides"].as_array().unwrap();
        assert_eq!(sides.len(), 4);
        for s in sides {
            let kind = s["kind"].as_str().unwrap();
            assert!(["wall", "outer", "interface"].contains(&kind));
            assert_eq!(kind == "interface", s.get("partner").is_some());
            assert_eq!(kind == "interface", s.get("cgns").is_some());
        }
    }
    assert!(v["conventions"].as_str().unwrap().contains("j_min"));
}

fn read_records(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        let body = &bytes[at + 4..at + 4 + len];
        let tail = u32::from_le_bytes(bytes[at + 4 + len..at + 8 + len].try_into().unwrap());
        assert_eq!(tail as usize, len, "record markers agree");
        out.push(body);
        at += len + 8;
    }
    out
}

#[test]
fn plot3d_binary_reads_back_exactly() {
    let m = mesh();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.xyz");
    plot3d::write_binary(&m.grids, &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let recs = read_records(&bytes);
    assert_eq!(recs.len(), 2 + m.grids.len());
    assert_eq!(
        i32::from_le_bytes(recs[0].try_into().unwrap()) as usize,
        m.grids.len()
    );
    let dims: Vec<i32> = recs[1]
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    for (b, g) in m.grids.iter().enumerate() {
        assert_eq!(dims[2 * b] as usize, g.ni + 1);
        assert_eq!(dims[2 * b + 1] as usize, g.nj + 1);
        let vals: Vec<f64> = recs[2 + b]
            .chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let n = g.nodes.len();
        assert_eq!(vals.len(), 2 * n);
        for (k, p) in g.nodes.iter().enumerate() {
            assert_eq!(vals[k], p[0]);
            assert_eq!(vals[n + k], p[1]);
        }
    }
}

#[test]
fn plot3d_ascii_reads_back_exactly() {
    let m = mesh();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.p3d");
    plot3d::write_ascii(&m.grids, &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let mut tok = text.split_whitespace();
    let nb: usize = tok.next().unwrap().parse().unwrap();
    assert_eq!(nb, m.grids.len());
    let dims: Vec<(usize, usize)> = (0..nb)
        .map(|_| {
            (
                tok.next().unwrap().parse().unwrap(),
                tok.next().unwrap().parse().unwrap(),
            )
        })
        .collect();
    for (g, d) in m.grids.iter().zip(&dims) {
        assert_eq!(*d, (g.ni + 1, g.nj + 1));
        for axis in 0..2 {
            for p in &g.nodes {
                let v: f64 = tok.next().unwrap().parse().unwrap();
                assert_eq!(v, p[axis]);
            }
        }
    }
    assert!(tok.next().is_none());
}

/// A tiny independent reader of the Gmsh 4.1 ASCII sections used here.
struct Msh {
    physical: Vec<(i32, i32, String)>,
    nodes: HashMap<usize, [f64; 2]>,
    lines: Vec<(usize, [usize; 2])>,
    quads: Vec<(usize, [usize; 4])>,
    curve_phys: HashMap<usize, i32>,
}

fn read_msh(text: &str) -> Msh {
    let mut lines = text.lines();
    let mut msh = Msh {
        physical: vec![],
        nodes: HashMap::new(),
        lines: vec![],
        quads: vec![],
        curve_phys: HashMap::new(),
    };
    while let Some(l) = lines.next() {
        match l {
            "$MeshFormat" => assert_eq!(lines.next().unwrap(), "4.1 0 8"),
            "$PhysicalNames" => {
                let n: usize = lines.next().unwrap().parse().unwrap();
                for _ in 0..n {
                    let l = lines.next().unwrap();
                    let mut it = l.splitn(3, ' ');
                    let dim = it.next().unwrap().parse().unwrap();
                    let tag = it.next().unwrap().parse().unwrap();
                    msh.physical
                        .push((dim, tag, it.next().unwrap().trim_matches('"').to_string()));
                }
            }
            "$Entities" => {
                let c: Vec<usize> = lines
                    .next()
                    .unwrap()
                    .split(' ')
                    .map(|v| v.parse().unwrap())
                    .collect();
                for _ in 0..c[1] {
                    let f: Vec<&str> = lines.next().unwrap().split(' ').collect();
                    assert_eq!(f[7], "1");
                    msh.curve_phys
                        .insert(f[0].parse().unwrap(), f[8].parse().unwrap());
                }
                for _ in 0..c[2] {
                    lines.next();
                }
            }
            "$Nodes" => {
                let h: Vec<usize> = lines
                    .next()
                    .unwrap()
                    .split(' ')
                    .map(|v| v.parse().unwrap())
                    .collect();
                for _ in 0..h[0] {
                    let b: Vec<usize> = lines
                        .next()
                        .unwrap()
                        .split(' ')
                        .map(|v| v.parse().unwrap())
                        .collect();
                    let tags: Vec<usize> = (0..b[3])
                        .map(|_| lines.next().unwrap().parse().unwrap())
                        .collect();
                    for t in tags {
                        let xyz: Vec<f64> = lines
                            .next()
                            .unwrap()
                            .split(' ')
                            .map(|v| v.parse().unwrap())
                            .collect();
                        msh.nodes.insert(t, [xyz[0], xyz[1]]);
                    }
                }
                assert_eq!(msh.nodes.len(), h[1]);
            }
            "$Elements" => {
                let h: Vec<usize> = lines
                    .next()
                    .unwrap()
                    .split(' ')
                    .map(|v| v.parse().unwrap())
                    .collect();
                let mut count = 0;
                for _ in 0..h[0] {
                    let b: Vec<usize> = lines
                        .next()
                        .unwrap()
                        .split(' ')
                        .map(|v| v.parse().unwrap())
                        .collect();
                    for _ in 0..b[3] {
                        let e: Vec<usize> = lines
                            .next()
                            .unwrap()
                            .split(' ')
                            .map(|v| v.parse().unwrap())
                            .collect();
                        count += 1;
                        match b[2] {
                            1 => msh.lines.push((b[1], [e[1], e[2]])),
                            3 => msh.quads.push((b[1], [e[1], e[2], e[3], e[4]])),
                            t => panic!("unexpected element type {t}"),
                        }
                    }
                }
                assert_eq!(count, h[1]);
            }
            _ => {}
        }
    }
    msh
}

#[test]
fn gmsh_msh_merges_shared_nodes_on_templates() {
    for m in meshes().into_iter().skip(1) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mesh.msh");
        gmsh::write_msh(&m, &path).unwrap();
        let msh = read_msh(&std::fs::read_to_string(&path).unwrap());
        let distinct: BTreeSet<(u64, u64)> = m
            .grids
            .iter()
            .flat_map(|g| g.nodes.iter().map(|p| (p[0].to_bits(), p[1].to_bits())))
            .collect();
        assert_eq!(msh.nodes.len(), distinct.len());
        for (_, q) in &msh.quads {
            let p: Vec<[f64; 2]> = q.iter().map(|t| msh.nodes[t]).collect();
            let area2: f64 = (0..4)
                .map(|k| p[k][0] * p[(k + 1) % 4][1] - p[(k + 1) % 4][0] * p[k][1])
                .sum();
            assert!(area2 > 0.0);
        }
        let outer = msh
            .lines
            .iter()
            .filter(|(c, _)| msh.curve_phys[c] == 2)
            .count();
        let mut expected = 0;
        for (b, g) in m.layout.blocks.iter().zip(&m.grids) {
            for (s, side) in b.sides.iter().enumerate() {
                if m.layout.edges[side.edge as usize].kind == EdgeKind::Wall(-1) {
                    expected += if s % 2 == 0 { g.ni } else { g.nj };
                }
            }
        }
        assert_eq!(outer, expected, "one line element per bounding-circle cell");
        assert!(outer >= 4 * 7);
    }
}

#[test]
fn gmsh_msh_merges_shared_nodes_and_keeps_every_cell() {
    let m = mesh();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.msh");
    gmsh::write_msh(&m, &path).unwrap();
    let msh = read_msh(&std::fs::read_to_string(&path).unwrap());
    // Shared nodes merged: the node count equals the number of distinct coordinates.
    let distinct: BTreeSet<(u64, u64)> = m
        .grids
        .iter()
        .flat_map(|g| g.nodes.iter().map(|p| (p[0].to_bits(), p[1].to_bits())))
        .collect();
    assert_eq!(msh.nodes.len(), distinct.len());
    let node_coords: BTreeSet<(u64, u64)> = msh
        .nodes
        .values()
        .map(|p| (p[0].to_bits(), p[1].to_bits()))
        .collect();
    assert_eq!(node_coords, distinct);
    // Every cell present once, counter-clockwise.
    let cells: usize = m.grids.iter().map(|g| g.ni * g.nj).sum();
    assert_eq!(msh.quads.len(), cells);
    let mut centroids = BTreeSet::new();
    for (_, q) in &msh.quads {
        let p: Vec<[f64; 2]> = q.iter().map(|t| msh.nodes[t]).collect();
        let area2: f64 = (0..4)
            .map(|k| p[k][0] * p[(k + 1) % 4][1] - p[(k + 1) % 4][0] * p[k][1])
            .sum();
        assert!(area2 > 0.0);
        let c = [(p[0][0] + p[2][0]) * 0.5, (p[0][1] + p[2][1]) * 0.5];
        assert!(
            centroids.insert((c[0].to_bits(), c[1].to_bits())),
            "cell twice"
        );
    }
    // Physical groups: fluid, outer, interfaces, wall_2.
    let names: BTreeSet<&str> = msh.physical.iter().map(|p| p.2.as_str()).collect();
    assert_eq!(
        names,
        ["fluid", "interfaces", "outer", "wall_2"]
            .into_iter()
            .collect()
    );
    // Boundary lines: the outer (bottom) border has 3 * CELLS_X segments.
    let outer = msh
        .lines
        .iter()
        .filter(|(c, _)| msh.curve_phys[c] == 2)
        .count();
    assert_eq!(outer, 3 * CELLS_X);
    let wall = msh
        .lines
        .iter()
        .filter(|(c, _)| msh.curve_phys[c] == 12)
        .count();
    assert_eq!(wall, 3 * CELLS_X + 2 * 2 * CELLS_Y);
}

#[test]
fn geo_script_declares_every_block_transfinite() {
    let m = mesh();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.geo");
    geo::write_geo(&m, &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text.matches("Plane Surface(").count(), m.grids.len());
    assert_eq!(text.matches("Transfinite Surface{").count(), m.grids.len());
    assert_eq!(text.matches("Recombine Surface{").count(), m.grids.len());
    assert_eq!(
        text.matches("Transfinite Curve{").count(),
        m.layout.edges.len()
    );
    for (k, e) in m.layout.edges.iter().enumerate() {
        let horizontal =
            m.layout.vertices[e.ends[0] as usize][1] == m.layout.vertices[e.ends[1] as usize][1];
        let n = if horizontal { CELLS_X } else { CELLS_Y } + 1;
        assert!(text.contains(&format!("Transfinite Curve{{{}}} = {n};", k + 1)));
    }
}

#[test]
fn writers_are_deterministic() {
    let m = mesh();
    let dir = tempfile::tempdir().unwrap();
    let mut first = Vec::new();
    for round in 0..2 {
        let p = |n: &str| dir.path().join(format!("{round}{n}"));
        plot3d::write_binary(&m.grids, &p("mesh.xyz")).unwrap();
        gmsh::write_msh(&m, &p("mesh.msh")).unwrap();
        geo::write_geo(&m, &p("mesh.geo")).unwrap();
        let files: Vec<Vec<u8>> = ["mesh.xyz", "mesh.msh", "mesh.geo"]
            .iter()
            .map(|n| std::fs::read(p(n)).unwrap())
            .collect();
        if round == 0 {
            first = files;
        } else {
            assert_eq!(first, files);
        }
    }
    // No temporary files left behind.
    for entry in std::fs::read_dir(dir.path()).unwrap() {
        let name = entry.unwrap().file_name();
        assert!(!name.to_string_lossy().ends_with(".tmp"));
    }
}

#[test]
fn writing_into_a_missing_directory_fails_cleanly() {
    let m = mesh();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no/such/dir/mesh.msh");
    assert!(gmsh::write_msh(&m, &path).is_err());
    assert!(!path.exists());
}
