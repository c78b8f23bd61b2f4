//! Domain validation and JSON input: every error class gives its typed variant and a message
//! naming the offending hole.

use medial_blocks::domain::{Circle, Domain, DomainError};

fn bound() -> Circle {
    Circle::new(0.0, 0.0, 10.0)
}

fn ok_holes() -> Vec<Circle> {
    vec![
        Circle::new(-3.0, 0.0, 1.0),
        Circle::new(3.0, 0.0, 1.0),
        Circle::new(0.0, 4.0, 1.5),
    ]
}

fn err(holes: Vec<Circle>) -> DomainError {
    Domain::bounded(bound(), holes).expect_err("domain should be refused")
}

#[test]
fn valid_domain_is_accepted() {
    let d = Domain::bounded(bound(), ok_holes()).unwrap();
    assert_eq!(d.holes().len(), 3);
    assert_eq!(d.circle(-1), bound());
    assert_eq!(d.circle(2), Circle::new(0.0, 4.0, 1.5));
    assert_eq!(d.bounding(), bound());
    // No holes is a valid (disk) domain.
    assert!(Domain::bounded(bound(), vec![]).is_ok());
}

#[test]
fn non_finite_values_name_hole_and_field() {
    for (value, field, idx) in [
        (f64::NAN, "center x", 0usize),
        (f64::INFINITY, "center y", 1),
        (f64::NEG_INFINITY, "radius", 2),
    ] {
        let mut h = ok_holes();
        match field {
            "center x" => h[idx].center[0] = value,
            "center y" => h[idx].center[1] = value,
            _ => h[idx].radius = value,
        }
        let e = err(h);
        match &e {
            DomainError::NonFinite {
                circle, field: f, ..
            } => {
                assert_eq!(*circle, idx as i32);
                assert_eq!(*f, field);
            }
            other => panic!("wrong variant {other:?}"),
        }
        let msg = e.to_string();
        assert!(msg.contains(&format!("hole {idx}")), "{msg}");
        assert!(msg.contains(field), "{msg}");
    }
    let e = Domain::bounded(Circle::new(0.0, f64::NAN, 1.0), vec![]).unwrap_err();
    assert!(matches!(e, DomainError::NonFinite { circle: -1, .. }));
    assert!(e.to_string().contains("bounding circle"));
}

#[test]
fn non_positive_radius() {
    for r in [0.0, -0.0, -1.0] {
        let mut h = ok_holes();
        h[1].radius = r;
        let e = err(h);
        assert!(
            matches!(e, DomainError::NonPositiveRadius { circle: 1, .. }),
            "{e:?}"
        );
        assert!(e.to_string().contains("hole 1"));
    }
    let e = Domain::bounded(Circle::new(0.0, 0.0, -2.0), vec![]).unwrap_err();
    assert!(matches!(
        e,
        DomainError::NonPositiveRadius { circle: -1, .. }
    ));
}

#[test]
fn out_of_range_magnitudes() {
    let mut h = ok_holes();
    h[2].center[0] = 1e200;
    let e = err(h);
    assert!(
        matches!(e, DomainError::OutOfRange { circle: 2, .. }),
        "{e:?}"
    );
}

#[test]
fn hole_outside_or_touching_the_bounding_circle() {
    // Fully outside, crossing, exactly touching, touching within the tolerance.
    for hole in [
        Circle::new(20.0, 0.0, 1.0),
        Circle::new(9.5, 0.0, 1.0),
        Circle::new(9.0, 0.0, 1.0),
        Circle::new(0.0, 9.0 - 5e-9, 1.0),
    ] {
        let mut h = ok_holes();
        h.push(hole);
        let e = err(h);
        assert!(
            matches!(e, DomainError::HoleNotInside { hole: 3, .. }),
            "{hole:?}: {e:?}"
        );
        assert!(e.to_string().contains("hole 3"), "{e}");
    }
    // Just beyond the tolerance (1e-9 * R = 1e-8) is accepted.
    let mut h = ok_holes();
    h.push(Circle::new(0.0, -(9.0 - 1e-7), 1.0));
    assert!(Domain::bounded(bound(), h).is_ok());
}

