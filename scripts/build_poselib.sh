#!/usr/bin/env bash
# Builds and installs the PoseLib that COLMAP 4 links (POSELIB_REVISION in
# common.sh) into the cache and prints the install prefix. The prefix is keyed
# by PoseLib's files, the build type and the compiler, so a warm run (from any
# clone) rebuilds nothing; it is renamed into place only when installed.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
stdout_is_result

[ -n "$POSELIB_REVISION" ] || die "COLMAP $COLMAP_VERSION does not use PoseLib"

compiler="$(${CXX:-c++} --version 2>/dev/null | head -n1 || echo unknown)"
key="$(printf 'files=%s type=%s compiler=%s\n' "$POSELIB_TREE_SHA256" \
  "$DPSFM_BUILD_TYPE" "$compiler" | sha256sum | cut -c1-16)"
prefix="$DPSFM_CACHE_DIR/poselib/poselib-$POSELIB_REVISION-$key"
mkdir -p "$DPSFM_CACHE_DIR/poselib"

exec 9>"$prefix.lock"
flock 9
if [ -f "$prefix/.dpsfm-complete" ]; then
  result "$prefix"
  exit 0
fi

source_dir="$("$DPSFM_ROOT/scripts/fetch_archive.sh" "poselib-$POSELIB_REVISION" \
  "$POSELIB_ARCHIVE" "$POSELIB_ARCHIVE_SHA256" "$POSELIB_TREE_SHA256" "$POSELIB_URL")"
build_dir="$prefix.build"
rm -rf "$build_dir" "$prefix.part"
configure() {
  cmake -S "$source_dir" -B "$build_dir" -G Ninja \
    -DCMAKE_BUILD_TYPE="$DPSFM_BUILD_TYPE" \
    -DCMAKE_INSTALL_PREFIX="$prefix" -DMARCH_NATIVE=OFF \
    -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >"$prefix.configure.log" 2>&1 \
    || { tail -n 30 "$prefix.configure.log" >&2; die "PoseLib's CMake configuration failed (log: $prefix.configure.log)"; }
}
stage "configure PoseLib" configure
stage "build PoseLib" cmake --build "$build_dir" -j "$(jobs_count)"
# Installed under its final prefix name (PoseLib's CMake package files are
# relocatable, but its install step writes absolute paths into the manifest),
# through DESTDIR so the prefix appears only when complete.
DESTDIR="$prefix.part" cmake --install "$build_dir" >/dev/null
rm -rf "$prefix"
mv "$prefix.part$prefix" "$prefix"
rm -rf "$prefix.part" "$build_dir"
touch "$prefix/.dpsfm-complete"
result "$prefix"
