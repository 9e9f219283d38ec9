# Shared settings for the dp-sfm scripts. Source it; do not run it.
# Everything that survives between runs lives under DPSFM_CACHE_DIR, outside
# the clone, so a fresh clone on the same machine reuses the COLMAP build.

set -euo pipefail

DPSFM_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
DPSFM_CACHE_DIR="${DPSFM_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/dp-sfm}"
export CCACHE_DIR="${CCACHE_DIR:-$DPSFM_CACHE_DIR/ccache}"
export CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-5G}"
# A fresh clone gives every file a new mtime/ctime; the contents decide.
export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-include_file_mtime,include_file_ctime,time_macros}"

# Source archives that no package registry serves may sit in ../shared/sources
# beside the clone (a local mirror); a file there is used when its sha256
# matches, and the same release is otherwise downloaded from its usual home.
DPSFM_SOURCES_DIR="${DPSFM_SOURCES_DIR:-$DPSFM_ROOT/../shared/sources}"

# The COLMAP release the plugin is built against: 4.1.1 by default,
# DPSFM_COLMAP_VERSION=3.10 for the COLMAP of 2024. Each version has its own
# pinned source and its own cached build, so switching rebuilds nothing.
#   COLMAP_ARCHIVE[_SHA256]  the archive's file name and checksum
#   COLMAP_TREE_SHA256       the checksum of the extracted files (tree_sha256):
#                            archives of one tag made by different hosts differ
#                            in their bytes but not in the files they hold
#   COLMAP_URL               where a machine with internet access gets it
DPSFM_COLMAP_VERSION="${DPSFM_COLMAP_VERSION:-4.1.1}"
case "$DPSFM_COLMAP_VERSION" in
  4.1.1)
    COLMAP_VERSION="4.1.1"
    COLMAP_ARCHIVE="colmap-4.1.1.tar.gz"
    COLMAP_ARCHIVE_SHA256="40c13979bca58db4cd0429e1a0e51c1482dd6adb12ec9ac1e0796bdaf6e20d9c"
    COLMAP_TREE_SHA256="5b2153a2e08716034b8be05ff7b6698a911424c923abba2508d776407404cb57"
    COLMAP_URL="https://github.com/colmap/colmap/archive/refs/tags/4.1.1.tar.gz"
    # COLMAP 4 needs PoseLib; 4.1.1 pins a commit that no archive at hand
    # holds, and builds with the newest one that does (see docs/building.md).
    POSELIB_REVISION="a69263d"
    POSELIB_ARCHIVE="PoseLib-a69263d.tar.gz"
    POSELIB_ARCHIVE_SHA256="23b53638f5de08077d55fb09399c65bf9d3b2e56f3cbad765e538a08ad6211dc"
    POSELIB_TREE_SHA256="bfa1560f4f309b977f19105d24c3a838c26f70b906a41a496b3547c0d5117b93"
    POSELIB_URL="https://github.com/PoseLib/PoseLib/archive/a69263d5d824b5de11e48756f33f6e8ebb231f0c.tar.gz"
    ;;
  3.10)
    # Debian's orig tarball of colmap 3.10, through apt (fetch_colmap.sh).
    COLMAP_VERSION="3.10"
    COLMAP_DEBIAN_VERSION="3.10-2"
    COLMAP_DEBIAN_SUITE="trixie"
    COLMAP_ARCHIVE="colmap_${COLMAP_VERSION}.orig.tar.gz"
    COLMAP_ARCHIVE_SHA256="61850f323e201ab6a1abbfb0e4a8b3ba1c4cedbf55e0a5716bdea1df8ae1813a"
    COLMAP_TREE_SHA256=""
    COLMAP_URL=""
    POSELIB_REVISION=""
    ;;
  *)
    printf '[dp-sfm] error: DPSFM_COLMAP_VERSION=%s is not a version dp-sfm builds (4.1.1, the default, or 3.10); to build against your own COLMAP 4.1.x/4.2.x checkout, see docs/building.md\n' "$DPSFM_COLMAP_VERSION" >&2
    exit 1
    ;;
