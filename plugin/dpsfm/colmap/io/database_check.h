// Cross-check of the model against the project database, opened strictly
// read-only: COLMAP's own Database class creates tables and WAL files on
// open, and a wrong path would silently create an empty database.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "colmap/scene/reconstruction.h"

namespace dpsfm {

struct DatabaseCheck {
  int num_database_images = 0;
  // Model images the database does not know, and model images whose camera
  // size differs from the database's camera for that image.
  std::vector<std::string> missing_images;
  std::vector<std::string> camera_mismatches;
  // The database's camera of each model image: the ORIGINAL camera, with its
  // distortion, where the model is a dense workspace's undistorted one.
  std::map<std::string, colmap::Camera> original_cameras;
};

// Reads image names and camera sizes from the database. Throws InputError if
// the file is not a COLMAP database, or if none of the model's images is in
// it (the database belongs to another project).
DatabaseCheck CheckModelAgainstDatabase(
    const std::string& database_path,
    const colmap::Reconstruction& reconstruction);

}  // namespace dpsfm
