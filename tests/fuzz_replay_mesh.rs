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
/// too slow: `MESH_FUZZ_SECONDS=60 cargo test --test fuzz_replay_mesh -- --ignored`. A failing
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
