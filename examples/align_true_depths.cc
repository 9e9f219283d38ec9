// Gives a dense workspace made by the real COLMAP pipeline (mapper, then
// image_undistorter) the generator's true depth maps, expressed in that
// workspace's own frame and units, in place of PatchMatch stereo (which
// needs CUDA). The mapper-to-truth similarity comes from the camera
// centres of the images both models share (Umeyama); each output depth is
// the true surface point seen along the workspace camera's ray, mapped into
// the workspace's frame. Also writes the ground truth of the workspace:
// the generator's, with the true scale of the workspace's units (metres
// per unit, from the true camera centres).
//
// dp_scale_estimator then takes the DP frames' original (distorted)
// geometry from the mapper's model with --original_model_path.
//
//   dpsfm_align_true_depths --truth_path GENERATED_SCENE
//       --workspace_path PIPELINE_DENSE --ground_truth_output FILE.json
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "colmap/mvs/depth_map.h"
#include "colmap/scene/reconstruction.h"
#include "dpsfm/colmap/util/colmap_compat.h"

namespace fs = std::filesystem;

namespace {

struct Similarity {
  // truth = scale * rotation * model + translation
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  // RMS distance of the aligned model centres from the true ones, in
  // truth units.
  double rms_residual = 0;
};

Similarity AlignCenters(const std::vector<Eigen::Vector3d>& model_centers,
                        const std::vector<Eigen::Vector3d>& truth_centers) {
  const int n = static_cast<int>(model_centers.size());
  if (n < 3) {
    throw std::runtime_error("need at least 3 shared images to align, got " +
                             std::to_string(n));
  }
  Eigen::Matrix3Xd source(3, n), target(3, n);
  for (int i = 0; i < n; ++i) {
    source.col(i) = model_centers[i];
    target.col(i) = truth_centers[i];
  }
  const Eigen::Matrix4d transform = Eigen::umeyama(source, target, true);
  Similarity similarity;
  similarity.scale = transform.block<3, 1>(0, 0).norm();
  similarity.rotation = transform.block<3, 3>(0, 0) / similarity.scale;
  similarity.translation = transform.block<3, 1>(0, 3);
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    sum += (similarity.scale * similarity.rotation * source.col(i) +
            similarity.translation - target.col(i))
               .squaredNorm();
  }
  similarity.rms_residual = std::sqrt(sum / n);
  return similarity;
}

// The depth map of `image` (workspace camera, workspace units) from the
// true depth map of the same image in the truth model.
colmap::mvs::DepthMap TransferDepthMap(const colmap::Image& image,
                                       const colmap::Camera& camera,
                                       const colmap::Image& truth_image,
                                       const colmap::Camera& truth_camera,
                                       const colmap::mvs::DepthMap& truth_depth,
                                       const Similarity& similarity) {
  const int width = static_cast<int>(camera.width);
  const int height = static_cast<int>(camera.height);
  const double sx =
      static_cast<double>(truth_depth.GetWidth()) / truth_camera.width;
  const double sy =
      static_cast<double>(truth_depth.GetHeight()) / truth_camera.height;
  const colmap::Rigid3d cam_from_world = image.CamFromWorld();
  const Eigen::Matrix3d world_from_cam =
      dpsfm::RotationOf(cam_from_world).toRotationMatrix().transpose();
  const colmap::Rigid3d truth_cam_from_world = truth_image.CamFromWorld();
  const Eigen::Quaterniond truth_rotation =
      dpsfm::RotationOf(truth_cam_from_world);
  const colmap::Rigid3d truth_world_from_cam =
      colmap::Inverse(truth_cam_from_world);
  std::vector<float> depths(static_cast<size_t>(width) * height, 0.0f);
#pragma omp parallel for schedule(static)
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      // The workspace camera's ray, as a direction in the truth frame, then
      // in the true camera (the centres agree up to the alignment error).
      const std::optional<Eigen::Vector2d> cam =
          dpsfm::CamFromImg(camera, Eigen::Vector2d(x + 0.5, y + 0.5));
      if (!cam) continue;
      const Eigen::Vector3d truth_ray =
          truth_rotation *
          (similarity.rotation * (world_from_cam * cam->homogeneous()));
      const std::optional<Eigen::Vector2d> uv =
          dpsfm::ImgFromCam(truth_camera, truth_ray);
      if (!uv) continue;
      const int col = static_cast<int>(std::floor(uv->x() * sx));
      const int row = static_cast<int>(std::floor(uv->y() * sy));
      if (col < 0 || row < 0 ||
          col >= static_cast<int>(truth_depth.GetWidth()) ||
          row >= static_cast<int>(truth_depth.GetHeight())) {
        continue;
      }
      const float truth_z = truth_depth.Get(row, col);
      if (!(truth_z > 0)) continue;
      const std::optional<Eigen::Vector2d> truth_cam =
          dpsfm::CamFromImg(truth_camera, *uv);
      if (!truth_cam) continue;
      const Eigen::Vector3d point_truth =
          truth_world_from_cam * (Eigen::Vector3d(truth_cam->homogeneous()) *
                                  static_cast<double>(truth_z));
      const Eigen::Vector3d point = similarity.rotation.transpose() *
                                    (point_truth - similarity.translation) /
                                    similarity.scale;
      const double z = (cam_from_world * point).z();
      if (z > 0) depths[static_cast<size_t>(y) * width + x] = z;
    }
  }
  float min_depth = 0, max_depth = 0;
  for (const float z : depths) {
    if (z > 0 && (min_depth == 0 || z < min_depth)) min_depth = z;
    max_depth = std::max(max_depth, z);
  }
  colmap::mvs::DepthMap map(width, height, min_depth, max_depth);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      map.Set(y, x, depths[static_cast<size_t>(y) * width + x]);
    }
  }
  return map;
}

