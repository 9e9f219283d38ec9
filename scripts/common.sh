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

# The COLMAP release the plugin is built against, and the pinned source
# tarball (Debian's orig tarball of colmap 3.10).
COLMAP_VERSION="3.10"
COLMAP_DEBIAN_VERSION="3.10-2"
COLMAP_DEBIAN_SUITE="trixie"
COLMAP_TARBALL="colmap_${COLMAP_VERSION}.orig.tar.gz"
COLMAP_TARBALL_SHA256="61850f323e201ab6a1abbfb0e4a8b3ba1c4cedbf55e0a5716bdea1df8ae1813a"

# Options of the cached build. They are part of the cache key: change one and
# the build lands in a new directory instead of silently reusing the old one.
DPSFM_BUILD_TYPE="${DPSFM_BUILD_TYPE:-Release}"
DPSFM_COLMAP_OPTIONS=(
  -DCUDA_ENABLED=OFF -DGUI_ENABLED=OFF -DOPENGL_ENABLED=OFF
  -DCGAL_ENABLED=OFF -DTESTS_ENABLED=OFF -DIPO_ENABLED=OFF
)

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
