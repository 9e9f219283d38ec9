#!/usr/bin/env bash
# Real dual-pixel captures benchmark (`make real`): the Canon EOS R6 Mark II
# + RF 50 mm f/4 captures with measured depth in ../shared/realdp (read in
# place, never copied into the repository). Each of the seven scenes
# becomes a single-view dense workspace whose depth is the measured depth
# divided by a known factor (dpsfm_make_realdp_workspace), in two
# encodings: the 8-bit sRGB files as given, and 16-bit linear light (their
# inverse sRGB, as DPRSplit output would be). The camera's DP profile is
# calibrated from the flat-plane captures (0.6 m and 1.5 m at f/4 and f/20,
# focus unknown) in each encoding with `colmap dp_psf_calibrator`, with
# and without its transfer term; the calibrated profile takes the target
# distances from the lens's entrance pupil (39.9 mm in front of the
# focal-plane mark: the RF 50 mm's patent prescription traced paraxially,
# whole-group focus at ~0.95 m), the origin of the scenes' depths.
# `colmap dp_scale_estimator` then runs per
# scene and mode: the defaults (auto profile) without and with the
# recorded "1 m" focus in lens.csv, the calibrated profile without and
# with it, the paper's translating disk (checked against the data) without
# and with it, and the planes' own profile (no transfer term), with the
# target distances from the thin lens's position and from the entrance
# pupil.
# Prints per run r_s = s_est / s_true, its 95 % interval, and the two
# cues; per encoding and mode the answers, how many
# are within 10 %, how many intervals hold the truth, the confidently
# wrong ones and e_s; and the transfer table: the planes' own profile on
# every scene, left out in turn. Gates nothing.
#
# Environment: DPSFM_REALDP_DIR (default ../shared/realdp next to the
# clone, then /work/shared/realdp), DPSFM_REAL_DIR (output, default
# <cache>/real), DPSFM_REAL_SCALE (the known factor, default 0.37).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
source "$(dirname "${BASH_SOURCE[0]}")/realdp_captures.sh"

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
pupil_mm=$REALDP_ENTRANCE_PUPIL_MM
calibrate() {  # encoding
  local enc="$1" cal="$out/calibration/$1"
  realdp_calibration_set "$realdp" "$out/bin/dpsfm_make_realdp_workspace" "$cal" "$enc"
  realdp_calibrate "$colmap" "$cal" \
    || { tail -n 3 "$cal/log" >&2; log "calibration ($enc) failed"; return 0; }
  log "calibration ($enc): $(grep -o 'centroid offset [0-9.]* R (95.*' "$cal/log" | tail -n 1)"
  log "  $(grep -o 'Profile: .*' "$cal/log" | tail -n 1)"
  # The planes' own profile, without the transfer term: how far it carries
  # to the scenes is what this benchmark measures (the transfer table).
  "$colmap" dp_psf_calibrator --dp_image_path "$cal/dp" \
    --targets_path "$cal/targets.csv" --output_path "$cal/planes_only.dpsf" \
    --DPPsfCalibrator.transfer_uncertainty 0 >"$cal/planes_only.log" 2>&1 || true
  # The same with the distances from the entrance pupil (the origin of the
  # scenes' depths) instead of the thin lens's position.
  "$colmap" dp_psf_calibrator --dp_image_path "$cal/dp" \
    --targets_path "$cal/targets.csv" --output_path "$cal/planes_pupil.dpsf" \
    --DPPsfCalibrator.transfer_uncertainty 0 \
    --DPPsfCalibrator.entrance_pupil_mm "$pupil_mm" >"$cal/planes_pupil.log" 2>&1 || true
  # The same, were the planes' distances taken from the lens's front.
  awk -F, -v front="$REALDP_LENS_FRONT_MM" 'BEGIN { OFS = "," }
    NR > 1 { $2 = $2 + front / 1000 } { print }' "$cal/targets.csv" >"$cal/targets_front.csv"
  "$colmap" dp_psf_calibrator --dp_image_path "$cal/dp" \
    --targets_path "$cal/targets_front.csv" --output_path "$cal/planes_front.dpsf" \
    --DPPsfCalibrator.transfer_uncertainty 0 \
    --DPPsfCalibrator.entrance_pupil_mm "$pupil_mm" >"$cal/planes_front.log" 2>&1 || true
  log "  planes only: $(grep -o 'strength [0-9.]* R' "$cal/planes_only.dpsf" | head -n 1); with the entrance pupil at $pupil_mm mm: $(grep -o 'strength [0-9.]* R' "$cal/planes_pupil.dpsf" | head -n 1); from the lens front: $(grep -o 'strength [0-9.]* R' "$cal/planes_front.dpsf" | head -n 1)"
}
for enc in "${encodings[@]}"; do calibrate "$enc"; done

