//! scratch: where the smallest angle is
use medial_blocks::{mesh, Domain, Options};
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let d = Domain::from_json_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let m = mesh(&d, &Options::default()).unwrap();
    let mut best = (f64::INFINITY, 0, 0, 0, [0.0; 2]);
    for (b, g) in m.grids.iter().enumerate() {
        for j in 0..g.nj {
            for i in 0..g.ni {
                let q = [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ];
                for k in 0..4 {
                    let (o, a, c) = (q[k], q[(k + 1) % 4], q[(k + 3) % 4]);
                    let e1 = [a[0] - o[0], a[1] - o[1]];
                    let e2 = [c[0] - o[0], c[1] - o[1]];
                    let ang = (e1[0] * e2[1] - e1[1] * e2[0])
                        .atan2(e1[0] * e2[0] + e1[1] * e2[1])
                        .to_degrees();
                    if ang < best.0 {
                        best = (ang, b, i, j, o);
                    }
                }
            }
        }
    }
    let g = &m.grids[best.1];
    println!(
        "min {:.2} block {} ni {} nj {} at i {} j {} corner {:?}",
        best.0, best.1, g.ni, g.nj, best.2, best.3, best.4
    );
    let q = [
        g.node(best.2, best.3),
        g.node(best.2 + 1, best.3),
        g.node(best.2 + 1, best.3 + 1),
        g.node(best.2, best.3 + 1),
    ];
    println!("cell {:?}", q);
}
