#!/usr/bin/env python3
"""Metric scale for a COLMAP model from Python (pycolmap, hloc pipelines).

Runs dp-sfm's scale step on a workspace or sparse model (written by COLMAP,
pycolmap or hloc), checks that it succeeded, and reads the report and the
rescaled, metric model back with pycolmap. Needs only pycolmap and numpy.

  # the patched COLMAP (checkout route): the executable is `colmap`
  python scale_with_dp.py --exe colmap --workspace_path dense \\
      --dp_image_path dp --lens_path lens.csv --report_path dp_scale.json
  # dp-sfm built against an installed COLMAP: the executable is `dpsfm`
  python scale_with_dp.py --exe dpsfm --input_path sfm --dp_image_path dp \\
      --image_path images

--workspace_path is a dense workspace (image_undistorter, patch_match_stereo);
--input_path a sparse model (e.g. hloc's sfm folder). The model is rescaled
in place, or into --output_path. Any other option (e.g. --database_path,
--force 1) is passed to the command as it is; `<exe> dp_scale_estimator
--help` lists them. The command's log goes beside the report (.log); when
the command fails, its last ERROR line is printed and its exit code kept.
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np
import pycolmap


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exe", default="colmap", help="colmap or dpsfm")
    model = parser.add_mutually_exclusive_group(required=True)
    model.add_argument("--workspace_path")
    model.add_argument("--input_path")
    parser.add_argument("--dp_image_path", required=True)
    parser.add_argument("--report_path", default="dp_scale.json")
    parser.add_argument("--output_path")
    args, passed_on = parser.parse_known_args()

    command = [args.exe, "dp_scale_estimator"]
    for name in ("workspace_path", "input_path", "dp_image_path",
                 "report_path", "output_path"):
        if getattr(args, name):
            command += ["--" + name, getattr(args, name)]
    log_path = os.path.splitext(args.report_path)[0] + ".log"
    with open(log_path, "w") as log:
        code = subprocess.run(command + passed_on, stderr=log).returncode
    if code != 0:
        with open(log_path) as log:
            errors = [line for line in log if line.startswith("ERROR")]
        print(errors[-1].rstrip() if errors else f"{args.exe} failed",
              f"(exit {code}; the log: {log_path})", file=sys.stderr)
        sys.exit(code)

    with open(args.report_path) as file:
        report = json.load(file)
    if not report["success"]:
        sys.exit("no scale: " + report.get("reason", "see the report"))
    scale = report["scale"]
    print(f"scale {scale:.9g} metres per model unit, 95 % interval "
          f"[{report['scale_ci_low']:.9g}, {report['scale_ci_high']:.9g}]")

    folder = args.output_path or args.workspace_path or args.input_path
    if args.workspace_path:
        folder = os.path.join(folder, "sparse")
    metric = pycolmap.Reconstruction(folder)
    centres = np.array([image.projection_center()
                        for image in metric.images.values() if image.has_pose])
    extent = np.ptp(centres, axis=0)
    print(f"metric model {folder} (pycolmap {pycolmap.__version__}): "
          f"{len(centres)} images, {metric.num_points3D()} points, camera "
          f"centres within {extent[0]:.3f} x {extent[1]:.3f} x "
          f"{extent[2]:.3f} m")


if __name__ == "__main__":
    main()
