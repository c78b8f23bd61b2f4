//! The binary writers (`--binary`, [`Encoding::Binary`]) against the ASCII ones, through
//! decoders written here from the formats' specifications (VTK XML appended raw data with
//! UInt64 headers; Gmsh MSH 4.1 binary): every array and section of the binary file holds
//! bit for bit the values the ASCII file spells (shortest round-trip digits read back
//! exactly), with the same XML skeleton / the same sections; the bytes do not depend on the
//! thread count; the CLI's `--binary` writes these forms for `mesh` and `mesh-sequence`.
//!
//! (By hand, the real readers agreed too: VTK 9.7.2's XML readers and the Gmsh 4.15.2 SDK,
//! from PyPI, read the ASCII and binary files of the hexagon, lattice, 300 bubbles and a
//! periodic layout into identical arrays; issue 8's twelfth-session note.)

use crate::common;

use medial_blocks::domain::Circle;
use medial_blocks::layouts;
use medial_blocks::output::{gmsh, vtk, vtu, write_files_encoded, Encoding, Format};
use medial_blocks::periodic::{mesh_periodic, PeriodicDomain};
use medial_blocks::{mesh, Mesh, Options};

fn circle(center: [f64; 2], radius: f64) -> Circle {
    Circle { center, radius }
}

fn meshes() -> Vec<(&'static str, Mesh)> {
    let opts = |cells| Options {
        cells,
        ..Options::default()
    };
    let pd = PeriodicDomain::new(
        [1.0, 1.0],
        vec![
            circle([0.2, 0.3], 0.1),
            circle([0.7, 0.25], 0.12),
            circle([0.45, 0.75], 0.15),
            circle([0.9, 0.8], 0.08),
        ],
    )
    .unwrap();
    let edge = PeriodicDomain::new(
        [2.0, 1.0],
        vec![circle([0.05, 0.5], 0.2), circle([1.2, 0.95], 0.15)],
    )
    .unwrap();
    vec![
        ("hexagon", mesh(&layouts::hexagon(), &opts(5)).unwrap()),
        (
            "lattice",
            mesh(&layouts::lattice().unwrap(), &opts(4)).unwrap(),
        ),
        (
            "square lattice",
            mesh(&layouts::square_lattice(9).unwrap(), &opts(3)).unwrap(),
        ),
        (
            "bubbles",
            mesh(&layouts::bubbles(40, 5).unwrap(), &opts(6)).unwrap(),
        ),
        ("periodic", mesh_periodic(&pd, &opts(4)).unwrap()),
        (
            "periodic across edges",
            mesh_periodic(&edge, &opts(3)).unwrap(),
        ),
    ]
}

// ---------------------------------------------------------------------------------------
// VTK XML
// ---------------------------------------------------------------------------------------

/// One `<DataArray>`: its type, name, number of components and its values as 8-byte words
/// (integers sign-extended, floats as bits), in file order.
#[derive(Debug, PartialEq)]
struct Array {
    ty: String,
    name: String,
    components: Option<String>,
    words: Vec<u64>,
}

impl Array {
    /// The array opened by `tag`, of type `ty`, holding `words`.
    fn of_tag(tag: &str, ty: String, words: Vec<u64>) -> Array {
        Array {
            name: attr(tag, "Name").unwrap().to_string(),
            components: attr(tag, "NumberOfComponents").map(str::to_string),
            ty,
            words,
        }
    }
}

/// The value of attribute `key` in the tag `tag`.
fn attr<'a>(tag: &'a str, key: &str) -> Option<&'a str> {
    let k = format!(" {key}=\"");
    let i = tag.find(&k)? + k.len();
    Some(&tag[i..i + tag[i..].find('"')?])
}

