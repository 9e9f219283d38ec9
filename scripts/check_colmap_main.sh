#!/usr/bin/env bash
# Compiles dp-sfm's sources that include COLMAP headers (the plugin's COLMAP
# layer and commands, the examples, the tests) against the newest COLMAP
# source at hand: COLMAP's main branch of 2026-08 (4.2.0.dev0, in
# ../shared/sources). A compile check only: COLMAP itself does not link from
# that tree with the PoseLib we have, so nothing is linked or run. Prints each
# file that fails and exits non-zero if any does.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

# COLMAP's main branch is fetched, verified and patched by CMake
# (DPSFM_COLMAP_RELEASE=main, cmake/ColmapRelease.cmake) and configured with
# dp-sfm; nothing is built through Ninja.
build_dir="$DPSFM_CACHE_DIR/build/colmap-main-check"
mkdir -p "$build_dir"
point_source "$build_dir"
configure() {
  cmake -S "$build_dir/.source" -B "$build_dir" -G Ninja \
    -DDPSFM_COLMAP_RELEASE=main -DCMAKE_BUILD_TYPE="${DPSFM_BUILD_TYPE:-Release}" \
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >"$build_dir/configure.log" 2>&1 \
    || { grep -v '^-- ' "$build_dir/configure.log" | tail -n 30 >&2; die "CMake configuration against COLMAP's main branch failed (log: $build_dir/configure.log)"; }
}
stage "configure against COLMAP's main branch" configure
source_dir="$(sed -n 's/^COLMAP_SOURCE_DIR:[A-Z]*=//p' "$build_dir/CMakeCache.txt")"
log "$(grep -o 'COLMAP_VERSION "[^"]*"' "$source_dir/CMakeLists.txt") from $source_dir"

# Every object of dp-sfm's own targets that sees COLMAP headers: the COLMAP
# layer, the commands, the examples and the tests of tests/{colmap,e2e,scripts}
# (the core and its tests include no COLMAP header). Compiled one by one from
# compile_commands.json: building them through Ninja would first build the
# COLMAP libraries they link.
mapfile -t files < <(python3 - "$build_dir/compile_commands.json" <<'PY'
import json, re, sys
pattern = re.compile(r"/(plugin/dpsfm/(colmap|exe)|examples|tests/(colmap|e2e|scripts))/.+\.cc$")
for entry in json.load(open(sys.argv[1])):
    if pattern.search(entry["file"]):
        print(entry["file"])
PY
)
[ ${#files[@]} -gt 0 ] || die "found no dp-sfm sources in $build_dir/compile_commands.json"
log "compiling ${#files[@]} files against $source_dir (syntax and types only)"
start=$SECONDS
: >"$build_dir/compile.log"
compile_one() {
  python3 - "$build_dir/compile_commands.json" "$1" <<'PY'
import json, shlex, subprocess, sys
entry = next(e for e in json.load(open(sys.argv[1])) if e["file"] == sys.argv[2])
args = shlex.split(entry["command"])
# Drop the output file: check syntax and types only.
if "-o" in args:
    k = args.index("-o"); del args[k:k + 2]
args.append("-fsyntax-only")
sys.exit(subprocess.call(args, cwd=entry["directory"]))
PY
}
export -f compile_one
export build_dir
failed=0
printf '%s\n' "${files[@]}" | xargs -P "$(jobs_count)" -I{} bash -c \
  'compile_one "$1" >>"$build_dir/compile.log" 2>&1 || { echo "FAILED: $1" >>"$build_dir/compile.log"; exit 1; }' _ {} \
  || failed=1
grep -E '^FAILED: ' "$build_dir/compile.log" | sed 's/^/[dp-sfm] /' >&2 || true
grep -E 'error:' "$build_dir/compile.log" | head -n 40 >&2 || true
log "compiled ${#files[@]} files in $((SECONDS - start)) s (log: $build_dir/compile.log)"
[ "$failed" -eq 0 ] || die "dp-sfm does not compile against COLMAP's main branch (4.2.0.dev0)"
log "dp-sfm compiles against COLMAP's main branch (4.2.0.dev0): ${#files[@]} files, no errors"
