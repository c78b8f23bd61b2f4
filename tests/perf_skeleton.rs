//! Exact mode's layout skeleton built in parallel (`skeleton_layout_par`, issue #8) against
//! the one loop over the pieces it replaces at scale: the same vertices, edges (numbered in
//! first-use order), blocks and medial edges, on one thread and on several, for layouts
//! whose pieces cut into several parallel parts (more than 2 048 pieces), co-circular groups
//! (vertices with many spokes) and small ones.

use medial_blocks::blocking::collapsed_blocking_excluding;
use medial_blocks::exact_mode::skeletons_agree;
use medial_blocks::layouts;
use medial_blocks::mesher::Options;
use medial_blocks::sampling::SamplingOptions;
use medial_blocks::Domain;

fn agree_on(d: &Domain, what: &str) {
    let s = SamplingOptions {
        soft_rounds: false,
        ..SamplingOptions::default()
    };
    let cb = collapsed_blocking_excluding(d, &Options::default(), &s, false, &[]).unwrap();
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert!(
            pool.install(|| skeletons_agree(&cb)).unwrap(),
            "{what}, {threads} threads"
        );
    }
}

#[test]
fn parallel_skeleton_is_the_serial_one() {
    agree_on(&layouts::bubbles(1500, 5).unwrap(), "1 500 bubbles");
    agree_on(&layouts::bubbles(60, 2).unwrap(), "60 bubbles");
    agree_on(&Domain::hexagon_example(), "hexagon example");
    agree_on(&layouts::lattice().unwrap(), "lattice");
    agree_on(&layouts::square_lattice(8).unwrap(), "8 x 8 square lattice");
}
