//! Every integration test, in one binary (`cargo test --test suite`; one module per file of
//! `tests/`, named after it, so `cargo test --test suite perf_quality::` runs one file's
//! tests). One binary links the library once, where 99 binaries linked it 99 times: a fresh
//! `cargo test --no-run` 259 -> 201 s on the 2-core machine, target/debug 7.1 -> 2.3 GB, the
//! run 72 -> 53 s (thirty-eighth session; with the test profile's line tables, Cargo.toml).
//! A new test file needs its line here; helpers shared by the files are in [`common`]
//! (`use crate::common;`).

mod common;

#[path = "apollonius_exact.rs"]
mod apollonius_exact;

#[path = "apollonius_predicate.rs"]
mod apollonius_predicate;

#[path = "apollonius_solve.rs"]
mod apollonius_solve;

#[path = "back_grid.rs"]
mod back_grid;

#[path = "back_output.rs"]
mod back_output;

#[path = "degen_families.rs"]
mod degen_families;

#[path = "degen_output.rs"]
mod degen_output;

#[path = "degen_refine.rs"]
mod degen_refine;

#[path = "engine_cli.rs"]
mod engine_cli;

#[path = "engine_invariants.rs"]
mod engine_invariants;

#[path = "engine_predicates.rs"]
mod engine_predicates;

#[path = "engine_shuffle.rs"]
mod engine_shuffle;

#[path = "exactmode_attempts.rs"]
mod exactmode_attempts;

#[path = "exactmode_block_cells.rs"]
mod exactmode_block_cells;

#[path = "exactmode_cli.rs"]
mod exactmode_cli;

#[path = "exactmode_degenerate.rs"]
mod exactmode_degenerate;

#[path = "exactmode_interface_growth.rs"]
mod exactmode_interface_growth;

#[path = "exactmode_properties.rs"]
mod exactmode_properties;

#[path = "exactmode_quality.rs"]
mod exactmode_quality;

#[path = "exactmode_resolution.rs"]
mod exactmode_resolution;

#[path = "exactmode_sampling.rs"]
mod exactmode_sampling;

#[path = "formats_writers.rs"]
mod formats_writers;

#[path = "front_blocking.rs"]
mod front_blocking;

#[path = "front_domain.rs"]
mod front_domain;

#[path = "front_parallel.rs"]
mod front_parallel;

#[path = "front_sampling.rs"]
mod front_sampling;

#[path = "front_stress.rs"]
mod front_stress;

#[path = "fuzz_replay_mesh.rs"]
mod fuzz_replay_mesh;

#[path = "fuzz_replay_parse.rs"]
mod fuzz_replay_parse;

#[path = "fuzz_replay_periodic.rs"]
mod fuzz_replay_periodic;

#[path = "fuzz_replay_triangulate.rs"]
mod fuzz_replay_triangulate;

#[path = "geometry_renumbered.rs"]
mod geometry_renumbered;

#[path = "geometry_sparse_extend.rs"]
mod geometry_sparse_extend;

#[path = "output_binary.rs"]
mod output_binary;

#[path = "output_replace.rs"]
mod output_replace;

#[path = "perf_apollonius.rs"]
mod perf_apollonius;

#[path = "perf_apollonius_fast.rs"]
mod perf_apollonius_fast;

#[path = "perf_blocking.rs"]
mod perf_blocking;

#[path = "perf_blocks_parallel.rs"]
mod perf_blocks_parallel;

#[path = "perf_connectivity.rs"]
mod perf_connectivity;

#[path = "perf_connectivity_writer.rs"]
mod perf_connectivity_writer;

#[path = "perf_densities.rs"]
mod perf_densities;

#[path = "perf_equivalence.rs"]
mod perf_equivalence;

#[path = "perf_exact_cache.rs"]
mod perf_exact_cache;

#[path = "perf_front.rs"]
mod perf_front;

#[path = "perf_front_tri.rs"]
mod perf_front_tri;