scenes=(casual/orbbec/001 casual/orbbec/002 casual/orbbec/003
        casual/iphone/001 casual/iphone/002 box/001 box/002)
modes=(defaults defaults_focus calibrated calibrated_focus translating_disk
       translating_disk_focus planes_only planes_pupil planes_front)
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
        translating_disk_focus) args=(--lens_path "$ws/lens.csv"
                                      --DPScaleEstimator.psf_model translating_disk) ;;
        calibrated) args+=(--DPScaleEstimator.psf_model calibrated
                           --DPScaleEstimator.psf_path "$profile") ;;
        calibrated_focus) args=(--lens_path "$ws/lens.csv"
                                --DPScaleEstimator.psf_model calibrated
                                --DPScaleEstimator.psf_path "$profile") ;;
        planes_only) args+=(--DPScaleEstimator.psf_model calibrated
                            --DPScaleEstimator.psf_path "$out/calibration/$enc/planes_only.dpsf") ;;
        planes_pupil) args+=(--DPScaleEstimator.psf_model calibrated
                             --DPScaleEstimator.psf_path "$out/calibration/$enc/planes_pupil.dpsf") ;;
        planes_front) args+=(--DPScaleEstimator.psf_model calibrated
                             --DPScaleEstimator.psf_path "$out/calibration/$enc/planes_front.dpsf") ;;
      esac
      if [[ "$mode" == calibrated* || "$mode" == planes_* ]] && [ ! -f "$profile" ]; then
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

python3 - "$results" "${encodings[*]}" "${modes[*]}" <<'PY'
import sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
encodings, modes = sys.argv[2].split(), sys.argv[3].split()
print("\n| encoding | scene | mode | r_s | 95 % interval | from | focus (m) | DP cue | recorded-focus cue | or refused because |")
print("|---|---|---|---|---|---|---|---|---|---|")
for enc, name, mode, rs, lo, hi, g, why, dp, fc, agree, source in rows:
    if rs:
        print("| %s | %s | %s | %s | [%s, %s] | %s | %s | %s | %s %s | |" % (enc, name, mode, rs, lo, hi, source, g, dp, fc, agree))
    else:
        print("| %s | %s | %s | | | | | %s | %s | %s |" % (enc, name, mode, dp, fc, why))
# The planes_* runs measure the DP cue under the planes' own profiles,
# calibrated with --DPPsfCalibrator.transfer_uncertainty 0: their intervals
# leave out, by construction, how the profile transfers from the planes to
# a scene, so they are summarised apart from the modes a user runs.
product = [m for m in modes if not m.startswith("planes_")]
measured = [m for m in modes if m.startswith("planes_")]
for title, group in (("the modes a user runs", product),
                     ("measurement runs (profiles without their transfer term)", measured)):
  print("\n%s" % title)
  print("| encoding | mode | answered | within 10 % | intervals holding the truth | confidently wrong | e_s over answers |")
  print("|---|---|---|---|---|---|---|")
  for enc in encodings:
    for mode in group:
        mine = [r for r in rows if r[0] == enc and r[2] == mode]
        ans = [r for r in mine if r[3]]
        es = sum(abs(1 - float(r[3])) for r in ans) / len(ans) if ans else float("nan")
        hold = sum(1 for r in ans if float(r[4]) <= 1 <= float(r[5]))
        near = sum(1 for r in ans if abs(1 - float(r[3])) <= 0.10)
        wrong = sum(1 for r in ans if abs(1 - float(r[3])) > 0.10 and not float(r[4]) <= 1 <= float(r[5]))
        print("| %s | %s | %d of %d | %d | %d of %d | %d | %s |" % (enc, mode, len(ans), len(mine), near, hold, len(ans), wrong, "%.3f" % es if ans else "-"))
