//! Meshes made without keeping their nodes (`Options::keep_nodes` false, issue 8: the grids
//! measured as they are made, their nodes dropped) against the same meshes with their nodes:
//! the same layout, block dimensions and report, bit for bit, on layouts of every kind the
//! exact mesher meets (size-driven and fixed counts, clustering, collapses, co-circular
//! lattices, inserted holes and their templates) and on those that must keep their nodes
//! (smoothing, one hole, paper mode, transitions), periodic boxes likewise; the CLI's `--format json` (which asks for no
//! nodes) against `--format json,svg` (which keeps them).

use crate::common;

use medial_blocks::connectivity::connectivity;
use medial_blocks::exact_mode::Clustering;
use medial_blocks::output::report::Report;
use medial_blocks::{layouts, mesh, Domain, Mesh, Options};
use proptest::prelude::*;

fn dropping(options: &Options) -> Options {
    Options {
        keep_nodes: false,
        ..options.clone()
    }
}

fn report_json(m: &Mesh) -> String {
    serde_json::to_string(&Report::from_mesh(m)).expect("report serialises")
}

/// Mesh `domain` with and without the nodes; the measured mesh must have dropped them
/// exactly when `drops` (and then hold one measurement per block). Returns whether the
/// meshes had a block.
fn check(domain: &Domain, options: &Options, drops: bool) -> bool {
    let kept = mesh(domain, options).expect("mesh with nodes");
    let measured = mesh(domain, &dropping(options)).expect("mesh without nodes");
    assert!(
        kept.measured.is_none(),
        "a mesh with its nodes has no measurement"
    );
    assert_eq!(measured.layout, kept.layout, "the same layout");
    let dims = |m: &Mesh| m.grids.iter().map(|g| (g.ni, g.nj)).collect::<Vec<_>>();
    assert_eq!(dims(&measured), dims(&kept), "the same block dimensions");
    assert_eq!(measured.geometry, kept.geometry);
    assert_eq!(measured.collapsed_arcs, kept.collapsed_arcs);
    assert_eq!(measured.inserted_holes, kept.inserted_holes);
    match &measured.measured {
        Some(m) => {
            assert!(drops, "nodes dropped where they must be kept");
            assert_eq!(m.blocks(), kept.grids.len());
            assert!(measured.grids.iter().all(|g| g.nodes.is_empty()));
        }
        None => {
            assert!(!drops, "nodes kept where they could be dropped");
            assert_eq!(common::node_bits(&measured), common::node_bits(&kept));
        }
    }
    // The report (every figure, the growth ratios across interfaces and the wall
    // orthogonality among them) and the block connectivity, from the dimensions alone.
    assert_eq!(report_json(&measured), report_json(&kept));
    assert_eq!(
        connectivity(&measured.layout, &measured.grids),
        connectivity(&kept.layout, &kept.grids)
    );
    !kept.grids.is_empty()
}

#[test]
fn measured_meshes_report_what_their_nodes_would() {
    let fixed = |n| Options {
        block_cells: Some(n),
        ..Options::default()
    };
    let clustered = Options {
        clustering: Clustering {
            first: Some(medial_blocks::exact_mode::FirstCell::Relative(1e-3)),
            growth: 1.05,
        },
        ..Options::default()
    };
    let collapsing = Options {
        collapse_fraction: 0.5,
        ..Options::default()
    };
    let unrefined = Options {
        refine_ratio: None,
        ..Options::default()
    };
    // A low ratio inserts holes: their templates' blocks are measured after the medial ones
    // (whose nodes on the holes' arcs are kept until the templates are made).
    let refined = Options {
        refine_ratio: Some(0.6),
        ..Options::default()
    };
    let exact = |m: &Mesh| m.geometry == medial_blocks::mesh::Geometry::Exact;
    let mut templates = 0;
    for (n, seed) in [(2, 1), (3, 2), (10, 3), (40, 4), (150, 5), (400, 6)] {
        let d = layouts::bubbles(n, seed).expect("layout");
        for o in [
            &Options::default(),
            &fixed(16),
            &fixed(4),
            &clustered,
            &collapsing,
            &unrefined,
            &refined,
        ] {
            let m = mesh(&d, o).expect("mesh");
            templates += m.template_blocks;
            assert!(check(&d, o, exact(&m)));
        }
    }
    // Co-circular lattices (collapsed zero-length arcs) and the built-in examples.
    for d in [
        layouts::square_lattice(4).expect("lattice"),
        layouts::lattice().expect("lattice"),
        layouts::hexagon(),
        Domain::hexagon_example(),
    ] {
        for o in [&Options::default(), &fixed(8), &refined] {
            let m = mesh(&d, o).expect("mesh");
            templates += m.template_blocks;
            assert!(check(&d, o, exact(&m)));
        }
    }
    assert!(
        templates > 100,
        "{templates} template blocks: too few to tell"
    );
}

