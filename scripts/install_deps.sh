#!/usr/bin/env bash
# Installs the Debian 12 packages dp-sfm and COLMAP (4.1.1 and 3.10) need, and the test
# suite's COLMAP 4 reader (pycolmap 4.2.1 from PyPI, in a virtualenv in the
# cache: the oracle of the rescaling tests on current-format models). Does
# nothing (and needs no network) when they are all present. Uses sudo only
# when not root. Never edits the system's apt sources.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

PACKAGES=(
  build-essential cmake ninja-build ccache git pkg-config
  libeigen3-dev libgoogle-glog-dev libgflags-dev libceres-dev libflann-dev
  libfreeimage-dev libmetis-dev libsqlite3-dev libboost-program-options-dev
  libboost-filesystem-dev libboost-graph-dev libboost-system-dev
  libsuitesparse-dev libglew-dev libopencv-dev libgtest-dev libfftw3-dev
  libdeflate-dev nlohmann-json3-dev libexiv2-dev python3 python3-venv
  # COLMAP 4: OpenImageIO replaced FreeImage (its CMake package names
  # /usr/bin/iconvert, hence the tools), faiss for retrieval; CA certificates
  # for the sources CMake downloads on a machine without ../shared/sources.
  libopenimageio-dev openimageio-tools libfaiss-dev ca-certificates
  # The installed route is compiled with Clang (and its OpenMP runtime), so
  # that CI builds the plugin and its tests with a second compiler.
  clang-14 libomp-14-dev
)

PYCOLMAP_VERSION="4.2.1"
venv="$DPSFM_CACHE_DIR/venv/pycolmap-$PYCOLMAP_VERSION"

# pycolmap in its own virtualenv; one that cannot import it (an interrupted
# install) is made again.
install_pycolmap() {
  if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c "import pycolmap" 2>/dev/null; then
    return
  fi
  log "installing pycolmap $PYCOLMAP_VERSION (PyPI) into $venv"
  rm -rf "$venv"
  mkdir -p "$(dirname "$venv")"
  python3 -m venv "$venv" >&2
  "$venv/bin/pip" install -q --disable-pip-version-check \
    "pycolmap==$PYCOLMAP_VERSION" >&2 \
    || { rm -rf "$venv"; die "pip could not install pycolmap $PYCOLMAP_VERSION"; }
}

missing=()
for pkg in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  log "all ${#PACKAGES[@]} build dependencies are installed"
else
  log "installing ${#missing[@]} packages: ${missing[*]}"
  as_root apt-get update -q >&2
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q \
    --no-install-recommends "${missing[@]}" >&2
fi
install_pycolmap