#[test]
fn overlapping_and_touching_holes() {
    // Overlapping.
    let mut h = ok_holes();
    h.push(Circle::new(-1.5, 0.0, 1.0));
    let e = err(h);
    assert!(
        matches!(
            e,
            DomainError::HolesOverlap {
                first: 0,
                second: 3,
                ..
            }
        ),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(msg.contains("holes 0 and 3"), "{msg}");
    // Exactly touching.
    let mut h = ok_holes();
    h.push(Circle::new(3.0, -3.0, 1.0)); // touches hole 1 at (3, -1)... distance 3, radii 2: apart
    h.push(Circle::new(-3.0, 2.5, 1.5)); // touches hole 0: distance 2.5 = 1 + 1.5
    let e = err(h);
    assert!(
        matches!(
            e,
            DomainError::HolesOverlap {
                first: 0,
                second: 4,
                ..
            }
        ),
        "{e:?}"
    );
    // Touching within the tolerance (1e-8 here).
    let mut h = ok_holes();
    h.push(Circle::new(3.0, 2.0 + 5e-9, 1.0));
    let e = err(h);
    assert!(
        matches!(
            e,
            DomainError::HolesOverlap {
                first: 1,
                second: 3,
                ..
            }
        ),
        "{e:?}"
    );
    // Beyond the tolerance is fine.
    let mut h = ok_holes();
    h.push(Circle::new(3.0, 2.0 + 1e-7, 1.0));
    assert!(Domain::bounded(bound(), h).is_ok());
    // A hole inside another.
    let mut h = ok_holes();
    h.push(Circle::new(0.0, 4.0, 0.5));
    assert!(matches!(
        err(h),
        DomainError::HolesOverlap {
            first: 2,
            second: 3,
            ..
        }
    ));
}

#[test]
fn duplicate_holes() {
    let mut h = ok_holes();
    h.push(Circle::new(3.0, 0.0, 1.0));
    let e = err(h);
    assert_eq!(
        e,
        DomainError::DuplicateHole {
            first: 1,
            second: 3
        }
    );
    assert!(e.to_string().contains("hole 3") && e.to_string().contains("hole 1"));
    // -0.0 and 0.0 are the same coordinate.
    let h = vec![Circle::new(0.0, 0.0, 1.0), Circle::new(-0.0, 0.0, 1.0)];
    assert!(matches!(err(h), DomainError::DuplicateHole { .. }));
}

#[test]
fn too_many_holes() {
    let holes: Vec<Circle> = (0..5)
        .map(|i| Circle::new(-8.0 + 3.0 * i as f64, 0.0, 1.0))
        .collect();
    let e = Domain::bounded_with_limit(bound(), holes.clone(), 4).unwrap_err();
    assert_eq!(e, DomainError::TooManyHoles { count: 5, max: 4 });
    assert!(Domain::bounded_with_limit(bound(), holes.clone(), 5).is_ok());
    // Also through JSON, without storing the extra holes.
    let d = Domain::bounded(bound(), holes).unwrap();
    let e = Domain::from_json_str_with_limit(&d.to_json_string(), 3).unwrap_err();
    assert_eq!(e, DomainError::TooManyHoles { count: 5, max: 3 });
    assert!(Domain::from_json_str_with_limit(&d.to_json_string(), 5).is_ok());
    const { assert!(Domain::MAX_HOLES >= 100_000) };
}

#[test]
fn json_round_trip() {
    let d = Domain::bounded(
        Circle::new(0.1, -0.2, 10.0 / 3.0),
        vec![
            Circle::new(1.0 / 3.0, 0.0, 0.1),
            Circle::new(-1.0, 1e-3, 0.7),
        ],
    )
    .unwrap();
    let text = d.to_json_string();
    assert_eq!(Domain::from_json_str(&text).unwrap(), d);
    let d = Domain::hexagon_example();
    assert_eq!(Domain::from_json_str(&d.to_json_string()).unwrap(), d);
    let text = r#"{"bounding": {"center": [0, 0], "radius": 5},
                   "holes": [{"center": [1, 1], "radius": 0.5}, {"center": [-1, -1], "radius": 0.5}]}"#;
    let d = Domain::from_json_str(text).unwrap();
    assert_eq!(d.holes()[1], Circle::new(-1.0, -1.0, 0.5));
}

