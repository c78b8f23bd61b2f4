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
