//! Helpers shared by the integration tests: `use crate::common;` at the top of a test file
//! (the test binary, `tests/suite.rs`, declares the module once).
//!
//! Not every helper is used by the tests of every configuration, hence `dead_code` allowed.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// The built `medial-blocks` binary, ready for arguments.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_medial-blocks"))
}

/// Run the binary with `args` and collect its output.
pub fn run(args: &[&str]) -> Output {
    bin()
        .args(args)
        .output()
        .expect("the medial-blocks binary runs")
}

/// Every node of every grid of `m` as bits (x then y, block after block): two meshes have
/// the same nodes exactly when these are equal.
pub fn node_bits(m: &medial_blocks::Mesh) -> Vec<u64> {
    m.grids
        .iter()
        .flat_map(|g| {
            g.nodes
                .iter()
                .flat_map(|p| [p[0].to_bits(), p[1].to_bits()])
        })
        .collect()
}

/// Every file under `dir` as (path relative to `dir` with `/` separators, bytes), sorted by
/// path: two trees are byte-identical exactly when their `tree`s are equal.
pub fn tree(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("readable directory") {
            let p = e.expect("directory entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p
                    .strip_prefix(dir)
                    .expect("under dir")
                    .to_string_lossy()
                    .replace('\\', "/");
                out.push((rel, std::fs::read(&p).expect("readable file")));
            }
        }
    }
    out.sort();
    out
}

/// Up to `h` random holes inside the circle of radius `big_r` about `center`, radii in
/// `[0.03, 0.18] big_r`, gaps to each other and to the bounding circle of at least
/// `min_gap * big_r` (rejection sampling, at most 20 000 draws).
pub fn random_holes(
    rng: &mut medial_blocks::layouts::SplitMix64,
    h: usize,
    big_r: f64,
    center: [f64; 2],
    min_gap: f64,
) -> Vec<medial_blocks::Circle> {
    let mut holes: Vec<medial_blocks::Circle> = Vec::new();
    let mut tries = 0;
    while holes.len() < h && tries < 20_000 {
        tries += 1;
        let r = big_r * (0.03 + 0.15 * rng.next_f64());
        let a = rng.next_f64() * std::f64::consts::TAU;
        let d = (big_r - r - min_gap * big_r) * rng.next_f64().sqrt();
        let c = [center[0] + d * a.cos(), center[1] + d * a.sin()];
        let ok = holes.iter().all(|o| {
            let dd = (c[0] - o.center[0]).hypot(c[1] - o.center[1]);
            dd - r - o.radius > min_gap * big_r
        });
        if ok {
            holes.push(medial_blocks::Circle {
                center: c,
                radius: r,
            });
        }
    }
    holes
}

/// The stages of a `timings.json` add up to its total (exclusive times; `other` included),
/// and the total is not negative.
pub fn assert_stages_add_up(t: &serde_json::Value) {
    let total = t["total_seconds"].as_f64().expect("total_seconds");
    let sum: f64 = t["stages"]
        .as_object()
        .expect("stages")
        .values()
        .map(|v| v.as_f64().expect("a stage's seconds"))
        .sum();
    assert!(
        total >= 0.0 && (sum - total).abs() <= 1e-6 * total.max(1.0),
        "stages add up to {sum}, total {total}: {t}"
    );
}