/// The XML lines outside the data arrays (every `<DataArray` line replaced by `DATA`), and the
/// arrays of an ASCII file.
fn read_ascii_vtk(text: &str) -> (Vec<String>, Vec<Array>) {
    let mut skeleton = Vec::new();
    let mut arrays = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("<DataArray") {
        skeleton.extend(rest[..i].lines().map(|l| l.trim().to_string()));
        let tag_end = i + rest[i..].find('>').unwrap();
        let tag = &rest[i..=tag_end];
        assert_eq!(attr(tag, "format"), Some("ascii"), "{tag}");
        let close = tag_end + rest[tag_end..].find("</DataArray>").unwrap();
        let ty = attr(tag, "type").unwrap().to_string();
        let words = rest[tag_end + 1..close]
            .split_whitespace()
            .map(|t| match ty.as_str() {
                "Float64" => t.parse::<f64>().unwrap().to_bits(),
                _ => t.parse::<i64>().unwrap() as u64,
            })
            .collect();
        arrays.push(Array::of_tag(tag, ty, words));
        skeleton.push("DATA".into());
        rest = &rest[close + "</DataArray>".len()..];
    }
    skeleton.extend(rest.lines().map(|l| l.trim().to_string()));
    skeleton.retain(|l| !l.is_empty());
    (skeleton, arrays)
}

/// The same for a file with raw appended data: every array's offset points at a UInt64 byte
/// count followed by that many bytes, the arrays follow each other with no gap in tag order,
/// and the block ends exactly before `</AppendedData>`.
fn read_binary_vtk(bytes: &[u8]) -> (Vec<String>, Vec<Array>) {
    let open = b"<AppendedData encoding=\"raw\">";
    let at = bytes
        .windows(open.len())
        .position(|w| w == open)
        .expect("no AppendedData");
    let xml = std::str::from_utf8(&bytes[..at]).unwrap();
    let mut p = at + open.len();
    while bytes[p].is_ascii_whitespace() {
        p += 1;
    }
    assert_eq!(bytes[p], b'_', "appended data must start with '_'");
    let base = p + 1;
    let mut skeleton = Vec::new();
    let mut arrays = Vec::new();
    let mut rest = xml;
    let mut next = 0usize;
    while let Some(i) = rest.find("<DataArray") {
        skeleton.extend(rest[..i].lines().map(|l| l.trim().to_string()));
        let tag_end = i + rest[i..].find("/>").unwrap();
        let tag = &rest[i..tag_end + 2];
        assert_eq!(attr(tag, "format"), Some("appended"), "{tag}");
        let offset: usize = attr(tag, "offset").unwrap().parse().unwrap();
        assert_eq!(offset, next, "arrays must follow each other: {tag}");
        let start = base + offset;
        let n = u64::from_le_bytes(bytes[start..start + 8].try_into().unwrap()) as usize;
        let data = &bytes[start + 8..start + 8 + n];
        next = offset + 8 + n;
        let ty = attr(tag, "type").unwrap().to_string();
        let size = match ty.as_str() {
            "Float64" | "Int64" => 8,
            "Int32" => 4,
            "UInt8" => 1,
            other => panic!("unexpected type {other}"),
        };
        assert_eq!(n % size, 0);
        let words = data
            .chunks(size)
            .map(|c| match ty.as_str() {
                "Float64" => u64::from_le_bytes(c.try_into().unwrap()),
                "Int64" => i64::from_le_bytes(c.try_into().unwrap()) as u64,
                "Int32" => i32::from_le_bytes(c.try_into().unwrap()) as i64 as u64,
                _ => c[0] as u64,
            })
            .collect();
        arrays.push(Array::of_tag(tag, ty, words));
        skeleton.push("DATA".into());
        rest = &rest[tag_end + 2..];
    }
    skeleton.extend(rest.lines().map(|l| l.trim().to_string()));
    skeleton.retain(|l| !l.is_empty());
    assert_eq!(
        &bytes[base + next..],
        b"\n  </AppendedData>\n</VTKFile>\n",
        "the appended block must end after the last array"
    );
    (skeleton, arrays)
}

/// The binary file's skeleton is the ASCII one with the appended block before `</VTKFile>`.
fn assert_same_vtk(ascii: &[u8], binary: &[u8], what: &str) {
    let (mut sa, aa) = read_ascii_vtk(std::str::from_utf8(ascii).unwrap());
    let (sb, ab) = read_binary_vtk(binary);
    assert_eq!(sa.pop().as_deref(), Some("</VTKFile>"));
    assert_eq!(sa, sb, "{what}: XML skeleton");
    assert!(!aa.is_empty());
    assert_eq!(aa.len(), ab.len(), "{what}: array count");
    for (a, b) in aa.iter().zip(&ab) {
        assert!(!a.words.is_empty(), "{what}: {}", a.name);
        assert_eq!(a, b, "{what}: array {}", a.name);
    }
}

