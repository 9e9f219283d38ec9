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
# A phone (4.38 mm f/1.73, 5.6 mm sensor) photographing a tabletop from
# 20-25 cm: DP frames at half the image size.
"$generator" --output_path "$out/phone" --seed 21 --num_views 6 \
  --camera phone --width 1200 --height 900 --scene_scale 0.25
# Two apertures per tripod position (images DP_000N_f2.8, DP_000N_f5.6).
"$generator" --output_path "$out/multi_aperture" --seed 22 --num_views 4 \
  --width 800 --height 540 --f_numbers 2.8,5.6
# PatchMatch-like depth maps: 2 % relative noise, 20 % holes, half size.
"$generator" --output_path "$out/depth_artefacts" --seed 23 --num_views 6 \
  --width 800 --height 540 --depth_noise 0.02 --depth_holes 0.2 \
  --depth_map_factor 2
# No texture at all: only the edges between flat surfaces.
"$generator" --output_path "$out/textureless" --seed 24 --num_views 4 \
  --width 640 --height 432 --texture_contrast 0
# Rendered by following light through the aperture (a half-aperture split
# with 10 % crosstalk; examples/aperture_renderer.h), with captures of a
# textured plane for dp_psf_calibrator made the same way: no kernel, profile
# or thin-lens code shared with the estimator.
"$generator" --output_path "$out/aperture" --seed 31 --num_views 6 \
  --width 800 --height 540 --renderer aperture --calibration_captures 4
