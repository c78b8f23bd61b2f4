//! Replays every file of the committed `mesh` fuzz corpus (`fuzz/corpus/mesh/`) through the
//! fuzz target's decode + mesh + invariant check (`medial_blocks::fuzzing::check_layout_bytes`),
//! so `cargo test` keeps the corpus green without nightly or cargo-fuzz.

use medial_blocks::fuzzing::{check_layout_bytes, CheckReport};
use std::path::{Path, PathBuf};

fn corpus(name: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(name);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("corpus directory")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

#[test]
fn replay_mesh_corpus() {
    let files = corpus("mesh");
    assert!(files.len() >= 20, "corpus has only {} files", files.len());
    // Near-touching layouts take up to a second or two each: replay on every core.
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let results: Vec<(PathBuf, Result<Option<CheckReport>, String>)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let files = &files;
                s.spawn(move || {
                    files
                        .iter()
                        .skip(t)
                        .step_by(threads)
                        .map(|f| {
                            let data = std::fs::read(f).expect("readable corpus file");
                            (f.clone(), check_layout_bytes(&data))
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("replay thread"))
            .collect()
    });
    let mut failures = Vec::new();
    let (mut meshed, mut inverted) = (0, 0);
    for (f, res) in results {
        match res {
            Ok(Some(r)) => {
                meshed += 1;
                inverted += usize::from(r.inverted_cells > 0);
            }
            Ok(None) => {}
            Err(e) => failures.push(format!("{}: {e}", f.display())),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // Most seeds are valid layouts (the decoder is not just refusing everything).
    assert!(
        meshed * 3 >= files.len() * 2,
        "only {meshed} of {} files meshed",
        files.len()
    );
    eprintln!(
        "{meshed} of {} corpus layouts meshed, {inverted} with inverted cells (paper mode)",
        files.len()
    );
}

/// Found by the seed corpus (`near_bounding_tight`, `ngon_5_tight_bound`): a valid domain whose
/// holes come within `1e-8 R` of the bounding circle (10 gap tolerances) was refused by uniform
/// boundary sampling ("the circle already has the most samples allowed (16384)"). Adaptive
/// sampling bisects only near the close approaches, with a precision floor on the spacing:
/// meshed at `1e-8 R` (default options) and at `2e-9 R` (twice the validation tolerance; paper
/// mode, as exact mode spends about 10 s on such a layout), checked by the fuzz mesh checker.
#[test]
fn near_touching_bounding_circle_is_meshed() {
    use medial_blocks::{mesh, Circle, Domain, Options};
    let r = 0.44;
    // (gap / R, centre offset, options): far from the origin the precision floor of the
    // sample spacing is far above the gap.
    let cases = [
        (1e-8, 0.0, Options::default()),
        (2e-9, 0.0, Options::paper()),
        (2e-9, 1e3, Options::paper()),
        (2e-9, 1e5, Options::paper()),
    ];
    for (eps, off, options) in cases {
        let holes = (0..5)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * f64::from(k) / 5.0;
                Circle::new(off + a.cos(), a.sin(), r)
            })
            .collect();
        let d = Domain::bounded(Circle::new(off, 0.0, (1.0 + r) * (1.0 + eps)), holes).unwrap();
        let m = mesh(&d, &options).unwrap_or_else(|e| panic!("gap {eps} R: {e}"));
        medial_blocks::fuzzing::check_mesh(&d, &m).unwrap();
    }
}

/// A cheap stable-toolchain exploration of the `mesh` target (random bytes through the same
/// decode + mesh + check), for machines without nightly or when libFuzzer with a sanitizer is
/// too slow: `MESH_FUZZ_SECONDS=60 cargo test --test suite -- --ignored fuzz_replay_mesh::`. A failing
/// input is printed as hex: save it under `fuzz/corpus/mesh/` as a regression.
#[test]
#[ignore = "exploration, run on demand with MESH_FUZZ_SECONDS"]
fn random_bytes_exploration() {
    let (runs, meshed, failures) =
        medial_blocks::fuzzing::explore_random_bytes(8, check_layout_bytes);
    eprintln!(
        "{runs} inputs, {meshed} meshed, {} failures",
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Issue 9 (a): a bounded domain small for its coordinates. The bounding circle's samples were
/// spaced by the precision floor of the holes (a sagitta of up to 128 ulps of the
/// coordinates), so hole samples a few ulps from the bounding circle lay outside its chords
/// and consecutive bounding samples were not Delaunay neighbours ("boundary sampling of
/// circle -1 did not converge"). The bounding circle is now sampled finer where the floor's
/// sagitta exceeds half the nearest gap. Bounding radius 0.34 centred at (307952, -125388):
/// the nearest hole is 20 ulps of the coordinates from it (6.7e-10 R). Both modes.
#[test]
fn small_domain_far_from_the_origin_is_meshed() {
    use medial_blocks::{mesh, Domain, Options};
    let d = Domain::from_json_str(
        r#"{"bounding":{"center":[307952.125,-125387.71875],"radius":0.33902680766223553},"holes":[{"center":[307952.25,-125387.4375],"radius":0.03125},{"center":[307952.25,-125387.625],"radius":0.03125000000000001},{"center":[307952.25,-125387.8125],"radius":0.03125},{"center":[307952.25,-125388.0],"radius":0.031249999999999997},{"center":[307952.125,-125387.4375],"radius":0.03125},{"center":[307952.125,-125387.625],"radius":0.03125},{"center":[307952.125,-125387.8125],"radius":0.031249999999999997},{"center":[307952.125,-125388.0],"radius":0.031249999999999997},{"center":[307952.0,-125387.4375],"radius":0.03125},{"center":[307952.0,-125387.625],"radius":0.03125},{"center":[307952.0,-125387.8125],"radius":0.03125000000000001},{"center":[307952.0,-125388.0],"radius":0.03125}]}"#,
    )
    .unwrap();
    let unit = f64::EPSILON * Domain::coordinate_magnitude(&d.bounding());
    let gap = medial_blocks::sampling::nearest_gaps(&d)[0];
    assert!(gap > 10.0 * unit && gap < 40.0 * unit, "{}", gap / unit);
    for options in [Options::default(), Options::paper()] {
        let m = mesh(&d, &options).unwrap_or_else(|e| panic!("{:?}: {e}", options.mode));
        medial_blocks::fuzzing::check_mesh(&d, &m).unwrap();
    }
}

/// Issue 9 (a): bounding radius 6.5e-7 at (1.31, -0.97), a hole 3.3 ulps of the coordinates
/// (4.5e-16, 7e-10 R) from the bounding circle: just above the smallest gap validation accepts
/// there ([`Domain::MIN_GAP_ULPS`] = 3 units), and meshed. The same layout with the hole 2
/// units from the circle (still above the tolerance 2.2 units) is refused with a typed error.
#[test]
fn tiny_domain_near_ulp_gap_is_meshed() {
    use medial_blocks::{mesh, Domain, DomainError, Options};
    let text = r#"{"bounding":{"center":[1.31414794921875,-0.966156005859375],"radius":6.455111792826174e-7},"holes":[{"center":[1.314148001945173,-0.9661555856619058],"radius":2.2201857063919303e-7},{"center":[1.31414794921875,-0.966156005859375],"radius":1.9153230823576448e-7}]}"#;
    let d = Domain::from_json_str(text).unwrap();
    let unit = f64::EPSILON * Domain::coordinate_magnitude(&d.bounding());
    let gap = d.bounding_gap(0).unwrap();
    assert!(gap > 3.0 * unit && gap < 4.0 * unit, "{}", gap / unit);
    for options in [Options::default(), Options::paper()] {
        let m = mesh(&d, &options).unwrap_or_else(|e| panic!("{:?}: {e}", options.mode));
        medial_blocks::fuzzing::check_mesh(&d, &m).unwrap();
    }
    let mut holes = d.holes().to_vec();
    holes[0].radius += 0.5 * unit;
    let e = Domain::bounded(d.bounding(), holes).unwrap_err();
    assert!(
        matches!(
            e,
            DomainError::GapBelowPrecision {
                first: -1,
                second: 0,
                ..
            }
        ),
        "{e:?}"
    );
}

/// Found by a stress test of issue 9 (small domains far from the origin with gaps of a few
/// ulps), but not a precision problem: the same layout moved to the origin (a near-touching
/// domain, a hole 5e-9 R from the bounding circle) failed the same way in paper mode. Macro
/// refinement inserts two adjacent holes (5 and 6) with 5 sides each; hole 6's widest side
/// (135 degrees) faces hole 5. The per-hole preparation filled hole 5 first, after which the
/// pair between them could not be split, so hole 6 was split 16 times on other sides without
/// ever getting under the width bound, and ended with 21 sides ("inserted hole 6: 21 arcs
/// around the hole (need an even number >= 4)"); exact mode met the same far from the origin
/// (centre (-171098.1358, -77056.1411)) after falling back to the paper pipeline. Fixed:
/// when the per-hole order cannot fit every hole, all holes are prepared together before any
/// is filled, with parity repaired along a path of splittable pairs
/// (`blocking::fill_inserted_holes`).
#[test]
fn inserted_hole_with_odd_arc_count_is_meshed() {
    use medial_blocks::{mesh, Domain, Options};
    let d = Domain::from_json_str(
        r#"{"bounding": {"center": [0.0, 0.0], "radius": 0.00018499169007752184}, "holes": [{"center": [0.00015034133684821427, 3.3688993426039815e-05], "radius": 3.092181383829158e-05}, {"center": [0.0001205284206662327, -8.090236224234104e-05], "radius": 1.389862540292113e-05}, {"center": [9.736412903293967e-05, -9.479095751885325e-05], "radius": 1.3109242980482222e-05}, {"center": [6.413974915631115e-05, -0.00012390152551233768], "radius": 1.0186837052707806e-05}, {"center": [6.50527945253998e-05, 0.00013194206985644996], "radius": 2.1953554392145494e-05}]}"#,
    )
    .unwrap();
    // The same layout far from the origin, where exact mode falls back to the paper pipeline.
    let off = [-171098.1358, -77056.1411];
    let shift = |c: medial_blocks::Circle| {
        medial_blocks::Circle::new(c.center[0] + off[0], c.center[1] + off[1], c.radius)
    };
    let far = Domain::bounded(
        shift(d.bounding()),
        d.holes().iter().copied().map(shift).collect(),
    )
    .unwrap();
    for d in [d, far] {
        for options in [Options::default(), Options::paper()] {
            let m = mesh(&d, &options).unwrap_or_else(|e| panic!("{:?}: {e}", options.mode));
            medial_blocks::fuzzing::check_mesh(&d, &m).unwrap();
        }
    }
}