#[test]
fn vts_binary_holds_the_ascii_values_bit_for_bit() {
    for (name, m) in meshes() {
        for (b, g) in m.grids.iter().enumerate() {
            let (mut a, mut x) = (Vec::new(), Vec::new());
            vtk::write_vts(&mut a, b, g).unwrap();
            vtk::write_vts_encoded(&mut x, b, g, Encoding::Binary).unwrap();
            assert_same_vtk(&a, &x, &format!("{name} block {b}"));
            // And the points are the grid's nodes themselves, z = 0.
            let (_, arrays) = read_binary_vtk(&x);
            let pts = arrays.iter().find(|a| a.name == "Points").unwrap();
            let want: Vec<u64> = g
                .nodes
                .iter()
                .flat_map(|p| [p[0].to_bits(), p[1].to_bits(), 0f64.to_bits()])
                .collect();
            assert_eq!(pts.words, want, "{name} block {b}");
        }
    }
}

#[test]
fn vtu_binary_holds_the_ascii_values_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    for (name, m) in meshes() {
        let (a, b) = (dir.path().join("a.vtu"), dir.path().join("b.vtu"));
        vtu::write_vtu(&m, &a).unwrap();
        vtu::write_vtu_encoded(&m, &b, Encoding::Binary).unwrap();
        let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
        assert_same_vtk(&a, &b, name);
        let (_, arrays) = read_binary_vtk(&b);
        let cells: usize = m.grids.iter().map(|g| g.cells()).sum();
        let of = |n: &str| &arrays.iter().find(|a| a.name == n).unwrap().words;
        assert_eq!(of("types").len(), cells);
        assert_eq!(of("connectivity").len(), 4 * cells);
        assert_eq!(of("offsets").last().copied(), Some(4 * cells as u64));
    }
}

