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
mkdir -p "$out/bin" "$out/srgb8" "$out/linear16"
cp "$build_dir/colmap/src/colmap/exe/colmap" \
   "$build_dir/examples/dpsfm_make_realdp_workspace" "$out/bin/"
colmap="$out/bin/colmap"
log "source: $(git -C "$DPSFM_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$DPSFM_ROOT" status --porcelain 2>/dev/null | grep -q . && echo ' (with uncommitted changes)'); captures: $realdp"

# Every command with its default geometry, as a new user would run it.

start=$SECONDS
# The frames as given (8-bit sRGB) and as 16-bit linear light (their inverse
# sRGB, as DPRSplit output would be): the answers must agree.
encodings=(srgb8 linear16)
calibrate() {  # encoding
  local enc="$1" cal="$out/calibration/$1" d f
  mkdir -p "$cal/dp/left" "$cal/dp/right"
  echo "name,target_distance_m,focus_distance_m,focal_length_mm,f_number,pixel_pitch_um" >"$cal/targets.csv"
  for d in 0600 1500; do
    for f in f4 f20; do
      "$out/bin/dpsfm_make_realdp_workspace" --capture_path "$realdp/flat/001/$d/$f" \
        --output_path "$cal" --name "${d}_$f" --frames_only 1 \
        --linear16 "$([ "$enc" = linear16 ] && echo 1 || echo 0)" >/dev/null \
        || die "calibration frames failed: flat/001/$d/$f"
      echo "${d}_$f.png,$(awk "BEGIN{print $d/1000}"),,49.57,${f#f},46.875" >>"$cal/targets.csv"
    done
  done
  "$colmap" dp_psf_calibrator --dp_image_path "$cal/dp" \
    --targets_path "$cal/targets.csv" --output_path "$cal/r6m2_rf50_f4.dpsf" \
    --DPPsfCalibrator.camera "Canon / Canon EOS R6m2" \
    --DPPsfCalibrator.lens "RF50mm F1.8 STM" >"$cal/log" 2>&1 \
    || { tail -n 3 "$cal/log" >&2; log "calibration ($enc) failed"; return 0; }
  log "calibration ($enc): $(grep -o 'centroid offset [0-9.]* R (95.*' "$cal/log" | tail -n 1)"
  log "  $(grep -o 'Profile: .*' "$cal/log" | tail -n 1)"
}
for enc in "${encodings[@]}"; do calibrate "$enc"; done

scenes=(casual/orbbec/001 casual/orbbec/002 casual/orbbec/003
        casual/iphone/001 casual/iphone/002 box/001 box/002)
modes=(defaults defaults_focus calibrated calibrated_focus translating_disk)
results="$out/results.tsv"
: >"$results"
for enc in "${encodings[@]}"; do
  profile="$out/calibration/$enc/r6m2_rf50_f4.dpsf"
  for scene in "${scenes[@]}"; do
    name="${scene//\//_}"
    ws="$out/$enc/$name"
    "$out/bin/dpsfm_make_realdp_workspace" --capture_path "$realdp/$scene" \
      --output_path "$ws" --name "$name" --true_scale "$truth" \
      --recorded_focus_m 1.0 --linear16 "$([ "$enc" = linear16 ] && echo 1 || echo 0)" \
      >"$ws.make.log" 2>&1 || die "workspace failed: $ws.make.log"
    # The same lens data without the recorded focus.
    cut -d, -f1-4 "$ws/lens.csv" >"$ws/lens_no_focus.csv"
    for mode in "${modes[@]}"; do
      args=(--lens_path "$ws/lens_no_focus.csv")
      case "$mode" in
        defaults_focus) args=(--lens_path "$ws/lens.csv") ;;
        translating_disk) args+=(--DPScaleEstimator.psf_model translating_disk) ;;
        calibrated) args+=(--DPScaleEstimator.psf_model calibrated
                           --DPScaleEstimator.psf_path "$profile") ;;
        calibrated_focus) args=(--lens_path "$ws/lens.csv"
                                --DPScaleEstimator.psf_model calibrated
                                --DPScaleEstimator.psf_path "$profile") ;;
      esac
      if [[ "$mode" == calibrated* && ! -f "$profile" ]]; then
        printf '%s\t%s\t%s\t\t\t\t\tno profile (calibration refused)\t\t\t\t\n' "$enc" "$name" "$mode" >>"$results"
        continue
      fi
      report="$ws.$mode.json"
      "$colmap" dp_scale_estimator --workspace_path "$ws/dense" \
        --dp_image_path "$ws/dp" --dry_run 1 --report_path "$report" \
        "${args[@]}" >"$ws.$mode.log" 2>&1 || true
      python3 - "$report" "$ws.$mode.log" "$truth" "$name" "$mode" "$enc" >>"$results" <<'PY'
