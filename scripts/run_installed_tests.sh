#!/usr/bin/env bash
# `make test-installed`: dp-sfm on the installed route, proved here.
#  1. COLMAP's libraries, headers and CMake package are installed from the
#     cached checkout build (make test's) into a prefix in the cache, without
#     its `colmap` executable (the patch series changes only that one), and
#     nothing in the prefix may know the dp-sfm commands.
#     COLMAP's release build fetched PoseLib (FETCH_POSELIB), so PoseLib is
#     installed with it.
#  2. dp-sfm is configured against that prefix alone (find_package(COLMAP),
#     no COLMAP_SOURCE_DIR) with the fetched sources (COLMAP's, PoseLib's)
#     and COLMAP's build tree hidden (a private mount namespace), and built:
#     `dpsfm`.
#     It is compiled with Clang (clang++-14), where make test's build uses
#     GCC, and with neither GPL library (-DDPSFM_WITH_FFTW=OFF
#     -DDPSFM_WITH_EXIV2=OFF: the permissive build, README "Licence").
#  3. Its unit tests (the `fast` label) run, then `dpsfm` is installed into
#     a prefix of its own and its end-to-end tests run: the dp-sfm commands
#     through `dpsfm`, COLMAP's own through the cached build's `colmap`
#     behind a wrapper that refuses the dp-sfm ones.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

colmap_is_4 || die "the installed route needs COLMAP 4 (not DPSFM_COLMAP_VERSION=$DPSFM_COLMAP_VERSION)"
total_start=$SECONDS
checkout_build="$(build_tree)"
# The fetched sources (COLMAP's, PoseLib's) and COLMAP's build tree.
fetched="$checkout_build/_deps"
[ -d "$fetched" ] || die "$checkout_build has no fetched sources (_deps): not a release build"

# 1. The installed COLMAP, keyed by the checkout build it comes from.
prefix="$DPSFM_CACHE_DIR/installed/$(basename "$checkout_build")"
install_colmap() {
  rm -rf "$prefix.part"
  cmake --install "$checkout_build/colmap" --prefix "$prefix.part" >"$prefix.install.log" \
    || die "installing COLMAP from $checkout_build failed (log: $prefix.install.log)"
  # The executable is the patched one: leave it out.
  rm -f "$prefix.part/bin/colmap"
  rmdir "$prefix.part/bin" 2>/dev/null || true
  [ -n "$(find "$prefix.part" -name 'PoseLibConfig.cmake' -print -quit)" ] \
    || die "PoseLib was not installed with COLMAP (log: $prefix.install.log)"
  local knows
  knows="$(grep -rl -e dp_scale_estimator -e dp_psf_calibrator "$prefix.part" || true)"
  [ -z "$knows" ] || die "the installed COLMAP knows the dp-sfm commands: $knows"
  rm -rf "$prefix"
  mv "$prefix.part" "$prefix"
}
mkdir -p "$DPSFM_CACHE_DIR/installed"
exec 8>"$prefix.lock"
flock 8
stage "install COLMAP $DPSFM_COLMAP_VERSION into $prefix" install_colmap
log "the installed COLMAP: $(grep -o 'COLMAP_VERSION [0-9.]*' "$prefix/share/colmap/colmap-config.cmake"), $(find "$prefix/lib" -name '*.a' | wc -l) libraries (PoseLib's among them), no executable; nothing in it knows dp_scale_estimator"

# 2. dp-sfm against it. The build tree reaches the clone through a symlink,
# as the checkout build does, so another clone reuses it.
build_dir="$DPSFM_CACHE_DIR/build/installed-clang-$(basename "$checkout_build")"
mkdir -p "$build_dir"
exec 9>"$build_dir.lock"
flock 9
point_source "$build_dir"

# The fetched sources and COLMAP's build tree out of reach: empty folders mounted over
# them for the configure and the build, in a private mount namespace (root,
# and a kernel or container that allows it; else the build.ninja check below
# alone).
empty="$DPSFM_CACHE_DIR/installed/.empty"
mkdir -p "$empty"
if [ "$(id -u)" -eq 0 ] && unshare --mount --propagation private \
     mount --bind "$empty" "$empty" 2>/dev/null; then
  hide=1
else
  hide=0
  log "cannot mount in a private namespace here: COLMAP's trees stay visible, and only the build's files are checked not to name them"
fi
hidden() {
  if [ "$hide" -eq 1 ]; then
    unshare --mount --propagation private bash -c '
      set -e; empty="$1"; shift
      mount --bind "$empty" "$1"; mount --bind "$empty" "$2"; shift 2
      exec "$@"' _ "$empty" "$fetched" "$checkout_build/colmap" "$@"
  else
    "$@"
  fi
}
command -v clang++-14 >/dev/null || die "clang++-14 is missing (make deps installs it)"
configure() {
  hidden cmake -S "$build_dir/.source" -B "$build_dir" -G Ninja \
    -DCMAKE_BUILD_TYPE="$DPSFM_BUILD_TYPE" \
    -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
    -DDPSFM_WITH_FFTW=OFF -DDPSFM_WITH_EXIV2=OFF \
    -DCMAKE_PREFIX_PATH="$prefix" \
    -DDPSFM_TEST_COLMAP="$checkout_build/bin/colmap" \
    -DDPSFM_BENCHMARKS_ENABLED=OFF \
    >"$build_dir/configure.log" 2>&1 \
    || { tail -n 30 "$build_dir/configure.log" >&2; die "configuring dp-sfm against $prefix failed (log: $build_dir/configure.log)"; }
}
stage "configure dp-sfm against the installed COLMAP" configure
grep -o 'dp-sfm: building against .*' "$build_dir/configure.log" | sed 's/^/[dp-sfm] /' >&2
start=$SECONDS
stage "build dpsfm" hidden cmake --build "$build_dir" --target dpsfm -j "$(jobs_count)"
log "warm cache to a built dpsfm: $((SECONDS - start)) s of build after the configure"
stage "build the tests" hidden cmake --build "$build_dir" -j "$(jobs_count)"
# Nothing built may point into the fetched sources or COLMAP's build tree.
if grep -q -e "$fetched/" -e "$checkout_build/colmap/" "$build_dir/build.ninja"; then
  die "the installed-route build refers to COLMAP's sources or build tree ($build_dir/build.ninja)"
fi

# 3. Installed, then tested.
rm -rf "$build_dir/install"
cmake --install "$build_dir" --prefix "$build_dir/install" >/dev/null
"$build_dir/install/bin/dpsfm" version | sed 's/^/[dp-sfm] installed: /' >&2
status=0
stage "test (unit tests, Clang)" ctest --test-dir "$build_dir" -L fast \
  -j "$(jobs_count)" --output-on-failure --timeout 900 "$@" || status=$?
stage "test (end to end, through dpsfm)" ctest --test-dir "$build_dir" -L e2e \
  -j "$(jobs_count)" --output-on-failure --timeout 900 "$@" || status=$?
log "total $((SECONDS - total_start)) s"
exit $status
