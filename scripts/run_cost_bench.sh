#!/usr/bin/env bash
# Cost benchmark (part of `make bench`, alone `make cost`): where the time
# of `colmap dp_scale_estimator` goes, per stage and per PSF path, against
# the time to decode the DP frames. Dry runs, defaults otherwise:
#  - scenes of `make accuracy` (accuracy_suite.sh, the same generator
#    options and seeds, plus calibration captures of a planar target made by
#    the same simulated camera), each with the self-calibrated profile
#    (auto), the paper's translating disk, and a measured-kernel profile
#    calibrated from the captures with `colmap dp_psf_calibrator` (as
#    `make profiles` does: the captures' camera and lens setting are the
#    scene's, so no transfer uncertainty);
#  - three of the seven real Canon R6 II scenes of `make real`
#    (realdp_captures.sh; single views of 768x512, 8-bit sRGB as given,
#    with the recorded "1 m" focus: without it these refuse before the
#    intensity stage), with auto, the translating disk and the camera's
#    profile as `make real` calibrates it from the flat planes, and the
#    last two again at one search bound (8 px: the profile reads these
#    views' blur larger and grows its bound where the disk refuses at its
#    first, so without it the two compare different work);
#  - the 300-view workspace of `make large` (3000x2000, the view budget),
#    with auto, the translating disk and the measured-kernel profile of
#    tabletop_50f2.8 (the same generated camera and lens, 50 mm f/2.8, whose
#    captures are 1200x800: the profile carries over to the 3000x2000
#    frames of the same sensor), when that scene's profile has been made.
# Each run's figures are the median of DPSFM_COST_RUNS runs (3): decode
# (the report's `read`: reading and decoding the frames, in the read-ahead
# thread, a view's two files at once: wall time), blur search, profile fit, linear, intensity (the final
# estimate's), the view budget's checkpoints (their estimates in sum), the
# estimate's total (the report's `total`), after it (wall minus total:
# plots, report, start-up), wall, peak RSS, and total / decode. Prints
# tables; gates nothing.
#
# Environment: DPSFM_COST_SCENES (accuracy scene ids, default below),
# DPSFM_COST_RUNS (3), DPSFM_COST_REAL=0 (skip the real scenes; they are
# left out without the captures), DPSFM_COST_LARGE=0 (skip the 300 views),
# DPSFM_COST_COLMAP (another binary that has dp_scale_estimator, e.g. an
# older build's or `dpsfm`, to compare; the profiles are calibrated with
# the tree's own), DPSFM_COST_BEFORE (a binary to compare with, run in turn
# with the measured one: each run of the one is followed by the same run of
# the other, so both see the machine as it is then, and a before -> after
# table follows; two binaries measured one after the other drifted by
# several per cent against each other, docs/benchmark.md),
# DPSFM_COST_DIR (<cache>/cost).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
source "$(dirname "${BASH_SOURCE[0]}")/accuracy_suite.sh"
source "$(dirname "${BASH_SOURCE[0]}")/realdp_captures.sh"

build_dir="$(build_tree)"
out="${DPSFM_COST_DIR:-$DPSFM_CACHE_DIR/cost}"
runs="${DPSFM_COST_RUNS:-3}"
# Six of the 29: the three scene types, a phone (2016x1512 frames; `auto`
# refuses it, as make accuracy does), sensor noise and a gain artefact.
read -r -a scenes <<<"${DPSFM_COST_SCENES:-tabletop_50f2.8 facade_85f4 planes_35f2 tabletop_phone planes_noise planes_gain}"
mkdir -p "$out/scenes" "$out/runs" "$out/bin"
# Run copies of the binaries: a rebuild during the benchmark must not
# change them halfway.
cp "$build_dir/colmap/src/colmap/exe/colmap" "$build_dir/examples/dpsfm_make_example" \
   "$build_dir/examples/dpsfm_make_realdp_workspace" "$out/bin/"
calibrator="$out/bin/colmap"
colmap="${DPSFM_COST_COLMAP:-$out/bin/colmap}"
before="${DPSFM_COST_BEFORE:-}"
if [ -n "$before" ]; then
  [ -x "$before" ] || die "DPSFM_COST_BEFORE: no binary at $before"
  cp "$before" "$out/bin/colmap-before"
  before="$out/bin/colmap-before"
