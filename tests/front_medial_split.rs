//! Issue #8: the medial graph built by strips of vertices on several threads
//! (`medial::parallel::split_with`) equals the serial construction (`medial_graph_serial`,
//! the documented walk order) bit for bit, whatever the number of strips, and gives up (the
//! caller then runs the serial one, for its error) when the classes are inconsistent.

use medial_blocks::domain::Domain;
use medial_blocks::layouts;
use medial_blocks::medial::parallel::split_with;
use medial_blocks::medial::{medial_graph, medial_graph_serial, TriangleKind};
use medial_blocks::sampling::{sample_and_triangulate, SamplingOptions};

fn domains() -> Vec<Domain> {
    let mut out = vec![layouts::hexagon(), layouts::lattice().unwrap()];
    out.push(layouts::square_lattice(16).unwrap());
    for (n, seed) in [(2, 1), (20, 2), (300, 1), (700, 3)] {
        out.push(layouts::bubbles(n, seed).unwrap());
    }
    out
}

#[test]
fn split_graph_equals_the_serial_one() {
    for d in domains() {
        let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
        let serial = medial_graph_serial(&s.samples, &s.triangulation, &s.kinds).unwrap();
        assert_eq!(s.medial, serial);
        assert_eq!(
            medial_graph(&s.samples, &s.triangulation, &s.kinds).unwrap(),
            serial
        );
        for parts in [1, 2, 3, 7, 16, 1000] {
            let split = split_with(&s.samples, &s.triangulation, &s.kinds, parts)
                .expect("the split construction checks out on a valid sampling");
            assert_eq!(split, serial, "{parts} parts, {} holes", d.hole_count());
        }
    }
}

#[test]
fn split_graph_gives_up_where_the_serial_one_fails() {
    let d = layouts::bubbles(200, 4).unwrap();
    let s = sample_and_triangulate(&d, &SamplingOptions::default()).unwrap();
    // An interior triangle relabelled as a hole's: walks into it fail.
    let mut kinds = s.kinds.clone();
    let t = s.medial.vertices[s.medial.vertices.len() / 2].triangle as usize;
    kinds[t] = TriangleKind::Hole(0);
    assert!(medial_graph_serial(&s.samples, &s.triangulation, &kinds).is_err());
    for parts in [1, 2, 5] {
        assert!(split_with(&s.samples, &s.triangulation, &kinds, parts).is_none());
    }
    assert_eq!(
        medial_graph(&s.samples, &s.triangulation, &kinds)
            .unwrap_err()
            .to_string(),
        medial_graph_serial(&s.samples, &s.triangulation, &kinds)
            .unwrap_err()
            .to_string()
    );
    // Wrong lengths: not attempted.
    assert!(split_with(&s.samples, &s.triangulation, &kinds[1..], 2).is_none());
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