PY
# Transfer: the planes' own profile (no transfer term, distances from the
# entrance pupil as the calibrated profile's) predicting each scene. Its DP
# cue is in the report whether or not the run answered. Leave one scene
# out: the transfer term from the other six (their largest |ln r_s|, as the
# calibrator's default was chosen from all seven) in quadrature with the
# profile's own uncertainty, applied to the held-out scene's DP interval as
# the estimator applies a profile's uncertainty. The blur ratio: per scene,
# the blur the profile reads over the blur the thin lens predicts from the
# measured depth (focus fitted, L1), by true |r| (px) and by side of the
# focus.
#
# Then the candidates for the DP cue reading low, each measured: the
# origin of the planes' distances (the focal-plane mark with the thin
# lens's position, the entrance pupil, the lens's front), the side of the
# focus (the planes are one depth each, one on each side; the scenes span
# both), the frames' encoding (8-bit sRGB against 16-bit linear), and the
# depth sensors: the profile-free recorded-focus cue with the focus the
# planes themselves fitted (the captures share one fixed focus), which
# reads a depth map's own scale error and no DP profile.
python3 - "$out" "$truth" "${encodings[*]}" <<'PY'
import glob, json, math, os, re, sys
out, truth, encodings = sys.argv[1], float(sys.argv[2]), sys.argv[3].split()
f_mm, f_number, pitch = 49.57, 4.0, 0.046875
aperture = f_mm / f_number
def r_true(z, g):
    return aperture * f_mm / (1 - f_mm / g) * (1 / g - 1 / z) / (2 * pitch)
def median(v):
    v = sorted(v); n = len(v)
    return float("nan") if n == 0 else (v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2]))
def report(enc, name, mode):
    try:
        return json.load(open(os.path.join(out, enc, "%s.%s.json" % (name, mode))))
    except Exception:
        return {}
def dp_cue(enc, name, mode):
    c = report(enc, name, mode).get("cues", {}).get("dual_pixel", {})
    return c["scale"] / truth if c.get("valid") else float("nan")
def fitted(patches):
    zs = [1000 * truth * p["depth_model"] for p in patches]
    rs = [p["radius_px"] for p in patches]
    best = None
    for g in range(600, 1600, 5):
        for k in [x / 100 for x in range(40, 200)]:
            e = sum(abs(y - k * r_true(z, g)) for z, y in zip(zs, rs))
            if best is None or e < best[0]:
                best = (e, g, k)
    return best[1], best[2], zs, rs
def object_mm(d):
    return 0.5 * (d + math.sqrt(d * d - 4 * d * f_mm))
def planes_focus_m(enc, profile):
    m = re.search(r"focus fitted at ([0-9.]+) m",
                  open(os.path.join(out, "calibration", enc, profile + ".log")).read())
    return float(m.group(1)) if m else float("nan")
names = sorted(os.path.basename(f).split(".")[0]
               for f in glob.glob(os.path.join(out, encodings[0], "*.planes_pupil.json")))
