//! The VTU writer read back by a small parser written here; SVG block colours; the layout
//! generators; CGNS read back through the C library (with the `cgns` feature).

use medial_blocks::layouts::{self, Layout, SplitMix64};
use medial_blocks::mesh::Mesh;
use medial_blocks::output::{svg, vtu};
use medial_blocks::{mesh, Domain, Options};
use std::collections::HashSet;

fn mesh_of(domain: &Domain, cells: usize) -> Mesh {
    mesh(
        domain,
        &Options {
            cells,
            ..Options::default()
        },
    )
    .unwrap()
}

/// The text of the `<DataArray ...>` whose opening tag contains `marker`.
fn data_array<'a>(xml: &'a str, marker: &str) -> &'a str {
    let start = xml.find(marker).unwrap_or_else(|| panic!("no {marker}"));
    let body = &xml[start..];
    let open = body.find('>').unwrap() + 1;
    let close = body.find("</DataArray>").unwrap();
    &body[open..close]
}

fn numbers(s: &str) -> Vec<f64> {
    s.split_whitespace().map(|t| t.parse().unwrap()).collect()
}

fn attr(xml: &str, name: &str) -> usize {
    let key = format!("{name}=\"");
    let i = xml.find(&key).unwrap() + key.len();
    xml[i..i + xml[i..].find('"').unwrap()].parse().unwrap()
}

#[test]
fn vtu_reads_back() {
    let m = mesh_of(&Domain::hexagon_example(), 4);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.vtu");
    vtu::write_vtu(&m, &path).unwrap();
    let xml = std::fs::read_to_string(&path).unwrap();
    assert!(xml.contains("type=\"UnstructuredGrid\""));
    let pts = numbers(data_array(&xml, "Name=\"Points\""));
    let conn = numbers(data_array(&xml, "Name=\"connectivity\""));
    let offsets = numbers(data_array(&xml, "Name=\"offsets\""));
    let types = numbers(data_array(&xml, "Name=\"types\""));
    let ids = numbers(data_array(&xml, "Name=\"block_id\""));
    let sj = numbers(data_array(&xml, "Name=\"scaled_jacobian\""));
    let cells: usize = m.grids.iter().map(|g| g.cells()).sum();
    let npts = pts.len() / 3;
    assert_eq!(attr(&xml, "NumberOfPoints"), npts);
    assert_eq!(attr(&xml, "NumberOfCells"), cells);
    assert_eq!(conn.len(), 4 * cells);
    assert_eq!(types.len(), cells);
    assert!(types.iter().all(|&t| t == 9.0));
    assert_eq!(ids.len(), cells);
    assert_eq!(sj.len(), cells);
    for (k, &o) in offsets.iter().enumerate() {
        assert_eq!(o, 4.0 * (k + 1) as f64);
    }
    // Merged: fewer points than block nodes, and no two points at the same place.
    let block_nodes: usize = m.grids.iter().map(|g| g.nodes.len()).sum();
    assert!(npts < block_nodes);
    let distinct: HashSet<(u64, u64)> = (0..npts)
        .map(|p| (pts[3 * p].to_bits(), pts[3 * p + 1].to_bits()))
        .collect();
    assert_eq!(distinct.len(), npts, "duplicate points");
    // Every cell's corners are its grid cell's corners, block by block, i fastest.
    let mut c = 0;
    for (b, g) in m.grids.iter().enumerate() {
        for j in 0..g.nj {
            for i in 0..g.ni {
                let want = [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ];
                for (k, w) in want.iter().enumerate() {
                    let p = conn[4 * c + k] as usize;
                    assert!(p < npts);
                    let (x, y) = (pts[3 * p], pts[3 * p + 1]);
                    assert!(
                        (x - w[0]).abs() < 1e-12 && (y - w[1]).abs() < 1e-12,
                        "block {b} cell ({i},{j}) corner {k}"
                    );
                    assert_eq!(pts[3 * p + 2], 0.0);
                }
                assert_eq!(ids[c], b as f64);
                assert!(sj[c] > 0.0 && sj[c] <= 1.0 + 1e-12);
                c += 1;
            }
        }
    }
}

#[test]
fn svg_neighbouring_blocks_differ_in_colour() {
    for domain in [Domain::hexagon_example(), layouts::lattice().unwrap()] {
        let m = mesh_of(&domain, 2);
        let colours = svg::block_colours(&m);
        assert_eq!(colours.len(), m.layout.blocks.len());
        let mut users = vec![Vec::new(); m.layout.edges.len()];
        for (b, block) in m.layout.blocks.iter().enumerate() {
            for s in &block.sides {
                users[s.edge as usize].push(b);
            }
        }
        for u in users.iter().filter(|u| u.len() == 2) {
            assert_ne!(colours[u[0]], colours[u[1]], "blocks {u:?}");
        }
        assert!(colours.iter().any(|&c| c != colours[0]));
        let text = svg::to_string(&m).unwrap();
        let fills = svg::BLOCK_FILLS
            .iter()
            .map(|f| text.matches(&format!("fill=\"{f}\"")).count())
            .sum::<usize>();
        assert_eq!(fills, m.layout.blocks.len());
    }
}

