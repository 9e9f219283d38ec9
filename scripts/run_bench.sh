#!/usr/bin/env bash
# Builds everything (cached) and runs the benchmarks: the core's, then the
# cost of the command per stage and path (run_cost_bench.sh). They print
# figures and never fail on speed. Extra arguments go to the core benchmark.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
build_dir="$(build_tree)"
for bench in "$build_dir"/benchmarks/*_bench; do
  stage "$(basename "$bench")" "$bench" "$@"
done
stage cost bash "$DPSFM_ROOT/scripts/run_cost_bench.sh"
