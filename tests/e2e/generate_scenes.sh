#!/usr/bin/env bash
# Generates the scenes the end-to-end tests run on (CTest fixture).
# Usage: generate_scenes.sh <dpsfm_make_example> <output dir>
set -euo pipefail
generator="$1"
out="$2"
rm -rf "$out"
mkdir -p "$out"
# A DSLR-like capture: 8 views, 50 mm f/2.8, 1200x800, known random scale.
"$generator" --output_path "$out/dslr" --seed 7 --num_views 8
# Pan-focus: 24 mm at f/16 gives under a pixel of blur; no scale exists.
"$generator" --output_path "$out/pan_focus" --seed 8 --num_views 4 \
  --focal_length_mm 24 --f_number 16
# Distorted original images (SIMPLE_RADIAL k1 = -0.1): DP views and sparse/0
# in the distorted geometry, dense/ undistorted, cameras in database.db.
"$generator" --output_path "$out/distorted" --seed 9 --num_views 6 \
  --radial_k1 -0.1
