#!/usr/bin/env bash
# Installs the Debian 12 packages dp-sfm and COLMAP 3.10 need. Does nothing
# (and needs no network) when they are all present. Uses sudo only when not
# root. Never edits the system's apt sources.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

PACKAGES=(
  build-essential cmake ninja-build ccache git pkg-config
  libeigen3-dev libgoogle-glog-dev libgflags-dev libceres-dev libflann-dev
  libfreeimage-dev libmetis-dev libsqlite3-dev libboost-program-options-dev
  libboost-filesystem-dev libboost-graph-dev libboost-system-dev
  libsuitesparse-dev libglew-dev libopencv-dev libgtest-dev
  nlohmann-json3-dev
)

missing=()
for pkg in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  log "all ${#PACKAGES[@]} build dependencies are installed"
  exit 0
fi

log "installing ${#missing[@]} packages: ${missing[*]}"
as_root apt-get update -q
as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