fi
generator="$out/bin/dpsfm_make_example"
log "source: $(git -C "$DPSFM_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$DPSFM_ROOT" status --porcelain 2>/dev/null | grep -q . && echo ' (with uncommitted changes)'); estimating with $colmap${before:+, in turn with $before}"

# 1. The scenes and their profiles, made once (kept while their generator
# options are the same).
for id in "${scenes[@]}"; do
  k="$(suite_index "$id")" || die "no accuracy scene '$id' (accuracy_suite.sh)"
  entry="${suite[$((k - 1))]}"
  options="--seed $((100 + k)) --num_views 8 $(field "$entry" 5) --calibration_captures 6"
  dir="$out/scenes/$id"
  key="$options; dp_psf_calibrator --DPPsfCalibrator.transfer_uncertainty 0"
  if [ "$(cat "$dir.options" 2>/dev/null)" != "$key" ]; then
    rm -rf "$dir" "$dir.options"
    log "generating $id ..."
    # shellcheck disable=SC2086
    "$generator" --output_path "$dir" $options >"$dir.generate.log" 2>&1 \
      || die "generation failed: $dir.generate.log"
    "$calibrator" dp_psf_calibrator --dp_image_path "$dir/calibration/dp" \
      --targets_path "$dir/calibration/targets.csv" \
      --output_path "$dir/camera.dpsf" \
      --DPPsfCalibrator.transfer_uncertainty 0 >"$dir.calibrate.log" 2>&1 \
      || log "$id: no profile from its captures ($(tail -n 1 "$dir.calibrate.log"))"
    echo "$key" >"$dir.options"
  fi
done
# The real scenes and the camera's profile, made once per captures folder.
real_scenes=(box/001 casual/orbbec/001 casual/iphone/001)
real_names=()
if [ "${DPSFM_COST_REAL:-1}" = 1 ]; then
  if ! realdp="$(find_realdp 2>/dev/null)"; then
    log "no real DP captures (DPSFM_REALDP_DIR): the real scenes are left out"
  else
    realdp="$realdp/canon_r6m2_rf50"
    real="$out/real"
    focus_m=1.0  # the captures' recorded focus
    for scene in "${real_scenes[@]}"; do real_names+=("r6m2_${scene//\//_}"); done
    key="$realdp; --recorded_focus_m $focus_m"
    if [ "$(cat "$real.options" 2>/dev/null)" != "$key" ]; then
      rm -rf "$real" "$real.options"
      log "calibrating the R6 II profile from $realdp/flat ..."
      realdp_calibration_set "$realdp" "$out/bin/dpsfm_make_realdp_workspace" "$real/calibration" srgb8
      realdp_calibrate "$calibrator" "$real/calibration" \
        || die "calibration failed: $real/calibration/log"
      for k in "${!real_scenes[@]}"; do
        scene="${real_scenes[k]}" name="${real_names[k]}"
        "$out/bin/dpsfm_make_realdp_workspace" --capture_path "$realdp/$scene" \
          --output_path "$real/$name" --name "${name#r6m2_}" \
          --recorded_focus_m "$focus_m" >"$real/$name.make.log" 2>&1 \
          || die "workspace failed: $real/$name.make.log"
      done
      echo "$key" >"$real.options"
    fi
  fi
fi
large_ws=""
if [ "${DPSFM_COST_LARGE:-1}" = 1 ]; then
  base="$DPSFM_CACHE_DIR/large/base10_3000x2000_seed31"
  if [ ! -f "$base/ground_truth.json" ]; then
    log "no $base: run make large once (it generates the 10 views, about 15 min); the 300 views are left out"
  else
    rm -rf "$out/large300"
    "$build_dir/examples/dpsfm_repeat_workspace" --input_path "$base" \
      --output_path "$out/large300" --times 30 >&2 || die "repeat failed"
    large_ws="$out/large300"
  fi
fi

