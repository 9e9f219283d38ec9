#include "dpsfm/colmap/io/workspace.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "dpsfm/core/optics/encoding.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;

std::string Join(const std::string& a, const std::string& b) {
  return (fs::path(a) / b).string();
}

void RequireDir(const std::string& path, const std::string& what) {
  if (!fs::exists(path)) {
    throw InputError(what + " does not exist: " + path);
  }
  if (!fs::is_directory(path)) {
    throw InputError(what + " is not a directory: " + path);
  }
}

void RequireFile(const std::string& path, const std::string& what) {
  if (!fs::exists(path)) {
    throw InputError(what + " does not exist: " + path);
  }
  if (!fs::is_regular_file(path)) {
    throw InputError(what + " is not a regular file: " + path);
  }
}

// 0 means "not given"; anything else must be a finite positive number.
bool OptionalPositive(double value) {
  return value == 0.0 || (std::isfinite(value) && value > 0.0);
}

std::string NotPositive(const char* name, double value) {
  std::ostringstream message;
  message << "--DPScaleEstimator." << name << " must be a positive number, got "
          << value;
  return message.str();
}

}  // namespace

bool ScaleRunOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_MESSAGE(
      workspace_path.empty() != input_path.empty(),
      "give exactly one of --workspace_path (dense workspace) and "
      "--input_path (sparse model)");
  DPSFM_CHECK_OPTION_MESSAGE(!dp_image_path.empty(),
                             "--dp_image_path is required");
  DPSFM_CHECK_OPTION_MESSAGE(
      input_type == "geometric" || input_type == "photometric",
      "--input_type must be geometric or photometric, got '" + input_type +
          "'");
  DPSFM_CHECK_OPTION_MESSAGE(OptionalPositive(focal_length_mm),
                             NotPositive("focal_length_mm", focal_length_mm));
  DPSFM_CHECK_OPTION_MESSAGE(OptionalPositive(f_number),
                             NotPositive("f_number", f_number));
  DPSFM_CHECK_OPTION_MESSAGE(OptionalPositive(pixel_pitch_um),
                             NotPositive("pixel_pitch_um", pixel_pitch_um));
  DPSFM_CHECK_OPTION_MESSAGE(
      std::isfinite(lens_check_tolerance) && lens_check_tolerance >= 0,
      "--DPScaleEstimator.lens_check_tolerance must be a number >= 0, got " +
          std::to_string(lens_check_tolerance));
  DPSFM_CHECK_OPTION_MESSAGE(
      IsDPEncodingName(dp_encoding),
      "--DPScaleEstimator.dp_encoding must be auto, linear or srgb, got '" +
          dp_encoding + "'");
  DPSFM_CHECK_OPTION_MESSAGE(
      prefetch_views >= 0 && prefetch_views <= 8,
      "--DPScaleEstimator.prefetch_views must be in [0, 8], got " +
          std::to_string(prefetch_views));
  std::string budget_failure;
  if (!view_budget.Check(&budget_failure)) {
    return internal::FailOptionCheck(
        failure, "invalid DPScaleEstimator view budget: " + budget_failure);
  }
  return true;
}

bool IsModelDir(const std::string& dir) {
  for (const char* ext : {".bin", ".txt"}) {
    if (fs::is_regular_file(Join(dir, std::string("cameras") + ext)) &&
        fs::is_regular_file(Join(dir, std::string("images") + ext)) &&
        fs::is_regular_file(Join(dir, std::string("points3D") + ext))) {
      return true;
    }
  }
  return false;
}

WorkspaceLayout ResolveWorkspaceLayout(const ScaleRunOptions& options) {
  std::string failure;
  if (!options.Check(&failure)) throw InputError(failure);
  WorkspaceLayout layout;
  if (!options.workspace_path.empty()) {
    layout.dense = true;
    RequireDir(options.workspace_path, "--workspace_path");
    layout.model_path = Join(options.workspace_path, "sparse");
    RequireDir(layout.model_path, "the dense workspace's sparse model");
    if (!IsModelDir(layout.model_path)) {
      throw InputError(
          "the dense workspace has no model (cameras, images, points3D as "
          ".bin or .txt) in " +
          layout.model_path);
    }
    layout.depth_maps_path =
        Join(Join(options.workspace_path, "stereo"), "depth_maps");
    if (!fs::is_directory(layout.depth_maps_path)) {
      throw InputError(
          "the dense workspace has no depth maps (" + layout.depth_maps_path +
          "): run colmap patch_match_stereo on it (it needs CUDA), or, "
          "without CUDA, give its sparse model with --input_path (e.g. "
          "sparse/0, depths from the triangulated points) instead of "
          "--workspace_path");
    }
  } else {
    RequireDir(options.input_path, "--input_path");
    layout.model_path = options.input_path;
    if (!IsModelDir(layout.model_path)) {
      throw InputError(
          "--input_path has no model (cameras, images, points3D as .bin or "
          ".txt): " +
          options.input_path);
    }
  }

  RequireDir(options.dp_image_path, "--dp_image_path");
  layout.left_path = Join(options.dp_image_path, "left");
  RequireDir(layout.left_path, "the left DP views folder");
  const std::string right = Join(options.dp_image_path, "right");
  const std::string sum = Join(options.dp_image_path, "sum");
  if (fs::is_directory(right)) {
    layout.right_path = right;
  } else if (fs::is_directory(sum)) {
    layout.sum_path = sum;
  } else {
    throw InputError("--dp_image_path has neither right/ nor sum/: " +
                     options.dp_image_path);
  }

  std::stringstream extra(options.extra_model_paths);
  std::string model;
  while (std::getline(extra, model, ',')) {
    if (model.empty()) continue;
    RequireDir(model, "--extra_model_paths entry");
    if (!IsModelDir(model)) {
      throw InputError("--extra_model_paths entry has no model: " + model);
    }
  }
  if (!options.image_path.empty()) {
    RequireDir(options.image_path, "--image_path");
  }
  if (!options.original_model_path.empty()) {
    if (options.workspace_path.empty()) {
      throw InputError(
          "--original_model_path is for a dense workspace "
          "(--workspace_path); a sparse model is in the original geometry "
          "already");
    }
    RequireDir(options.original_model_path, "--original_model_path");
    if (!IsModelDir(options.original_model_path)) {
      throw InputError("--original_model_path has no model: " +
                       options.original_model_path);
    }
  }
  if (!options.database_path.empty()) {
    // Opening a missing database would silently create an empty one.
    RequireFile(options.database_path, "--database_path");
  }
  if (!options.lens_path.empty()) {
    RequireFile(options.lens_path, "--lens_path");
  }
  if (!options.report_path.empty()) {
    const fs::path parent = fs::path(options.report_path).parent_path();
    if (!parent.empty() && !fs::is_directory(parent)) {
      throw InputError("the folder of --report_path does not exist: " +
                       parent.string());
    }
  }
  return layout;
}

}  // namespace dpsfm
