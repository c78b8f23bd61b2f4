//! `mesh`, `mesh_periodic` and `Report::from_mesh` move their work onto a rayon worker when
//! called from outside the pool (issue 8, `timings::on_pool_worker`). The mesh must not
//! depend on where the call comes from: a plain thread, a worker of the global pool, a
//! one-thread and a three-thread pool of the caller's own. `mesh_timed` from a plain thread
//! still records the stages that ran on the worker.

use crate::common;
use medial_blocks::mesher::mesh_timed;

use medial_blocks::output::report::Report;
use medial_blocks::periodic::{mesh_periodic, PeriodicDomain};
use medial_blocks::{layouts, mesh, Circle, Mesh, Options};

/// The block corners and every node's bits: equal exactly when the meshes are.
fn fingerprint(m: &Mesh) -> (Vec<[u32; 4]>, Vec<u64>) {
    let corners = m.layout.blocks.iter().map(|b| b.corners).collect();
    (corners, common::node_bits(m))
}

/// `f` from a plain thread, a global worker, and pools of one and three threads.
fn from_everywhere<T: Send>(f: impl Fn() -> T + Sync) -> Vec<T> {
    let plain = std::thread::scope(|s| s.spawn(&f).join().unwrap());
    let global = rayon::scope(|_| f());
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(&f)
    };
    vec![plain, global, pool(1), pool(3)]
}

#[test]
fn bounded_meshes_and_reports_do_not_depend_on_the_calling_thread() {
    let _turn = common::turn();
    let domain = layouts::bubbles(300, 5).unwrap();
    let options = Options {
        block_cells: Some(8),
        ..Options::default()
    };
    let runs = from_everywhere(|| {
        let m = mesh(&domain, &options).unwrap();
        let r = serde_json::to_string(&Report::from_mesh(&m)).unwrap();
        (fingerprint(&m), r)
    });
    assert!(runs[0].0 .0.len() > 1000, "a real layout");
    for r in &runs[1..] {
        assert!(r.0 == runs[0].0, "the same mesh from every thread");
        assert_eq!(r.1, runs[0].1, "the same report from every thread");
    }
}

#[test]
fn periodic_meshes_do_not_depend_on_the_calling_thread() {
    let _turn = common::turn();
    let holes = vec![
        Circle::new(0.3, 0.3, 0.12),
        Circle::new(0.75, 0.35, 0.1),
        Circle::new(0.5, 0.8, 0.15),
    ];
    let pd = PeriodicDomain::new([1.0, 1.0], holes).unwrap();
    let runs = from_everywhere(|| fingerprint(&mesh_periodic(&pd, &Options::default()).unwrap()));
    assert!(!runs[0].0.is_empty());
    for r in &runs[1..] {
        assert!(*r == runs[0]);
    }
}

/// Called from a plain thread, the stages run on a worker but are recorded for the caller,
/// in the same numbers as from inside the pool.
#[test]
fn mesh_timed_records_the_stages_that_ran_on_the_worker() {
    let _turn = common::turn();
    let domain = layouts::lattice().unwrap();
    let calls = |t: &medial_blocks::timings::Timings| {
        let mut c = t.calls.clone();
        c.sort();
        c
    };
    let outside = std::thread::spawn(move || {
        let (m, t) = mesh_timed(&domain, &Options::default()).unwrap();
        (m.layout.blocks.len(), calls(&t), t.total_seconds)
    })
    .join()
    .unwrap();
    let domain = layouts::lattice().unwrap();
    let inside = rayon::scope(|_| {
        let (m, t) = mesh_timed(&domain, &Options::default()).unwrap();
        (m.layout.blocks.len(), calls(&t))
    });
    let names: Vec<&str> = outside.1.iter().map(|(n, _)| n.as_str()).collect();
    for stage in [
        "sampling",
        "triangulation",
        "blocking",
        "exact_geometry",
        "grids",
    ] {
        assert!(names.contains(&stage), "{stage} recorded: {names:?}");
    }
    assert_eq!(outside.0, inside.0);
    assert_eq!(outside.1, inside.1, "the same stages, entered as often");
    assert!(outside.2 > 0.0);
}
