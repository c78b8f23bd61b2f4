use medial_blocks::domain::{Circle, Domain};
use medial_blocks::fuzzing::check_mesh;
use medial_blocks::quality::measure;
use medial_blocks::{layouts, mesh, Options};

fn ngon(n: usize) -> Domain {
    let r = 0.6 * (std::f64::consts::PI / n as f64).sin();
    let d = 1.0;
    let holes = (0..n)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / n as f64;
            Circle::new(d * a.cos(), d * a.sin(), r)
        })
        .collect();
    Domain::bounded(Circle::new(0.0, 0.0, 2.5), holes).unwrap()
}

#[test]
fn scratch() {
    let mut ds: Vec<(String, Domain)> = vec![
        ("hexagon".into(), layouts::hexagon()),
        ("lattice".into(), layouts::lattice().unwrap()),
        ("bubbles".into(), layouts::bubbles(20, 1).unwrap()),
        ("sq16".into(), layouts::square_lattice(16).unwrap()),
        ("sq9".into(), layouts::square_lattice(9).unwrap()),
    ];
    for n in 4..=12 {
        ds.push((format!("ngon{n}"), ngon(n)));
    }
    for (name, d) in &ds {
        let m = mesh(d, &Options::default()).unwrap();
        let q = measure(&m.grids);
        println!(
            "{name}: geom {:?} blocks {} groups {} collapsed {} inserted {} splits {} tmpl {} angles {:.1}-{:.1} inv {} check {:?}",
            m.geometry,
            m.layout.blocks.len(),
            m.cocircular_groups.len(),
            m.collapsed_arcs,
            m.inserted_holes.len(),
            m.split_arcs,
            m.template_blocks,
            q.min_angle_deg,
            q.max_angle_deg,
            q.inverted_cells,
            check_mesh(d, &m)
        );
    }
}

fn rlayout(seed: u64, h: usize, min_gap: f64) -> Domain {
    let mut rng = layouts::SplitMix64(seed);
    let big_r = 1.0 + 4.0 * rng.next_f64();
    let mut holes: Vec<Circle> = Vec::new();
    let mut tries = 0;
    while holes.len() < h && tries < 20_000 {
        tries += 1;
        let r = big_r * (0.03 + 0.15 * rng.next_f64());
        let a = rng.next_f64() * std::f64::consts::TAU;
        let d = (big_r - r - min_gap * big_r) * rng.next_f64().sqrt();
        let c = [d * a.cos(), d * a.sin()];
        let ok = holes.iter().all(|o| {
            let dd = (c[0] - o.center[0]).hypot(c[1] - o.center[1]);
            dd - r - o.radius > min_gap * big_r
        });
        if ok {
            holes.push(Circle { center: c, radius: r });
        }
    }
    Domain::bounded(Circle::new(0.0, 0.0, big_r), holes).expect("valid layout")
}

#[test]
fn scratch_random() {
    let (mut exact, mut paper, mut ins) = (0, 0, 0);
    for seed in 0..60u64 {
        let d = rlayout(seed * 7919 + 3, 2 + (seed as usize % 14), 0.002 + 0.0008 * (seed % 50) as f64);
        if d.hole_count() < 2 { continue; }
        let m = match mesh(&d, &Options { cells: 4, ..Options::default() }) {
            Ok(m) => m,
            Err(e) => { println!("seed {seed}: ERR {e}"); continue; }
        };
        let q = measure(&m.grids);
        let c = check_mesh(&d, &m);
        if m.geometry == medial_blocks::mesh::Geometry::Exact { exact += 1 } else { paper += 1 }
        if !m.inserted_holes.is_empty() { ins += 1 }
        if m.geometry != medial_blocks::mesh::Geometry::Exact || c.is_err() || q.inverted_cells > 0 {
            println!("seed {seed}: h {} geom {:?} ins {} coll {} inv {} {:?}", d.hole_count(), m.geometry, m.inserted_holes.len(), m.collapsed_arcs, q.inverted_cells, c);
        }
    }
    println!("exact {exact} paper {paper} with-inserted {ins}");
}