#[test]
fn generators_make_what_they_promise() {
    assert_eq!(layouts::hexagon(), Domain::hexagon_example());
    let lattice = layouts::lattice().unwrap();
    assert_eq!(lattice.hole_count(), 21);
    let large = lattice.holes().iter().filter(|h| h.radius > 0.5).count();
    assert_eq!(large, 12);
    assert_eq!(mesh_of(&lattice, 2).layout.blocks.len(), 120);
    assert_eq!(layouts::square_lattice(10).unwrap().hole_count(), 9);
    assert_eq!(layouts::square_lattice(1).unwrap().hole_count(), 1);
    assert!(layouts::square_lattice(0).is_err());
    let b = layouts::bubbles(50, 9).unwrap();
    assert_eq!(b.hole_count(), 50);
    // Deterministic, and the seed matters.
    assert_eq!(b, layouts::bubbles(50, 9).unwrap());
    assert_ne!(b, layouts::bubbles(50, 10).unwrap());
    assert!(layouts::generate(Layout::Hexagon, Some(5), 0).is_err());
    assert_eq!(
        layouts::generate(Layout::Bubbles, None, 1)
            .unwrap()
            .hole_count(),
        layouts::DEFAULT_BUBBLES
    );
    // SplitMix64 reference values (seed 0).
    let mut r = SplitMix64(0);
    assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
    assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
}

#[test]
fn many_bubbles_in_linear_time() {
    let t = std::time::Instant::now();
    let b = layouts::bubbles(100_000, 3).unwrap();
    assert_eq!(b.hole_count(), 100_000);
    assert!(t.elapsed().as_secs() < 30);
}

#[cfg(feature = "cgns")]
mod cgns_read_back {
    use super::*;
    use std::ffi::{c_char, c_int, CString};

    #[link(name = "cgns")]
    extern "C" {
        fn cg_open(filename: *const c_char, mode: c_int, f: *mut c_int) -> c_int;
        fn cg_close(f: c_int) -> c_int;
        fn cg_nzones(f: c_int, b: c_int, n: *mut c_int) -> c_int;
        fn cg_zone_read(f: c_int, b: c_int, z: c_int, name: *mut c_char, size: *mut i32) -> c_int;
        fn cg_coord_read(
            f: c_int,
            b: c_int,
            z: c_int,
            name: *const c_char,
            t: c_int,
            rmin: *const i32,
            rmax: *const i32,
            data: *mut f64,
        ) -> c_int;
        fn cg_n1to1(f: c_int, b: c_int, z: c_int, n: *mut c_int) -> c_int;
        fn cg_nbocos(f: c_int, b: c_int, z: c_int, n: *mut c_int) -> c_int;
    }

    #[test]
    fn cgns_reads_back() {
        let m = mesh_of(&Domain::hexagon_example(), 3);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mesh.cgns");
        medial_blocks::output::cgns::write_cgns(&m, &path).unwrap();
        let conn = medial_blocks::connectivity::connectivity(&m.layout, &m.grids).unwrap();
        let cpath = CString::new(path.to_str().unwrap()).unwrap();
        unsafe {
            let mut f = 0;
            assert_eq!(cg_open(cpath.as_ptr(), 0, &mut f), 0);
            let mut nz = 0;
            assert_eq!(cg_nzones(f, 1, &mut nz), 0);
            assert_eq!(nz as usize, m.grids.len());
            // Zones come back sorted by name, which is block order (block_NNNN).
            for (k, g) in m.grids.iter().enumerate() {
                let z = k as c_int + 1;
                let mut name = [0 as c_char; 64];
                let mut size = [0i32; 6];
                assert_eq!(
                    cg_zone_read(f, 1, z, name.as_mut_ptr(), size.as_mut_ptr()),
                    0
                );
                assert_eq!(
                    size[..4],
                    [g.ni as i32 + 1, g.nj as i32 + 1, g.ni as i32, g.nj as i32]
                );
                let (rmin, rmax) = ([1i32, 1], [g.ni as i32 + 1, g.nj as i32 + 1]);
                for (axis, cname) in ["CoordinateX", "CoordinateY"].iter().enumerate() {
                    let mut data = vec![0.0f64; g.nodes.len()];
                    let cn = CString::new(*cname).unwrap();
                    assert_eq!(
                        cg_coord_read(
                            f,
                            1,
                            z,
                            cn.as_ptr(),
                            4,
                            rmin.as_ptr(),
                            rmax.as_ptr(),
                            data.as_mut_ptr()
                        ),
                        0
                    );
                    for (p, v) in g.nodes.iter().zip(&data) {
                        assert_eq!(p[axis], *v);
                    }
                }
                let (mut n1, mut nb) = (0, 0);
                assert_eq!(cg_n1to1(f, 1, z, &mut n1), 0);
                assert_eq!(cg_nbocos(f, 1, z, &mut nb), 0);
                let interfaces = conn[k].sides.iter().filter(|s| s.partner.is_some()).count();
                assert_eq!(n1 as usize, interfaces);
                assert_eq!(nb as usize, 4 - interfaces);
            }
            assert_eq!(cg_close(f), 0);
        }
    }
}