/// The `.vtu` writers stream (issue 8): points block by block from the compact numbering, the
/// cell figures a chunk of blocks at a time (binary: each array's part written at its place).
/// On a mesh of many waves of chunks at 1 and at 3 threads, the binary file's cell arrays
/// are `cell_fields` of every block in block order, its points the merged nodes of
/// `number_nodes`, its connectivity their ids, the ASCII file holds the same values, and the
/// thread count changes no byte of either.
#[test]
fn vtu_streamed_over_many_waves_holds_every_block() {
    use medial_blocks::numbering::number_nodes;
    use medial_blocks::quality::cell_fields;
    let opts = Options {
        block_cells: Some(5),
        ..Options::default()
    };
    let m = mesh(&layouts::bubbles(220, 9).unwrap(), &opts).unwrap();
    assert!(
        m.grids.len() > 3 * 4 * 64,
        "{} blocks: one wave",
        m.grids.len()
    );
    let dir = tempfile::tempdir().unwrap();
    let write = |threads: usize, encoding: Encoding| {
        let path = dir.path().join(format!("{threads}-{encoding:?}.vtu"));
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| vtu::write_vtu_encoded(&m, &path, encoding).unwrap());
        std::fs::read(path).unwrap()
    };
    let binary = write(1, Encoding::Binary);
    assert_eq!(binary, write(3, Encoding::Binary));
    let ascii = write(3, Encoding::Ascii);
    assert_eq!(ascii, write(1, Encoding::Ascii));
    assert_same_vtk(&ascii, &binary, "many waves");

    let (_, arrays) = read_binary_vtk(&binary);
    let of = |n: &str| &arrays.iter().find(|a| a.name == n).unwrap().words;
    let fields: Vec<_> = m.grids.iter().map(cell_fields).collect();
    for (k, name) in vtk::CELL_ARRAYS.iter().enumerate() {
        let want: Vec<u64> = fields
            .iter()
            .flat_map(|f| {
                let values = match k {
                    0 => &f.min_angle_deg,
                    1 => &f.max_angle_deg,
                    2 => &f.min_jacobian,
                    3 => &f.equiangle_skewness,
                    4 => &f.edge_ratio,
                    5 => &f.scaled_jacobian,
                    _ => &f.aspect_ratio,
                };
                values.iter().map(|x| x.to_bits())
            })
            .collect();
        assert_eq!(of(name), &want, "{name}");
    }
    let nodes = number_nodes(&m.layout, &m.grids);
    let points: Vec<u64> = nodes
        .coords
        .iter()
        .flat_map(|p| [p[0].to_bits(), p[1].to_bits(), 0f64.to_bits()])
        .collect();
    assert_eq!(of("Points"), &points);
    let mut corners = Vec::new();
    for (g, ids) in m.grids.iter().zip(&nodes.block_nodes) {
        let id = |i: usize, j: usize| u64::from(ids[i + j * (g.ni + 1)]);
        for j in 0..g.nj {
            for i in 0..g.ni {
                corners.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    assert_eq!(of("connectivity"), &corners);

    // The `.msh` writers stream the same numbering: the binary and ASCII files agree, and
    // their nodes are the merged nodes in id order.
    let (a, b) = (dir.path().join("a.msh"), dir.path().join("b.msh"));
    gmsh::write_msh(&m, &a).unwrap();
    gmsh::write_msh_encoded(&m, &b, Encoding::Binary).unwrap();
    let ascii = read_ascii_msh(&std::fs::read(a).unwrap());
    assert_eq!(ascii, read_binary_msh(&std::fs::read(b).unwrap()));
    let msh_points: Vec<u64> = ascii
        .nodes
        .iter()
        .flat_map(|e| e.records.iter().flat_map(|r| r[1..].iter().copied()))
        .collect();
    assert_eq!(msh_points, points);
}

// ---------------------------------------------------------------------------------------
// Gmsh MSH 4.1
// ---------------------------------------------------------------------------------------

/// An entity of `$Entities`: tag, bounding box, physical tags, bounding entities.
#[derive(Debug, PartialEq)]
struct Entity {
    tag: i64,
    bbox: [u64; 6],
    physical: Vec<i64>,
    bounds: Vec<i64>,
}

/// An entity block of `$Nodes` or `$Elements`: its three ints and its records (a node:
/// tag then x, y, z bits; an element: tag then node tags).
#[derive(Debug, PartialEq)]
struct EntityBlock {
    head: [i64; 3],
    records: Vec<Vec<u64>>,
}

#[derive(Debug, PartialEq)]
struct Msh {
    physical_names: String,
    counts: [u64; 4],
    curves: Vec<Entity>,
    surfaces: Vec<Entity>,
    nodes_head: [u64; 4],
    nodes: Vec<EntityBlock>,
    elements_head: [u64; 4],
    elements: Vec<EntityBlock>,
}

/// Nodes per element of the types the writer uses (1: line, 3: quad).
fn nodes_per_element(ty: i64) -> usize {
    match ty {
        1 => 2,
        3 => 4,
        other => panic!("unexpected element type {other}"),
    }
}

/// The text between `$NAME\n` and `\n$EndNAME` (after `from`).
fn section<'a>(bytes: &'a [u8], name: &str) -> &'a [u8] {
    let open = format!("${name}\n");
    let close = format!("\n$End{name}\n");
    let find = |pat: &[u8], from: usize| {
        from + bytes[from..]
            .windows(pat.len())
            .position(|w| w == pat)
            .unwrap_or_else(|| panic!("no {}", String::from_utf8_lossy(pat)))
    };
    let start = find(open.as_bytes(), 0) + open.len();
    // The binary data may contain the closing bytes by chance only after its own end is
    // known; the sections here are read front to back, so take the last closing marker.
    let end = bytes
        .windows(close.len())
        .rposition(|w| w == close.as_bytes())
        .unwrap();
    assert!(end >= start);
    &bytes[start..end]
}