for enc in encodings:
    prof = os.path.join(out, "calibration", enc, "planes_pupil.dpsf")
    if not os.path.exists(prof):
        continue
    own = float(re.search(r"^uncertainty ([0-9.eE+-]+)", open(prof).read(), re.M).group(1))
    rows = {}
    for name in names:
        r = report(enc, name, "planes_pupil")
        c = r.get("cues", {}).get("dual_pixel", {})
        if not c.get("valid"):
            continue
        s, lo, hi = c["scale"] / truth, c["ci"][0] / truth, c["ci"][1] / truth
        patches = [p for p in r.get("patches", []) if p.get("used") or p.get("selected")]
        g, k, zs, rs = fitted(patches)
        bins, sides = {}, {}
        for z, y in zip(zs, rs):
            t = r_true(z, g)
            if abs(t) >= 0.3:
                bins.setdefault(min(int(abs(t)), 3), []).append(y / t)
            if abs(t) >= 0.5:
                sides.setdefault(t > 0, []).append(y / t)
        rows[name] = (s, lo, hi, g, k, bins, sides)
    print("\n%s: the planes' own profile (distances from the entrance pupil, uncertainty %.1f %%) on each scene, and left out in turn" % (enc, 100 * own))
    print("| scene | r_s (planes only) | its interval | focus fitted with the truth (m) | blur read / thin lens | by true blur 0-1 / 1-2 / 2-3 / 3+ px | nearer / farther than the focus | transfer term from the other six | interval with it | holds |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    held = 0
    for name, (s, lo, hi, g, k, bins, sides) in rows.items():
        others = [rows[m][0] for m in rows if m != name]
        t = max(abs(math.log(x)) for x in others)
        u = math.hypot(own, t)
        lo2, hi2 = lo / (1 - own) * (1 - u), hi / (1 + own) * (1 + u)
        ok = lo2 <= 1 <= hi2
        held += ok
        by = " / ".join("%.2f" % median(bins.get(b, [])) if bins.get(b) else "-" for b in range(4))
        side = " / ".join("%.2f (%d)" % (median(sides[x]), len(sides[x])) if sides.get(x) else "- (0)" for x in (False, True))
        print("| %s | %.3f | [%.3f, %.3f] | %.3f | %.2f | %s | %s | %.3f | [%.3f, %.3f] | %s |" % (
            name, s, lo, hi, g / 1000, k, by, side, t, lo2, hi2, "yes" if ok else "NO"))
    if rows:
        errs = [abs(math.log(v[0])) for v in rows.values()]
        print("%s: held-out intervals holding the truth %d of %d; |ln r_s| median %.3f, largest %.3f; mean ln r_s %+.3f" % (
            enc, held, len(rows), median(errs), max(errs), sum(math.log(v[0]) for v in rows.values()) / len(rows)))

# The candidates, on the 8-bit frames.
enc = encodings[0]
origins = [("planes_only", "mark, thin lens"), ("planes_pupil", "entrance pupil"), ("planes_front", "lens front")]
print("\nWhy the DP cue reads low (%s; DP cue r_s with the planes' own profile; focus cues profile-free)" % enc)
print("| scene | " + " | ".join("origin: %s" % o for _, o in origins) +
      " | 16-bit linear (pupil) | recorded-focus cue, 1 m | with the planes' focus | DP / that |")
print("|---|" + "---|" * (len(origins) + 4))
cols = {k: [] for k in ["thin", "pupil", "front", "linear", "focus", "planes_focus", "ratio"]}
g_planes = planes_focus_m(enc, "planes_pupil")
for name in names:
    vals = [dp_cue(enc, name, m) for m, _ in origins]
    lin = dp_cue(encodings[-1], name, "planes_pupil")
    fc = report(enc, name, "calibrated_focus").get("cues", {}).get("recorded_focus", {})
    focus = fc["scale"] / truth if fc.get("valid") else float("nan")
    # The recorded "1 m" from the mark against the planes' own fitted focus,
    # each the thin lens's object distance (u + v = d, 1/u + 1/v = 1/f).
    planes = focus * object_mm(1000 * g_planes) / object_mm(1000.0)
    ratio = vals[1] / planes
    for key, v in zip(["thin", "pupil", "front", "linear", "focus", "planes_focus", "ratio"],
                      vals + [lin, focus, planes, ratio]):
        if not math.isnan(v):
            cols[key].append(v)
    print("| %s | %s | %.3f | %.3f | %.3f | %.3f |" % (
        name, " | ".join("%.3f" % v for v in vals), lin, focus, planes, ratio))
print("| median | %s | %.3f | %.3f | %.3f | %.3f |" % (
    " | ".join("%.3f" % median(cols[k]) for k in ["thin", "pupil", "front"]),
    median(cols["linear"]), median(cols["focus"]), median(cols["planes_focus"]), median(cols["ratio"])))
print("planes' fitted focus (m from the mark): thin lens %.4f, entrance pupil %.4f, lens front %.4f" % (
    planes_focus_m(enc, "planes_only"), g_planes, planes_focus_m(enc, "planes_front")))
PY
log "total $((SECONDS - start)) s; reports, logs and the profiles in $out"
