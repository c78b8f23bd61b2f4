//! Issue #8: the classes and sampling checks computed by ranges of triangles on the thread
//! pool (`sampling::classify_and_check_in`) equal the serial passes, whatever the number of
//! ranges.

use medial_blocks::domain::Domain;
use medial_blocks::layouts;
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};

fn domains() -> Vec<Domain> {
    let mut out = vec![layouts::hexagon(), layouts::lattice().unwrap()];
    out.push(layouts::square_lattice(16).unwrap());
    for (n, seed) in [(2, 1), (20, 2), (300, 1), (700, 3)] {
        out.push(layouts::bubbles(n, seed).unwrap());
    }
    out
}

/// The classes and sampling violations by ranges of triangles on the thread pool
/// (`classify_and_check_in`) equal the separate serial passes (`classify`, then
/// `check_invariants`), for any number of ranges: on good samplings and on coarse ones that
/// break the invariants (violations of every range, in order).
#[test]
fn split_classes_and_checks_equal_the_serial_ones() {
    use medial_blocks::geometry::Triangulation;
    use medial_blocks::medial::classify;
    use medial_blocks::sampling::{
        check_invariants, classify_and_check_in, nearest_gaps, sample, Samples,
    };
    let mut cases: Vec<Samples> = Vec::new();
    for d in domains() {
        let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
        cases.push(s.samples);
        // 8 samples a circle: many triangles with two boundary edges, missing edges.
        let gaps = nearest_gaps(&d);
        cases.push(sample(&d, &vec![8; gaps.len()], &gaps));
    }
    let mut broken = 0;
    for samples in cases {
        let Ok(tri) = Triangulation::new(&samples.points) else {
            continue;
        };
        let kinds = classify(&samples, &tri);
        let check = check_invariants(&samples, &tri, &kinds);
        broken += usize::from(!check.is_empty());
        for parts in [1, 2, 3, 7, 1000] {
            let (k, v) = classify_and_check_in(&samples, &tri, parts);
            assert_eq!(k, kinds, "{parts} parts");
            assert_eq!(v, check, "{parts} parts");
        }
    }
    assert!(broken >= 3, "only {broken} samplings broke the invariants");
}