#[test]
fn meshes_that_need_their_nodes_keep_them() {
    let d = layouts::bubbles(60, 7).expect("layout");
    // Smoothing moves the nodes after they are made; paper mode has no measured pass.
    check(
        &d,
        &Options {
            smooth: 3,
            ..Options::default()
        },
        false,
    );
    check(&d, &Options::paper(), false);
    // One hole (the ring is measured against a seeded mesh), none.
    let one = Domain::bounded(
        medial_blocks::Circle::new(0.0, 0.0, 1.0),
        vec![medial_blocks::Circle::new(0.3, 0.1, 0.2)],
    )
    .expect("domain");
    check(&one, &Options::default(), false);
    let none = Domain::bounded(medial_blocks::Circle::new(0.0, 0.0, 1.0), vec![]).expect("domain");
    check(&none, &Options::default(), false);
    // Transition rings and periodic boxes join nodes: kept whatever was asked.
    let t =
        medial_blocks::transition::mesh_with_transition(&d, &dropping(&Options::default()), 0.05)
            .expect("transition");
    assert!(t.measured.is_none() && t.grids.iter().all(|g| !g.nodes.is_empty()));
}

/// Periodic boxes measured as their grids are made: the same layout, dimensions and report
/// (interfaces across the box's edges among the growth ratios), with inserted holes too.
#[test]
fn periodic_boxes_measured_report_what_their_nodes_would() {
    use medial_blocks::{mesh_periodic, PeriodicDomain};
    let two = PeriodicDomain::new(
        [2.0, 1.0],
        vec![
            medial_blocks::Circle::new(0.1, 0.1, 0.2),
            medial_blocks::Circle::new(1.2, 0.6, 0.25),
        ],
    )
    .expect("periodic");
    let mut boxes = vec![two];
    for (n, seed) in [(30, 1), (120, 2), (300, 3)] {
        boxes.push(layouts::periodic_bubbles(n, seed).expect("periodic layout"));
    }
    let mut templates = 0;
    for pd in &boxes {
        for o in [
            Options::default(),
            Options {
                block_cells: Some(16),
                ..Options::default()
            },
            Options {
                refine_ratio: Some(0.7),
                ..Options::default()
            },
            Options {
                smooth: 2,
                ..Options::default()
            },
        ] {
            let kept = mesh_periodic(pd, &o).expect("periodic mesh");
            let measured = mesh_periodic(pd, &dropping(&o)).expect("periodic mesh");
            templates += kept.template_blocks;
            let drops = o.smooth == 0 && kept.geometry == medial_blocks::mesh::Geometry::Exact;
            assert_eq!(measured.measured.is_some(), drops);
            assert_eq!(measured.layout, kept.layout);
            let dims = |m: &Mesh| m.grids.iter().map(|g| (g.ni, g.nj)).collect::<Vec<_>>();
            assert_eq!(dims(&measured), dims(&kept));
            if drops {
                assert!(measured.grids.iter().all(|g| g.nodes.is_empty()));
            }
            assert_eq!(report_json(&measured), report_json(&kept));
        }
    }
    assert!(templates > 0, "no inserted hole: too few to tell");
}

/// A mesh without nodes writes its json files (the same as with its nodes) and refuses every
/// writer of grids with an error that says why, rather than writing empty or wrong files.
#[test]
fn writers_of_grids_refuse_a_mesh_without_nodes() {
    use medial_blocks::output::{plot3d, vtk, write_files, Format};
    let d = layouts::bubbles(30, 2).expect("layout");
    let kept = mesh(&d, &Options::default()).expect("mesh");
    let measured = mesh(&d, &dropping(&Options::default())).expect("mesh");
    assert!(measured.measured.is_some());
    let dir = tempfile::tempdir().expect("temp dir");
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    write_files(&kept, &a, &[Format::Json]).expect("json with nodes");
    write_files(&measured, &b, &[Format::Json]).expect("json without nodes");
    assert_eq!(common::tree(&a), common::tree(&b));
    let says = |e: std::io::Error| {
        assert!(e.to_string().contains("keep_nodes"), "{e}");
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput, "{e}");
    };
    for &f in Format::ALL.iter().filter(|&&f| f != Format::Json) {
        let out = dir.path().join(f.name());
        says(write_files(&measured, &out, &[f]).expect_err("refused"));
        assert!(!out.join("report.json").exists());
    }
    let xyz = dir.path().join("mesh.xyz");
    says(plot3d::write_binary(&measured.grids, &xyz).expect_err("refused"));
    says(plot3d::write_ascii(&measured.grids, &xyz).expect_err("refused"));
    let mut sink = Vec::new();
    says(vtk::write_vts(&mut sink, 0, &measured.grids[0]).expect_err("refused"));
}

/// The measured report does not depend on the thread count either.
#[test]
fn measured_reports_are_the_same_for_every_thread_count() {
    let d = layouts::bubbles(300, 11).expect("layout");
    let o = dropping(&Options {
        block_cells: Some(16),
        ..Options::default()
    });
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| report_json(&mesh(&d, &o).expect("mesh")))
    };
    let one = on(1);
    assert_eq!(on(2), one);
    assert_eq!(on(3), one);
}