#[path = "perf_grid_nodes.rs"]
mod perf_grid_nodes;

#[path = "perf_medial_parallel.rs"]
mod perf_medial_parallel;

#[path = "perf_measured.rs"]
mod perf_measured;

#[path = "perf_memory_classes.rs"]
mod perf_memory_classes;

#[path = "perf_memory_tri.rs"]
mod perf_memory_tri;

#[path = "perf_numbering.rs"]
mod perf_numbering;

#[path = "perf_options.rs"]
mod perf_options;

#[path = "perf_periodic.rs"]
mod perf_periodic;

#[path = "perf_pool_hop.rs"]
mod perf_pool_hop;

#[path = "perf_quality.rs"]
mod perf_quality;

#[path = "perf_quality_atan.rs"]
mod perf_quality_atan;

#[path = "perf_quality_corners.rs"]
mod perf_quality_corners;

#[path = "perf_resample.rs"]
mod perf_resample;

#[path = "perf_spatial_order.rs"]
mod perf_spatial_order;

#[path = "perf_rounding.rs"]
mod perf_rounding;

#[path = "perf_sampling_parallel.rs"]
mod perf_sampling_parallel;

#[path = "perf_scale.rs"]
mod perf_scale;

#[path = "perf_skeleton.rs"]
mod perf_skeleton;

#[path = "perf_text_numbers.rs"]
mod perf_text_numbers;

#[path = "perf_text_writers.rs"]
mod perf_text_writers;

#[path = "perf_triangulation.rs"]
mod perf_triangulation;

#[path = "perf_writer_memory.rs"]
mod perf_writer_memory;

#[path = "perf_writers.rs"]
mod perf_writers;

#[path = "periodic_cli.rs"]
mod periodic_cli;

#[path = "periodic_degenerate.rs"]
mod periodic_degenerate;

#[path = "periodic_elongated.rs"]
mod periodic_elongated;

#[path = "periodic_exact.rs"]
mod periodic_exact;

#[path = "periodic_mesh.rs"]
mod periodic_mesh;

#[path = "periodic_refine.rs"]
mod periodic_refine;

#[path = "pipeline_mesh.rs"]
mod pipeline_mesh;

#[path = "reliability_bad_input.rs"]
mod reliability_bad_input;

#[path = "reliability_determinism.rs"]
mod reliability_determinism;

#[path = "reliability_inserted.rs"]
mod reliability_inserted;

#[path = "reliability_numbering.rs"]
mod reliability_numbering;

#[path = "reliability_output.rs"]
mod reliability_output;

#[path = "reliability_readers.rs"]
mod reliability_readers;

#[path = "sequence_cli.rs"]
mod sequence_cli;

#[path = "sequence_counts.rs"]
mod sequence_counts;

#[path = "template_core.rs"]
mod template_core;

#[path = "transition_mesh.rs"]
mod transition_mesh;

#[path = "ux_affinity.rs"]
mod ux_affinity;

#[path = "ux_allocator.rs"]
mod ux_allocator;

#[path = "ux_cli.rs"]
mod ux_cli;

#[path = "ux_quality.rs"]
mod ux_quality;

#[path = "ux_writers.rs"]
mod ux_writers;

/// Every `tests/*.rs` file is a module of this binary: with `autotests = false` in Cargo.toml,
/// a file without its two lines above would never be compiled nor run.
#[test]
fn every_test_file_is_a_module_of_the_suite() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let suite = std::fs::read_to_string(dir.join("suite.rs")).unwrap();
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let stem = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or_default();
        if path.extension().is_some_and(|e| e == "rs") && stem != "suite" {
            let line = format!("#[path = \"{stem}.rs\"]\nmod {stem};\n");
            if !suite.contains(&line) {
                missing.push(stem.to_string());
            }
        }
    }
    missing.sort();
    assert!(
        missing.is_empty(),
        "tests/suite.rs declares no module for tests/{{{}}}.rs",
        missing.join(",")
    );
}
