# Helpers for the scripts make runs (the build, examples, benchmarks,
# the installed route). Source it; do not run it. The build itself is
# make -> scripts/build.sh -> CMake; its settings (the COLMAP release, the
# cache, ccache) come from the Makefile's exported variables.

set -euo pipefail

DPSFM_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
DPSFM_CACHE_DIR="${DPSFM_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/dp-sfm}"
DPSFM_COLMAP_VERSION="${DPSFM_COLMAP_VERSION:-4.1.1}"

log() { printf '[dp-sfm] %s\n' "$*" >&2; }
die() { printf '[dp-sfm] error: %s\n' "$*" >&2; exit 1; }

# The build tree make built (DPSFM_BUILD_DIR), checked to be one.
build_tree() {
  local dir="${DPSFM_BUILD_DIR:-}"
  [ -n "$dir" ] || die "DPSFM_BUILD_DIR is not set: run this through make (make example, make bench, ...)"
  [ -f "$dir/CMakeCache.txt" ] || die "$dir is not a build directory: run make build first"
  printf '%s\n' "$dir"
}

# point_source BUILD_DIR: points BUILD_DIR/.source, the path through which
# a cached build tree reaches its sources, at this clone. When another clone
# built there last, the tree's own objects (plugin, tests, examples,
# benchmarks; COLMAP's come from its fetched sources) are removed first:
# ninja compares file times, and a file this clone changed before the other
# clone's build would look older than its object and not be compiled again.
# ccache brings back, by content, every object that did not change.
point_source() {
  local build_dir="$1" previous dir
  previous="$(readlink "$build_dir/.source" 2>/dev/null || true)"
  if [ -n "$previous" ] && [ "$previous" != "$DPSFM_ROOT" ]; then
    for dir in plugin tests examples benchmarks; do
      if [ -d "$build_dir/$dir" ]; then
        find "$build_dir/$dir" -name '*.o' -delete
      fi
    done
  fi
  ln -sfn "$DPSFM_ROOT" "$build_dir/.source"
}

# COLMAP 4 renamed options and added commands; 3.10 is the other build.
colmap_is_4() { [[ "$DPSFM_COLMAP_VERSION" != 3.* ]]; }

# stage NAME CMD...: runs CMD and prints how long it took.
stage() {
  local name="$1"; shift
  local start=$SECONDS
  log "stage '$name' ..."
  "$@"
  log "stage '$name' took $((SECONDS - start)) s"
}

# timed_dry_run COLMAP PREFIX WORKSPACE ARGS...: one dry run of `COLMAP
# dp_scale_estimator` on WORKSPACE (its dense/, dp/ and lens.csv) with ARGS;
# /usr/bin/time's wall, user and system seconds and peak RSS (KB) in
# PREFIX.time, the report in PREFIX.json, the log in PREFIX.log. A refusal
# is logged, not fatal: the benchmarks print it.
timed_dry_run() {
  local colmap="$1" prefix="$2" ws="$3"
  shift 3
  rm -f "$prefix.json"
  /usr/bin/time -f "%e %U %S %M" -o "$prefix.time" \
    "$colmap" dp_scale_estimator --workspace_path "$ws/dense" \
    --dp_image_path "$ws/dp" --lens_path "$ws/lens.csv" --dry_run 1 \
    --report_path "$prefix.json" "$@" >"$prefix.log" 2>&1 \
    || log "$(basename "$prefix"): $(tail -n 1 "$prefix.log")"
}

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

jobs_count() {
  local n
  n=$(nproc 2>/dev/null || echo 2)
  echo "${DPSFM_JOBS:-$n}"
}