/// The `spans` of a `timings.json` (every entry of every stage, in closing order) against its
/// per-stage figures: per stage, as many spans as `calls`, their seconds adding up to the
/// stage's row (to rounding), their page faults to its `fault_stages` count exactly, and no
/// span of a stage that has no row.
pub fn assert_spans_add_up(t: &serde_json::Value) {
    let spans = t["spans"].as_array().expect("spans");
    let calls = t["calls"].as_object().expect("calls");
    for (name, n) in calls {
        let mine: Vec<&serde_json::Value> = spans.iter().filter(|s| s["stage"] == **name).collect();
        assert_eq!(mine.len() as u64, n.as_u64().unwrap(), "{name}: {t}");
        let wall: f64 = mine.iter().map(|s| s["seconds"].as_f64().unwrap()).sum();
        let row = t["stages"][name.as_str()].as_f64().unwrap();
        assert!(
            (wall - row).abs() <= 1e-9 * row.max(1.0),
            "{name}: {wall} vs {row}"
        );
        if !t["fault_stages"].is_null() {
            let faults: u64 = mine
                .iter()
                .map(|s| s["page_faults"].as_u64().unwrap())
                .sum();
            assert_eq!(
                faults,
                t["fault_stages"][name.as_str()].as_u64().unwrap(),
                "{name}"
            );
        }
        assert!(mine.iter().all(|s| s["depth"].is_u64()), "{name}");
    }
    for s in spans {
        let name = s["stage"].as_str().expect("a stage name");
        assert!(
            calls.contains_key(name),
            "span of {name} without calls: {t}"
        );
    }
    // The rework, recounted: the meshing stages' spans after the first `quality_check`, up
    // to the first span of another stage (the mesh is done).
    let first = spans.iter().position(|s| s["stage"] == "quality_check");
    let after = first.map_or(&[][..], |f| &spans[f + 1..]);
    let meshing = medial_blocks::timings::REWORK_STAGES;
    let redone: Vec<&serde_json::Value> = after
        .iter()
        .take_while(|s| meshing.contains(&s["stage"].as_str().unwrap()))
        .collect();
    let checks = redone
        .iter()
        .filter(|s| s["stage"] == "quality_check")
        .count();
    assert_eq!(t["rework"]["checks"].as_u64(), Some(checks as u64), "{t}");
    let seconds: f64 = redone.iter().map(|s| s["seconds"].as_f64().unwrap()).sum();
    let got = t["rework"]["seconds"].as_f64().unwrap();
    assert!(
        (seconds - got).abs() <= 1e-12,
        "rework {got} vs {seconds}: {t}"
    );
}

/// Inverted cells, recomputed here from the nodes (not through the crate's quality code): a
/// cell counts when the cross product of its two edges at some corner, counter-clockwise, is
/// not positive (zero, negative or NaN).
pub fn count_inverted_cells(grids: &[medial_blocks::mesh::BlockGrid]) -> usize {
    let mut bad = 0;
    for g in grids {
        let at = |i: usize, j: usize| g.nodes[i + j * (g.ni + 1)];
        for j in 0..g.nj {
            for i in 0..g.ni {
                let p = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                let flipped = (0..4).any(|k| {
                    let (o, a, b) = (p[k], p[(k + 1) % 4], p[(k + 3) % 4]);
                    let cross = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
                    cross.is_nan() || cross <= 0.0
                });
                bad += usize::from(flipped);
            }
        }
    }
    bad
}

/// A small set of meshes covering every kind of block side: the hexagon (exact mode),
/// `paper` in paper mode, `uniform` with 4 x 4 cells per block, and a periodic box with two
/// holes (connectivity and writer tests).
pub fn small_meshes(
    paper: &medial_blocks::Domain,
    uniform: &medial_blocks::Domain,
) -> Vec<medial_blocks::Mesh> {
    use medial_blocks::periodic::{mesh_periodic, PeriodicDomain};
    use medial_blocks::{layouts, mesh, Circle, Mode, Options};
    let mut out = vec![
        mesh(&layouts::hexagon(), &Options::default()).unwrap(),
        mesh(
            paper,
            &Options {
                mode: Mode::Paper,
                ..Options::default()
            },
        )
        .unwrap(),
        mesh(
            uniform,
            &Options {
                cells: 4,
                block_cells: Some(4),
                ..Options::default()
            },
        )
        .unwrap(),
    ];
    let pd = PeriodicDomain::new(
        [2.0, 1.0],
        vec![Circle::new(0.1, 0.1, 0.2), Circle::new(1.2, 0.6, 0.25)],
    )
    .unwrap();
    out.push(mesh_periodic(&pd, &Options::default()).unwrap());
    out
}

/// Everything a triangulation exposes (points, triangles in order, neighbours, vertex
/// triangles, duplicates) is equal.
pub fn assert_same_triangulation(
    a: &medial_blocks::geometry::Triangulation,
    b: &medial_blocks::geometry::Triangulation,
) {
    assert_eq!(a.points(), b.points());
    assert_eq!(a.len(), b.len());
    for t in 0..a.len() {
        assert_eq!(a.triangle(t), b.triangle(t), "triangle {t}");
        assert_eq!(a.neighbors(t), b.neighbors(t), "neighbours of {t}");
    }
    for v in 0..=a.points().len() {
        assert_eq!(a.vertex_triangle(v), b.vertex_triangle(v), "vertex {v}");
    }
    assert_eq!(a.duplicates(), b.duplicates());
}

/// A hole site for the Apollonius tests.
pub fn hole_site(x: f64, y: f64, r: f64) -> medial_blocks::apollonius::Site {
    medial_blocks::apollonius::Site::hole(medial_blocks::Circle {
        center: [x, y],
        radius: r,
    })
}

