//! Periodic domains (issue 6): one period tiles the plane.

use medial_blocks::connectivity::{connectivity, SideKind};
use medial_blocks::periodic::{mesh_periodic, PeriodicDomain};
use medial_blocks::quality::measure;
use medial_blocks::{AnyDomain, Circle, DomainError, Mesh, Options};
use proptest::prelude::*;

/// Deterministic pseudo-random holes (rejection sampling with periodic images).
fn random_holes(n: usize, size: [f64; 2], rmin: f64, rmax: f64, seed: u64) -> Vec<Circle> {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out: Vec<Circle> = Vec::new();
    let mut tries = 0;
    while out.len() < n && tries < 100_000 {
        tries += 1;
        let c = Circle::new(
            next() * size[0],
            next() * size[1],
            rmin + next() * (rmax - rmin),
        );
        let ok = out.iter().all(|o| {
            let mut dx = (c.center[0] - o.center[0]).abs() % size[0];
            dx = dx.min(size[0] - dx);
            let mut dy = (c.center[1] - o.center[1]).abs() % size[1];
            dy = dy.min(size[1] - dy);
            dx.hypot(dy) > c.radius + o.radius + 0.02 * size[0].min(size[1])
        });
        if ok {
            out.push(c);
        }
    }
    out
}

/// Check the periodic invariants of `mesh` for `pd`; returns the quality line.
fn check(pd: &PeriodicDomain, mesh: &Mesh) {
    let h = pd.hole_count();
    // Six blocks per hole (inserted ones by refinement included), two fewer per collapsed
    // (zero-length or short) arc orbit, two more per split arc, and the templates.
    let hi = h + mesh.inserted_holes.len();
    assert_eq!(
        mesh.layout.blocks.len(),
        6 * hi + 2 * mesh.split_arcs + mesh.template_blocks - 2 * mesh.collapsed_arcs,
        "six blocks per hole minus two per collapsed arc"
    );
    let size = pd.size();
    let tol = 1e-12 * size[0].max(size[1]);
    let conn = connectivity(&mesh.layout, &mesh.grids).expect("connectivity");
    let mut periodic_sides = 0;
    for bc in &conn {
        for sc in &bc.sides {
            assert!(
                sc.kind != SideKind::Outer,
                "no side on an auxiliary bounding circle"
            );
            if sc.kind == SideKind::Periodic {
                periodic_sides += 1;
                let p = sc.partner.expect("partner");
                let t = sc.translation.expect("translation");
                let own = mesh.grids[bc.block].side(sc.side);
                let mut other = mesh.grids[p.block].side(p.side);
                if !p.same_direction {
                    other.reverse();
                }
                assert_eq!(own.len(), other.len(), "periodic partners' node counts");
                for (a, b) in own.iter().zip(&other) {
                    let d = (a[0] + t[0] - b[0]).hypot(a[1] + t[1] - b[1]);
                    assert!(d <= tol, "periodic node mismatch {d:e}");
                }
                // The partner names this side back with the opposite translation.
                let back = conn[p.block].sides[p.side];
                assert_eq!(back.kind, SideKind::Periodic);
                assert_eq!(
                    back.partner.map(|q| (q.block, q.side)),
                    Some((bc.block, sc.side))
                );
                assert_eq!(back.translation, Some([-t[0], -t[1]]));
                // Translations are period shifts.
                for d in 0..2 {
                    let k = t[d] / size[d];
                    assert_eq!(k, k.round(), "translation {t:?} is a period shift");
                }
            }
        }
    }
    assert!(periodic_sides > 0, "a period has a zig-zag boundary");
    // The period's area: Lx Ly minus the holes (walls are polygons of short chords).
    let mut area = 0.0;
    for g in &mesh.grids {
        for j in 0..g.nj {
            for i in 0..g.ni {
                let p = [
                    g.node(i, j),
                    g.node(i + 1, j),
                    g.node(i + 1, j + 1),
                    g.node(i, j + 1),
                ];
                let mut a = 0.0;
                for k in 0..4 {
                    let (u, v) = (p[k], p[(k + 1) % 4]);
                    a += u[0] * v[1] - v[0] * u[1];
                }
                area += 0.5 * a;
            }
        }
    }
    let holes: f64 = pd
        .holes()
        .iter()
        .map(|c| std::f64::consts::PI * c.radius * c.radius)
        .sum();
    let want = size[0] * size[1] - holes;
    assert!(
        (area - want).abs() < 0.01 * size[0] * size[1],
        "period area {area} vs {want}"
    );
}

#[test]
fn twenty_bubbles_give_120_blocks() {
    let size = [1.0, 1.0];
    let holes = random_holes(20, size, 0.04, 0.11, 7);
    assert_eq!(holes.len(), 20);
    let pd = PeriodicDomain::new(size, holes).unwrap();
    let mesh = mesh_periodic(&pd, &Options::default()).unwrap();
    check(&pd, &mesh);
    assert_eq!(mesh.layout.blocks.len(), 120);
    assert_eq!(mesh.medial_vertices, 40);
    assert_eq!(mesh.medial_arcs, 60);
    let q = measure(&mesh.grids);
    eprintln!(
        "20 bubbles: {} blocks, {} cells, angles {:.1}..{:.1}, mean {:.1}/{:.1}, inverted {}",
        mesh.layout.blocks.len(),
        q.cells,
        q.min_angle_deg,
        q.max_angle_deg,
        q.mean_min_angle_deg,
        q.mean_max_angle_deg,
        q.inverted_cells
    );
}

