# The real Canon EOS R6 Mark II + RF 50 mm f/4 captures of ../shared/realdp
# (read in place, never copied into the repository), as `make real`
# (run_real_bench.sh) and `make bench`'s cost benchmark (run_cost_bench.sh)
# use them. Source it after common.sh.

# The folder holding canon_r6m2_rf50/: DPSFM_REALDP_DIR, else
# ../shared/realdp next to the clone, else /work/shared/realdp.
find_realdp() {
  local d
  for d in "${DPSFM_REALDP_DIR:-}" "$DPSFM_ROOT/../shared/realdp" /work/shared/realdp; do
    [ -n "$d" ] && [ -d "$d/canon_r6m2_rf50" ] && { (cd "$d" && pwd); return; }
  done
  die "no real DP captures found (set DPSFM_REALDP_DIR to the folder holding canon_r6m2_rf50/)"
}

# realdp_calibration_set CAPTURES MAKE_WORKSPACE CAL ENCODING: the flat-plane
# captures (0.6 m and 1.5 m at f/4 and f/20, focus unknown) as a
# `dp_psf_calibrator` input in CAL: CAL/dp/{left,right} in ENCODING (srgb8,
# the files as given, or linear16) and CAL/targets.csv.
realdp_calibration_set() {
  local captures="$1" make_workspace="$2" cal="$3" enc="$4" d f
  mkdir -p "$cal/dp/left" "$cal/dp/right"
  echo "name,target_distance_m,focus_distance_m,focal_length_mm,f_number,pixel_pitch_um" >"$cal/targets.csv"
  for d in 0600 1500; do
    for f in f4 f20; do
      "$make_workspace" --capture_path "$captures/flat/001/$d/$f" \
        --output_path "$cal" --name "${d}_$f" --frames_only 1 \
        --linear16 "$([ "$enc" = linear16 ] && echo 1 || echo 0)" >/dev/null \
        || die "calibration frames failed: flat/001/$d/$f"
      echo "${d}_$f.png,$(awk "BEGIN{print $d/1000}"),,49.57,${f#f},46.875" >>"$cal/targets.csv"
    done
  done
}

# The RF 50 mm F1.8 STM's entrance pupil, in mm in front of the focal-plane
# mark at ~1 m focus: its patent prescription (lens/lens_web.json) traced
# paraxially, whole-group focus. Scene depths (SfM, a depth camera
# registered to the frame) are measured from the entrance pupil; the planes'
# distances from the mark.
REALDP_ENTRANCE_PUPIL_MM=39.9
# Where the lens's front would put the planes if "from the camera" meant
# from it: the RF mount's 20 mm flange, the lens's 40.5 mm, and the ~2.6 mm
# its group moves out to focus at ~1 m (f^2 / (g - f)), in front of the mark.
REALDP_LENS_FRONT_MM=63

# realdp_calibrate COLMAP CAL: the camera's profile from CAL (as made by
# realdp_calibration_set) into CAL/r6m2_rf50_f4.dpsf, with the calibrator's
# defaults (its transfer term included) and the lens's entrance pupil, the
# log in CAL/log.
realdp_calibrate() {
  local colmap="$1" cal="$2"
  "$colmap" dp_psf_calibrator --dp_image_path "$cal/dp" \
    --targets_path "$cal/targets.csv" --output_path "$cal/r6m2_rf50_f4.dpsf" \
    --DPPsfCalibrator.camera "Canon / Canon EOS R6m2" \
    --DPPsfCalibrator.lens "RF50mm F1.8 STM" \
    --DPPsfCalibrator.entrance_pupil_mm "$REALDP_ENTRANCE_PUPIL_MM" >"$cal/log" 2>&1
}
