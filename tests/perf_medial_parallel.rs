//! The parallel medial walk (`medial::medial_arcs_parallel`, cells of vertices walked on their
//! own) against the one-by-one walk it replaces (`medial::medial_arcs_serial`), field by field,
//! for cell sizes from one vertex (every arc crosses cells) to the whole graph, on valid
//! graphs and on corrupted triangle classes (where the parallel walk must give up, never
//! return something else); and `medial_graph` against a one-pass reference of its vertices.

use medial_blocks::domain::Domain;
use medial_blocks::medial::{
    circumcenter, medial_arcs_parallel, medial_arcs_serial, medial_graph, MedialVertex,
    TriangleKind,
};
use medial_blocks::sampling::{sample_and_triangulate, SampledDomain, SamplingOptions};

fn domains() -> Vec<Domain> {
    let mut out = vec![
        medial_blocks::layouts::hexagon(),
        medial_blocks::layouts::lattice().unwrap(),
        medial_blocks::layouts::square_lattice(16).unwrap(),
    ];
    for (n, seed) in [(20, 1), (200, 2), (700, 3)] {
        out.push(medial_blocks::layouts::bubbles(n, seed).unwrap());
    }
    out
}

/// The vertices as one pass over the triangles in order computes them.
fn reference_vertices(s: &SampledDomain, kinds: &[TriangleKind]) -> Option<Vec<MedialVertex>> {
    let tri = &s.triangulation;
    let mut out = Vec::new();
    for (t, k) in kinds.iter().enumerate() {
        if *k == TriangleKind::Interior {
            let v = tri.triangle(t);
            let p = v.map(|i| s.samples.points[i as usize]);
            out.push(MedialVertex {
                triangle: t as u32,
                position: circumcenter(p[0], p[1], p[2])?,
                samples: v,
                circles: v.map(|i| s.samples.circle_of[i as usize]),
            });
        }
    }
    Some(out)
}

#[test]
fn parallel_walk_equals_the_one_by_one_walk() {
    for d in domains() {
        let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
        let (tri, kinds) = (&s.triangulation, &s.kinds);
        let vertices = reference_vertices(&s, kinds).unwrap();
        let serial = medial_arcs_serial(&s.samples, tri, kinds, &vertices).unwrap();
        assert_eq!(serial, s.medial.arcs);
        assert_eq!(vertices, s.medial.vertices);
        for per_cell in [1, 3, 16, 100, 2048, usize::MAX] {
            let par = medial_arcs_parallel(&s.samples, tri, kinds, &vertices, per_cell)
                .unwrap_or_else(|| panic!("parallel walk gave up, {per_cell} per cell"));
            assert_eq!(par.len(), serial.len());
            for (a, b) in par.iter().zip(&serial) {
                assert_eq!(a, b, "{per_cell} per cell");
            }
        }
        let full = medial_graph(&s.samples, tri, kinds).unwrap();
        assert_eq!(full, s.medial);
    }
}

/// Corrupted classes (an interior triangle turned boundary, or a boundary one turned
/// interior): the parallel walk gives the one-by-one walk's arcs or gives up, and
/// `medial_graph` gives the one-by-one result (its error when it fails).
#[test]
fn parallel_walk_gives_up_on_broken_graphs() {
    let d = medial_blocks::layouts::bubbles(120, 5).unwrap();
    let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
    let tri = &s.triangulation;
    let interior: Vec<usize> = (0..tri.len())
        .filter(|&t| s.kinds[t] == TriangleKind::Interior)
        .collect();
    let boundary: Vec<usize> = (0..tri.len())
        .filter(|&t| matches!(s.kinds[t], TriangleKind::Boundary { .. }))
        .collect();
    let mut cases = Vec::new();
    for k in (0..interior.len()).step_by(interior.len() / 7 + 1) {
        let mut kinds = s.kinds.clone();
        kinds[interior[k]] = TriangleKind::Boundary { edge: 0 };
        cases.push(kinds);
    }
    for k in (0..boundary.len()).step_by(boundary.len() / 7 + 1) {
        let mut kinds = s.kinds.clone();
        kinds[boundary[k]] = TriangleKind::Interior;
        cases.push(kinds);
    }
    let mut errors = 0;
    for kinds in &cases {
        let vertices = reference_vertices(&s, kinds).unwrap();
        let serial = medial_arcs_serial(&s.samples, tri, kinds, &vertices);
        for per_cell in [1, 8, 64, usize::MAX] {
            if let Some(par) = medial_arcs_parallel(&s.samples, tri, kinds, &vertices, per_cell) {
                assert_eq!(Some(&par), serial.as_ref().ok());
            }
        }
        let full = medial_graph(&s.samples, tri, kinds);
        match (&full, &serial) {
            (Ok(g), Ok(arcs)) => {
                assert_eq!(&g.arcs, arcs);
                assert_eq!(g.vertices, vertices);
            }
            (Err(a), Err(b)) => {
                assert_eq!(a.to_string(), b.to_string());
                errors += 1;
            }
            _ => panic!("medial_graph and the one-by-one walk disagree: {full:?}"),
        }
    }
    assert!(errors > 0, "no corrupted case failed");
}
