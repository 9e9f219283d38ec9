#!/usr/bin/env bash
# The README's main job on the built-in example. It builds everything
# (cached), generates a synthetic dual-pixel capture with a known metric
# scale (a tabletop scene, 8 views, DSLR-like 50 mm f/2.8), and then:
#  1. dense path: `colmap dp_scale_estimator` on the generated dense
#     workspace, rescaling it in place; prints true and estimated scale;
#  2. real pipeline: COLMAP's feature_extractor, exhaustive_matcher and
#     mapper on the generated images, then `dp_scale_estimator` in sparse
#     mode on the mapper's model; prints the camera distances of the
#     rescaled model against the true ones in metres; on COLMAP 4 the same
#     for global_mapper's model (GLOMAP, merged into COLMAP 4.0);
#  3. the real pipeline's dense path: image_undistorter on the mapper's
#     model, the generator's true depth maps moved into the mapper's frame
#     and units (PatchMatch stereo needs CUDA; the mapper-to-truth
#     similarity comes from the camera centres), then `dp_scale_estimator`
#     on that dense workspace; prints the scale against the truth of the
#     mapper's units and the camera distances in metres.
# Reports with plots are written next to the scene. Safe to re-run: the
# scene is regenerated under $DPSFM_EXAMPLE_DIR (default <cache>/example).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

total_start=$SECONDS
build_dir="$(build_tree)"
colmap="$build_dir/colmap/src/colmap/exe/colmap"
examples="$build_dir/examples"
scene="${DPSFM_EXAMPLE_DIR:-$DPSFM_CACHE_DIR/example}"
seed="${DPSFM_EXAMPLE_SEED:-1}"
logs="$scene/logs"

rm -rf "$scene"
stage "generate example scene" "$examples/dpsfm_make_example" \
  --output_path "$scene" --seed "$seed" --num_views 8
mkdir -p "$logs"

# 1. Dense workspace, rescaled in place.
stage "dp_scale_estimator (dense workspace)" "$colmap" dp_scale_estimator \
  --workspace_path "$scene/dense" --dp_image_path "$scene/dp" \
  --database_path "$scene/database.db" --lens_path "$scene/lens.csv" \
  --report_path "$scene/report_dense.json" 2>"$logs/dense.log" \
  || { tail -n 5 "$logs/dense.log" >&2; die "dp_scale_estimator failed on the dense workspace"; }

# 2. The real COLMAP pipeline on the generated images (CPU SIFT).
pipeline="$scene/pipeline"
mkdir -p "$pipeline/sparse"
run_colmap() {
  local name="$1"; shift
  "$colmap" "$@" >"$logs/$name.log" 2>&1 \
    || { tail -n 5 "$logs/$name.log" >&2; die "colmap $1 failed (log: $logs/$name.log)"; }
}
# COLMAP 4 renamed SiftExtraction / SiftMatching to FeatureExtraction /
# FeatureMatching.
if colmap_is_4; then features=Feature; else features=Sift; fi
stage "colmap feature_extractor" run_colmap feature_extractor feature_extractor \
  --database_path "$pipeline/database.db" --image_path "$scene/images" \
  --ImageReader.single_camera 1 --ImageReader.camera_model SIMPLE_RADIAL \
  --${features}Extraction.use_gpu 0
stage "colmap exhaustive_matcher" run_colmap exhaustive_matcher exhaustive_matcher \
  --database_path "$pipeline/database.db" --${features}Matching.use_gpu 0
stage "colmap mapper" run_colmap mapper mapper \
  --database_path "$pipeline/database.db" --image_path "$scene/images" \
  --output_path "$pipeline/sparse"
[ -d "$pipeline/sparse/0" ] || die "the mapper made no model (log: $logs/mapper.log)"
# 3 needs the mapper's model in its own units: undistort it before 2
# rescales it.
stage "colmap image_undistorter" run_colmap image_undistorter image_undistorter \
  --image_path "$scene/images" --input_path "$pipeline/sparse/0" \
  --output_path "$pipeline/dense"