fn json_err(text: &str) -> String {
    match Domain::from_json_str(text) {
        Err(DomainError::Json(m)) => m,
        other => panic!("expected a JSON error for {text:?}, got {other:?}"),
    }
}

#[test]
fn malformed_json() {
    let good = r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [{"center": [1, 1], "radius": 0.5}]}"#;
    // Truncated at every length.
    for cut in 0..good.len() {
        let m = json_err(&good[..cut]);
        assert!(m.contains("line"), "{m}");
    }
    // Wrong types.
    json_err(r#"{"bounding": {"center": [0, 0], "radius": "5"}, "holes": []}"#);
    json_err(r#"{"bounding": {"center": [0], "radius": 5}, "holes": []}"#);
    json_err(r#"{"bounding": {"center": [0, 0, 0], "radius": 5}, "holes": []}"#);
    json_err(r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": {}}"#);
    json_err(r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [1]}"#);
    json_err(r#"[]"#);
    json_err(
        r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [{"center": [1, 1], "radius": null}]}"#,
    );
    // Out-of-range number literal.
    json_err(r#"{"bounding": {"center": [0, 0], "radius": 1e999}, "holes": []}"#);
    // Missing fields.
    let m = json_err(r#"{"bounding": {"center": [0, 0], "radius": 5}}"#);
    assert!(m.contains("holes"), "{m}");
    let m = json_err(r#"{"bounding": {"center": [0, 0]}, "holes": []}"#);
    assert!(m.contains("radius"), "{m}");
    // Unknown fields, at both levels.
    let m = json_err(r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [], "extra": 1}"#);
    assert!(m.contains("extra"), "{m}");
    let m = json_err(
        r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [{"center": [1, 1], "radius": 0.5, "mass": 2}]}"#,
    );
    assert!(m.contains("mass"), "{m}");
    // Trailing garbage.
    json_err(&format!("{good} x"));
    // Validation errors still come through typed.
    let e = Domain::from_json_str(
        r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [{"center": [1, 1], "radius": -0.5}]}"#,
    )
    .unwrap_err();
    assert!(matches!(
        e,
        DomainError::NonPositiveRadius { circle: 0, .. }
    ));
}

/// 10^5 holes on a jittered lattice validate fast (no quadratic pair loop), and an overlap
/// planted among them is found and named.
#[test]
fn many_holes_validate_fast() {
    let n = 316usize;
    let mut holes = Vec::with_capacity(n * n);
    let mut s = 7u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for i in 0..n {
        for j in 0..n {
            let x = (i as f64 - n as f64 / 2.0) + 0.2 * (rnd() - 0.5);
            let y = (j as f64 - n as f64 / 2.0) + 0.2 * (rnd() - 0.5);
            holes.push(Circle::new(x, y, 0.2 + 0.1 * rnd()));
        }
    }
    let b = Circle::new(0.0, 0.0, 400.0);
    let t = std::time::Instant::now();
    assert!(Domain::bounded(b, holes.clone()).is_ok());
    assert!(t.elapsed().as_secs_f64() < 5.0, "took {:?}", t.elapsed());
    let k = holes.len() - 10;
    holes[k] = Circle::new(holes[500].center[0] + 0.3, holes[500].center[1], 0.2);
    let e = Domain::bounded(b, holes).unwrap_err();
    assert!(
        matches!(e, DomainError::HolesOverlap { first: 500, second, .. } if second == k),
        "{e:?}"
    );
}