/// The stride is the least `s` with `s^2 FULL_GRID_CELLS >= cells` (1 up to the limit), and
/// it never decreases with the cell count.
#[test]
fn svg_grid_line_stride_is_the_least_that_fits() {
    let full = svg::FULL_GRID_CELLS;
    assert_eq!(svg::grid_line_stride(0), 1);
    assert_eq!(svg::grid_line_stride(full), 1);
    assert_eq!(svg::grid_line_stride(full + 1), 2);
    assert_eq!(svg::grid_line_stride(4 * full), 2);
    assert_eq!(svg::grid_line_stride(4 * full + 1), 3);
    let mut last = 1;
    let mut rng = SplitMix64(7);
    let mut sizes: Vec<usize> = (0..2000)
        .map(|_| (rng.next_u64() % 200_000_000) as usize)
        .collect();
    sizes.sort_unstable();
    for cells in sizes {
        let s = svg::grid_line_stride(cells);
        assert!(s >= last, "monotone at {cells}");
        last = s;
        if cells > full {
            assert!(
                s * s * full >= cells && (s - 1) * (s - 1) * full < cells,
                "{cells}: {s}"
            );
        } else {
            assert_eq!(s, 1);
        }
    }
}

/// The grid lines of the SVG: every line through every node up to the limit; beyond it every
/// `s`-th line of each block through every `s`-th node and the line's last node. Counted from
/// the file: the paths of the grid group and the points of each.
#[test]
fn svg_draws_grid_lines_at_the_pictures_resolution() {
    let hexagon = Domain::hexagon_example();
    for (block_cells, want_stride) in [(8, 1), (90, 2)] {
        let m = mesh(
            &hexagon,
            &Options {
                block_cells: Some(block_cells),
                ..Options::default()
            },
        )
        .unwrap();
        let cells: usize = m.grids.iter().map(|g| g.cells()).sum();
        let s = svg::grid_line_stride(cells);
        assert_eq!(s, want_stride, "{cells} cells");
        let text = svg::to_string(&m).unwrap();
        // The points of each path in the group whose opening tag starts with `head`.
        let group_points = |head: &str| -> Vec<usize> {
            let start = text.find(head).unwrap_or_else(|| panic!("no {head}"));
            let group = &text[start..start + text[start..].find("</g>").unwrap()];
            group
                .lines()
                .filter(|l| l.trim_start().starts_with("<path"))
                .map(|l| l.matches(" L").count() + 1)
                .collect()
        };
        let points = group_points("<g stroke=\"#b0b0b0\"");
        let mut want = Vec::new();
        // Nodes 0, s, 2s, ... below n, then n.
        let along = |n: usize| n.div_ceil(s) + 1;
        for g in &m.grids {
            want.extend((1..g.nj).filter(|j| j % s == 0).map(|_| along(g.ni)));
            want.extend((1..g.ni).filter(|i| i % s == 0).map(|_| along(g.nj)));
        }
        assert_eq!(points.len(), want.len(), "grid paths at stride {s}");
        assert_eq!(points, want, "points per grid path at stride {s}");
        if s == 1 {
            let all: usize = m.grids.iter().map(|g| g.ni - 1 + g.nj - 1).sum();
            assert_eq!(points.len(), all, "every line below the limit");
        }
        // Block fills: every s-th node of each side but its last; one path per block.
        let fills: Vec<usize> = m
            .grids
            .iter()
            .map(|g| 2 * g.ni.div_ceil(s) + 2 * g.nj.div_ceil(s))
            .collect();
        assert_eq!(
            group_points("<g stroke=\"none\">"),
            fills,
            "fills at stride {s}"
        );
        // Outlines and medial edges: each layout edge once, every s-th node and its ends.
        let mut drawn = vec![false; m.layout.edges.len()];
        let mut want_edges = Vec::new();
        for (b, block) in m.layout.blocks.iter().enumerate() {
            for (k, side) in block.sides.iter().enumerate() {
                let e = side.edge as usize;
                if !drawn[e] {
                    drawn[e] = true;
                    want_edges.push(along(m.grids[b].side(k).len() - 1));
                }
            }
        }
        let mut got_edges = group_points("<g stroke=\"#303030\"");
        got_edges.extend(group_points("<g stroke=\"#d62728\""));
        got_edges.sort_unstable();
        want_edges.sort_unstable();
        assert_eq!(
            got_edges, want_edges,
            "outlines and medial edges at stride {s}"
        );
    }
}