stage "dp_scale_estimator (mapper's sparse model)" "$colmap" dp_scale_estimator \
  --input_path "$pipeline/sparse/0" --dp_image_path "$scene/dp" \
  --database_path "$pipeline/database.db" --lens_path "$scene/lens.csv" \
  --report_path "$scene/report_sparse.json" 2>"$logs/sparse.log" \
  || { tail -n 5 "$logs/sparse.log" >&2; die "dp_scale_estimator failed on the mapper's model"; }
if colmap_is_4; then
  mkdir -p "$pipeline/global"
  stage "colmap global_mapper" run_colmap global_mapper global_mapper \
    --database_path "$pipeline/database.db" --image_path "$scene/images" \
    --output_path "$pipeline/global"
  [ -d "$pipeline/global/0" ] || die "global_mapper made no model (log: $logs/global_mapper.log)"
  stage "dp_scale_estimator (global_mapper's model)" "$colmap" dp_scale_estimator \
    --input_path "$pipeline/global/0" --dp_image_path "$scene/dp" \
    --database_path "$pipeline/database.db" --lens_path "$scene/lens.csv" \
    --report_path "$scene/report_global.json" 2>"$logs/global.log" \
    || { tail -n 5 "$logs/global.log" >&2; die "dp_scale_estimator failed on global_mapper's model"; }
fi

# 3. The mapper's dense workspace with the true depths in its units. The DP
# frames keep the original images' geometry: --original_model_path gives
# the mapper's refined (distorted) cameras (the project database holds only
# their priors). Rescaling sparse/0 in step 2 left its cameras as they were.
stage "true depth maps in the mapper's frame" "$examples/dpsfm_align_true_depths" \
  --truth_path "$scene" --workspace_path "$pipeline/dense" \
  --ground_truth_output "$pipeline/ground_truth.json" >"$logs/align.log" \
  || die "aligning the true depth maps failed"
stage "dp_scale_estimator (mapper's dense workspace)" "$colmap" dp_scale_estimator \
  --workspace_path "$pipeline/dense" --dp_image_path "$scene/dp" \
  --original_model_path "$pipeline/sparse/0" --lens_path "$scene/lens.csv" \
  --report_path "$scene/report_pipeline_dense.json" 2>"$logs/pipeline_dense.log" \
  || { tail -n 5 "$logs/pipeline_dense.log" >&2; die "dp_scale_estimator failed on the mapper's dense workspace"; }

echo
echo "== Built-in example: $scene"
echo "== 1. Dense workspace (generated model, depth maps):"
grep -E "Linear estimate|files rescaled" "$logs/dense.log" | sed 's/^.*\] /   /'
"$examples/dpsfm_compare_to_truth" --ground_truth "$scene/ground_truth.json" \
  --report "$scene/report_dense.json"
echo
echo "== 2. Real COLMAP pipeline (feature_extractor, exhaustive_matcher, mapper), sparse mode:"
grep -E "Linear estimate|files rescaled" "$logs/sparse.log" | sed 's/^.*\] /   /'
"$examples/dpsfm_compare_to_truth" --ground_truth "$scene/ground_truth.json" \
  --report "$scene/report_sparse.json" --model_path "$pipeline/sparse/0"
if colmap_is_4; then
  echo
  echo "== 2b. The same with COLMAP 4's global_mapper, sparse mode:"
  grep -E "Linear estimate|files rescaled" "$logs/global.log" | sed 's/^.*\] /   /'
  "$examples/dpsfm_compare_to_truth" --ground_truth "$scene/ground_truth.json" \
    --report "$scene/report_global.json" --model_path "$pipeline/global/0"
fi
echo
echo "== 3. Real pipeline, dense: the mapper's model undistorted, true depths in its units:"
sed 's/^/   /' "$logs/align.log"
grep -E "Linear estimate|files rescaled" "$logs/pipeline_dense.log" | sed 's/^.*\] /   /'
"$examples/dpsfm_compare_to_truth" --ground_truth "$pipeline/ground_truth.json" \
  --report "$scene/report_pipeline_dense.json"
"$examples/dpsfm_compare_to_truth" --ground_truth "$pipeline/ground_truth.json" \
  --report "$scene/report_pipeline_dense.json" --model_path "$pipeline/dense/sparse"
echo
echo "Reports and plots: $scene/report_{dense,sparse,global,pipeline_dense}*.{json,png}"
log "total $((SECONDS - total_start)) s"
