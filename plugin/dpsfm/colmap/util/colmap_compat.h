// The one place where the COLMAP versions dp-sfm builds into differ.
//
// The plugin is written against COLMAP 4's API (4.1.x, the default build, and
// 4.2.x). COLMAP 3.10 spells some of the same things differently; this header
// gives both the one spelling the rest of the code uses. CMake passes
// DPSFM_COLMAP_VERSION_MAJOR / _MINOR (cmake/CheckColmapSource.cmake).
//
// What differs, 3.10 -> 4.x:
//  - poses: an image's pose is its frame's pose composed with its rig's
//    sensor pose; Image::CamFromWorld() returns a value, and images enter a
//    reconstruction through frames (AddRegisteredImage below);
//  - Rigid3d: rotation() / translation() accessors instead of fields;
//  - Camera::CamFromImg / ImgFromCam: std::optional results, and ImgFromCam
//    takes a 3D point in the camera frame;
//  - SyntheticDatasetOptions counts rigs and frames, not cameras and images;
//  - Database::Open opens a database (a constructor did);
//  - SiftExtraction / SiftMatching options are FeatureExtraction /
//    FeatureMatching;
//  - OptionManager::Parse returns false on bad options instead of exiting;
//  - logging: LOG_HEADING1/2 instead of PrintHeading1/2;
//  - model reading: 3.10 splits text lines at single spaces and does not
//    compare tracks with the 2D points they list.

#pragma once

#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "colmap/controllers/option_manager.h"
#include "colmap/geometry/rigid3.h"
#include "colmap/scene/camera.h"
#include "colmap/scene/database.h"
#include "colmap/scene/image.h"
#include "colmap/scene/reconstruction.h"
#include "colmap/scene/synthetic.h"
#include "colmap/util/misc.h"

#ifndef DPSFM_COLMAP_VERSION_MAJOR
#error "DPSFM_COLMAP_VERSION_MAJOR is not set (link dpsfm_colmap_headers)"
#endif

#define DPSFM_COLMAP_4 (DPSFM_COLMAP_VERSION_MAJOR >= 4)

#if !DPSFM_COLMAP_4
// COLMAP 4's heading macros (util/misc.h there).
#define LOG_HEADING1(message) colmap::PrintHeading1(message)
#define LOG_HEADING2(message) colmap::PrintHeading2(message)
#endif

namespace dpsfm {

// Whether COLMAP's model writer writes rigs.* and frames.* beside cameras,
// images and points3D (COLMAP 4; 3.10 writes the three alone).
constexpr bool kWriterWritesRigsAndFrames = DPSFM_COLMAP_4;

// Whether COLMAP's model reader compares each 3D point's track with the 2D
// points it lists (COLMAP 4: Reconstruction::AddPoint3D's THROW_CHECK_EQ on
// the 2D point's point3D_id; 3.10 stores the point without comparing).
constexpr bool kReaderChecksTrackReferences = DPSFM_COLMAP_4;

// Whether COLMAP's text model reader splits a line's fields at single
// spaces (3.10: getline(line, item, ' '), so two spaces or a tab between
// fields make an empty field that std::stoul / std::stold throw on) rather
// than at any run of whitespace (4.x: operator>>).
constexpr bool kTextReaderSplitsAtSingleSpaces = !DPSFM_COLMAP_4;

// The option sections of feature extraction and matching (COLMAP 4 renamed
// SiftExtraction / SiftMatching).
constexpr const char* kFeatureExtractionSection =
    DPSFM_COLMAP_4 ? "FeatureExtraction" : "SiftExtraction";
constexpr const char* kFeatureMatchingSection =
    DPSFM_COLMAP_4 ? "FeatureMatching" : "SiftMatching";

// The rotation and translation of a rigid transform.
inline Eigen::Quaterniond RotationOf(const colmap::Rigid3d& transform) {
#if DPSFM_COLMAP_4
  return transform.rotation();
#else
  return transform.rotation;
#endif
}
inline Eigen::Vector3d TranslationOf(const colmap::Rigid3d& transform) {
#if DPSFM_COLMAP_4
  return transform.translation();
#else
  return transform.translation;
#endif
}

// The normalized camera coordinates (x/z, y/z) of an image point, or nothing
// where the camera model cannot unproject it.
inline std::optional<Eigen::Vector2d> CamFromImg(
    const colmap::Camera& camera, const Eigen::Vector2d& image_point) {
  return camera.CamFromImg(image_point);
}

// The image point of a point in the camera frame, or nothing where the
// camera model cannot project it (behind the camera, for one).
inline std::optional<Eigen::Vector2d> ImgFromCam(
    const colmap::Camera& camera, const Eigen::Vector3d& cam_point) {
#if DPSFM_COLMAP_4
  return camera.ImgFromCam(cam_point);
#else
  if (cam_point.z() <= 0) return std::nullopt;
  return camera.ImgFromCam(cam_point.hnormalized());
#endif
}

// Adds a camera, with its own single-camera rig on COLMAP 4.
inline void AddCamera(colmap::Reconstruction* reconstruction,
                      colmap::Camera camera) {
#if DPSFM_COLMAP_4
  reconstruction->AddCameraWithTrivialRig(std::move(camera));
#else
  reconstruction->AddCamera(std::move(camera));
#endif
}

// Adds an image at the given pose and registers it: on COLMAP 4 through a
// frame of its camera's single-camera rig (AddCamera above), since assigning
// to Image::CamFromWorld() there changes nothing.
inline void AddRegisteredImage(colmap::Reconstruction* reconstruction,
                               colmap::Image image,
                               const colmap::Rigid3d& cam_from_world) {
#if DPSFM_COLMAP_4
  reconstruction->AddImageWithTrivialFrame(std::move(image), cam_from_world);
#else
  const colmap::image_t image_id = image.ImageId();
  image.CamFromWorld() = cam_from_world;
  reconstruction->AddImage(std::move(image));
  reconstruction->RegisterImage(image_id);
#endif
}

// Opens (creates) a COLMAP database.
inline std::shared_ptr<colmap::Database> OpenDatabase(const std::string& path) {
#if DPSFM_COLMAP_4
  return colmap::Database::Open(path);
#else
  return std::make_shared<colmap::Database>(path);
#endif
}

// Options of COLMAP's synthetic dataset (tests): `num_cameras` cameras and
// `num_images` images (a multiple of it). On COLMAP 4 the cameras form rigs
// of `cameras_per_rig` (the others' sensor poses hold translations); 3.10
// has no rigs.
inline colmap::SyntheticDatasetOptions SyntheticOptions(
    int num_cameras, int num_images, int cameras_per_rig = 1) {
  colmap::SyntheticDatasetOptions options;
#if DPSFM_COLMAP_4
  options.num_rigs = num_cameras / cameras_per_rig;
  options.num_cameras_per_rig = cameras_per_rig;
  options.num_frames_per_rig = num_images / num_cameras;
#else
  (void)cameras_per_rig;
  options.num_cameras = num_cameras;
  options.num_images = num_images;
#endif
  return options;
}

// Parses a command's options; false (after COLMAP printed why) on bad ones.
// COLMAP 3.10 exits the process itself instead.
inline bool ParseOptions(colmap::OptionManager* options,
                         int argc,
                         char** argv) {
#if DPSFM_COLMAP_4
  return options->Parse(argc, argv);
#else
  options->Parse(argc, argv);
  return true;
#endif
}

}  // namespace dpsfm
