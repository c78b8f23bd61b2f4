//! Elongated periodic boxes: the array of copies grows along the short side only.
//!
//! A few holes in a box of aspect ratio 6 or more have empty regions far longer than the
//! short period, so their Delaunay circles reach over many copies along the short side. The
//! tiling used to grow equally in both directions up to `7 x 7` copies and refused such boxes;
//! it now grows per axis as far as the offending circles need (at most 7 long periods a side).
//!
//! Oracle (independent of the mesher): in exact mode every node of a block's medial side
//! lies on the medial axis of the *infinite* periodic layout: among all images of all holes
//! (enumerated here by brute force far beyond any tiling), the two nearest by clearance
//! `|p - c| - r` are equally near, and the ends of that side (medial vertices) have three
//! equally near images. With too small a tiling a vertex would be the centre of a circle that
//! some missing image enters.

use medial_blocks::fuzzing::{check_periodic_mesh, Checks};
use medial_blocks::periodic::{mesh_periodic, periodic_layout, PeriodicDomain};
use medial_blocks::{Circle, Mesh, MeshError, Options};

/// Only zero-length arcs are collapsed, so medial vertices stay exact, and no hole is
/// inserted (refinement, tested in `periodic_refine.rs`, would mesh another layout).
fn zero_only() -> Options {
    Options {
        collapse_fraction: 0.0,
        refine_ratio: None,
        ..Options::default()
    }
}

/// The four least clearances `|p - c| - r` of `p` to the images of the holes within
/// `2 max(Lx, Ly) + 2` periods in each direction, ascending.
fn clearances(pd: &PeriodicDomain, p: [f64; 2]) -> [f64; 4] {
    let size = pd.size();
    let l = size[0].max(size[1]);
    let reach = size.map(|s| (2.0 * l / s).ceil() as i64 + 2);
    let mut out = [f64::INFINITY; 4];
    for c in pd.holes() {
        for a in -reach[0]..=reach[0] {
            for b in -reach[1]..=reach[1] {
                let q = [
                    c.center[0] + a as f64 * size[0],
                    c.center[1] + b as f64 * size[1],
                ];
                let d = (p[0] - q[0]).hypot(p[1] - q[1]) - c.radius;
                if d < out[3] {
                    out[3] = d;
                    out.sort_by(f64::total_cmp);
                }
            }
        }
    }
    out
}

/// The medial sides (side 2, opposite the wall) lie on the medial axis of the infinite
/// layout, their ends on its vertices.
fn assert_on_infinite_medial_axis(pd: &PeriodicDomain, m: &Mesh) {
    let size = pd.size();
    let tol = 1e-9 * size[0].max(size[1]);
    for (b, g) in m.grids.iter().enumerate() {
        let far = g.side(2);
        for (i, &p) in far.iter().enumerate() {
            let d = clearances(pd, p);
            let end = i == 0 || i + 1 == far.len();
            let k = if end { 2 } else { 1 };
            assert!(
                d[k] - d[0] <= tol,
                "{}: block {b} medial node {i} {p:?}: nearest images {:?}",
                pd.to_json_string(),
                d
            );
            assert!(d[0] > 0.0, "block {b}: node {p:?} inside a hole");
        }
    }
}

fn mesh(size: [f64; 2], holes: &[Circle]) -> (PeriodicDomain, Mesh) {
    let pd = PeriodicDomain::new(size, holes.to_vec()).expect("valid periodic domain");
    let m =
        mesh_periodic(&pd, &zero_only()).unwrap_or_else(|e| panic!("{}: {e}", pd.to_json_string()));
    check_periodic_mesh(
        &pd,
        &m,
        Checks {
            no_inverted_cells: true,
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", pd.to_json_string()));
    (pd, m)
}

#[test]
fn one_hole_in_elongated_boxes() {
    for a in [6.0, 10.0, 25.0] {
        for size in [[a, 1.0], [1.0, a]] {
            let c = Circle::new(0.3, 0.25, 0.2);
            let (pd, m) = mesh(size, &[c]);
            // The four images at the corners of a period are co-circular: one zero-length arc.
            assert_eq!((m.medial_vertices, m.medial_arcs), (2, 3), "{size:?}");
            assert_eq!(m.collapsed_arcs, 1, "{size:?}");
            assert_eq!(m.layout.blocks.len(), 4, "{size:?}");
            assert_on_infinite_medial_axis(&pd, &m);
        }
    }
}

#[test]
fn a_few_holes_in_elongated_boxes() {
    let cases: [([f64; 2], Vec<Circle>); 4] = [
        (
            [1.0, 8.0],
            vec![Circle::new(0.3, 0.25, 0.2), Circle::new(0.6, 0.75, 0.1)],
        ),
        (
            [12.0, 1.0],
            vec![
                Circle::new(0.3, 0.25, 0.2),
                Circle::new(5.0, 0.6, 0.3),
                Circle::new(9.1, 0.1, 0.05),
            ],
        ),
        (
            [40.0, 1.5],
            vec![Circle::new(3.0, 0.7, 0.4), Circle::new(21.0, 0.2, 0.25)],
        ),
        (
            [0.5, 7.0],
            vec![Circle::new(0.25, 1.0, 0.1), Circle::new(0.1, 4.0, 0.05)],
        ),
    ];
    for (size, holes) in cases {
        let (pd, m) = mesh(size, &holes);
        assert_eq!(
            m.layout.blocks.len(),
            6 * holes.len() - 2 * m.collapsed_arcs
        );
        assert_on_infinite_medial_axis(&pd, &m);
    }
}

#[test]
fn the_tiling_grows_along_the_short_side_only() {
    // A 3 x 3 array suffices for a square box with one hole and for a dense elongated one.
    let square = PeriodicDomain::new([1.0, 1.0], vec![Circle::new(0.5, 0.5, 0.2)]).unwrap();
    assert_eq!(
        periodic_layout(&square, &zero_only()).unwrap().tiling,
        [1, 1]
    );
    let row: Vec<Circle> = (0..20)
        .map(|k| Circle::new(0.5 * k as f64 + 0.25, 0.25, 0.1))
        .collect();
    let dense = PeriodicDomain::new([10.0, 0.5], row).unwrap();
    assert_eq!(
        periodic_layout(&dense, &zero_only()).unwrap().tiling,
        [1, 1]
    );
    // One hole in a 10 x 0.5 box: empty circles of radius about 5 around x = 5.3 span about
    // 20 short periods, so the array needs about 10 copies either side along y, still 1 along x.
    let sparse = PeriodicDomain::new([10.0, 0.5], vec![Circle::new(0.3, 0.25, 0.2)]).unwrap();
    let t = periodic_layout(&sparse, &zero_only()).unwrap().tiling;
    assert_eq!(t[0], 1, "{t:?}");
    assert!((10..=12).contains(&t[1]), "{t:?}");
}

#[test]
fn boxes_too_elongated_for_the_sample_limit_are_refused_with_a_reason() {
    let pd = PeriodicDomain::new([1e6, 1.0], vec![Circle::new(0.3, 0.25, 0.2)]).unwrap();
    let e = mesh_periodic(&pd, &Options::default()).expect_err("needs millions of copies");
    let text = e.to_string();
    assert!(matches!(e, MeshError::Tiling(_)), "{e:?}");
    assert!(
        text.starts_with("periodic tiling: ")
            && text.contains("copies of the box")
            && text.contains("limit"),
        "{text}"
    );
}
