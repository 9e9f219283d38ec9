#!/usr/bin/env bash
# DP PSF profile benchmark (`make profiles`): generated scenes whose sensor
# has a DP split profile other than the paper's translating disk (sharper,
# softer, crosstalk, a soft rim, a split that changes across the frame) and
# the translating disk itself. Each scene comes with calibration captures of
# a planar target made by the same simulated camera; `colmap
# dp_psf_calibrator` turns them into a profile file. `colmap
# dp_scale_estimator` then runs with --DPScaleEstimator.psf_model
# translating_disk, auto and calibrated (dry runs). Prints r_s = s_est /
# s_true per scene and mode, e_s per profile and mode, and the runtime of
# `auto` against `translating_disk`. Prints tables; gates nothing.
#
# Environment: DPSFM_PROFILE_DIR (default <cache>/profiles),
# DPSFM_PROFILE_SEEDS (scenes per profile, default 2).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="$(build_tree)"
colmap="$build_dir/colmap/src/colmap/exe/colmap"
generator="$build_dir/examples/dpsfm_make_example"
out="${DPSFM_PROFILE_DIR:-$DPSFM_CACHE_DIR/profiles}"
seeds="${DPSFM_PROFILE_SEEDS:-2}"
rm -rf "$out"
mkdir -p "$out/bin"
# Run copies of the binaries: a rebuild in the same tree during the run
# must not change them halfway.
cp "$colmap" "$generator" "$out/bin/"
colmap="$out/bin/colmap"
generator="$out/bin/dpsfm_make_example"
log "source: $(git -C "$DPSFM_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$DPSFM_ROOT" status --porcelain 2>/dev/null | grep -q . && echo ' (with uncommitted changes)')"

# name | generator options for the sensor's DP PSF.
profiles=(
  "translating disk (the model)|"
  "sharp split (p 0.35)|--psf_split_exponent 0.35"
  "soft split (p 2.2)|--psf_split_exponent 2.2"
  "crosstalk 0.12|--psf_crosstalk 0.12"
  "soft rim 0.2, split p 0.6|--psf_split_exponent 0.6 --psf_rim_softness 0.2"
  "split changing across the frame (p 0.4 to 1.5)|--psf_split_exponent 0.4 --psf_split_exponent_right 1.5"
)
modes=(translating_disk auto calibrated)
scenes=(tabletop planes facade)

results="$out/results.tsv"
: >"$results"
p=0
for entry in "${profiles[@]}"; do
  name="${entry%%|*}"
  flags="${entry#*|}"
  for ((k = 0; k < seeds; ++k)); do
    scene="${scenes[$((k % ${#scenes[@]}))]}"
    dir="$out/p${p}_s${k}"
    # shellcheck disable=SC2086
    "$generator" --output_path "$dir" --seed $((100 + 10 * p + k)) \
      --scene "$scene" --num_views 8 --calibration_captures 6 $flags \
      >"$dir.generate.log" 2>&1 || die "generation failed: $dir.generate.log"
    truth="$(python3 -c "import json,sys;print(json.load(open(sys.argv[1]))['scale'])" "$dir/ground_truth.json")"
    calibrated_args=()
    if "$colmap" dp_psf_calibrator --dp_image_path "$dir/calibration/dp" \
        --targets_path "$dir/calibration/targets.csv" \
        --output_path "$dir/camera.dpsf" \
        --DPPsfCalibrator.transfer_uncertainty 0 >"$dir.calibrate.log" 2>&1; then
      calibrated_args=(--DPScaleEstimator.psf_path "$dir/camera.dpsf")
    fi
    for mode in "${modes[@]}"; do
      args=()
      [ "$mode" = calibrated ] && args=("${calibrated_args[@]}")
      if [ "$mode" = calibrated ] && [ ${#args[@]} -eq 0 ]; then
        printf '%s\t%s\t%s\t%s\t%s\n' "$p" "$name" "$scene" "$mode" "no-calibration" >>"$results"
        continue
      fi
      start=$(date +%s.%N)
      if "$colmap" dp_scale_estimator --workspace_path "$dir/dense" \
          --dp_image_path "$dir/dp" --lens_path "$dir/lens.csv" --dry_run 1 \
          --report_path "$dir/report_$mode.json" \
          --DPScaleEstimator.psf_model "$mode" "${args[@]}" \
          >"$dir.$mode.log" 2>&1; then
        seconds=$(python3 -c "import sys;print(float(sys.argv[2])-float(sys.argv[1]))" "$start" "$(date +%s.%N)")
        ratio="$(python3 -c "import json,sys;print(json.load(open(sys.argv[1]))['scale']/float(sys.argv[2]))" "$dir/report_$mode.json" "$truth")"
        printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$p" "$name" "$scene" "$mode" "$ratio" "$seconds" >>"$results"
      else
        printf '%s\t%s\t%s\t%s\t%s\n' "$p" "$name" "$scene" "$mode" "refused" >>"$results"
      fi
    done
    log "profile '$name', $scene: $(grep -P "^$p\t.*\t$scene\t" "$results" | cut -f4,5 | tr '\t\n' '= ')"
  done
  p=$((p + 1))
done

python3 - "$results" <<'PY'
import collections, sys
rows = [line.rstrip("\n").split("\t") for line in open(sys.argv[1]) if line.strip()]
modes = ["translating_disk", "auto", "calibrated"]
cells = collections.OrderedDict()
times = collections.defaultdict(float)
for row in rows:
    key = row[1]
    cells.setdefault(key, {m: [] for m in modes})
    value = row[4]
    cells[key][row[3]].append(value)
    if len(row) > 5:
        times[row[3]] += float(row[5])
print("| true profile | " + " | ".join("r_s " + m for m in modes) + " | " +
      " | ".join("e_s " + m for m in modes) + " |")
print("|---" * 7 + "|")
totals = {m: [] for m in modes}
for name, by_mode in cells.items():
    line = "| " + name + " |"
    for m in modes:
        line += " " + ", ".join(
            "%.3f" % float(v) if v not in ("refused", "no-calibration") else v
            for v in by_mode[m]) + " |"
    for m in modes:
        errs = [abs(1 - float(v)) for v in by_mode[m]
                if v not in ("refused", "no-calibration")]
        if name != "translating disk (the model)":
            totals[m] += errs
        line += (" %.3f |" % (sum(errs) / len(errs))) if errs else " - |"
    print(line)
print("| **mean, non-model profiles** | | | | " + " | ".join(
    ("%.3f" % (sum(t) / len(t))) if t else "-" for t in
    (totals[m] for m in modes)) + " |")
if times["translating_disk"] > 0:
    print("\nruntime of the estimation runs: translating_disk %.1f s, auto %.1f s "
          "(x %.2f), calibrated %.1f s" % (times["translating_disk"], times["auto"],
          times["auto"] / times["translating_disk"], times["calibrated"]))
PY