struct Paths {
  std::string truth;
  std::string workspace;
  std::string ground_truth_output;
};

int Run(const Paths& paths) {
  const fs::path truth_root(paths.truth);
  const fs::path workspace(paths.workspace);
  colmap::Reconstruction truth_model, model;
  truth_model.Read((truth_root / "dense/sparse").string());
  model.Read((workspace / "sparse").string());
  std::ifstream truth_file((truth_root / "ground_truth.json").string());
  if (!truth_file) throw std::runtime_error("cannot read ground_truth.json");
  nlohmann::json truth = nlohmann::json::parse(truth_file);

  std::map<std::string, colmap::image_t> truth_ids;
  for (const auto& entry : truth_model.Images()) {
    truth_ids[entry.second.Name()] = entry.first;
  }
  // Two alignments of the workspace's camera centres: to the generated
  // model's (whose depth maps are transferred; it may have been rescaled
  // already, so its units are not assumed), and to the true centres in
  // metres (which give the workspace's true scale).
  std::vector<Eigen::Vector3d> model_centers, truth_centers, metric_centers;
  for (const colmap::image_t id : model.RegImageIds()) {
    const std::string& name = model.Image(id).Name();
    const auto truth_id = truth_ids.find(name);
    if (truth_id == truth_ids.end() || !truth.at("views").contains(name)) {
      throw std::runtime_error("image " + name +
                               " is not in the generated scene");
    }
    model_centers.push_back(model.Image(id).ProjectionCenter());
    truth_centers.push_back(
        truth_model.Image(truth_id->second).ProjectionCenter());
    const auto& center = truth["views"][name].at("center_m");
    metric_centers.emplace_back(center[0], center[1], center[2]);
  }
  const Similarity similarity = AlignCenters(model_centers, truth_centers);
  const Similarity metric = AlignCenters(model_centers, metric_centers);
  truth["scale"] = metric.scale;
  truth["model_unit"] = "metres / scale, in the frame of " + paths.workspace;
  truth["alignment"] = {{"rms_center_residual_m", metric.rms_residual}};

  const fs::path depth_dir = workspace / "stereo/depth_maps";
  fs::create_directories(depth_dir);
  for (const colmap::image_t id : model.RegImageIds()) {
    const colmap::Image& image = model.Image(id);
    const colmap::Image& truth_image =
        truth_model.Image(truth_ids.at(image.Name()));
    colmap::mvs::DepthMap truth_depth;
    truth_depth.Read((truth_root / "dense/stereo/depth_maps" /
                      (image.Name() + ".geometric.bin"))
                         .string());
    const colmap::mvs::DepthMap depth =
        TransferDepthMap(image,
                         model.Camera(image.CameraId()),
                         truth_image,
                         truth_model.Camera(truth_image.CameraId()),
                         truth_depth,
                         similarity);
    for (const char* type : {".geometric.bin", ".photometric.bin"}) {
      depth.Write((depth_dir / (image.Name() + type)).string());
    }
  }
  std::ofstream(paths.ground_truth_output) << truth.dump(2) << "\n";
  std::printf(
      "Aligned %zu images of %s to the generated scene: camera centres "
      "within %.2f mm RMS; true scale of the workspace %.6g m per model "
      "unit; true depth maps written to %s\n",
      model_centers.size(),
      paths.workspace.c_str(),
      1e3 * metric.rms_residual,
      metric.scale,
      depth_dir.string().c_str());
  return EXIT_SUCCESS;
}

}  // namespace

int main(int argc, char** argv) {
  Paths paths;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--truth_path") paths.truth = argv[i + 1];
    if (flag == "--workspace_path") paths.workspace = argv[i + 1];
    if (flag == "--ground_truth_output") {
      paths.ground_truth_output = argv[i + 1];
    }
  }
  if (paths.truth.empty() || paths.workspace.empty() ||
      paths.ground_truth_output.empty()) {
    std::cerr << "usage: dpsfm_align_true_depths --truth_path GENERATED_SCENE "
                 "--workspace_path PIPELINE_DENSE --ground_truth_output "
                 "FILE.json\n";
    return EXIT_FAILURE;
  }
  try {
    return Run(paths);
  } catch (const std::exception& error) {
    std::cerr << "ERROR: dpsfm_align_true_depths: " << error.what()
              << std::endl;
    return EXIT_FAILURE;
  }
}
