#!/usr/bin/env bash
# Makes a verified, extracted source tree in the cache and prints its path.
# Usage: fetch_archive.sh NAME ARCHIVE SHA256 TREE_SHA256 URL
#  1. ARCHIVE from DPSFM_SOURCES_DIR (../shared/sources) when it is there and
#     its sha256 is SHA256; otherwise a copy downloaded from URL earlier, or
#     now (curl or wget). Nothing else is ever downloaded.
#  2. Extracted without its top folder, and checked by the checksum of its
#     files (TREE_SHA256): a host's own archive of the same tag has other
#     bytes than a git-archive mirror but the same files. A mismatch stops.
#  3. Renamed into place only when complete, so an interrupted run leaves
#     nothing half-extracted behind.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
stdout_is_result

[ $# -eq 5 ] || die "usage: fetch_archive.sh NAME ARCHIVE SHA256 TREE_SHA256 URL"
name="$1" archive="$2" sha256="$3" tree_sha256_expected="$4" url="$5"

tree_dir="$DPSFM_CACHE_DIR/src/$name-${tree_sha256_expected:0:16}"
if [ -f "$tree_dir/.dpsfm-verified" ]; then
  result "$tree_dir"
  exit 0
fi

download() {
  local out="$1"
  log "downloading $name from $url"
  if command -v curl >/dev/null; then
    curl -fsSL --retry 3 -o "$out.part" "$url"
  elif command -v wget >/dev/null; then
    wget -q -O "$out.part" "$url"
  else
    die "neither curl nor wget is installed to download $url"
  fi || { rm -f "$out.part"; die "could not download $url; put $archive into $DPSFM_SOURCES_DIR (sha256 $sha256)"; }
  mv "$out.part" "$out"
}

mirror="$DPSFM_SOURCES_DIR/$archive"
downloaded="$DPSFM_CACHE_DIR/downloads/$archive"
if [ -f "$mirror" ] && [ "$(sha256sum < "$mirror" | cut -d' ' -f1)" = "$sha256" ]; then
  source_archive="$mirror"
  log "$name from $mirror (sha256 matches)"
else
  [ -f "$mirror" ] && log "warning: $mirror does not have the pinned sha256 $sha256; not using it"
  mkdir -p "$(dirname "$downloaded")"
  [ -f "$downloaded" ] || download "$downloaded"
  source_archive="$downloaded"
fi

mkdir -p "$DPSFM_CACHE_DIR/src"
work="$(mktemp -d "$DPSFM_CACHE_DIR/src/.work.XXXXXX")"
trap 'rm -rf "$work"' EXIT
tar -xzf "$source_archive" -C "$work" --strip-components=1 \
  || die "cannot extract $source_archive"
actual="$(tree_sha256 "$work")"
if [ "$actual" != "$tree_sha256_expected" ]; then
  [ "$source_archive" = "$downloaded" ] && rm -f "$downloaded"
  die "the files of $source_archive are not those of $name (tree sha256 $actual, pinned $tree_sha256_expected)"
fi
touch "$work/.dpsfm-verified"
rm -rf "$tree_dir"
mv "$work" "$tree_dir"
trap - EXIT
result "$tree_dir"