# 2. The runs: run NAME WORKSPACE_ROOT ARGS... (one dry run, its report and
# /usr/bin/time's figures kept as runs/NAME.json and runs/NAME.time).
run() {
  local name="$1"
  shift
  if [ -n "$before" ]; then
    timed_dry_run "$before" "$out/runs-before/$name" "$@"
  fi
  timed_dry_run "$colmap" "$out/runs/$name" "$@"
}
rm -rf "$out/runs-before"
rm -f "$out"/runs/*
[ -z "$before" ] || mkdir -p "$out/runs-before"
real_bound=8
start=$SECONDS
for ((i = 1; i <= runs; ++i)); do
  for id in "${scenes[@]}"; do
    dir="$out/scenes/$id"
    run "$id.auto.$i" "$dir"
    run "$id.translating_disk.$i" "$dir" --DPScaleEstimator.psf_model translating_disk
    if [ -f "$dir/camera.dpsf" ]; then
      run "$id.measured_kernels.$i" "$dir" --DPScaleEstimator.psf_model calibrated \
        --DPScaleEstimator.psf_path "$dir/camera.dpsf"
    fi
  done
  for name in "${real_names[@]}"; do
    dir="$out/real/$name"
    run "$name.auto.$i" "$dir"
    run "$name.translating_disk.$i" "$dir" --DPScaleEstimator.psf_model translating_disk
    run "$name.measured_kernels.$i" "$dir" --DPScaleEstimator.psf_model calibrated \
      --DPScaleEstimator.psf_path "$out/real/calibration/r6m2_rf50_f4.dpsf"
    # The same two at one search bound: the measured profile reads these
    # views' blur larger and grows its bound (3.5 -> 8 px) where the disk
    # refuses at its first, so the rows above compare different work.
    run "$name.translating_disk_at_${real_bound}px.$i" "$dir" \
      --DPScaleEstimator.psf_model translating_disk --DPScaleEstimator.max_radius_px "$real_bound"
    run "$name.measured_kernels_at_${real_bound}px.$i" "$dir" --DPScaleEstimator.psf_model calibrated \
      --DPScaleEstimator.psf_path "$out/real/calibration/r6m2_rf50_f4.dpsf" \
      --DPScaleEstimator.max_radius_px "$real_bound"
  done
  if [ -n "$large_ws" ]; then
    run "large300.auto.$i" "$large_ws"
    run "large300.translating_disk.$i" "$large_ws" --DPScaleEstimator.psf_model translating_disk
    large_profile="$out/scenes/tabletop_50f2.8/camera.dpsf"
    if [ -f "$large_profile" ]; then
      run "large300.measured_kernels.$i" "$large_ws" --DPScaleEstimator.psf_model calibrated \
        --DPScaleEstimator.psf_path "$large_profile"
    fi
  fi
  log "round $i of $runs done ($((SECONDS - start)) s)"
done

python3 - "$out/runs" "$runs" "$real_bound" "${before:+$out/runs-before}" <<'PY'
import collections, json, os, statistics, sys
runs_dir, runs, real_bound, before_dir = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]

def load(runs_dir):
    rows = collections.OrderedDict()
    for name in sorted(os.listdir(runs_dir)):
        if not name.endswith(".time"):
            continue
        scene, path, _ = name[:-5].rsplit(".", 2)
        wall, user, system, rss_kb = open(os.path.join(runs_dir, name)).read().split()[-4:]
        figures = {"wall": float(wall), "cpu": float(user) + float(system),
                   "rss": float(rss_kb) / 1024 / 1024}
        try:
            r = json.load(open(os.path.join(runs_dir, name[:-5] + ".json")))
        except Exception:
            r = {}
        t = r.get("timings", {})
        for key in ["read", "read_wait", "blur", "psf_fit", "linear", "intensity", "total"]:
            figures[key] = t.get(key, float("nan"))
        figures["after"] = figures["wall"] - figures["total"]
        # The view budget's checkpoints (each a whole estimate: profile fit,
        # linear, intensity); the profile fit and intensity columns are the
        # final estimate's alone.
        figures["checkpoints"] = sum(c.get("seconds", float("nan")) for c in
                                     r.get("view_budget", {}).get("checkpoints", []))
        figures["views"] = r.get("view_budget", {}).get("views_visited") or len(r.get("views", []))
        figures["scale"] = r.get("scale") if r.get("success") else None
        rows.setdefault((scene, path), []).append(figures)
    return rows

rows = load(runs_dir)

def median(values):
    values = [v for v in values if v == v]
    return statistics.median(values) if values else float("nan")

print("\nMedians of %d runs (seconds; decode = reading and decoding the frames,"
      " overlapped with the blur search but for `wait`):\n" % runs)
print("| scene | path | views | decode | wait | blur search | profile fit | linear | intensity | checkpoints | total | after | wall | peak RSS (GiB) | total / decode | scale |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
# Sums per group of scenes: the accuracy scenes, the real R6 II ones.
sums = collections.defaultdict(lambda: collections.defaultdict(lambda: [0.0, 0.0]))
totals = collections.defaultdict(lambda: collections.defaultdict(dict))
for (scene, path), figures in rows.items():
    m = {k: median([f[k] for f in figures]) for k in figures[0] if k not in ("scale",)}
    scales = {f["scale"] for f in figures}
    scale = ("%.6g" % figures[0]["scale"]) if figures[0]["scale"] else "refused"
    if len(scales) > 1:
        scale += " (runs differ)"
    ratio = m["total"] / m["read"] if m["read"] > 0 else float("nan")
    print("| %s | %s | %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %s |" % (
        scene, path, m["views"], m["read"], m["read_wait"], m["blur"], m["psf_fit"],
        m["linear"], m["intensity"], m["checkpoints"], m["total"], m["after"], m["wall"],
        m["rss"], ratio, scale))
    if not scene.startswith("large"):
        group = "Real R6 II scenes" if scene.startswith("r6m2_") else "Accuracy scenes"
        sums[group][path][0] += m["total"]
        sums[group][path][1] += m["read"]
        totals[group][scene][path] = m["total"]
    else:
        print("|  | per visited view | | | | | | | | | | | %.2f | %.3f | | |" % (
            m["wall"] / max(m["views"], 1), m["rss"] / max(m["views"], 1)))
for group, group_sums in sums.items():
    print("\n%s, in sum: " % group + "; ".join(
        "%s total %.1f s = %.1f x decode (%.1f s)" % (p, s[0], s[0] / s[1] if s[1] else float("nan"), s[1])
        for p, s in group_sums.items()))
    for suffix, where in (("", ""), ("_at_%spx" % real_bound,
                                     " at one search bound (%s px)" % real_bound)):
        m_path, d_path = "measured_kernels" + suffix, "translating_disk" + suffix
        both = [t for t in totals[group].values() if m_path in t and d_path in t]
        if both:
            print("Measured-kernel profile / translating disk%s, totals over the %d scenes that have both: %.2f"
                  % (where, len(both), sum(t[m_path] for t in both) / sum(t[d_path] for t in both)))

# Before -> after, from runs made in turn (DPSFM_COST_BEFORE).
if before_dir:
    before_rows = load(before_dir)
    keys = ["read", "blur", "psf_fit", "intensity", "checkpoints", "total", "wall", "cpu", "rss"]
    print("\nBefore -> after, medians of %d runs made in turn (seconds):\n" % runs)
    print("| scene | path | decode | blur search | profile fit | intensity | checkpoints | total | wall | CPU | peak RSS (GiB) | total / decode | scale before -> after |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    group_sums = collections.defaultdict(lambda: [0.0] * 6)
    for (scene, path), after in rows.items():
        old = before_rows.get((scene, path))
        if not old:
            continue
        mb = {k: median([f[k] for f in old]) for k in keys}
        ma = {k: median([f[k] for f in after]) for k in keys}
        cells = ["%.2f -> %.2f" % (mb[k], ma[k]) for k in keys]
        ratio = lambda m: m["total"] / m["read"] if m["read"] > 0 else float("nan")
        cells.append("%.1f -> %.1f" % (ratio(mb), ratio(ma)))
        sb, sa = old[0]["scale"], after[0]["scale"]
        if sb and sa:
            cells.append("%.6g -> %.6g (%+.1e)" % (sb, sa, sa / sb - 1))
        else:
            cells.append("%s -> %s" % ("%.6g" % sb if sb else "refused", "%.6g" % sa if sa else "refused"))
        print("| %s | %s | %s |" % (scene, path, " | ".join(cells)))
        if not scene.startswith("large") and not scene.startswith("r6m2_"):
            s = group_sums[path]
            for k, key in enumerate(["total", "read", "cpu"]):
                s[k] += mb[key]
                s[k + 3] += ma[key]
    # The decode column is the reads' wall time: a change in how frames are
    # read moves it, so the after total is also set against before's reads.
    for path, s in group_sums.items():
        print("\nAccuracy scenes, %s, in sum: total %.1f -> %.1f s (%+.1f %%), %.1fx -> %.1fx decode (%.1f -> %.1f s; after's total %.1fx before's decode), CPU %.1f -> %.1f s"
              % (path, s[0], s[3], 100 * (s[3] / s[0] - 1), s[0] / s[1], s[3] / s[4], s[1], s[4], s[3] / s[1], s[2], s[5]))
PY
log "cost benchmark took $((SECONDS - start)) s of runs"
