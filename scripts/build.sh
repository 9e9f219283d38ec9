#!/usr/bin/env bash
# Builds COLMAP (DPSFM_COLMAP_VERSION: 4.1.1 by default, or 3.10) with the
# dp-sfm plugin in one CMake tree and prints the build directory. COLMAP 4's
# PoseLib is built first, into its own cache entry (build_poselib.sh). The
# build directory is cached outside the clone, keyed by
# COLMAP version + patch series + build options, so a fresh clone on the same
# machine reuses it and COLMAP is not rebuilt. The build tree reaches the
# clone through a symlink (<build>/.source), so whichever clone runs the
# build, CMake sees one source path and only the plugin is recompiled.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
stdout_is_result

stage "install dependencies" "$DPSFM_ROOT/scripts/install_deps.sh"

prefix_path=()
if [ -n "$POSELIB_REVISION" ]; then
  start=$SECONDS
  log "stage 'PoseLib' ..."
  poselib_prefix="$("$DPSFM_ROOT/scripts/build_poselib.sh")"
  log "stage 'PoseLib' took $((SECONDS - start)) s ($poselib_prefix)"
  prefix_path=(-DCMAKE_PREFIX_PATH="$poselib_prefix")
fi

start=$SECONDS
log "stage 'fetch COLMAP source' ..."
colmap_source="$("$DPSFM_ROOT/scripts/fetch_colmap.sh")"
log "stage 'fetch COLMAP source' took $((SECONDS - start)) s ($colmap_source)"

build_key="$("$DPSFM_ROOT/scripts/cache_key.sh" "$DPSFM_ROOT/colmap_patches" build)"
build_dir="$DPSFM_CACHE_DIR/build/colmap-$COLMAP_VERSION-$build_key"
mkdir -p "$build_dir"

# One build at a time per tree (two clones building at once would race).
exec 9>"$build_dir.lock"
if ! flock -n 9; then
  log "waiting for another build in $build_dir"
  flock 9
fi

ln -sfn "$DPSFM_ROOT" "$build_dir/.source"
# A link in the clone to the build, for convenience (ignored by git).
ln -sfn "$build_dir" "$DPSFM_ROOT/build"

configure() {
  cmake -S "$build_dir/.source" -B "$build_dir" -G Ninja \
    -DCMAKE_BUILD_TYPE="$DPSFM_BUILD_TYPE" \
    -DCOLMAP_SOURCE_DIR="$colmap_source" \
    "${DPSFM_COLMAP_OPTIONS[@]}" "${prefix_path[@]}" >"$build_dir/configure.log" 2>&1 \
    || { tail -n 40 "$build_dir/configure.log" >&2; die "CMake configuration failed (log: $build_dir/configure.log)"; }
}
if [ ! -f "$build_dir/build.ninja" ]; then
  stage "configure" configure
fi

ccache --zero-stats >/dev/null 2>&1 || true
stage "build" cmake --build "$build_dir" -j "$(jobs_count)"
# The programs a user runs, in one folder (docs/user-guide.md puts it on
# PATH): COLMAP with the plugin's commands, and the capture-to-workspace tool.
mkdir -p "$build_dir/bin"
ln -sfn ../colmap/src/colmap/exe/colmap "$build_dir/bin/colmap"
ln -sfn ../examples/dpsfm_make_realdp_workspace \
  "$build_dir/bin/dpsfm_make_realdp_workspace"
ccache --show-stats 2>/dev/null | grep -E "Hits|Misses|hit rate" | head -n 3 | sed 's/^/[dp-sfm] ccache: /' >&2 || true
result "$build_dir"
