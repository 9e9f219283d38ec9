#!/usr/bin/env bash
# Real dual-pixel captures benchmark (`make real`): the Canon EOS R6 Mark II
# + RF 50 mm f/4 captures with measured depth in ../shared/realdp (read in
# place, never copied into the repository). Each scene becomes a
# single-view dense workspace whose depth is the measured depth divided by
# a known factor (dpsfm_make_realdp_workspace); the camera's DP profile is
# calibrated from the flat-plane captures (0.6 m and 1.5 m at f/4 and f/20,
# focus unknown) with `colmap dp_psf_calibrator`; `colmap
# dp_scale_estimator` then runs per scene with the defaults (auto; lens.csv
# records the nominal 1 m focus, which the scale is pinned to when the DP
# profile leaves it open), with the defaults but that pin off, with the
# paper's translating disk, and with the calibrated profile. Prints
# r_s = s_est / s_true, its 95 % interval and the focus distance per scene
# and mode, and per mode the answers, e_s over them and how many intervals
# hold the truth. Prints tables; gates nothing.
#
# Environment: DPSFM_REALDP_DIR (default ../shared/realdp next to the
# clone, then /work/shared/realdp), DPSFM_REAL_DIR (output, default
# <cache>/real), DPSFM_REAL_SCALE (the known factor, default 0.37).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

find_realdp() {
  local d
  for d in "${DPSFM_REALDP_DIR:-}" "$DPSFM_ROOT/../shared/realdp" /work/shared/realdp; do
    [ -n "$d" ] && [ -d "$d/canon_r6m2_rf50" ] && { (cd "$d" && pwd); return; }
  done
  die "no real DP captures found (set DPSFM_REALDP_DIR to the folder holding canon_r6m2_rf50/)"
}
realdp="$(find_realdp)/canon_r6m2_rf50"
build_dir="$(build_tree)"
out="${DPSFM_REAL_DIR:-$DPSFM_CACHE_DIR/real}"
truth="${DPSFM_REAL_SCALE:-0.37}"
rm -rf "$out"
mkdir -p "$out/bin" "$out/calibration/dp/left" "$out/calibration/dp/right"
cp "$build_dir/colmap/src/colmap/exe/colmap" \
   "$build_dir/examples/dpsfm_make_realdp_workspace" "$out/bin/"
colmap="$out/bin/colmap"
log "source: $(git -C "$DPSFM_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$DPSFM_ROOT" status --porcelain 2>/dev/null | grep -q . && echo ' (with uncommitted changes)'); captures: $realdp"

# Every command with its default geometry, as a new user would run it.

start=$SECONDS
targets="$out/calibration/targets.csv"
echo "name,target_distance_m,focus_distance_m,focal_length_mm,f_number,pixel_pitch_um" >"$targets"
for d in 0600 1500; do
  for f in f4 f20; do
    cp "$realdp/flat/001/$d/$f/l.png" "$out/calibration/dp/left/${d}_$f.png"
    cp "$realdp/flat/001/$d/$f/r.png" "$out/calibration/dp/right/${d}_$f.png"
    echo "${d}_$f.png,$(awk "BEGIN{print $d/1000}"),,49.57,${f#f},46.875" >>"$targets"
  done
done
"$colmap" dp_psf_calibrator --dp_image_path "$out/calibration/dp" \
  --targets_path "$targets" --output_path "$out/calibration/r6m2_rf50_f4.dpsf" \
  --DPPsfCalibrator.camera "Canon / Canon EOS R6m2" \
  --DPPsfCalibrator.lens "RF50mm F1.8 STM" >"$out/calibration/log" 2>&1 \
  || { tail -n 3 "$out/calibration/log" >&2; die "calibration failed"; }
log "calibration ($((SECONDS - start)) s): $(grep -o 'centroid offset [0-9.]* R (95.*' "$out/calibration/log" | tail -n 1)"
log "measured shape: $(grep -o 'kernel shapes measured.*' "$out/calibration/log" | tail -n 1)"
# The same calibration with the split family's shape at the fitted strength
# instead of the deconvolved kernels, for comparison.
"$colmap" dp_psf_calibrator --dp_image_path "$out/calibration/dp" \
  --targets_path "$targets" --output_path "$out/calibration/family.dpsf" \
  --DPPsfCalibrator.measure_shape 0 >"$out/calibration/family.log" 2>&1 \
  || { tail -n 3 "$out/calibration/family.log" >&2; die "calibration failed"; }

scenes=(casual/orbbec/001 casual/orbbec/002 casual/orbbec/003 box/001 box/002)
modes=(defaults no_focus_pin translating_disk calibrated calibrated_no_pin
       family family_no_pin)