/// A bounding-circle site for the Apollonius tests.
pub fn bounding_site(x: f64, y: f64, r: f64) -> medial_blocks::apollonius::Site {
    medial_blocks::apollonius::Site::bounding(medial_blocks::Circle {
        center: [x, y],
        radius: r,
    })
}

/// The hole of radius `r` externally tangent, at the angle `t`, to the circle of centre `p`
/// and radius `rho` (random Apollonius triples are three of these around one circle).
pub fn hole_tangent(p: [f64; 2], rho: f64, t: f64, r: f64) -> medial_blocks::apollonius::Site {
    let d = rho + r;
    hole_site(p[0] + d * t.cos(), p[1] + d * t.sin(), r)
}

/// The bounding circle of radius `rho + gap` internally tangent, at the angle `t`, to the
/// circle of centre `p` and radius `rho` (its centre is `gap` from `p`).
pub fn bounding_tangent(
    p: [f64; 2],
    rho: f64,
    t: f64,
    gap: f64,
) -> medial_blocks::apollonius::Site {
    bounding_site(p[0] + gap * t.cos(), p[1] + gap * t.sin(), rho + gap)
}

/// The nodes of an `(ni + 1) x (nj + 1)` lattice, each moved by up to `jitter / 2` in both
/// directions, sheared by `shear` and stretched by `(sx, sy)`, row by row (quality tests
/// spoil some of them afterwards).
pub fn jittered_lattice(
    r: &mut medial_blocks::layouts::SplitMix64,
    ni: usize,
    nj: usize,
    [sx, sy]: [f64; 2],
    shear: f64,
    jitter: f64,
) -> Vec<[f64; 2]> {
    let mut nodes = Vec::with_capacity((ni + 1) * (nj + 1));
    for j in 0..=nj {
        for i in 0..=ni {
            let x = i as f64 + jitter * (r.next_f64() - 0.5);
            let y = j as f64 + jitter * (r.next_f64() - 0.5);
            nodes.push([sx * (x + shear * y), sy * y]);
        }
    }
    nodes
}

/// A layout whose refinement inserts holes (tiny holes next to larger ones).
pub const INSERTING: &str = r#"{"bounding": {"center": [0.0, 0.0], "radius": 1.0}, "holes": [{"center": [0.3191541531691544, -0.3717929964389844], "radius": 0.24464422640973763}, {"center": [-0.11404744597041541, 0.08146095395643421], "radius": 0.11128467651604039}, {"center": [-0.42552889518459386, -0.38974998510540637], "radius": 0.0750062319977368}, {"center": [0.2359704484055954, 0.25273697336967405], "radius": 0.13286706779388338}, {"center": [-0.42666764696355597, -0.6507308368236295], "radius": 0.09961340826274921}, {"center": [-0.23212309121288838, 0.8791544668853195], "radius": 0.05751471364390008}, {"center": [-0.32687904034838855, -0.5760590860014616], "radius": 0.024988992683331306}, {"center": [-0.24251728387830382, 0.7025270240084398], "radius": 0.11940545640071007}, {"center": [-0.4207493523072746, 0.7239570940575171], "radius": 0.060101631399608516}, {"center": [-0.05955622155850428, -0.08922488265519388], "radius": 0.00012118752906053852}, {"center": [-0.07489413579200777, 0.6892364901244837], "radius": 0.00010388535976705469}, {"center": [0.9854949986492719, -0.13332433619018963], "radius": 0.00010024369325342005}]}"#;

/// A layout (far from the origin) whose refinement inserts a hole without resampling any
/// other circle: the samples before are a prefix of the samples after.
pub const PREFIX: &str = r#"{"bounding": {"center": [99.80518032777042, 222.13404102732048], "radius": 1.0}, "holes": [{"center": [100.01448901478783, 222.33167266433094], "radius": 0.20821141244148114}, {"center": [99.15416679567457, 222.4725675840845], "radius": 0.24053959701870642}, {"center": [100.49276751007557, 221.92556284706956], "radius": 0.00010638887682197367}, {"center": [100.68302868175985, 221.93803595726027], "radius": 0.00014962206114609836}, {"center": [99.46589073326423, 222.3685354043989], "radius": 0.0001105205087575796}]}"#;