fn read_ascii_msh(bytes: &[u8]) -> Msh {
    let text = std::str::from_utf8(bytes).unwrap();
    assert!(text.starts_with("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"));
    let sec = |n| std::str::from_utf8(section(bytes, n)).unwrap();
    let mut t = sec("Entities").split_whitespace();
    let mut int = || t.next().unwrap().parse::<i64>().unwrap();
    let counts = [0; 4].map(|_| int() as u64);
    assert_eq!(counts[0], 0);
    let mut t = sec("Entities").split_whitespace().skip(4);
    let mut entities = |n: u64| -> Vec<Entity> {
        let mut next = || t.next().unwrap();
        (0..n)
            .map(|_| {
                let tag = next().parse().unwrap();
                let bbox = [0; 6].map(|_| next().parse::<f64>().unwrap().to_bits());
                let np: usize = next().parse().unwrap();
                let physical = (0..np).map(|_| next().parse().unwrap()).collect();
                let nb: usize = next().parse().unwrap();
                let bounds = (0..nb).map(|_| next().parse().unwrap()).collect();
                Entity {
                    tag,
                    bbox,
                    physical,
                    bounds,
                }
            })
            .collect()
    };
    let curves = entities(counts[1]);
    let surfaces = entities(counts[2]);

    let mut t = sec("Nodes").split_whitespace();
    let mut next = move || t.next().unwrap();
    let nodes_head = [0; 4].map(|_| next().parse::<u64>().unwrap());
    let nodes = (0..nodes_head[0])
        .map(|_| {
            let head = [0; 3].map(|_| next().parse::<i64>().unwrap());
            let n: usize = next().parse().unwrap();
            let tags: Vec<u64> = (0..n).map(|_| next().parse().unwrap()).collect();
            let records = tags
                .iter()
                .map(|&tag| {
                    let mut r = vec![tag];
                    r.extend((0..3).map(|_| next().parse::<f64>().unwrap().to_bits()));
                    r
                })
                .collect();
            EntityBlock { head, records }
        })
        .collect();

    let mut t = sec("Elements").split_whitespace();
    let mut next = move || t.next().unwrap().parse::<i64>().unwrap();
    let elements_head = [0; 4].map(|_| next() as u64);
    let elements = (0..elements_head[0])
        .map(|_| {
            let head = [next(), next(), next()];
            let n = next() as usize;
            let k = nodes_per_element(head[2]);
            let records = (0..n)
                .map(|_| (0..=k).map(|_| next() as u64).collect())
                .collect();
            EntityBlock { head, records }
        })
        .collect();
    Msh {
        physical_names: sec("PhysicalNames").to_string(),
        counts,
        curves,
        surfaces,
        nodes_head,
        nodes,
        elements_head,
        elements,
    }
}

/// A little-endian reader of Gmsh's binary fields (`int` 4 bytes, `size_t` 8 bytes as the
/// header's `data-size` says, `double` 8 bytes).
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        a
    }
    fn int(&mut self) -> i64 {
        i32::from_le_bytes(self.take(4).try_into().unwrap()) as i64
    }
    fn size(&mut self) -> u64 {
        u64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn double(&mut self) -> u64 {
        u64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn done(&self) {
        assert!(
            self.0.is_empty(),
            "{} bytes left in the section",
            self.0.len()
        );
    }
}

fn read_binary_msh(bytes: &[u8]) -> Msh {
    let mut head = b"$MeshFormat\n4.1 1 8\n".to_vec();
    head.extend_from_slice(&1i32.to_le_bytes());
    head.extend_from_slice(b"\n$EndMeshFormat\n");
    assert!(bytes.starts_with(&head), "binary header with the integer 1");
    let mut f = Fields(section(bytes, "Entities"));
    let counts = [f.size(), f.size(), f.size(), f.size()];
    assert_eq!(counts[0], 0);
    let mut entities = |n: u64| -> Vec<Entity> {
        (0..n)
            .map(|_| Entity {
                tag: f.int(),
                bbox: [0; 6].map(|_| f.double()),
                physical: (0..f.size()).map(|_| f.int()).collect(),
                bounds: (0..f.size()).map(|_| f.int()).collect(),
            })
            .collect()
    };
    let curves = entities(counts[1]);
    let surfaces = entities(counts[2]);
    f.done();

    let mut f = Fields(section(bytes, "Nodes"));
    let nodes_head = [f.size(), f.size(), f.size(), f.size()];
    let nodes = (0..nodes_head[0])
        .map(|_| {
            let head = [f.int(), f.int(), f.int()];
            let n = f.size() as usize;
            let tags: Vec<u64> = (0..n).map(|_| f.size()).collect();
            let records = tags
                .iter()
                .map(|&t| vec![t, f.double(), f.double(), f.double()])
                .collect();
            EntityBlock { head, records }
        })
        .collect();
    f.done();

    let mut f = Fields(section(bytes, "Elements"));
    let elements_head = [f.size(), f.size(), f.size(), f.size()];
    let elements = (0..elements_head[0])
        .map(|_| {
            let head = [f.int(), f.int(), f.int()];
            let n = f.size() as usize;
            let k = nodes_per_element(head[2]);
            let records = (0..n)
                .map(|_| (0..=k).map(|_| f.size()).collect())
                .collect();
            EntityBlock { head, records }
        })
        .collect();
    f.done();
    Msh {
        physical_names: String::from_utf8(section(bytes, "PhysicalNames").to_vec()).unwrap(),
        counts,
        curves,
        surfaces,
        nodes_head,
        nodes,
        elements_head,
        elements,
    }
}

#[test]
fn msh_binary_holds_the_ascii_sections_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    for (name, m) in meshes() {
        let (a, b) = (dir.path().join("a.msh"), dir.path().join("b.msh"));
        gmsh::write_msh(&m, &a).unwrap();
        gmsh::write_msh_encoded(&m, &b, Encoding::Binary).unwrap();
        let ascii = read_ascii_msh(&std::fs::read(a).unwrap());
        let binary = read_binary_msh(&std::fs::read(b).unwrap());
        assert_eq!(ascii.curves.len(), m.layout.edges.len(), "{name}");
        assert_eq!(ascii.surfaces.len(), m.layout.blocks.len(), "{name}");
        let cells: usize = m.grids.iter().map(|g| g.cells()).sum();
        let quads: usize = ascii
            .elements
            .iter()
            .filter(|e| e.head[2] == 3)
            .map(|e| e.records.len())
            .sum();
        assert_eq!(quads, cells, "{name}");
        assert_eq!(ascii, binary, "{name}");
    }
}

