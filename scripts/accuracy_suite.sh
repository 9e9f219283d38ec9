# The scenes of `make accuracy` (run_accuracy_bench.sh), also measured by
# `make bench`'s cost benchmark (run_cost_bench.sh). Source it. Scene k of
# the list (from 1) is generated with seed 100 + k.
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

# suite_index ID: the scene's position in the list (from 1), or nothing.
suite_index() {
  local k=0 entry
  for entry in "${suite[@]}"; do
    k=$((k + 1))
    [ "$(field "$entry" 1)" = "$1" ] && { echo "$k"; return 0; }
  done
  return 1
}