#[test]
fn one_hole_in_a_square_lattice() {
    // The Voronoi diagram of a square lattice is degenerate (four co-circular neighbours):
    // every copy must still be triangulated identically.
    for (size, c) in [
        ([1.0, 1.0], Circle::new(0.5, 0.5, 0.2)),
        ([1.0, 1.0], Circle::new(0.0, 0.0, 0.3)),
        ([2.0, 1.0], Circle::new(1.9, 0.95, 0.25)),
        ([1.0, 3.0], Circle::new(-0.3, 7.5, 0.1)),
    ] {
        let pd = PeriodicDomain::new(size, vec![c]).unwrap();
        let mesh = mesh_periodic(&pd, &Options::default()).unwrap();
        check(&pd, &mesh);
    }
}

#[test]
fn holes_crossing_edges_and_corners() {
    let size = [3.0, 2.0];
    let holes = vec![
        Circle::new(0.05, 0.05, 0.3), // a corner
        Circle::new(1.5, 1.98, 0.25), // the top edge
        Circle::new(2.9, 1.0, 0.2),   // the right edge
        Circle::new(1.4, 0.9, 0.35),
        Circle::new(-0.7, 0.8, 0.15), // outside the box: wrapped
    ];
    let pd = PeriodicDomain::new(size, holes).unwrap();
    for c in pd.holes() {
        assert!((0.0..size[0]).contains(&c.center[0]) && (0.0..size[1]).contains(&c.center[1]));
    }
    let mesh = mesh_periodic(&pd, &Options::default()).unwrap();
    check(&pd, &mesh);
}

#[test]
fn invalid_periodic_domains_are_refused() {
    let c = Circle::new(0.5, 0.5, 0.2);
    assert!(matches!(
        PeriodicDomain::new([0.0, 1.0], vec![c]),
        Err(DomainError::InvalidPeriod { axis: 0, .. })
    ));
    assert!(matches!(
        PeriodicDomain::new([1.0, f64::NAN], vec![c]),
        Err(DomainError::InvalidPeriod { axis: 1, .. })
    ));
    assert!(matches!(
        PeriodicDomain::new([1.0, -2.0], vec![c]),
        Err(DomainError::InvalidPeriod { axis: 1, .. })
    ));
    assert_eq!(
        PeriodicDomain::new([1.0, 1.0], vec![]),
        Err(DomainError::NoPeriodicHoles)
    );
    assert!(matches!(
        PeriodicDomain::new([1.0, 1.0], vec![Circle::new(0.5, 0.5, 0.5)]),
        Err(DomainError::HoleWiderThanPeriod { hole: 0, .. })
    ));
    // Overlap only through the periodic image (across the right edge).
    let err = PeriodicDomain::new(
        [1.0, 1.0],
        vec![Circle::new(0.1, 0.5, 0.1), Circle::new(0.92, 0.5, 0.1)],
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            DomainError::HolesOverlap {
                first: 0,
                second: 1,
                ..
            }
        ),
        "{err}"
    );
    assert!(matches!(
        PeriodicDomain::new([1.0, 1.0], vec![Circle::new(0.1, 0.5, -0.1)]),
        Err(DomainError::NonPositiveRadius { circle: 0, .. })
    ));
}

#[test]
fn json_forms() {
    let text = r#"{"periodic": {"size": [2, 1]}, "holes": [{"center": [2.5, -0.5], "radius": 0.2},
        {"center": [1.2, 0.3], "radius": 0.15}]}"#;
    let AnyDomain::Periodic(pd) = AnyDomain::from_json_str(text).unwrap() else {
        panic!("not periodic")
    };
    assert_eq!(pd.size(), [2.0, 1.0]);
    assert_eq!(pd.holes()[0].center, [0.5, 0.5]);
    let again = PeriodicDomain::from_json_str(&pd.to_json_string()).unwrap();
    assert_eq!(again, pd);
    let bounded = r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": []}"#;
    assert!(matches!(
        AnyDomain::from_json_str(bounded),
        Ok(AnyDomain::Bounded(_))
    ));
    assert!(matches!(
        AnyDomain::from_json_str(r#"{"periodic": {"size": [1, 1]}, "holes": [], "x": 1}"#),
        Err(DomainError::Json(_))
    ));
    assert!(matches!(
        AnyDomain::from_json_str("{\"periodic\": "),
        Err(DomainError::Json(_))
    ));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random layouts, holes anywhere (crossing edges and corners): six blocks per hole and
    /// exact periodic matching.
    #[test]
    fn random_periodic_layouts(
        n in 1usize..9,
        lx in 0.6f64..2.0,
        ly in 0.6f64..2.0,
        seed in any::<u64>(),
    ) {
        let size = [lx, ly];
        let m = lx.min(ly);
        let holes = random_holes(n, size, 0.03 * m, 0.18 * m, seed);
        let pd = PeriodicDomain::new(size, holes).unwrap();
        let mesh = mesh_periodic(&pd, &Options { cells: 6, ..Options::default() }).unwrap();
        check(&pd, &mesh);
    }
}
