#!/usr/bin/env bash
# make's one step to CMake: configures and builds a cached build tree.
# Usage: build.sh BUILD_DIR [CMAKE_ARGS...]
# What is built (the COLMAP release: fetched, verified and patched by CMake,
# cmake/ColmapRelease.cmake) is all in CMAKE_ARGS; this script adds only what
# CMake cannot do itself:
#  - one build at a time per tree (a lock beside it: two clones building at
#    once would race);
#  - the tree reaches the clone through a symlink (BUILD_DIR/.source), so
#    whichever clone builds, CMake sees one source path and only what
#    changed is recompiled (ccache, set up by the Makefile, does the rest;
#    point_source in common.sh says what happens when the clone changes);
#  - CMake's own output goes to BUILD_DIR/configure.log, shown on failure.
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: build.sh BUILD_DIR [CMAKE_ARGS...]" >&2; exit 2; }
build_dir="$1"; shift
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
root="$DPSFM_ROOT"

mkdir -p "$build_dir"
exec 9>"$build_dir.lock"
if ! flock -n 9; then
  log "waiting for another build in $build_dir"
  flock 9
fi
point_source "$build_dir"
# A link in the clone to its build, for convenience (ignored by git).
ln -sfn "$build_dir" "$root/build"

start=$SECONDS
if ! cmake -S "$build_dir/.source" -B "$build_dir" -G Ninja "$@" \
       >"$build_dir/configure.log" 2>&1; then
  grep -v '^-- ' "$build_dir/configure.log" | tail -n 30 >&2
  log "error: CMake configuration failed (log: $build_dir/configure.log)"
  exit 1
fi
grep '^-- dp-sfm: ' "$build_dir/configure.log" | sed 's/^-- /[/; s/: /] /' >&2 || true
log "configured in $((SECONDS - start)) s; building $build_dir"
start=$SECONDS
cmake --build "$build_dir" -j "${DPSFM_JOBS:-$(nproc)}"
log "built in $((SECONDS - start)) s"
