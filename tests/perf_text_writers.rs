//! The text writers of issue #8 (numbers through `output::text`, big arrays in parallel chunks)
//! against the `write!`-based writers they replaced, kept here as the reference: the same
//! bytes for `.vts`, `.vtu` and Plot3D ASCII files and for the node lines of `.msh`, on real
//! meshes with awkward values put into their grids (plain/exponent notation boundaries,
//! shortest-digit ties, negative zero, huge and tiny coordinates) and on meshes large enough
//! for many waves of chunks, with 1 and 3 threads.

use medial_blocks::numbering::number_nodes;
use medial_blocks::output::vtk::{write_vts, CELL_ARRAYS};
use medial_blocks::output::{write_files, Format};
use medial_blocks::quality::{cell_fields, CellFields};
use medial_blocks::{layouts, mesh, Mesh, Options};
use std::fmt::Write as _;

fn array(f: &CellFields, k: usize) -> &[f64] {
    [
        &f.min_angle_deg,
        &f.max_angle_deg,
        &f.min_jacobian,
        &f.equiangle_skewness,
        &f.edge_ratio,
        &f.scaled_jacobian,
        &f.aspect_ratio,
    ][k]
}

/// The former `floats` (`{:?}`, six a line) and `ints` (sixteen a line): each line nine
/// spaces, then ` v` per value.
fn ref_lines<T>(
    s: &mut String,
    values: impl Iterator<Item = T>,
    per_line: usize,
    f: fn(&T) -> String,
) {
    let mut k = 0;
    for x in values {
        if k % per_line == 0 {
            if k > 0 {
                s.push('\n');
            }
            s.push_str("         ");
        }
        write!(s, " {}", f(&x)).unwrap();
        k += 1;
    }
    if k > 0 {
        s.push('\n');
    }
}

fn ref_floats(s: &mut String, values: impl Iterator<Item = f64>) {
    ref_lines(s, values, 6, |x| format!("{x:?}"));
}

fn ref_ints(s: &mut String, values: impl Iterator<Item = usize>) {
    ref_lines(s, values, 16, |x| format!("{x}"));
}

fn ref_points(s: &mut String, coords: &[[f64; 2]]) {
    s.push_str("      <Points>\n        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in coords {
        writeln!(s, "          {:?} {:?} 0.0", p[0], p[1]).unwrap();
    }
    s.push_str("        </DataArray>\n      </Points>\n");
}

/// The former `.vts` writer.
fn ref_vts(b: usize, g: &medial_blocks::BlockGrid) -> String {
    let (ni, nj) = (g.ni, g.nj);
    let f = cell_fields(g);
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"StructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    writeln!(s, "  <StructuredGrid WholeExtent=\"0 {ni} 0 {nj} 0 0\">").unwrap();
    writeln!(s, "    <Piece Extent=\"0 {ni} 0 {nj} 0 0\">").unwrap();
    s.push_str("      <CellData Scalars=\"min_angle_deg\">\n        <DataArray type=\"Int32\" Name=\"block_id\" format=\"ascii\">\n");
    ref_ints(&mut s, std::iter::repeat_n(b, g.cells()));
    s.push_str("        </DataArray>\n");
    for (k, name) in CELL_ARRAYS.iter().enumerate() {
        writeln!(
            s,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        )
        .unwrap();
        ref_floats(&mut s, array(&f, k).iter().copied());
        s.push_str("        </DataArray>\n");
    }
    s.push_str("      </CellData>\n");
    ref_points(&mut s, &g.nodes);
    s.push_str("    </Piece>\n  </StructuredGrid>\n</VTKFile>\n");
    s
}

