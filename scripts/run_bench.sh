#!/usr/bin/env bash
# Builds everything (cached) and runs the benchmarks. They print figures and
# never fail on speed. Extra arguments go to the core benchmark.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
build_dir="$(build_tree)"
for bench in "$build_dir"/benchmarks/*_bench; do
  stage "$(basename "$bench")" "$bench" "$@"
done
