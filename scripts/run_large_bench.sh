#!/usr/bin/env bash
# Large-project benchmark (`make large`): a dense workspace of 3000x2000
# 16-bit DP frames, 10 distinct generated views (dpsfm_make_example, made
# once and kept in <cache>/large) repeated 30 times with their poses and
# depth maps (dpsfm_repeat_workspace, hard links) = 300 views. `colmap
# dp_scale_estimator` runs (dry run) on the 10 distinct views with every
# view visited (the reference), and on the 300 views with the defaults
# (the view budget and its stopping rule). Prints wall time, CPU time, peak
# RSS, views visited and the scale against the reference and the truth.
# DPSFM_LARGE_ALL=1 also runs the 300 views with --DPScaleEstimator.all_views 1
# (about 16 min and 8 GB before the budget existed). Gates nothing.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="$(build_tree)"
colmap="$build_dir/colmap/src/colmap/exe/colmap"
large="$DPSFM_CACHE_DIR/large"
base="$large/base10_3000x2000_seed31"
mkdir -p "$large"
log "source: $(git -C "$DPSFM_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$DPSFM_ROOT" status --porcelain 2>/dev/null | grep -q . && echo ' (with uncommitted changes)')"
if [ ! -f "$base/ground_truth.json" ]; then
  log "generating the 10 distinct views (once) ..."
  rm -rf "$base"
  "$build_dir/examples/dpsfm_make_example" --output_path "$base" --seed 31 \
    --num_views 10 --width 3000 --height 2000 >"$base.log" 2>&1 \
    || die "generation failed: $base.log"
fi
rm -rf "$large/repeat300"
"$build_dir/examples/dpsfm_repeat_workspace" --input_path "$base" \
  --output_path "$large/repeat300" --times 30 >&2 || die "repeat failed"
truth="$(python3 -c "import json,sys;print(json.load(open(sys.argv[1]))['scale'])" "$base/ground_truth.json")"

run() {  # name workspace extra-args...
  local name="$1"
  shift
  timed_dry_run "$colmap" "$large/$name" "$@"
}
run reference10 "$base" --DPScaleEstimator.all_views 1
run budget300 "$large/repeat300"
[ "${DPSFM_LARGE_ALL:-0}" = 1 ] && run all300 "$large/repeat300" \
  --DPScaleEstimator.all_views 1

python3 - "$large" "$truth" <<'PY'
import json, os, sys
large, truth = sys.argv[1], float(sys.argv[2])
ref = json.load(open(os.path.join(large, "reference10.json")))
print("\n| run | views visited | wall (s) | CPU (s) | peak RSS (GB) | s / s_reference | inside the reference's interval | r_s = s / s_true | 95 % interval / s_true |")
print("|---|---|---|---|---|---|---|---|---|")
for name in ["reference10", "budget300", "all300"]:
    path = os.path.join(large, name + ".json")
    if not os.path.exists(os.path.join(large, name + ".time")):
        continue
    wall, user, system, rss_kb = open(os.path.join(large, name + ".time")).read().split()[-4:]
    try:
        r = json.load(open(path))
    except Exception:
        r = {}
    vb = r.get("view_budget", {})
    if r.get("success"):
        s = r["scale"]
        inside = ref["scale_ci_low"] <= s <= ref["scale_ci_high"]
        print("| %s | %s of %s | %.1f | %.1f | %.2f | %.4f | %s | %.4f | [%.4f, %.4f] |" % (
            name, vb.get("views_visited"), vb.get("views_total"), float(wall),
            float(user) + float(system), float(rss_kb) / 1024 / 1024,
            s / ref["scale"], "yes" if inside else "NO", s / truth,
            r["scale_ci_low"] / truth, r["scale_ci_high"] / truth))
    else:
        print("| %s | refused | %.1f | | | | | | |" % (name, float(wall)))
    if vb.get("stop_reason"):
        print("\n%s: %s" % (name, vb["stop_reason"]))
PY