import json, sys
report, log, truth, name, mode, enc = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4], sys.argv[5], sys.argv[6]
try:
    r = json.load(open(report))
except Exception:
    r = {}
cues = r.get("cues", {})
def cue(c):
    c = cues.get(c, {})
    if not c.get("valid"):
        return ""
    return "%.3f [%.3f, %.3f]" % (c["scale"] / truth, c["ci"][0] / truth, c["ci"][1] / truth)
if r.get("success") and r.get("scale"):
    v = next(iter(r["views"].values()))
    lo, hi = r["scale_ci_low"] / truth, r["scale_ci_high"] / truth
    print("\t".join([enc, name, mode, "%.3f" % (r["scale"] / truth), "%.3f" % lo, "%.3f" % hi,
                     "%.2f" % (v.get("focus_distance_m") or float("nan")), "",
                     cue("dual_pixel"), cue("recorded_focus"), cues.get("agreement", ""),
                     r.get("scale_source", "")]))
else:
    err = open(log).read().split("ERROR: dp_scale_estimator: no scale: ")[-1]
    print("\t".join([enc, name, mode, "", "", "", "", err.strip().splitlines()[0][:110] if err.strip() else "failed",
                     cue("dual_pixel"), cue("recorded_focus"), cues.get("agreement", ""), ""]))
PY
    done
  done
done

python3 - "$results" <<'PY'
import sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
print("\n| encoding | scene | mode | r_s | 95 % interval | from | focus (m) | DP cue | recorded-focus cue | or refused because |")
print("|---|---|---|---|---|---|---|---|---|---|")
for enc, name, mode, rs, lo, hi, g, why, dp, fc, agree, source in rows:
    if rs:
        print("| %s | %s | %s | %s | [%s, %s] | %s | %s | %s | %s %s | |" % (enc, name, mode, rs, lo, hi, source, g, dp, fc, agree))
    else:
        print("| %s | %s | %s | | | | | %s | %s | %s |" % (enc, name, mode, dp, fc, why))
print("\n| encoding | mode | answered | within 10 % | intervals holding the truth | confidently wrong | e_s over answers |")
print("|---|---|---|---|---|---|---|")
for enc in ["srgb8", "linear16"]:
    for mode in ["defaults", "defaults_focus", "calibrated", "calibrated_focus", "translating_disk"]:
        mine = [r for r in rows if r[0] == enc and r[2] == mode]
        ans = [r for r in mine if r[3]]
        es = sum(abs(1 - float(r[3])) for r in ans) / len(ans) if ans else float("nan")
        hold = sum(1 for r in ans if float(r[4]) <= 1 <= float(r[5]))
        near = sum(1 for r in ans if abs(1 - float(r[3])) <= 0.10)
        wrong = sum(1 for r in ans if abs(1 - float(r[3])) > 0.10 and not float(r[4]) <= 1 <= float(r[5]))
        print("| %s | %s | %d of %d | %d | %d of %d | %d | %s |" % (enc, mode, len(ans), len(mine), near, hold, len(ans), wrong, "%.3f" % es if ans else "-"))
PY
log "total $((SECONDS - start)) s; reports, logs and the profiles in $out"
