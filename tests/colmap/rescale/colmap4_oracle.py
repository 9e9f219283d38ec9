#!/usr/bin/env python3
"""COLMAP 4.x as the oracle of dp-sfm's rescaling (pycolmap 4.2.1 from PyPI).

  make OUT [--rigs R] [--cameras_per_rig C] [--frames F] [--text] [--seed S]
      Writes a model made by COLMAP 4.2.1's own synthesizer into OUT: R rigs
      of C cameras each (non-reference sensors with a sensor_from_rig pose),
      F frames per rig, 3D points with tracks, with noise on observations,
      points and poses (reprojection errors ~0.5 px); binary, or text with
      --text.
  convert IN OUT [--text] [--two_camera_rig]
      Reads a model (any format COLMAP 4 reads, e.g. one COLMAP 3.x wrote)
      and writes it as COLMAP 4 does: rigs.* and frames.* beside the rest.
      --two_camera_rig splits the images over the two cameras of one rig
      (poses kept).
  map IMAGES OUT [--mapper global|incremental]
      COLMAP 4.2.1's pipeline (CPU SIFT, exhaustive matching, global_mapper
      or mapper) on IMAGES; the largest model goes to OUT.
  check ORIGINAL RESCALED SCALE [--truth ground_truth.json]
      Reads both models with COLMAP 4.2.1 (which takes each image's pose
      from its frame's rig_from_world and its rig's sensor_from_rig) and
      checks that every image's reprojection error is unchanged (1e-9
      relative) and that camera-centre distances and point coordinates are
      SCALE times the original's (1e-9 relative). Prints what it measured
      and exits 1 on any mismatch. With --truth (a generated scene's ground
      truth), the rescaled camera distances must also be metric: their
      median ratio to the true ones within --truth_tolerance (0.05).
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
    reconstruction = pycolmap.Reconstruction(args.input)
    if args.two_camera_rig:
        reconstruction = two_camera_rig(reconstruction)
    write(reconstruction, args.out, args.text)


def two_camera_rig(old):
    """The model's images split over two cameras of one rig (a copy of the
    first camera as a second sensor, sensor_from_rig a 0.1-unit offset),
    every image's pose kept: a frame per image, its rig_from_world
    sensor_from_rig^-1 * cam_from_world for the second sensor's images."""
    new = pycolmap.Reconstruction()
    first = old.cameras[min(old.cameras)]
    new.add_camera(first)
    second_id = max(old.cameras) + 1
    new.add_camera(pycolmap.Camera(model=first.model, width=first.width,
                                   height=first.height, params=first.params,
                                   camera_id=second_id))
    rig = pycolmap.Rig(rig_id=1)
    rig.add_ref_sensor(
        pycolmap.sensor_t(pycolmap.SensorType.CAMERA, first.camera_id))
    sensor_from_rig = pycolmap.Rigid3d(
        pycolmap.Rotation3d(np.array([0.02, -0.01, 0.03, 1.0]) /
                            np.linalg.norm([0.02, -0.01, 0.03, 1.0])),
        np.array([0.1, 0.02, -0.03]))
    rig.add_sensor(pycolmap.sensor_t(pycolmap.SensorType.CAMERA, second_id),
                   sensor_from_rig)
    new.add_rig(rig)
    images = sorted(old.images.values(), key=lambda image: image.name)
    for k, image in enumerate(images):
        camera_id = second_id if k % 2 else first.camera_id
        frame = pycolmap.Frame(frame_id=image.image_id, rig_id=1)
        cam_from_world = image.cam_from_world()
        frame.rig_from_world = (sensor_from_rig.inverse() * cam_from_world
                                if k % 2 else cam_from_world)
        frame.add_data_id(pycolmap.data_t(
            pycolmap.sensor_t(pycolmap.SensorType.CAMERA, camera_id),
            image.image_id))
        new.add_frame(frame)
        new.add_image(pycolmap.Image(name=image.name, points2D=image.points2D,
                                     camera_id=camera_id,
                                     image_id=image.image_id,
                                     frame_id=image.image_id))
        new.register_frame(image.image_id)
    for point_id, point in old.points3D.items():
        new.add_point3D_with_id(point_id, point)
    return new


def map_images(args):
    """COLMAP 4.2.1's own pipeline on the images: SIFT on the CPU,
    exhaustive matching, then the global (GLOMAP) or incremental mapper;
    the model with the most images goes to OUT."""
    import os
    import shutil
    work = args.out + ".work"
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    database = os.path.join(work, "database.db")
    extraction = pycolmap.FeatureExtractionOptions()
    extraction.use_gpu = False
    extraction.num_threads = 2
    reader = pycolmap.ImageReaderOptions()
    reader.camera_model = "SIMPLE_RADIAL"
    pycolmap.extract_features(database, args.images,
                              camera_mode=pycolmap.CameraMode.SINGLE,
                              reader_options=reader,
                              extraction_options=extraction,
                              device=pycolmap.Device.cpu)
    matching = pycolmap.FeatureMatchingOptions()
    matching.use_gpu = False
    matching.num_threads = 2
    pycolmap.match_exhaustive(database, matching_options=matching)
    mapped = os.path.join(work, "sparse")
    os.makedirs(mapped)
    if args.mapper == "global":
        models = pycolmap.global_mapping(database, args.images, mapped)
    else:
        models = pycolmap.incremental_mapping(database, args.images, mapped)
    if not models:
        sys.exit("the %s mapper made no model" % args.mapper)
    best = max(models.values(), key=lambda r: r.num_reg_images())
    write(best, args.out, False)
    print("%s mapper: %d of %d images registered, %d points" %
          (args.mapper, best.num_reg_images(), best.num_images(),
           best.num_points3D()))


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

    if args.truth:
        import json
        views = json.load(open(args.truth))["views"]
        ratios = []
        for a, b in itertools.combinations(
                [n for n in names if n in views], 2):
            true = np.linalg.norm(np.subtract(views[a]["center_m"],
                                              views[b]["center_m"]))
            ratios.append(np.linalg.norm(c1[a] - c1[b]) / true)
        ratio = float(np.median(ratios))
        print("camera distances against the truth: median ratio %.4f over "
              "%d pairs" % (ratio, len(ratios)))
        if abs(ratio - 1) > args.truth_tolerance:
            problems.append("camera distances are %.4f x the true ones" %
                            ratio)
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
    v.add_argument("--two_camera_rig", action="store_true")
    c = sub.add_parser("check")
    c.add_argument("original")
    c.add_argument("rescaled")
    c.add_argument("scale", type=float)
    c.add_argument("--truth", help="ground_truth.json of a generated scene")
    c.add_argument("--truth_tolerance", type=float, default=0.05)
    p = sub.add_parser("map")
    p.add_argument("images")
    p.add_argument("out")
    p.add_argument("--mapper", choices=["global", "incremental"],
                   default="global")
    args = parser.parse_args()
    if args.command == "make":
        make(args)
    elif args.command == "convert":
        convert(args)
    elif args.command == "map":
        map_images(args)
    else:
        sys.exit(check(args))


if __name__ == "__main__":
    main()
