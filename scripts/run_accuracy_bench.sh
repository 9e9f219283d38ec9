#!/usr/bin/env bash
# Accuracy benchmark (`make accuracy`): generates a suite of synthetic DP
# captures with known metric scale (scene types, lenses, apertures, a phone,
# sensor noise, gain artefacts, degraded depth maps, multi-aperture sets and
# scenes where the method must refuse), runs `colmap dp_scale_estimator` on
# each dense workspace (--dry_run 1), and prints the paper's measures: the
# scale ratio r_s = s_est / s_true per scene for the linear (initial) and
# the intensity (final) stage, and e_s = mean |1 - r_s| per setting and
# overall. Prints tables; it does not gate anything.
#
# Environment: DPSFM_ACCURACY_DIR (default <cache>/accuracy), DPSFM_JOBS
# (generation jobs, at most 2), DPSFM_ACCURACY_VIEWS (poses per scene, 8),
# DPSFM_ACCURACY_REUSE=1 (estimate again on the scenes of the last run),
# DPSFM_ACCURACY_PSF_MODEL (--DPScaleEstimator.psf_model of every run; empty
# = the command's default, auto, which refuses where the blur is too small
# to show the DP profile; translating_disk = the generator's sensor, what
# the accuracy tables measure).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="$(build_tree)"
colmap="$build_dir/colmap/src/colmap/exe/colmap"
generator="$build_dir/examples/dpsfm_make_example"
compare="$build_dir/examples/dpsfm_compare_to_truth"
out="${DPSFM_ACCURACY_DIR:-$DPSFM_CACHE_DIR/accuracy}"
views="${DPSFM_ACCURACY_VIEWS:-8}"
psf_args=()
if [ -n "${DPSFM_ACCURACY_PSF_MODEL:-}" ]; then
  psf_args=(--DPScaleEstimator.psf_model "$DPSFM_ACCURACY_PSF_MODEL")
fi
jobs="$(jobs_count)"
[ "$jobs" -gt 2 ] && jobs=2

# The suite: id | table | row | column | generator options. Tables:
# "lens" (scene x lens setting), "artefact" (artefact x scene, 50 mm
# f/2.8), "multi" (multi-aperture sets: each aperture alone and all
# together) and "failure" (the tool should refuse).
suite=(
  "tabletop_35f2|lens|tabletop|35 mm f/2|--scene tabletop --focal_length_mm 35 --f_number 2"
  "tabletop_50f2.8|lens|tabletop|50 mm f/2.8|--scene tabletop --focal_length_mm 50 --f_number 2.8"
  "tabletop_85f4|lens|tabletop|85 mm f/4|--scene tabletop --focal_length_mm 85 --f_number 4"
  "tabletop_50f8|lens|tabletop|50 mm f/8|--scene tabletop --focal_length_mm 50 --f_number 8"
  "tabletop_phone|lens|tabletop|phone f/1.73|--scene tabletop --camera phone"
  "facade_35f2|lens|facade|35 mm f/2|--scene facade --focal_length_mm 35 --f_number 2"
  "facade_50f2.8|lens|facade|50 mm f/2.8|--scene facade --focal_length_mm 50 --f_number 2.8"
  "facade_85f4|lens|facade|85 mm f/4|--scene facade --focal_length_mm 85 --f_number 4"
  "facade_50f8|lens|facade|50 mm f/8|--scene facade --focal_length_mm 50 --f_number 8"
  "facade_phone|lens|facade|phone f/1.73|--scene facade --camera phone"
  "planes_35f2|lens|planes|35 mm f/2|--scene planes --focal_length_mm 35 --f_number 2"
  "planes_50f2.8|lens|planes|50 mm f/2.8|--scene planes --focal_length_mm 50 --f_number 2.8"
  "planes_85f4|lens|planes|85 mm f/4|--scene planes --focal_length_mm 85 --f_number 4"
  "planes_50f8|lens|planes|50 mm f/8|--scene planes --focal_length_mm 50 --f_number 8"
  "planes_phone|lens|planes|phone f/1.73|--scene planes --camera phone"
  "tabletop_noise|artefact|sensor noise 0.01|tabletop|--scene tabletop --noise 0.01"
  "facade_noise|artefact|sensor noise 0.01|facade|--scene facade --noise 0.01"
  "planes_noise|artefact|sensor noise 0.01|planes|--scene planes --noise 0.01"
  "tabletop_gain|artefact|right gain 0.85, ramps 0.3|tabletop|--scene tabletop --right_gain 0.85 --gain_ramp 0.3"
  "facade_gain|artefact|right gain 0.85, ramps 0.3|facade|--scene facade --right_gain 0.85 --gain_ramp 0.3"
  "planes_gain|artefact|right gain 0.85, ramps 0.3|planes|--scene planes --right_gain 0.85 --gain_ramp 0.3"
  "tabletop_depth|artefact|depth 3 % noise, 20 % holes, 1/2 size|tabletop|--scene tabletop --depth_noise 0.03 --depth_holes 0.2 --depth_map_factor 2"
  "facade_depth|artefact|depth 3 % noise, 20 % holes, 1/2 size|facade|--scene facade --depth_noise 0.03 --depth_holes 0.2 --depth_map_factor 2"
  "planes_depth|artefact|depth 3 % noise, 20 % holes, 1/2 size|planes|--scene planes --depth_noise 0.03 --depth_holes 0.2 --depth_map_factor 2"
  "multi_tabletop_50|multi|tabletop 50 mm|2.8,5.6,11|--scene tabletop --focal_length_mm 50"
  "multi_planes_85|multi|planes 85 mm|4,8,16|--scene planes --focal_length_mm 85"
  "multi_facade_35|multi|facade 35 mm|2,4,8|--scene facade --focal_length_mm 35"
  "fail_pan_focus|failure|pan-focus: facade, 24 mm f/22|-|--scene facade --focal_length_mm 24 --f_number 22"
  "fail_textureless|failure|textureless: tabletop, 50 mm f/2.8, contrast 0|-|--scene tabletop --texture_contrast 0"
)

