#!/usr/bin/env bash
# The README's main job: builds everything (cached), generates the built-in
# example scene (a synthetic dual-pixel capture with a known metric scale, as
# a COLMAP workspace), runs `colmap dp_scale_estimator` on it and prints what
# it found next to the truth. Safe to re-run: the scene is regenerated each
# time under $DPSFM_EXAMPLE_DIR (default: <cache>/example).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build_dir="$("$DPSFM_ROOT/scripts/build.sh")"
colmap="$build_dir/colmap/src/colmap/exe/colmap"
generator="$build_dir/examples/dpsfm_make_example"
example_dir="${DPSFM_EXAMPLE_DIR:-$DPSFM_CACHE_DIR/example}"

rm -rf "$example_dir"
stage "generate example scene" "$generator" --output_path "$example_dir"

status=0
stage "dp_scale_estimator" "$colmap" dp_scale_estimator \
  --workspace_path "$example_dir/dense" \
  --dp_image_path "$example_dir/dp" \
  --lens_path "$example_dir/lens.csv" \
  --report_path "$example_dir/report.json" || status=$?

echo
echo "Example workspace: $example_dir"
echo "Ground truth:      $example_dir/ground_truth.json"
if [ -f "$example_dir/report.json" ]; then
  echo "Report:            $example_dir/report.json"
fi
[ $status -eq 0 ] || die "dp_scale_estimator failed on the example (exit $status)"
"$build_dir/examples/dpsfm_compare_to_truth" \
  --ground_truth "$example_dir/ground_truth.json" \
  --report "$example_dir/report.json"
