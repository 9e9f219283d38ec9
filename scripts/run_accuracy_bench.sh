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

source "$(dirname "${BASH_SOURCE[0]}")/accuracy_suite.sh"

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