// ---------------------------------------------------------------------------------------
// Every file, threads, CLI
// ---------------------------------------------------------------------------------------

/// Every file of `write_files_encoded` in binary is the same for 1 and 3 threads, and the
/// formats without a binary form are the ASCII run's files.
#[test]
fn binary_files_do_not_depend_on_threads_and_leave_the_text_formats_alone() {
    let (_, m) = meshes().swap_remove(1);
    let run = |threads: usize, encoding: Encoding| {
        let dir = tempfile::tempdir().unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| write_files_encoded(&m, dir.path(), Format::ALL, encoding).unwrap());
        common::tree(dir.path())
    };
    let one = run(1, Encoding::Binary);
    assert_eq!(one, run(3, Encoding::Binary));
    let ascii = run(2, Encoding::Ascii);
    let names = |t: &[(String, Vec<u8>)]| t.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&one), names(&ascii));
    for ((name, b), (_, a)) in one.iter().zip(&ascii) {
        let has_binary_form =
            name.ends_with(".vts") || name.ends_with(".vtu") || name.ends_with(".msh");
        assert_eq!(a == b, !has_binary_form, "{name}");
    }
}

#[test]
fn cli_binary_flag_writes_the_binary_forms() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m");
    let o = common::run(&[
        "-q",
        "mesh",
        "-o",
        out.to_str().unwrap(),
        "--format",
        "vtk,vtu,gmsh,json",
        "--binary",
        "--timings",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let vts = std::fs::read(out.join("mesh/block_0000.vts")).unwrap();
    read_binary_vtk(&vts);
    read_binary_vtk(&std::fs::read(out.join("mesh.vtu")).unwrap());
    read_binary_msh(&std::fs::read(out.join("mesh.msh")).unwrap());
    let t: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("timings.json")).unwrap()).unwrap();
    assert_eq!(t["binary"], true);

    // mesh-sequence: every frame's files in binary.
    let frames = dir.path().join("frames.jsonl");
    let hex = r#"{"bounding":{"center":[0,0],"radius":4},"holes":[{"center":[0,0],"radius":0.6},{"center":[1.5,0],"radius":0.6},{"center":[-1.5,0.2],"radius":0.5}]}"#;
    std::fs::write(&frames, format!("{hex}\n{hex}\n")).unwrap();
    let seq = dir.path().join("s");
    let o = common::run(&[
        "-q",
        "mesh-sequence",
        frames.to_str().unwrap(),
        "-o",
        seq.to_str().unwrap(),
        "--format",
        "vtu,gmsh",
        "--binary",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["frame_00000", "frame_00001"] {
        read_binary_vtk(&std::fs::read(seq.join(f).join("mesh.vtu")).unwrap());
        read_binary_msh(&std::fs::read(seq.join(f).join("mesh.msh")).unwrap());
    }
}