results="$out/results.tsv"
: >"$results"
for scene in "${scenes[@]}"; do
  name="${scene//\//_}"
  "$out/bin/dpsfm_make_realdp_workspace" --capture_path "$realdp/$scene" \
    --output_path "$out/$name" --name "$name" --true_scale "$truth" \
    --recorded_focus_m 1.0 \
    >"$out/$name.make.log" 2>&1 || die "workspace failed: $out/$name.make.log"
  for mode in "${modes[@]}"; do
    args=()
    case "$mode" in
      no_focus_pin) args=(--DPScaleEstimator.pin_to_recorded_focus 0) ;;
      translating_disk) args=(--DPScaleEstimator.psf_model translating_disk) ;;
      calibrated) args=(--DPScaleEstimator.psf_model calibrated
                        --DPScaleEstimator.psf_path "$out/calibration/r6m2_rf50_f4.dpsf") ;;
      calibrated_no_pin) args=(--DPScaleEstimator.psf_model calibrated
                        --DPScaleEstimator.psf_path "$out/calibration/r6m2_rf50_f4.dpsf"
                        --DPScaleEstimator.pin_to_recorded_focus 0) ;;
      family) args=(--DPScaleEstimator.psf_model calibrated
                    --DPScaleEstimator.psf_path "$out/calibration/family.dpsf") ;;
      family_no_pin) args=(--DPScaleEstimator.psf_model calibrated
                    --DPScaleEstimator.psf_path "$out/calibration/family.dpsf"
                    --DPScaleEstimator.pin_to_recorded_focus 0) ;;
    esac
    report="$out/$name.$mode.json"
    t0=$SECONDS
    "$colmap" dp_scale_estimator --workspace_path "$out/$name/dense" \
      --dp_image_path "$out/$name/dp" --lens_path "$out/$name/lens.csv" \
      --dry_run 1 --report_path "$report" "${args[@]}" \
      >"$out/$name.$mode.log" 2>&1 || true
    python3 - "$report" "$out/$name.$mode.log" "$truth" "$name" "$mode" >>"$results" <<'PY'
import json, sys
report, log, truth, name, mode = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4], sys.argv[5]
try:
    r = json.load(open(report))
except Exception:
    r = {}
if r.get("success") and r.get("scale"):
    v = next(iter(r["views"].values()))
    lo, hi = r["scale_ci_low"] / truth, r["scale_ci_high"] / truth
    fc = r.get("focus_check", {})
    rec = "%.3f" % (fc["scale_from_recorded_focus"] / truth) if fc.get("scale_from_recorded_focus") else ""
    print("\t".join([name, mode, "%.3f" % (r["scale"] / truth), "%.3f" % lo, "%.3f" % hi,
                     "%.2f" % (v.get("focus_distance_m") or float("nan")), "", rec,
                     "agrees" if fc.get("agrees") else ("DISAGREES" if fc else ""),
                     r.get("scale_source", "")]))
else:
    err = open(log).read().split("ERROR: dp_scale_estimator: no scale: ")[-1]
    print("\t".join([name, mode, "", "", "", "", err.strip().splitlines()[0][:110] if err.strip() else "failed", "", "", ""]))
PY
  done
done

python3 - "$results" <<'PY'
import sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
print("\n| scene | mode | r_s | 95 % interval | from | focus (m) | r_s from the recorded 1 m focus | or refused because |")
print("|---|---|---|---|---|---|---|---|")
for name, mode, rs, lo, hi, g, why, rec, agree, source in rows:
    if rs:
        print("| %s | %s | %s | [%s, %s] | %s | %s | %s %s | |" % (name, mode, rs, lo, hi, source, g, rec, agree))
    else:
        print("| %s | %s | | | | | | %s |" % (name, mode, why))
print("\n| mode | answered | e_s over answers | intervals holding the truth |")
print("|---|---|---|---|")
for mode in ["defaults", "no_focus_pin", "translating_disk", "calibrated",
             "calibrated_no_pin", "family", "family_no_pin"]:
    ans = [r for r in rows if r[1] == mode and r[2]]
    n = len([r for r in rows if r[1] == mode])
    es = sum(abs(1 - float(r[2])) for r in ans) / len(ans) if ans else float("nan")
    hold = sum(1 for r in ans if float(r[3]) <= 1 <= float(r[4]))
    print("| %s | %d of %d | %s | %d of %d |" % (mode, len(ans), n, "%.3f" % es if ans else "-", hold, len(ans)))
PY
log "total $((SECONDS - start)) s; reports, logs and the profile in $out"
