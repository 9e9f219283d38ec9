#!/usr/bin/env python3
"""COLMAP 4.x as the oracle of dp-sfm's rescaling (pycolmap 4.2.1 from PyPI).

  make OUT [--rigs R] [--cameras_per_rig C] [--frames F] [--text] [--seed S]
      Writes a model made by COLMAP 4.2.1's own synthesizer into OUT: R rigs
      of C cameras each (non-reference sensors with a sensor_from_rig pose),
      F frames per rig, 3D points with tracks, with noise on observations,
      points and poses (reprojection errors ~0.5 px); binary, or text with
      --text.
  convert IN OUT [--text]
      Reads a model (any format COLMAP 4 reads, e.g. one COLMAP 3.x wrote)
      and writes it as COLMAP 4 does: rigs.* and frames.* beside the rest.
  check ORIGINAL RESCALED SCALE
      Reads both models with COLMAP 4.2.1 (which takes each image's pose
      from its frame's rig_from_world and its rig's sensor_from_rig) and
      checks that every image's reprojection error is unchanged (1e-9
      relative) and that camera-centre distances and point coordinates are
      SCALE times the original's (1e-9 relative). Prints what it measured
      and exits 1 on any mismatch.
"""
import argparse
import itertools
import sys

import numpy as np
import pycolmap


def make(args):
    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs = args.rigs
    options.num_cameras_per_rig = args.cameras_per_rig
    options.num_frames_per_rig = args.frames
    options.num_points3D = 60
    pycolmap.set_random_seed(args.seed)
    reconstruction = pycolmap.synthesize_dataset(options)
    # Noisy observations and poses, so reprojection errors are real
    # (~0.5 px) rather than rounding (1e-14 px).
    noise = pycolmap.SyntheticNoiseOptions()
    noise.point2D_stddev = 0.5
    noise.point3D_stddev = 0.01
    noise.rig_from_world_translation_stddev = 0.01
    noise.rig_from_world_rotation_stddev = 0.2
    pycolmap.synthesize_noise(noise, reconstruction)
    write(reconstruction, args.out, args.text)
    print(reconstruction.summary())


def write(reconstruction, out, text):
    import os
    os.makedirs(out, exist_ok=True)
    if text:
        reconstruction.write_text(out)
    else:
        reconstruction.write_binary(out)


def convert(args):
    write(pycolmap.Reconstruction(args.input), args.out, args.text)


def image_errors(reconstruction):
    """Mean reprojection error per image name, from the poses COLMAP 4
    composes (sensor_from_rig * rig_from_world)."""
    errors = {}
    for image in reconstruction.images.values():
        camera = reconstruction.cameras[image.camera_id]
        cam_from_world = image.cam_from_world()
        residuals = []
        for point2D in image.points2D:
            if not point2D.has_point3D():
                continue
            xyz = reconstruction.points3D[point2D.point3D_id].xyz
            uv = camera.img_from_cam(cam_from_world * xyz)
            residuals.append(np.linalg.norm(uv - point2D.xy))
        errors[image.name] = float(np.mean(residuals)) if residuals else 0.0
    return errors


def centres(reconstruction):
    return {
        image.name: np.asarray(image.projection_center())
        for image in reconstruction.images.values()
    }


def relative(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def check(args):
    original = pycolmap.Reconstruction(args.original)
    rescaled = pycolmap.Reconstruction(args.rescaled)
    scale = args.scale
    problems = []
    if (original.num_rigs(), original.num_frames(), original.num_images()) != (
            rescaled.num_rigs(), rescaled.num_frames(), rescaled.num_images()):
        problems.append("rig / frame / image counts differ")

    e0, e1 = image_errors(original), image_errors(rescaled)
    worst_error = 0.0
    for name, error in e0.items():
        if name not in e1:
            problems.append("image %s is missing" % name)
            continue
        worst_error = max(worst_error,
                          abs(e1[name] - error) / max(error, 1e-3))
    if worst_error > 1e-9:
        problems.append("reprojection errors changed (worst %.3g)" % worst_error)

    c0, c1 = centres(original), centres(rescaled)
    worst_distance = 0.0
    names = sorted(c0)
    for a, b in itertools.combinations(names, 2):
        d0 = np.linalg.norm(c0[a] - c0[b])
        d1 = np.linalg.norm(c1[a] - c1[b])
        if d0 > 1e-12:
            worst_distance = max(worst_distance, relative(d1, scale * d0))
    if worst_distance > 1e-9:
        problems.append(
            "camera-centre distances are not %.17g x the original's "
            "(worst relative error %.3g)" % (scale, worst_distance))

    worst_point = 0.0
    for point_id, point in original.points3D.items():
        if point_id not in rescaled.points3D:
            problems.append("point %d is missing" % point_id)
            break
        p1 = rescaled.points3D[point_id].xyz
        worst_point = max(
            worst_point,
            np.linalg.norm(p1 - scale * point.xyz) /
            max(np.linalg.norm(scale * point.xyz), 1e-300))
    if worst_point > 1e-9:
        problems.append("points are not %.17g x the original's (worst %.3g)" %
                        (scale, worst_point))

    print("pycolmap %s: %d rigs, %d frames, %d images, %d points; worst "
          "relative: reprojection %.3g, centre distance %.3g, point %.3g" %
          (pycolmap.__version__, rescaled.num_rigs(), rescaled.num_frames(),
           rescaled.num_images(), rescaled.num_points3D(), worst_error,
           worst_distance, worst_point))
    for problem in problems:
        print("MISMATCH: " + problem)
    return 1 if problems else 0


def main():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command", required=True)
    m = sub.add_parser("make")
    m.add_argument("out")
    m.add_argument("--rigs", type=int, default=2)
    m.add_argument("--cameras_per_rig", type=int, default=2)
    m.add_argument("--frames", type=int, default=4)
    m.add_argument("--seed", type=int, default=1)
    m.add_argument("--text", action="store_true")
    v = sub.add_parser("convert")
    v.add_argument("input")
    v.add_argument("out")
    v.add_argument("--text", action="store_true")
    c = sub.add_parser("check")
    c.add_argument("original")
    c.add_argument("rescaled")
    c.add_argument("scale", type=float)
    args = parser.parse_args()
    if args.command == "make":
        make(args)
    elif args.command == "convert":
        convert(args)
    else:
        sys.exit(check(args))


if __name__ == "__main__":
    main()
