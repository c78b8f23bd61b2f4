//! Sequences keep block structure and node counts over runs of equal combinatorics (issue 6).
//! Node counts are read back from the written connectivity.json (`dims` per block).

use crate::common;

use common::tree;
use medial_blocks::exact_mode::imposed::ImposedCounts;
use medial_blocks::sequence::{mesh_frame, parse_frames, run_sequence, SequenceSummary};
use medial_blocks::{AnyDomain, Options};
use std::path::Path;
use std::sync::Arc;

/// Three holes in a circle, one moving by `step` per frame; `bad` frames have overlapping
/// holes.
fn bounded_frames(n: usize, step: f64, bad: &[usize]) -> String {
    (0..n)
        .map(|k| {
            if bad.contains(&k) {
                return r#"{"bounding": {"center": [0, 0], "radius": 5}, "holes": [{"center": [0, 0], "radius": 1}, {"center": [0.5, 0], "radius": 1}]}"#.to_string();
            }
            format!(
                r#"{{"bounding": {{"center": [0, 0], "radius": 5}}, "holes": [{{"center": [{}, {}], "radius": 1}}, {{"center": [2.5, 0.3], "radius": 0.8}}, {{"center": [0.2, 2.6], "radius": 0.9}}, {{"center": [-0.4, -2.7], "radius": 0.6}}]}}"#,
                -2.0 + step * k as f64,
                0.5 * step * k as f64
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn periodic_frames(n: usize, step: f64) -> String {
    (0..n)
        .map(|k| {
            let x = step * k as f64;
            format!(
                r#"{{"periodic": {{"size": [4, 3]}}, "holes": [{{"center": [{}, 0.5], "radius": 0.6}}, {{"center": [2.2, {}], "radius": 0.8}}, {{"center": [3.4, 0.2], "radius": 0.3}}]}}"#,
                0.5 + x,
                1.9 - x
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn run(text: &str, dir: &Path, threads: usize) -> SequenceSummary {
    let ticks = std::sync::atomic::AtomicUsize::new(0);
    let frames = parse_frames(text);
    let opts = Options {
        cells: 6,
        ..Options::default()
    };
    let summary = run_sequence(
        &frames,
        &opts,
        &[medial_blocks::output::Format::Json],
        medial_blocks::output::Encoding::Ascii,
        dir,
        threads,
        &|| {
            ticks.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        },
    )
    .unwrap();
    // The progress display advances once per frame, failed frames included.
    assert_eq!(ticks.into_inner(), frames.len(), "progress ticks");
    summary
}

/// `[ni, nj]` per block from `frame_NNNNN/connectivity.json`.
fn dims(dir: &Path, k: usize) -> Vec<[u64; 2]> {
    let path = dir.join(format!("frame_{k:05}/connectivity.json"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let d = b["dims"].as_array().unwrap();
            [d[0].as_u64().unwrap(), d[1].as_u64().unwrap()]
        })
        .collect()
}

fn check_run(text: &str, n: usize) {
    // On their own, some frames have other node counts than frame 0 (exact mode sizes cells
    // from the geometry), so the run really re-meshes them.
    let frames = parse_frames(text);
    let opts = Options {
        cells: 6,
        ..Options::default()
    };
    let own: Vec<_> = frames
        .iter()
        .map(|f| mesh_frame(f.as_ref().unwrap(), &opts).unwrap().structure())
        .collect();
    assert!(
        own.iter().any(|s| s != &own[0]),
        "a motion that changes counts"
    );
    let dir = tempfile::tempdir().unwrap();
    let s = run(text, dir.path(), 2);
    assert_eq!(s.failed, 0);
    let first = dims(dir.path(), 0);
    for k in 1..n {
        let f = &s.frames[k];
        assert!(f.same_combinatorics_as_previous, "frame {k}: {f:?}");
        assert!(f.same_block_structure_as_previous, "frame {k}");
        assert!(f.same_node_counts_as_previous, "frame {k}: {f:?}");
        assert_eq!(f.node_counts_from_frame, Some(0), "frame {k}");
        assert_eq!(dims(dir.path(), k), first, "frame {k}: ni, nj per block");
        assert_eq!(f.inverted_cells, 0);
    }
}

#[test]
fn small_motions_keep_blocks_and_node_counts() {
    check_run(&bounded_frames(6, 0.01, &[]), 6);
}

#[test]
fn periodic_small_motions_keep_blocks_and_node_counts() {
    check_run(&periodic_frames(5, 0.01), 5);
}

#[test]
fn reused_counts_are_the_first_frames_and_byte_identical_for_1_and_2_threads() {
    let text = bounded_frames(7, 0.02, &[4]);
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let s1 = run(&text, &a, 1);
    let s2 = run(&text, &b, 2);
    assert_eq!(s1, s2);
    assert!(
        tree(&a) == tree(&b),
        "outputs differ between 1 and 2 threads"
    );
    // The failed frame is reported, the others meshed; the run restarts after it.
    assert_eq!(s1.failed, 1);
    assert!(!s1.frames[4].ok && s1.frames[4].error.is_some());
    assert!(s1.frames.iter().enumerate().all(|(k, f)| f.ok == (k != 4)));
    assert_eq!(s1.frames[5].node_counts_from_frame, None);
    assert!(!s1.frames[5].same_combinatorics_as_previous);
    assert_eq!(s1.frames[6].node_counts_from_frame, Some(5));
    assert_eq!(dims(&a, 6), dims(&a, 5));
    assert_eq!(dims(&a, 3), dims(&a, 0));
    // Oracle: frame 2 is exactly frame 2 meshed alone with frame 0's counts imposed.
    let frames = parse_frames(&text);
    let opts = Options {
        cells: 6,
        ..Options::default()
    };
    let f0 = mesh_frame(frames[0].as_ref().unwrap(), &opts).unwrap();
    let want = f0.structure().unwrap();
    let imposed = Options {
        imposed_counts: Some(Arc::new(ImposedCounts::new(want.iter().cloned().collect()))),
        ..opts.clone()
    };
    let f2 = mesh_frame(frames[2].as_ref().unwrap(), &imposed).unwrap();
    assert_eq!(f2.structure().unwrap(), want);
    let single = dir.path().join("single");
    let alone = run(
        &format!(
            "{}\n{}",
            text.lines().next().unwrap(),
            text.lines().nth(2).unwrap()
        ),
        &single,
        1,
    );
    assert_eq!(alone.frames[1].node_counts_from_frame, Some(0));
    assert!(tree(&single.join("frame_00001")) == tree(&a.join("frame_00002")));
    assert!(tree(&single.join("frame_00000")) == tree(&a.join("frame_00000")));
}

#[test]
fn counts_that_do_not_fit_are_ignored() {
    // Imposed counts for another domain's blocks: the frame keeps its own counts.
    let frames = parse_frames(&bounded_frames(1, 0.0, &[]));
    let other = parse_frames(&periodic_frames(1, 0.0));
    let opts = Options {
        cells: 6,
        ..Options::default()
    };
    let own = mesh_frame(frames[0].as_ref().unwrap(), &opts).unwrap();
    let foreign = mesh_frame(other[0].as_ref().unwrap(), &opts).unwrap();
    let imposed = Options {
        imposed_counts: Some(Arc::new(ImposedCounts::new(
            foreign.structure().unwrap().into_iter().collect(),
        ))),
        ..opts.clone()
    };
    let again = mesh_frame(frames[0].as_ref().unwrap(), &imposed).unwrap();
    assert_eq!(again.mesh.grids, own.mesh.grids);
    // Partial counts (one block missing) are not used either.
    let mut partial: Vec<_> = own.structure().unwrap();
    partial.pop();
    let mut doubled = ImposedCounts::new(partial.into_iter().collect());
    for v in doubled.counts.values_mut() {
        *v = [2 * v[0], 2 * v[1]];
    }
    let again = mesh_frame(
        frames[0].as_ref().unwrap(),
        &Options {
            imposed_counts: Some(Arc::new(doubled)),
            ..opts.clone()
        },
    )
    .unwrap();
    assert_eq!(again.mesh.grids, own.mesh.grids);
    assert!(matches!(&other[0], Ok(AnyDomain::Periodic(_))));
}

/// Frames switching between bounded and periodic domains, in CRLF lines with a byte order
/// mark: every frame meshes, a switch is never "the same combinatorics", and two identical
/// periodic frames whose block keys are not unique (two holes: no counts can be imposed by
/// key) are still reported with the same blocks and node counts (they were reported with
/// differing counts).
#[test]
fn frames_switching_between_bounded_and_periodic() {
    let bounded = |x: f64| {
        format!(
            r#"{{"bounding": {{"center": [0, 0], "radius": 5}}, "holes": [{{"center": [0, 0], "radius": 1}}, {{"center": [{x}, 0], "radius": 1}}]}}"#
        )
    };
    let periodic = |x: f64| {
        format!(
            r#"{{"periodic": {{"size": [6, 6]}}, "holes": [{{"center": [0, 0], "radius": 1}}, {{"center": [{x}, 0], "radius": 1}}]}}"#
        )
    };
    let text = format!(
        "\u{feff}{}\r\n{}\r\n{}\r\n{}\r\n{}\r\n",
        bounded(2.5),
        periodic(2.5),
        bounded(2.6),
        periodic(2.6),
        periodic(2.6)
    );
    let dir = tempfile::tempdir().unwrap();
    let s = run(&text, dir.path(), 2);
    assert_eq!(s.failed, 0, "{s:?}");
    let f = &s.frames;
    for (k, frame) in f.iter().enumerate().take(4).skip(1) {
        assert!(!frame.same_combinatorics_as_previous, "frame {k}");
    }
    assert!(f[4].same_combinatorics_as_previous && f[4].same_block_structure_as_previous);
    assert!(f[4].same_node_counts_as_previous, "{:?}", f[4]);
    // The oracle: the node counts written for frames 3 and 4 are equal block for block.
    assert_eq!(dims(dir.path(), 3), dims(dir.path(), 4));
}

/// One hole moving off the centre of its bounding circle: exact mode's annulus
/// (`exact_mode::annulus`: eight blocks whose keys are told apart by their loop piece).
fn one_hole_frames(n: usize, step: f64) -> String {
    (0..n)
        .map(|k| {
            format!(
                r#"{{"bounding": {{"center": [0, 0], "radius": 4}}, "holes": [{{"center": [{}, {}], "radius": 1}}]}}"#,
                0.3 + step * k as f64,
                -0.5 * step * k as f64
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn one_hole_motions_keep_blocks_and_node_counts() {
    let text = one_hole_frames(5, 0.2);
    // Unique keys, so the run can impose counts by key.
    let frames = parse_frames(&text);
    let f0 = mesh_frame(frames[0].as_ref().unwrap(), &Options::default()).unwrap();
    assert_eq!(f0.mesh.grids.len(), 8);
    assert!(
        f0.structure().is_some(),
        "the annulus blocks have unique keys"
    );
    check_run(&text, 5);
}

/// What the sequential rule of [`run_sequence`] says about one frame, worked out here frame by
/// frame from [`mesh_frame`] alone (the slow oracle: no waves, every mesh made on its own).
#[derive(Debug, PartialEq)]
struct Expected {
    ok: bool,
    node_counts_from_frame: Option<usize>,
    counts_not_kept: bool,
    dims: Vec<[u64; 2]>,
    /// Cells, smallest and largest angle, inverted cells of the kept mesh, by
    /// [`medial_blocks::quality::measure`] (the summary takes them from `report.json`'s pass).
    figures: (usize, f64, f64, usize),
}

impl Expected {
    const FAILED: Expected = Expected {
        ok: false,
        node_counts_from_frame: None,
        counts_not_kept: false,
        dims: Vec::new(),
        figures: (0, 0.0, 0.0, 0),
    };
}

/// The rule, frame by frame: a frame after a run's frame is meshed with the run's first
/// frame's counts imposed and kept when that mesh has the run's keys and counts, the run's
/// combinatorics and no inverted cell; else it is meshed with its own counts and continues
/// the run when it has the run's combinatorics and keys, or starts a new run.
fn sequential_rule(text: &str, opts: &Options) -> (Vec<Expected>, usize, usize, usize) {
    let frames = parse_frames(text);
    // (first frame, its keys and counts, its combinatorics)
    type Run = (
        usize,
        Vec<(medial_blocks::exact_mode::imposed::BlockKey, [usize; 2])>,
        Vec<[medial_blocks::sequence::CircleTag; 3]>,
    );
    let mut run: Option<Run> = None;
    let mut out = Vec::new();
    let (mut imposed_kept, mut own_differ, mut unapplied_own) = (0, 0, 0);
    let dims_of = |m: &medial_blocks::sequence::FrameMesh| {
        m.mesh
            .grids
            .iter()
            .map(|g| [g.ni as u64 + 1, g.nj as u64 + 1])
            .collect::<Vec<_>>()
    };
    let figures_of = |m: &medial_blocks::sequence::FrameMesh| {
        let q = medial_blocks::quality::measure(&m.mesh.grids);
        (q.cells, q.min_angle_deg, q.max_angle_deg, q.inverted_cells)
    };
    for (k, frame) in frames.iter().enumerate() {
        // A failed frame ends its run.
        let Ok(domain) = frame else {
            out.push(Expected::FAILED);
            run = None;
            continue;
        };
        // The rejected attempt with the run's counts, when they were never applied.
        let mut unapplied = None;
        if let Some((s, want, comb)) = &run {
            let counts = Arc::new(ImposedCounts::new(want.iter().cloned().collect()));
            let imposed = Options {
                imposed_counts: Some(counts.clone()),
                ..opts.clone()
            };
            let attempt = mesh_frame(domain, &imposed);
            if !counts.applied() {
                unapplied = Some(attempt.as_ref().ok().map(|m| common::node_bits(&m.mesh)));
            }
            if let Ok(m) = attempt {
                if m.structure().as_ref() == Some(want)
                    && &m.combinatorics == comb
                    && common::count_inverted_cells(&m.mesh.grids) == 0
                {
                    imposed_kept += 1;
                    let own = mesh_frame(domain, opts).ok().and_then(|o| o.structure());
                    own_differ += usize::from(own.as_ref() != Some(want));
                    // Counts that differ from the frame's own were applied.
                    assert!(counts.applied() || own.as_ref() == Some(want), "frame {k}");
                    out.push(Expected {
                        ok: true,
                        node_counts_from_frame: Some(*s),
                        counts_not_kept: false,
                        dims: dims_of(&m),
                        figures: figures_of(&m),
                    });
                    continue;
                }
            }
        }
        let own = mesh_frame(domain, opts);
        if let Some(bits) = unapplied {
            // Counts never applied changed nothing: the attempt was the frame's own mesh.
            assert_eq!(
                bits,
                own.as_ref().ok().map(|m| common::node_bits(&m.mesh)),
                "frame {k}"
            );
            unapplied_own += 1;
        }
        let Ok(own) = own else {
            out.push(Expected::FAILED);
            run = None;
            continue;
        };
        let structure = own.structure();
        let continues = run.as_ref().is_some_and(|(_, want, comb)| {
            &own.combinatorics == comb
                && structure.as_ref().is_some_and(|st| {
                    st.len() == want.len() && st.iter().zip(want).all(|(a, b)| a.0 == b.0)
                })
        });
        if continues {
            let (s, want, _) = run.as_ref().unwrap();
            let same = structure.as_ref() == Some(want);
            out.push(Expected {
                ok: true,
                node_counts_from_frame: same.then_some(*s),
                counts_not_kept: !same,
                dims: dims_of(&own),
                figures: figures_of(&own),
            });
        } else {
            out.push(Expected {
                ok: true,
                node_counts_from_frame: None,
                counts_not_kept: false,
                dims: dims_of(&own),
                figures: figures_of(&own),
            });
            run = structure.map(|st| (k, st, own.combinatorics.clone()));
        }
    }
    (out, imposed_kept, own_differ, unapplied_own)
}

/// [`run_sequence`] on 1, 2 and 3 threads (waves of 1, 2 and 3 frames, which speculate
/// differently) settles every frame of `text` as `want` (the sequential rule) says, with the
/// same files each time.
fn settle_as_the_rule(text: &str, want: &[Expected]) {
    let dir = tempfile::tempdir().unwrap();
    let mut trees = Vec::new();
    for threads in [1, 2, 3] {
        let d = dir.path().join(format!("t{threads}"));
        let s = run(text, &d, threads);
        for (k, (f, e)) in s.frames.iter().zip(want).enumerate() {
            assert_eq!(f.ok, e.ok, "frame {k}, {threads} threads: {f:?}");
            assert_eq!(
                f.node_counts_from_frame, e.node_counts_from_frame,
                "frame {k}, {threads} threads: {f:?}"
            );
            assert_eq!(
                f.node_counts_not_kept.is_some(),
                e.counts_not_kept,
                "frame {k}, {threads} threads: {f:?}"
            );
            if f.ok {
                assert_eq!(dims(&d, k), e.dims, "frame {k}, {threads} threads");
                let got = (f.cells, f.min_angle_deg, f.max_angle_deg, f.inverted_cells);
                assert_eq!(got, e.figures, "frame {k}, {threads} threads");
            }
        }
        trees.push(tree(&d));
    }
    assert!(
        trees[0] == trees[1] && trees[1] == trees[2],
        "outputs differ between thread counts"
    );
}

/// [`run_sequence`] settles every frame as the sequential rule does, on 1, 2 and 3 threads
/// (waves of 1, 2 and 3 frames, which speculate differently), with the same files each time:
/// a sequence with runs whose later frames need the run's counts imposed, a change of
/// combinatorics inside a wave, and a failed frame.
#[test]
fn waves_settle_frames_as_the_sequential_rule() {
    // Four holes near a square, one moving along its side: the medial vertices flip at two
    // frames (the four nearly co-circular), then a failed frame, then the start again.
    let frame = |k: usize| {
        let d = -0.25 + 0.06 * k as f64;
        format!(
            r#"{{"bounding": {{"center": [0, 0], "radius": 4}}, "holes": [{{"center": [1.5, 1.5], "radius": 0.5}}, {{"center": [-1.5, 1.5], "radius": 0.6}}, {{"center": [-1.5, -1.5], "radius": 0.5}}, {{"center": [{}, {}], "radius": 0.6}}]}}"#,
            1.5 + d,
            -1.5 - 0.5 * d
        )
    };
    let mut lines: Vec<String> = (0..10).map(frame).collect();
    lines.push(bounded_frames(1, 0.0, &[0]));
    lines.extend([frame(0), frame(1), frame(2)]);
    let text = lines.join("\n");
    let opts = Options {
        cells: 6,
        ..Options::default()
    };
    let (want, imposed_kept, own_differ, unapplied_own) = sequential_rule(&text, &opts);
    let starts: Vec<usize> = (1..want.len())
        .filter(|&k| {
            want[k].ok
                && want[k - 1].ok
                && want[k].node_counts_from_frame.is_none()
                && !want[k].counts_not_kept
        })
        .collect();
    assert!(
        imposed_kept >= 8,
        "frames meshed with their run's counts: {imposed_kept}"
    );
    assert!(
        own_differ >= 1,
        "frames whose own counts differ from their run's: {own_differ}"
    );
    assert!(
        starts.len() >= 2,
        "new runs after a meshed frame: {starts:?}"
    );
    assert!(
        unapplied_own >= 2,
        "attempts that were the own mesh: {unapplied_own}"
    );
    assert!(!want[10].ok && want[11].ok && want[12].node_counts_from_frame == Some(11));
    settle_as_the_rule(&text, &want);
}

/// Thirty bubbles jittered by up to 8% of their radius per frame: the combinatorics change at
/// most frames, so the attempts of a wave's frames after a change (made with the counts of a
/// run that ended) are reused as those frames' own meshes where the new run's counts could not
/// apply to them; settled as the rule says on 1, 2 and 3 threads.
#[test]
fn changing_layouts_settle_as_the_sequential_rule() {
    let mut d = medial_blocks::layouts::bubbles(30, 4).unwrap();
    let mut rng = common::XorShift(0x9e37_79b9_7f4a_7c15);
    let mut lines = Vec::new();
    for _ in 0..8 {
        lines.push(d.to_json_string());
        let holes: Vec<_> = d
            .holes()
            .iter()
            .map(|h| {
                let a = std::f64::consts::TAU * rng.unit();
                let s = 0.08 * h.radius * rng.unit();
                medial_blocks::Circle::new(
                    h.center[0] + s * a.cos(),
                    h.center[1] + s * a.sin(),
                    h.radius,
                )
            })
            .collect();
        match medial_blocks::Domain::bounded(d.bounding(), holes) {
            Ok(next) => d = next,
            Err(_) => break,
        }
    }
    let text = lines.join("\n");
    let opts = Options {
        cells: 6,
        ..Options::default()
    };
    let (want, _, _, unapplied_own) = sequential_rule(&text, &opts);
    let starts = (1..want.len())
        .filter(|&k| want[k].node_counts_from_frame.is_none() && !want[k].counts_not_kept)
        .count();
    assert!(starts >= 3, "changes of combinatorics: {starts}");
    assert!(
        unapplied_own >= 3,
        "attempts that were the own mesh: {unapplied_own}"
    );
    settle_as_the_rule(&text, &want);
}

/// The three holes of [`periodic_frames`] (the first two moving by `step` per frame), the
/// whole layout also drifting by `(0.15, -0.12)` per frame from `(3.2, 2.6)`, with every
/// centre wrapped into the 4 x 3 box, as a particle code writes them: holes cross the box's
/// edges from one frame to the next.
fn periodic_crossing_frames(n: usize, step: f64) -> String {
    let size = [4.0, 3.0];
    let holes = |k: usize| {
        let (x, d) = (
            step * k as f64,
            [3.2 + 0.15 * k as f64, 2.6 - 0.12 * k as f64],
        );
        [
            ([0.5 + x, 0.5], 0.6),
            ([2.2, 1.9 - x], 0.8),
            ([3.4, 0.2], 0.3),
        ]
        .map(|(c, r)| ([0, 1].map(|a| (c[a] + d[a]).rem_euclid(size[a])), r))
    };
    (0..n)
        .map(|k| {
            let hs: Vec<String> = holes(k)
                .iter()
                .map(|(c, r)| format!(r#"{{"center": [{}, {}], "radius": {r}}}"#, c[0], c[1]))
                .collect();
            format!(
                r#"{{"periodic": {{"size": [4, 3]}}, "holes": [{}]}}"#,
                hs.join(", ")
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// A hole crossing the box's edge is the same hole on the torus: the run goes on (tags are
/// counted from nearest copies, `exact_mode::imposed::nearest_copy`). Before, every crossing
/// ended the run and the frame got its own node counts.
#[test]
fn periodic_holes_crossing_the_box_edges_keep_blocks_and_node_counts() {
    let n = 6;
    let text = periodic_crossing_frames(n, 0.01);
    // The frames really wrap: some centre jumps by more than half the box between frames.
    let frames = parse_frames(&text);
    let centres = |k: usize| match frames[k].as_ref().unwrap() {
        AnyDomain::Periodic(p) => p.holes().iter().map(|c| c.center).collect::<Vec<_>>(),
        AnyDomain::Bounded(_) => unreachable!(),
    };
    let jumps = (1..n)
        .filter(|&k| {
            centres(k)
                .iter()
                .zip(centres(k - 1))
                .any(|(a, b)| (a[0] - b[0]).abs() > 2.0 || (a[1] - b[1]).abs() > 1.5)
        })
        .count();
    assert!(jumps >= 2, "{jumps} frames with a hole across an edge");
    check_run(&text, n);
}

/// `n` bubbles of `layouts::periodic_bubbles(n, seed)` rescaled into an 8 x 6 box with
/// centres on a 1/64 grid (radii 0.6 of theirs, so no two meet), moved by `d` and wrapped
/// into the box: as JSON. Moves by multiples of 1/8 are exact in floating point, so every
/// such move is the same layout on the torus.
fn moved_bubbles(n: usize, seed: u64, d: [f64; 2]) -> String {
    let base = medial_blocks::layouts::periodic_bubbles(n, seed).unwrap();
    let [lx, ly] = base.size();
    let snap = |v: f64| (v * 64.0).round() / 64.0;
    let hs: Vec<String> = base
        .holes()
        .iter()
        .map(|c| {
            let x = (snap(c.center[0] * 8.0 / lx) + d[0]).rem_euclid(8.0);
            let y = (snap(c.center[1] * 6.0 / ly) + d[1]).rem_euclid(6.0);
            format!(r#"{{"center": [{x}, {y}], "radius": {}}}"#, c.radius * 0.6)
        })
        .collect();
    format!(
        r#"{{"periodic": {{"size": [8, 6]}}, "holes": [{}]}}"#,
        hs.join(", ")
    )
}

/// The frame of `text` (one domain) meshed as a sequence frame, with 6 cells.
fn frame_of(text: &str) -> medial_blocks::sequence::FrameMesh {
    let opts = Options {
        cells: 6,
        ..Options::default()
    };
    let f = parse_frames(text);
    mesh_frame(f[0].as_ref().unwrap(), &opts).unwrap()
}

/// The combinatorics and block keys of a periodic frame do not depend on which copy of each
/// hole the box holds: the same layout moved by whole and partial periods (centres wrapped
/// into the box, so holes cross its edges) has the same triples and keys.
#[test]
fn periodic_combinatorics_do_not_depend_on_the_copies_in_the_box() {
    let first = frame_of(&moved_bubbles(12, 5, [0.0, 0.0]));
    let keys = first.keys.clone().expect("exact mode keys");
    assert!(!first.combinatorics.is_empty());
    for d in [
        [4.0, 0.0],
        [0.0, 3.0],
        [2.5, 1.125],
        [-3.75, 5.5],
        [7.875, -0.25],
    ] {
        let m = frame_of(&moved_bubbles(12, 5, d));
        assert_eq!(m.combinatorics, first.combinatorics, "moved by {d:?}");
        assert_eq!(m.keys.as_ref(), Some(&keys), "moved by {d:?}");
        assert_eq!(m.mesh.grids.len(), first.mesh.grids.len());
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 16, ..Default::default() })]
    /// As above, on other layouts and moves (in eighths of a unit, so exact).
    #[test]
    fn periodic_keys_are_the_same_for_every_move_of_the_box(
        n in 3usize..14,
        seed in 0u64..1000,
        dx in -64i32..64,
        dy in -48i32..48,
    ) {
        let d = [dx as f64 / 8.0, dy as f64 / 8.0];
        let first = frame_of(&moved_bubbles(n, seed, [0.0, 0.0]));
        let m = frame_of(&moved_bubbles(n, seed, d));
        proptest::prop_assert_eq!(&m.combinatorics, &first.combinatorics);
        proptest::prop_assert_eq!(&m.keys, &first.keys);
    }
}