/// `--format json` (no writer reads a node: the CLI asks for none) writes the same
/// report.json and connectivity.json as `--format json,svg` (the SVG writer reads them), for
/// bounded and periodic layouts.
#[test]
fn cli_json_alone_writes_what_it_writes_beside_a_node_writer() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut runs = Vec::new();
    for kind in ["bubbles", "periodic-bubbles"] {
        let input = dir.path().join(format!("{kind}.json"));
        let input = input.to_str().expect("utf-8").to_string();
        let out = common::run(&[
            "example", kind, "--holes", "200", "--seed", "5", "-o", &input,
        ]);
        assert!(out.status.success());
        for extra in [
            &[][..],
            &["--block-cells", "16"][..],
            &["--first-height-rel", "1e-3"][..],
        ] {
            runs.push((input.clone(), extra));
        }
    }
    for (input, extra) in runs {
        let input = input.as_str();
        let alone = dir.path().join("alone");
        let beside = dir.path().join("beside");
        for (o, format) in [(&alone, "json"), (&beside, "json,svg")] {
            let mut args = vec!["--quiet", "mesh", input, "-o", o.to_str().expect("utf-8")];
            args.extend_from_slice(&["--format", format]);
            args.extend_from_slice(extra);
            let run = common::run(&args);
            assert!(
                run.status.success(),
                "{}",
                String::from_utf8_lossy(&run.stderr)
            );
        }
        for f in ["report.json", "connectivity.json"] {
            let a = std::fs::read(alone.join(f)).expect("written");
            let b = std::fs::read(beside.join(f)).expect("written");
            assert!(a == b, "{f} differs for {input} with {extra:?}");
        }
    }
}

/// `Options::exits_after_mesh` (the CLI's: the working memory of the attempt that gave the
/// mesh is never freed) changes nothing in the mesh: the same layout, nodes and report as the
/// default, with and without nodes, on bounded layouts (one of them resampled after its first
/// attempt, whose working memory is still freed) and on periodic boxes (one resampled, one fixed
/// on its sampling).
#[test]
fn leaving_working_memory_to_the_exit_gives_the_same_mesh() {
    use medial_blocks::mesher::mesh_timed;
    use medial_blocks::{mesh_periodic, timings};
    let _turn = common::turn();
    let same = |a: &Mesh, b: &Mesh| {
        assert_eq!(a.layout, b.layout);
        assert_eq!(common::node_bits(a), common::node_bits(b));
        assert_eq!(report_json(a), report_json(b));
        assert_eq!(a.inserted_holes, b.inserted_holes);
        assert_eq!(a.geometry, b.geometry);
    };
    let exiting = |o: &Options| Options {
        exits_after_mesh: true,
        ..o.clone()
    };
    let bounded = [
        Domain::from_json_str(include_str!("data/inserted_narrow_arc.json")).expect("layout"),
        Domain::from_json_str(include_str!("data/mixed_sizes_sharp_corner_a.json"))
            .expect("layout"),
        layouts::bubbles(80, 11).expect("layout"),
    ];
    let mut resampled = 0;
    for d in &bounded {
        for o in [
            Options::default(),
            Options {
                block_cells: Some(4),
                keep_nodes: false,
                ..Options::default()
            },
        ] {
            let (freed, t) = mesh_timed(d, &o).expect("mesh");
            let (kept, u) = mesh_timed(d, &exiting(&o)).expect("mesh");
            same(&freed, &kept);
            assert_eq!(t.calls, u.calls, "the same attempts");
            // One `blocking` span per attempt.
            let attempts = t
                .calls
                .iter()
                .find(|(s, _)| s == "blocking")
                .map_or(0, |c| c.1);
            resampled += usize::from(attempts > 1);
        }
    }
    assert!(resampled > 0, "no bounded layout took a second attempt");
    for json in [
        include_str!("data/periodic_resampled_60.json"),
        include_str!("data/periodic_backwards_100.json"),
    ] {
        let pd = match medial_blocks::AnyDomain::from_json_str(json).expect("layout") {
            medial_blocks::AnyDomain::Periodic(pd) => pd,
            other => panic!("not a periodic domain: {other:?}"),
        };
        let o = Options {
            block_cells: Some(4),
            ..Options::default()
        };
        let rec = timings::Recording::start();
        let freed = mesh_periodic(&pd, &o).expect("mesh");
        let t = rec.finish();
        let rec = timings::Recording::start();
        let kept = mesh_periodic(&pd, &exiting(&o)).expect("mesh");
        let u = rec.finish();
        same(&freed, &kept);
        assert_eq!(t.calls, u.calls, "the same attempts");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Random bubble layouts, fixed and size-driven counts, with and without inserted holes.
    #[test]
    fn measured_reports_equal_on_random_layouts(
        n in 2usize..120,
        seed in 0u64..1_000_000,
        cells in prop_oneof![Just(None), Just(Some(3usize)), Just(Some(16))],
        ratio in prop_oneof![Just(2.0), Just(0.7)],
    ) {
        let d = layouts::bubbles(n, seed).expect("layout");
        let o = Options { block_cells: cells, refine_ratio: Some(ratio), ..Options::default() };
        let m = mesh(&d, &o).expect("mesh");
        check(&d, &o, m.geometry == medial_blocks::mesh::Geometry::Exact);
    }
}
