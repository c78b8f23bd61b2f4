#!/usr/bin/env bash
# Run every cargo-fuzz target for SECONDS each on the nightly toolchain.
#
#   fuzz/run.sh SECONDS [TARGET...]      (from anywhere; default: every target)
#
# Installs cargo-fuzz if it is missing. The committed seeds in fuzz/corpus/TARGET/ are read;
# new corpus entries go to fuzz/work/corpus/TARGET/ (not committed: copy the small interesting
# ones into fuzz/corpus/TARGET/, which `cargo test` replays through tests/fuzz_replay_*.rs).
# Crashes go to fuzz/artifacts/TARGET/: turn each into a regression test (copy it into the
# corpus under a descriptive name, add a named test if the fix needs explaining), then fix.
# Exit status: 0 if every target ran clean, 1 if any target found a crash.
set -euo pipefail

if [ $# -lt 1 ] || ! [[ "$1" =~ ^[0-9]+$ ]]; then
    echo "usage: $0 SECONDS [TARGET...]" >&2
    exit 2
fi
seconds=$1
shift

cd "$(dirname "$0")/.."

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "cargo-fuzz not found: installing it (cargo install cargo-fuzz)" >&2
    cargo install cargo-fuzz
fi
if ! cargo +nightly --version >/dev/null 2>&1; then
    echo "the nightly toolchain is needed: rustup toolchain install nightly" >&2
    exit 2
fi

if [ $# -gt 0 ]; then
    targets=("$@")
else
    mapfile -t targets < <(cargo +nightly fuzz list)
fi

failed=()
for t in "${targets[@]}"; do
    mkdir -p "fuzz/corpus/$t" "fuzz/work/corpus/$t"
    echo "== fuzzing $t for ${seconds}s" >&2
    # -rss_limit_mb: the mesher may allocate a few hundred MB on a near-touching layout.
    if ! cargo +nightly fuzz run "$t" "fuzz/work/corpus/$t" "fuzz/corpus/$t" -- \
        -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=120 -print_final_stats=1; then
        failed+=("$t")
    fi
done

if [ ${#failed[@]} -gt 0 ]; then
    echo "crashes found in: ${failed[*]} (see fuzz/artifacts/)" >&2
    exit 1
fi
echo "every target ran ${seconds}s without a crash" >&2