/// Every cell of every grid of `m` as its four corners `(i, j)`, `(i + 1, j)`,
/// `(i + 1, j + 1)`, `(i, j + 1)` (counter-clockwise in a valid cell).
pub fn cells(m: &medial_blocks::Mesh) -> impl Iterator<Item = [[f64; 2]; 4]> + '_ {
    m.grids.iter().flat_map(|g| {
        (0..g.nj).flat_map(move |j| {
            (0..g.ni).map(move |i| {
                [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ]
            })
        })
    })
}

/// Marsaglia's xorshift64 (shifts 13, 7, 17): the tests' small seeded generator (seed non-zero).
pub struct XorShift(pub u64);

impl XorShift {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// Uniform in `[0, 1)`: the top 53 bits.
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// In `0..n` (`n > 0`; modulo bias is irrelevant here).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// FNV-1a over a triangulation's triangles, neighbours, duplicates and vertex triangles, in
/// order: equal hashes mean the same arrays (ids and order), as the golden values recorded
/// from an earlier engine check.
pub fn structure_hash(t: &medial_blocks::geometry::Triangulation) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u64| {
        h ^= x;
        h = h.wrapping_mul(0x100_0000_01b3);
    };
    eat(t.len() as u64);
    for i in 0..t.len() {
        for v in t.triangle(i) {
            eat(u64::from(v));
        }
        for m in t.neighbors(i) {
            eat(m.map_or(u64::MAX, u64::from));
        }
    }
    for &(a, b) in t.duplicates() {
        eat((u64::from(a) << 32) | u64::from(b));
    }
    for v in 0..t.points().len() {
        eat(t.vertex_triangle(v).map_or(u64::MAX, |x| x as u64));
    }
    h
}

/// Height of the cell at position `p` along side `s` of `g`, normal to the side: its area
/// over its edge on the side (the report's growth ratio, computed again here from the nodes).
pub fn side_cell_height(g: &medial_blocks::mesh::BlockGrid, s: usize, p: usize) -> f64 {
    let (ni, nj) = (g.ni, g.nj);
    let (i, j) = match s {
        0 => (p, 0),
        1 => (ni - 1, p),
        2 => (ni - 1 - p, nj - 1),
        _ => (0, nj - 1 - p),
    };
    let q = [
        g.node(i, j),
        g.node(i + 1, j),
        g.node(i + 1, j + 1),
        g.node(i, j + 1),
    ];
    let area = 0.5
        * ((q[2][0] - q[0][0]) * (q[3][1] - q[1][1]) - (q[2][1] - q[0][1]) * (q[3][0] - q[1][0]));
    let (a, b) = (q[s], q[(s + 1) % 4]);
    area.abs() / (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The growth ratios across the interfaces of `m` whose edge `kind` accepts (each interface
/// once, face by face, from [`side_cell_height`]): `(faces, faces over limit, largest ratio)`.
pub fn interface_growth(
    m: &medial_blocks::Mesh,
    kind: impl Fn(&medial_blocks::layout::EdgeKind) -> bool,
    limit: f64,
) -> (usize, usize, f64) {
    let conn = medial_blocks::connectivity::connectivity(&m.layout, &m.grids).unwrap();
    let (mut faces, mut over, mut worst) = (0, 0, 1.0f64);
    for bc in &conn {
        for sc in &bc.sides {
            let Some(p) = sc.partner else { continue };
            let edge = m.layout.blocks[bc.block].sides[sc.side].edge as usize;
            if !kind(&m.layout.edges[edge].kind) || (p.block, p.side) < (bc.block, sc.side) {
                continue;
            }
            let (ga, gb) = (&m.grids[bc.block], &m.grids[p.block]);
            let len = if sc.side % 2 == 0 { ga.ni } else { ga.nj };
            for i in 0..len {
                let q = if p.same_direction { i } else { len - 1 - i };
                let (ha, hb) = (
                    side_cell_height(ga, sc.side, i),
                    side_cell_height(gb, p.side, q),
                );
                let r = ha.max(hb) / ha.min(hb);
                faces += 1;
                over += usize::from(r > limit);
                worst = worst.max(r);
            }
        }
    }
    (faces, over, worst)
}

/// One test of the binary at a time, for tests that record stage timings
/// (`timings::Recording`, `mesh_timed`): a recording is its thread's, so a rayon worker that
/// steals a job of another test's mesh while it waits records that mesh's stages too (CI saw
/// a stage count doubled once). Each test binary has its own lock (this module is compiled
/// into each); hold the guard for the whole test.
#[allow(dead_code)]
pub fn turn() -> std::sync::MutexGuard<'static, ()> {
    static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    TURN.lock().unwrap_or_else(|e| e.into_inner())
}
