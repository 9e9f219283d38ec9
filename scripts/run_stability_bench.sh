#!/usr/bin/env bash
# Stability of the answers (`make stability`): how far each answer moves,
# in tenths of its own 95 % half-width, when nothing that should matter
# changes. Per scene, against the run with the defaults:
#   bound-1, bound+1  an explicit search bound 1 px below and above the
#                     automatic one the run ended with (the patches stay
#                     the automatic bound's; only the search's reach moves)
#   threads           --DPScaleEstimator.num_threads 1 against 2 (the
#                     default, all of this machine's)
#   reordered         the same source compiled so that its arithmetic
#                     rounds otherwise: dp-sfm built against the installed
#                     COLMAP (make test-installed's prefix, made first when
#                     missing) with -march=x86-64-v3 -ffp-contract=fast, so
#                     that the compiler fuses multiplies and adds into FMA
#                     instructions wherever it can (what GCC does by default
#                     on aarch64), run as `dpsfm` (on a machine without
#                     AVX2 and FMA this variant is left out)
# on the real captures of `make real` (the calibrated profile, with and
# without the recorded focus; the DP cue is measured whether or not the run
# answers) and on the generated scenes of `make accuracy` (the defaults).
# A move counts against the answer's half-width (the DP cue's when the run
# refused); "> 0.1" marks a move of more than a tenth. Gates nothing.
#
# It reuses what `make real` and `make accuracy` left in the cache
# (DPSFM_REAL_DIR, DPSFM_ACCURACY_DIR) and runs those benchmarks first when
# their output is missing. Output: DPSFM_STABILITY_DIR (default
# <cache>/stability).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="$(build_tree)"
real="${DPSFM_REAL_DIR:-$DPSFM_CACHE_DIR/real}"
accuracy="${DPSFM_ACCURACY_DIR:-$DPSFM_CACHE_DIR/accuracy}"
out="${DPSFM_STABILITY_DIR:-$DPSFM_CACHE_DIR/stability}"
rm -rf "$out"
mkdir -p "$out/bin"
cp "$build_dir/colmap/src/colmap/exe/colmap" "$out/bin/"
colmap="$out/bin/colmap"
[ -f "$real/results.tsv" ] || bash "$DPSFM_ROOT/scripts/run_real_bench.sh"
[ -d "$accuracy/scenes" ] || bash "$DPSFM_ROOT/scripts/run_accuracy_bench.sh"
start=$SECONDS
results="$out/results.tsv"
: >"$results"

# The reordered build (see the header): its own tree in the cache, keyed by
# the installed COLMAP it is built against.
reordered=""
build_reordered() {
  local prefix="$DPSFM_CACHE_DIR/installed/$(basename "$build_dir")"
  [ -d "$prefix" ] || bash "$DPSFM_ROOT/scripts/run_installed_tests.sh" \
    || die "the installed COLMAP for the reordered build could not be made"
  local tree="$DPSFM_CACHE_DIR/build/reordered-$(basename "$build_dir")"
  cmake -S "$DPSFM_ROOT" -B "$tree" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$prefix" -DDPSFM_BENCHMARKS_ENABLED=OFF \
    -DCMAKE_CXX_FLAGS="-march=x86-64-v3 -ffp-contract=fast" \
    -DDPSFM_FP_CONTRACT=fast \
    >"$out/reordered.configure.log" 2>&1 \
    || die "configuring the reordered build failed (log: $out/reordered.configure.log)"
  cmake --build "$tree" --target dpsfm -j "$(jobs_count)" \
    >"$out/reordered.build.log" 2>&1 \
    || die "the reordered build failed (log: $out/reordered.build.log)"
  cp "$tree/plugin/dpsfm" "$out/bin/dpsfm-reordered"
  reordered="$out/bin/dpsfm-reordered"
}
if grep -qw avx2 /proc/cpuinfo && grep -qw fma /proc/cpuinfo; then
  stage "build dp-sfm with fused multiply-adds" build_reordered
else
  log "this machine has no AVX2 and FMA: the reordered variant is left out"
fi

# run NAME VARIANT REPORT ARGS...: one estimate, its report in REPORT, by
# $binary (the patched colmap unless set).
run() {
  local name="$1" variant="$2" report="$3"
  shift 3
  "${binary:-$colmap}" dp_scale_estimator --dry_run 1 --report_path "$report" "$@" \
    >"$report.log" 2>&1 || true
  printf '%s\t%s\t%s\n' "$name" "$variant" "$report" >>"$results"
}

