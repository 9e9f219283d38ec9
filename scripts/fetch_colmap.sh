#!/usr/bin/env bash
# Makes a patched COLMAP source tree (DPSFM_COLMAP_VERSION) in the cache and
# prints its path.
#  1. COLMAP 4.x: the verified tree of fetch_archive.sh (../shared/sources or
#     COLMAP's own release of the tag).
#     COLMAP 3.10: Debian's orig tarball, downloaded once through apt with a
#     private deb-src entry for the next Debian release made from this
#     machine's own apt entry (the system's apt configuration is untouched),
#     its sha256 checked against the pinned value.
#  2. Applies colmap_patches/*.patch in order with git apply, into a directory
#     keyed by the version and patch series, renamed into place only when
#     complete (an interrupted run leaves nothing half-patched behind).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
stdout_is_result

download_dir="$DPSFM_CACHE_DIR/downloads"
tarball="$download_dir/$COLMAP_ARCHIVE"
mkdir -p "$download_dir"

# Writes a deb-src entry for COLMAP_DEBIAN_SUITE from the machine's own Debian
# mirror entry into $1 (deb822 format).
write_source_entry() {
  local out="$1" uri="" keyring="/usr/share/keyrings/debian-archive-keyring.gpg"
  if [ -f /etc/apt/sources.list.d/debian.sources ]; then
    uri=$(awk '/^URIs:/ {print $2; exit}' /etc/apt/sources.list.d/debian.sources)
    local k
    k=$(awk '/^Signed-By:/ {print $2; exit}' /etc/apt/sources.list.d/debian.sources)
    [ -n "$k" ] && keyring="$k"
  fi
  if [ -z "$uri" ] && [ -f /etc/apt/sources.list ]; then
    uri=$(awk '$1 == "deb" && $2 !~ /security/ {print ($2 ~ /^\[/ ? $3 : $2); exit}' /etc/apt/sources.list)
  fi
  [ -n "$uri" ] || die "cannot find this machine's Debian mirror in /etc/apt; download $COLMAP_ARCHIVE yourself into $download_dir"
  cat > "$out" <<EOT
Types: deb-src
URIs: $uri
Suites: $COLMAP_DEBIAN_SUITE
Components: main
Signed-By: $keyring
EOT
}

download_tarball() {
  local apt_dir
  apt_dir="$(mktemp -d "$DPSFM_CACHE_DIR/apt.XXXXXX")"
  mkdir -p "$apt_dir/lists/partial" "$apt_dir/get"
  write_source_entry "$apt_dir/colmap-src.sources"
  local apt_opts=(-o Dir::Etc::SourceList=/dev/null
                  -o "Dir::Etc::SourceParts=$apt_dir"
                  -o "Dir::State::Lists=$apt_dir/lists"
                  -o APT::Sandbox::User=root -q)
  log "downloading $COLMAP_ARCHIVE (Debian source package colmap=$COLMAP_DEBIAN_VERSION)"
  apt-get "${apt_opts[@]}" update >/dev/null
  # The .dsc and the Debian patch tarball may be gone from the mirror while
  # the orig tarball remains: accept the failure if the tarball arrived.
  (cd "$apt_dir/get" && apt-get "${apt_opts[@]}" source --download-only \
     "colmap=$COLMAP_DEBIAN_VERSION" >/dev/null 2>&1) || true
  [ -f "$apt_dir/get/$COLMAP_ARCHIVE" ] || {
    rm -rf "$apt_dir"
    die "could not download $COLMAP_ARCHIVE through apt; put it into $download_dir by hand"
  }
  mv "$apt_dir/get/$COLMAP_ARCHIVE" "$tarball.part"
  rm -rf "$apt_dir"
  mv "$tarball.part" "$tarball"
}

verify_tarball() {
  local actual
  actual="$(sha256sum "$tarball" | cut -d' ' -f1)"
  if [ "$actual" != "$COLMAP_ARCHIVE_SHA256" ]; then
    die "sha256 mismatch for $tarball: expected $COLMAP_ARCHIVE_SHA256, got $actual (delete it to download again)"
  fi
}

source_key="$("$DPSFM_ROOT/scripts/cache_key.sh" "$DPSFM_ROOT/colmap_patches" source)"
source_dir="$DPSFM_CACHE_DIR/src/colmap-$COLMAP_VERSION-$source_key"
if [ -f "$source_dir/.dpsfm-complete" ]; then
  result "$source_dir"
  exit 0
fi

mkdir -p "$DPSFM_CACHE_DIR/src"
work="$(mktemp -d "$DPSFM_CACHE_DIR/src/.work.XXXXXX")"
trap 'rm -rf "$work"' EXIT
if [ -n "$COLMAP_URL" ]; then
  pristine="$("$DPSFM_ROOT/scripts/fetch_archive.sh" "colmap-$COLMAP_VERSION" \
    "$COLMAP_ARCHIVE" "$COLMAP_ARCHIVE_SHA256" "$COLMAP_TREE_SHA256" "$COLMAP_URL")"
  cp -a "$pristine" "$work/colmap"
  rm -f "$work/colmap/.dpsfm-verified"
else
  [ -f "$tarball" ] || download_tarball
  verify_tarball
  tar -xzf "$tarball" -C "$work"
  [ -d "$work/colmap-$COLMAP_VERSION" ] || die "unexpected tarball layout in $tarball"
  mv "$work/colmap-$COLMAP_VERSION" "$work/colmap"
fi
apply_patch_series "$work/colmap" "COLMAP $COLMAP_VERSION"
touch "$work/colmap/.dpsfm-complete"
rm -rf "$source_dir"
mv "$work/colmap" "$source_dir"
result "$source_dir"