/// The former `.vtu` writer.
fn ref_vtu(m: &Mesh) -> String {
    let nodes = number_nodes(&m.layout, &m.grids);
    let cells: usize = m.grids.iter().map(|g| g.cells()).sum();
    let fields: Vec<_> = m.grids.iter().map(cell_fields).collect();
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
    writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{cells}\">",
        nodes.coords.len()
    )
    .unwrap();
    ref_points(&mut s, &nodes.coords);
    s.push_str("      <Cells>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for (g, ids) in m.grids.iter().zip(&nodes.block_nodes) {
        let id = |i: usize, j: usize| ids[i + j * (g.ni + 1)];
        for j in 0..g.nj {
            for i in 0..g.ni {
                writeln!(
                    s,
                    "          {} {} {} {}",
                    id(i, j),
                    id(i + 1, j),
                    id(i + 1, j + 1),
                    id(i, j + 1)
                )
                .unwrap();
            }
        }
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    ref_ints(&mut s, (1..=cells).map(|k| 4 * k));
    s.push_str("        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    ref_ints(&mut s, (0..cells).map(|_| 9));
    s.push_str("        </DataArray>\n      </Cells>\n      <CellData Scalars=\"min_angle_deg\">\n        <DataArray type=\"Int32\" Name=\"block_id\" format=\"ascii\">\n");
    ref_ints(
        &mut s,
        m.grids
            .iter()
            .enumerate()
            .flat_map(|(b, g)| std::iter::repeat_n(b, g.cells())),
    );
    s.push_str("        </DataArray>\n");
    for (k, name) in CELL_ARRAYS.iter().enumerate() {
        writeln!(
            s,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        )
        .unwrap();
        ref_floats(
            &mut s,
            fields.iter().flat_map(|f| array(f, k).iter().copied()),
        );
        s.push_str("        </DataArray>\n");
    }
    s.push_str("      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    s
}

/// The former Plot3D ASCII writer.
fn ref_p3d(m: &Mesh) -> String {
    let mut s = String::new();
    writeln!(s, "{}", m.grids.len()).unwrap();
    for g in &m.grids {
        writeln!(s, "{} {}", g.ni + 1, g.nj + 1).unwrap();
    }
    for g in &m.grids {
        for axis in 0..2 {
            for (k, p) in g.nodes.iter().enumerate() {
                let sep = if k % 4 == 3 || k + 1 == g.nodes.len() {
                    "\n"
                } else {
                    " "
                };
                write!(s, "{:e}{sep}", p[axis]).unwrap();
            }
        }
    }
    s
}

/// Values where formatting is delicate: the `{:?}` notation switches at 1e-4 and 1e16, ties
/// between shortest candidates (`981446413237567.25`), exact three-decimal halves, zeros.
fn awkward_values() -> [f64; 12] {
    [
        1.5e-5,
        -f64::from_bits(1e-4f64.to_bits() - 1),
        1e-4,
        0.0625,
        -0.0,
        981446413237567.0 + 0.25,
        f64::from_bits(1e16f64.to_bits() - 2),
        1e16,
        -2.5e17,
        1e-300,
        123456.789,
        5e-324,
    ]
}

/// `m` with awkward values in the interior nodes of its first blocks (sides untouched, so
/// merging across blocks stays as it was).
fn awkward(mut m: Mesh) -> Mesh {
    let values = awkward_values();
    let mut k = 0;
    for g in m.grids.iter_mut().take(8) {
        let w = g.ni + 1;
        for j in 1..g.nj {
            for i in 1..g.ni {
                let v = values[k % values.len()];
                g.nodes[i + j * w][k % 2] = v;
                k += 1;
            }
        }
    }
    m
}

/// A small mesh with awkward values, the same without them, and one with about 250 000
/// nodes (several waves of 4 096-point chunks in `mesh.vtu`).
fn meshes() -> Vec<Mesh> {
    let d = layouts::bubbles(40, 3).unwrap();
    let plain = mesh(&d, &Options::default()).unwrap();
    let big = mesh(&layouts::bubbles(150, 4).unwrap(), &Options::default()).unwrap();
    vec![awkward(plain.clone()), plain, big]
}

fn read(dir: &std::path::Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap()
}

#[test]
fn text_writers_write_the_reference_bytes() {
    for m in meshes() {
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let dir = tempfile::tempdir().unwrap();
            pool.install(|| {
                write_files(&m, dir.path(), &[Format::Vtk, Format::Vtu, Format::Plot3d]).unwrap()
            });
            assert_eq!(
                read(dir.path(), "mesh.vtu"),
                ref_vtu(&m),
                "vtu, {threads} threads"
            );
            assert_eq!(
                read(dir.path(), "mesh.p3d"),
                ref_p3d(&m),
                "p3d, {threads} threads"
            );
            for (b, g) in m.grids.iter().enumerate() {
                let got = read(dir.path(), &format!("mesh/block_{b:04}.vts"));
                assert_eq!(got, ref_vts(b, g), "vts of block {b}");
                let mut direct = Vec::new();
                write_vts(&mut direct, b, g).unwrap();
                assert_eq!(direct, got.as_bytes());
            }
        }
    }
}

#[test]
fn msh_node_lines_are_std_formatting() {
    for m in meshes() {
        let dir = tempfile::tempdir().unwrap();
        write_files(&m, dir.path(), &[Format::Gmsh]).unwrap();
        let msh = read(dir.path(), "mesh.msh");
        let nodes = number_nodes(&m.layout, &m.grids);
        let n = nodes.coords.len();
        let mut want = format!("$Nodes\n1 {n} 1 {n}\n2 1 0 {n}\n");
        for k in 1..=n {
            writeln!(want, "{k}").unwrap();
        }
        for p in &nodes.coords {
            writeln!(want, "{:e} {:e} 0", p[0], p[1]).unwrap();
        }
        want.push_str("$EndNodes\n");
        assert!(
            msh.contains(&want),
            "the $Nodes section is std's formatting"
        );
        // Element tags run 1..=total in file order, block after block of elements.
        let el = &msh[msh.find("$Elements\n").unwrap()..];
        let mut lines = el.lines().skip(1);
        let head: Vec<usize> = lines
            .next()
            .unwrap()
            .split(' ')
            .map(|t| t.parse().unwrap())
            .collect();
        let (blocks, total) = (head[0], head[1]);
        let mut next = 1;
        for _ in 0..blocks {
            let h: Vec<usize> = lines
                .next()
                .unwrap()
                .split(' ')
                .map(|t| t.parse().unwrap())
                .collect();
            for _ in 0..h[3] {
                let tag: usize = lines
                    .next()
                    .unwrap()
                    .split(' ')
                    .next()
                    .unwrap()
                    .parse()
                    .unwrap();
                assert_eq!(tag, next);
                next += 1;
            }
        }
        assert_eq!(next, total + 1);
        assert_eq!(lines.next(), Some("$EndElements"));
    }
}