# The automatic bound a report ended with (the largest of its views').
bound_of() {
  python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["search_bound"]["px"])' "$1" 2>/dev/null
}

# variants NAME ARGS...: the defaults, then each variant, of one workspace.
variants() {
  local name="$1"
  shift
  local base="$out/$name.base.json"
  run "$name" base "$base" "$@"
  local b
  b="$(bound_of "$base")"
  if [ -n "$b" ]; then
    run "$name" bound-1 "$out/$name.lo.json" "$@" \
      --DPScaleEstimator.max_radius_px "$(awk "BEGIN{print $b - 1}")"
    run "$name" bound+1 "$out/$name.hi.json" "$@" \
      --DPScaleEstimator.max_radius_px "$(awk "BEGIN{print $b + 1}")"
  fi
  run "$name" threads "$out/$name.t1.json" "$@" --DPScaleEstimator.num_threads 1
  if [ -n "$reordered" ]; then
    binary="$reordered" run "$name" reordered "$out/$name.fma.json" "$@"
  fi
}

# The real captures, 8-bit as given, with the calibrated profile.
profile="$real/calibration/srgb8/r6m2_rf50_f4.dpsf"
for ws in "$real"/srgb8/*/; do
  ws="${ws%/}"
  name="real_$(basename "$ws")"
  [ -f "$profile" ] || break
  for focus in 0 1; do
    lens="$ws/lens_no_focus.csv"
    [ "$focus" = 1 ] && lens="$ws/lens.csv"
    variants "$name$([ "$focus" = 1 ] && echo _focus)" \
      --workspace_path "$ws/dense" --dp_image_path "$ws/dp" \
      --lens_path "$lens" --DPScaleEstimator.psf_model calibrated \
      --DPScaleEstimator.psf_path "$profile"
  done
done

# The generated scenes: every single-setting scene and each multi-aperture
# set's all-together workspace, with the defaults.
for scene in "$accuracy"/scenes/*/; do
  scene="${scene%/}"
  name="$(basename "$scene")"
  case "$name" in fail_*) continue ;; esac
  workspaces=("$scene/dense")
  [ -d "$scene/subsets" ] && workspaces=("$scene/subsets/all/dense")
  for workspace in "${workspaces[@]}"; do
    [ -d "$workspace" ] || continue
    variants "gen_$name" --workspace_path "$workspace" \
      --dp_image_path "$scene/dp" --lens_path "$scene/lens.csv"
  done
done

python3 - "$results" <<'PY'
import json, sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
def answer(path):
    try:
        r = json.load(open(path))
    except Exception:
        return None
    if r.get("success"):
        return r["scale"], r["scale_ci_low"], r["scale_ci_high"], "answer"
    c = r.get("cues", {}).get("dual_pixel", {})
    if c.get("valid"):
        return c["scale"], c["ci"][0], c["ci"][1], "DP cue"
    return None
by = {}
for name, variant, path in rows:
    by.setdefault(name, {})[variant] = answer(path)
kinds = ["bound-1", "bound+1", "threads", "reordered"]
print("\n| scene | base (what) | 95 % half-width | " + " | ".join(kinds) + " |")
print("|---|---|---|" + "---|" * len(kinds))
worst = {k: (0.0, "") for k in kinds}
over = 0
for name, v in by.items():
    base = v.get("base")
    if base is None:
        print("| %s | refused, no DP cue | | %s |" % (name, " | ".join("" for _ in kinds)))
        continue
    s, lo, hi, what = base
    half = 0.5 * (hi - lo)
    cells = []
    for k in kinds:
        if k not in v:
            cells.append("")
            continue
        other = v[k]
        if other is None or other[3] != what:
            cells.append("%s -> %s" % (what, "refused" if other is None else other[3]))
            over += 1
            continue
        move = abs(other[0] - s) / half if half > 0 else float("inf")
        cells.append("%.3f%s" % (move, " > 0.1" if move > 0.1 else ""))
        over += move > 0.1
        if move > worst[k][0]:
            worst[k] = (move, name)
    print("| %s | %.4f (%s) | %.4f | %s |" % (name, s, what, half, " | ".join(cells)))
print("\nlargest move per variant, in half-widths: " + "; ".join(
    "%s %.3f (%s)" % (k, m, n) for k, (m, n) in worst.items()))
print("moves over a tenth of the half-width, or a changed outcome: %d" % over)
PY
log "total $((SECONDS - start)) s; reports in $out"
