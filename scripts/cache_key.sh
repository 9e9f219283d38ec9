#!/usr/bin/env bash
# Prints the cache keys of the COLMAP build:
#   source=<hash>  the patched COLMAP source (version, tarball, patch series)
#   build=<hash>   the build tree (source key + build options + compiler +
#                  the PoseLib it links, for COLMAP 4)
# Usage: cache_key.sh [PATCH_DIR] [source|build]
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

patch_dir="${1:-$DPSFM_ROOT/colmap_patches}"
which="${2:-build}"
[ -d "$patch_dir" ] || die "no patch directory at $patch_dir"

patch_series_hash() {
  # Names and contents, in application order, so renaming, reordering or
  # editing a patch all change the key.
  (cd "$patch_dir" && for p in $(ls -1 *.patch 2>/dev/null | LC_ALL=C sort); do
     printf '%s\n' "$p"; sha256sum < "$p"
   done) | sha256sum | cut -c1-16
}

source_key() {
  printf 'colmap=%s tarball=%s patches=%s\n' "$COLMAP_VERSION" \
    "$COLMAP_ARCHIVE_SHA256" "$(patch_series_hash)" | sha256sum | cut -c1-16
}

build_key() {
  local compiler
  compiler="$(${CXX:-c++} --version 2>/dev/null | head -n1 || echo unknown)"
  printf 'source=%s type=%s options=%s compiler=%s poselib=%s\n' \
    "$(source_key)" "$DPSFM_BUILD_TYPE" "${DPSFM_COLMAP_OPTIONS[*]}" \
    "$compiler" "${POSELIB_TREE_SHA256:-none}" \
    | sha256sum | cut -c1-16
}

case "$which" in
  source) source_key ;;
  build) build_key ;;
  *) die "unknown key kind '$which' (use source or build)" ;;
esac