esac

# The newest COLMAP source at hand (4.2.0.dev0): the plugin is compiled
# against its headers by scripts/check_colmap_main.sh (it does not link).
COLMAP_MAIN_ARCHIVE="colmap-main-5d968cf.tar.gz"
COLMAP_MAIN_ARCHIVE_SHA256="81adf4db8bf87b7a2c55aa89e27c9531fb011be99f17a339d195ae81c7ead8fb"
COLMAP_MAIN_TREE_SHA256="18c2ef9e22f3b2bdf1fc40ffbca63d556ed57e04cf52a613c78ff1a7831f7a24"
COLMAP_MAIN_URL="https://github.com/colmap/colmap/archive/5d968cf38aa2574fd284b0dc86c3d58d124940b3.tar.gz"

# Options of the cached build. They are part of the cache key: change one and
# the build lands in a new directory instead of silently reusing the old one.
DPSFM_BUILD_TYPE="${DPSFM_BUILD_TYPE:-Release}"
DPSFM_COLMAP_OPTIONS=(
  -DCUDA_ENABLED=OFF -DGUI_ENABLED=OFF -DOPENGL_ENABLED=OFF
  -DCGAL_ENABLED=OFF -DTESTS_ENABLED=OFF -DIPO_ENABLED=OFF
)
if [ -n "$POSELIB_REVISION" ]; then
  # Nothing is downloaded at build time: PoseLib is built by
  # build_poselib.sh, faiss comes from Debian, ONNX (learned features) is off.
  DPSFM_COLMAP_OPTIONS+=(
    -DFETCH_POSELIB=OFF -DFETCH_FAISS=OFF -DFETCH_ONNX=OFF -DONNX_ENABLED=OFF
    -DDOWNLOAD_ENABLED=OFF -DFETCHCONTENT_FULLY_DISCONNECTED=ON
  )
fi

# The patch series (colmap_patches/*.patch, in application order).
patch_series() { ls -1 "$DPSFM_ROOT"/colmap_patches/*.patch | LC_ALL=C sort; }

# Applies the patch series to the COLMAP tree $1 with git apply; stops
# naming the patch that does not apply to $2 (what the tree is).
apply_patch_series() {
  local patch
  for patch in $(patch_series); do
    log "applying $(basename "$patch")"
    (cd "$1" && git apply --whitespace=nowarn "$patch") \
      || die "patch $(basename "$patch") does not apply to $2"
  done
}

# The sha256 of the files under $1 (names and contents, in a fixed order).
tree_sha256() {
  (cd "$1" && find . -type f -print0 | LC_ALL=C sort -z | xargs -0 sha256sum) \
    | sha256sum | cut -d' ' -f1
}

log() { printf '[dp-sfm] %s\n' "$*" >&2; }

# For scripts whose standard output is a value (a path): everything they
# and the commands they run print goes to stderr from here on, and only
# `result VALUE` reaches the caller's stdout. (apt's progress on a fresh
# machine once landed in `build_dir="$(build.sh)"`.)
stdout_is_result() { exec 3>&1 1>&2; }
result() { printf '%s\n' "$1" >&3; }

# The cached build tree (builds what is missing), checked to be one.
build_tree() {
  local dir
  dir="$("$DPSFM_ROOT/scripts/build.sh")"
  [ -d "$dir" ] && [ -f "$dir/CMakeCache.txt" ] \
    || die "scripts/build.sh printed '${dir:0:200}', not a build directory"
  printf '%s\n' "$dir"
}
die() { printf '[dp-sfm] error: %s\n' "$*" >&2; exit 1; }

# stage NAME CMD...: runs CMD and prints how long it took.
stage() {
  local name="$1"; shift
  local start=$SECONDS
  log "stage '$name' ..."
  "$@"
  log "stage '$name' took $((SECONDS - start)) s"
}

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

jobs_count() {
  local n
  n=$(nproc 2>/dev/null || echo 2)
  echo "${DPSFM_JOBS:-$n}"
}