field() { cut -d'|' -f"$2" <<<"$1"; }

# DPSFM_ACCURACY_REUSE=1 keeps the scenes of the previous run (to re-run
# only the estimates after a change of the estimator).
reuse="${DPSFM_ACCURACY_REUSE:-0}"
if [ "$reuse" = 1 ] && [ -d "$out/scenes" ]; then
  rm -rf "$out/reports" "$out/subsets" "$out/bin" "$out"/logs/*.estimate.log
else
  reuse=0
  rm -rf "$out"
fi
mkdir -p "$out/scenes" "$out/logs" "$out/reports" "$out/bin"
# Run copies of the binaries: a rebuild in the same tree while the suite
# runs then neither breaks it nor mixes versions.
cp "$colmap" "$generator" "$compare" "$out/bin/"
colmap="$out/bin/colmap"
generator="$out/bin/dpsfm_make_example"
compare="$out/bin/dpsfm_compare_to_truth"

# 1. Generate, at most $jobs at a time.
generate() {
  local id="$1" table="$2" column="$3" options="$4" seed="$5"
  local extra=(--num_views "$views")
  [ "$table" = multi ] && extra=(--num_views 6 --f_numbers "$column")
  # shellcheck disable=SC2086
  "$generator" --output_path "$out/scenes/$id" --seed "$seed" \
    "${extra[@]}" $options >"$out/logs/$id.generate.log" 2>&1 \
    || { cat "$out/logs/$id.generate.log" >&2; return 1; }
}
start=$SECONDS
log "stage 'generate ${#suite[@]} scenes' ($jobs at a time) ..."
seed=100
running=0
for entry in "${suite[@]}"; do
  seed=$((seed + 1))
  [ "$reuse" = 1 ] && continue
  generate "$(field "$entry" 1)" "$(field "$entry" 2)" "$(field "$entry" 4)" \
    "$(field "$entry" 5)" "$seed" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n || die "scene generation failed"
    running=$((running - 1))
  fi
done
while [ "$running" -gt 0 ]; do
  wait -n || die "scene generation failed"
  running=$((running - 1))
done
log "stage 'generate' took $((SECONDS - start)) s"

# 2. Estimate. estimate RUN_ID TABLE ROW COLUMN WORKSPACE SCENE appends one
# line to results.tsv: table, row, column, run, exit status, r_s linear,
# r_s final, views used, intensity adopted, the ERROR line (if any).
results="$out/results.tsv"
: >"$results"
estimate() {
  local run="$1" table="$2" row="$3" column="$4" workspace="$5" scene="$6"
  local file="${run//\//_}"
  local report="$out/reports/$file.json" logfile="$out/logs/$file.estimate.log"
  local status=0
  "$colmap" dp_scale_estimator --workspace_path "$workspace" \
    --dp_image_path "$scene/dp" --lens_path "$scene/lens.csv" \
    --dry_run 1 --report_path "$report" "${psf_args[@]}" 2>"$logfile" \
    || status=$?
  local ratios="-	-	0	no"
  if [ -f "$report" ]; then
    ratios="$("$compare" --ground_truth "$scene/ground_truth.json" \
      --report "$report" --tsv)"
  fi
  local error
  error="$(grep -m1 '^ERROR: ' "$logfile" || true)"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$table" "$row" "$column" "$run" \
    "$status" "$ratios" "$error" >>"$results"
  log "$run: exit $status, r_s (linear, final, views, intensity) $(tr '\t' ' ' <<<"$ratios")"
}

# A dense workspace of only the images taken at f/<number> of a
# multi-aperture scene: its sparse model without the other images
# (colmap image_deleter), the scene's depth maps by reference.
aperture_subset() {
  local scene="$1" f_number="$2" subset="$3"
  mkdir -p "$subset/sparse"
  find "$scene/images" -name '*.jpg' ! -name "*_f${f_number}.jpg" \
    -printf '%f\n' >"$subset/delete.txt"
  "$colmap" image_deleter --input_path "$scene/dense/sparse" \
    --output_path "$subset/sparse" \
    --image_names_path "$subset/delete.txt" >"$subset/image_deleter.log" 2>&1 \
    || die "image_deleter failed (log: $subset/image_deleter.log)"
  ln -s "$scene/dense/stereo" "$subset/stereo"
}

start=$SECONDS
log "stage 'estimate' ..."
for entry in "${suite[@]}"; do
  id="$(field "$entry" 1)" table="$(field "$entry" 2)"
  row="$(field "$entry" 3)" column="$(field "$entry" 4)"
  scene="$out/scenes/$id"
  if [ "$table" = multi ]; then
    IFS=, read -r -a apertures <<<"$column"
    label="$row, f/${column//,/, }"
    k=0
    for f_number in "${apertures[@]}"; do
      k=$((k + 1))
      subset="$out/subsets/$id/f$f_number"
      aperture_subset "$scene" "$f_number" "$subset"
      estimate "$id/f$f_number" multi "$label" "aperture $k alone" "$subset" "$scene"
    done
    estimate "$id/all" multi "$label" "all together" "$scene/dense" "$scene"
  else
    estimate "$id" "$table" "$row" "$column" "$scene/dense" "$scene"
  fi
done
log "stage 'estimate' took $((SECONDS - start)) s"

# 3. Tables.
generation_times="$(grep -ho '([0-9.]* s)$' "$out"/logs/*.generate.log | tr -d '(s)' |
  awk '{ sum += $1; if ($1 > max) max = $1 } END { printf "%.1f s mean, %.1f s max", sum / NR, max }')"
source_state="$(git -C "$DPSFM_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)"
dirty="$(git -C "$DPSFM_ROOT" status --short -- plugin examples 2>/dev/null | awk '{ print $2 }' | tr '\n' ' ')"
[ -n "$dirty" ] && source_state="$source_state + uncommitted changes to $dirty"
{
  echo "Run $(date -u '+%Y-%m-%d %H:%M UTC') on $(nproc) cores; source: $source_state."
  echo "Accuracy benchmark: ${#suite[@]} generated scenes, $views poses each (multi-aperture sets 6 poses x 3 apertures)."
  echo "Cells: r_s = s_est / s_true of the linear (initial) / intensity (final) stage (views used); e_s = mean |1 - r_s| (linear / final)."
  echo "Generation: $generation_times per scene."
  echo
  awk -F'\t' -f "$DPSFM_ROOT/scripts/accuracy_tables.awk" "$results"
} | tee "$out/accuracy.md"
echo
log "tables: $out/accuracy.md; per-run results: $results; reports: $out/reports"
