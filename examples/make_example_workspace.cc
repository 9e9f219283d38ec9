// Generates a synthetic dual-pixel capture of a tabletop scene with a known
// metric scale, written as a complete COLMAP workspace:
//
//   <out>/images/<name>.jpg          "original" images (DP left + right)
//   <out>/sparse/0/                  sparse model with tracks (model units)
//   <out>/dense/sparse/              the same model (PINHOLE, undistorted)
//   <out>/dense/images/<name>.jpg
//   <out>/dense/stereo/depth_maps/<name>.jpg.{geometric,photometric}.bin
//   <out>/dense/fused.ply            points from the depth maps
//   <out>/dp/left/<name>.png, <out>/dp/right/<name>.png   16-bit DP views
//   <out>/lens.csv, <out>/ground_truth.json
//
// Model units are metres / s_true: the estimator should recover s_true.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <boost/filesystem.hpp>
#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colmap/mvs/depth_map.h"
#include "colmap/scene/database.h"
#include "colmap/scene/reconstruction.h"
#include "colmap/util/ply.h"
#include "dpsfm/core/dp_psf.h"
#include "dpsfm/core/dp_renderer.h"
#include "dpsfm/core/lens_model.h"
#include "synthetic_scene.h"

namespace fs = boost::filesystem;
using dpsfm::examples::PinholeView;
using dpsfm::examples::RenderedView;
using dpsfm::examples::TabletopScene;

namespace {

struct GeneratorOptions {
  std::string output_path;
  int seed = 1;
  int num_views = 10;
  int width = 1200;
  int height = 800;
  double focal_length_mm = 50.0;
  double f_number = 2.8;
  double sensor_width_mm = 36.0;
  // Metres per model unit; 0 draws one at random from the seed.
  double scale = 0.0;
  // Gaussian noise sigma on [0, 1] intensities of each DP view.
  double noise = 0.002;
  // Depth maps are this many times smaller than the images (PatchMatch's
  // max_image_size makes them so).
  int depth_map_factor = 1;
  // Mean gain of the right view relative to the left one.
  double right_gain = 1.0;
  // Radial distortion k1 of the original images (COLMAP SIMPLE_RADIAL).
  // The DP views and sparse/0 are in the distorted geometry; dense/ is
  // undistorted (PINHOLE), as image_undistorter makes it.
  double radial_k1 = 0.0;
  // "additive" (seamless surfaces) or "layers" (occlusion-aware "over"
  // compositing, seams at blur-bin boundaries): see DPRenderOptions.
  std::string compositing = "additive";
};

void WriteDepthMap(const cv::Mat& depth_model,
                   int factor,
                   const std::string& path) {
  cv::Mat small = depth_model;
  if (factor > 1) {
    cv::resize(depth_model,
               small,
               cv::Size(depth_model.cols / factor, depth_model.rows / factor),
               0,
               0,
               cv::INTER_NEAREST);
  }
  double min_depth, max_depth;
  cv::minMaxLoc(small, &min_depth, &max_depth);
  colmap::mvs::DepthMap map(small.cols,
                            small.rows,
                            static_cast<float>(min_depth),
                            static_cast<float>(max_depth));
  for (int r = 0; r < small.rows; ++r) {
    for (int c = 0; c < small.cols; ++c) {
      map.Set(r, c, small.at<float>(r, c));
    }
  }
  map.Write(path);
}

cv::Mat To16Bit(const cv::Mat& image) {
  cv::Mat out;
  image.convertTo(out, CV_16U, 65535.0);
  return out;
}

int Run(const GeneratorOptions& options) {
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double true_scale =
      options.scale > 0 ? options.scale
                        : std::exp(std::log(0.3) + unit(rng) * std::log(10.0));

  const TabletopScene scene = TabletopScene::Random(&rng, 6);
  const double pitch_mm = options.sensor_width_mm / options.width;
  const double focal_px = options.focal_length_mm / pitch_mm;
  dpsfm::DPLensData lens;
  lens.focal_length_mm = options.focal_length_mm;
  lens.f_number = options.f_number;
  lens.pixel_pitch_um = pitch_mm * 1e3;

  const fs::path out(options.output_path);
  for (const char* dir : {"images",
                          "sparse/0",
                          "dense/sparse",
                          "dense/images",
                          "dense/stereo/depth_maps",
                          "dense/stereo/normal_maps",
                          "dp/left",
                          "dp/right"}) {
    fs::create_directories(out / dir);
  }

  // Cameras on an arc in front of the scene, looking at its middle.
  const Eigen::Vector3d target(0.0, scene.wall_y * 0.4, 0.08);
  std::vector<PinholeView> views;
  for (int i = 0; i < options.num_views; ++i) {
    const double angle =
        -0.45 +
        0.9 * (options.num_views == 1 ? 0.5 : i / (options.num_views - 1.0));
    const double distance = 0.75 + 0.2 * unit(rng);
    const Eigen::Vector3d center =
        target + Eigen::Vector3d(distance * std::sin(angle),
                                 -distance * std::cos(angle),
                                 0.3 + 0.15 * unit(rng));
    views.push_back(PinholeView::LookAt(
        center, target, options.width, options.height, focal_px));
    views.back().k1 = options.radial_k1;
  }

  colmap::Reconstruction reconstruction;
  colmap::Camera camera = colmap::Camera::CreateFromModelName(
      1, "PINHOLE", focal_px, options.width, options.height);
  reconstruction.AddCamera(camera);

  const dpsfm::TranslatingDiskPsf psf;
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::ofstream lens_csv((out / "lens.csv").string());
  lens_csv << "name,focal_length_mm,f_number,pixel_pitch_um\n";
  nlohmann::json truth;
  truth["scale"] = true_scale;
  truth["model_unit"] = "metres / scale";

  // Renders in the undistorted (dense) geometry: depth maps, tracks, fused.
  std::vector<RenderedView> renders;
  std::vector<std::string> names;
  for (int i = 0; i < options.num_views; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "DP_%04d", i + 1);
    names.push_back(name);
    // The original (possibly distorted) image, and the undistorted one.
    const RenderedView render = dpsfm::examples::RenderView(scene, views[i]);
    PinholeView pinhole = views[i];
    pinhole.k1 = 0;
    renders.push_back(options.radial_k1 == 0
                          ? render
                          : dpsfm::examples::RenderView(scene, pinhole));

    // Focus somewhere inside the scene's depth range, as a photographer
    // focusing on the subject would.
    std::vector<float> depths;
    for (int r = 0; r < render.depth.rows; r += 4) {
      for (int c = 0; c < render.depth.cols; c += 4) {
        if (render.depth.at<float>(r, c) > 0) {
          depths.push_back(render.depth.at<float>(r, c));
        }
      }
    }
    std::sort(depths.begin(), depths.end());
    const double focus_m =
        depths[static_cast<size_t>((0.3 + 0.4 * unit(rng)) * depths.size())];

    cv::Mat radius(render.depth.size(), CV_32FC1);
    for (int r = 0; r < radius.rows; ++r) {
      for (int c = 0; c < radius.cols; ++c) {
        const float z = render.depth.at<float>(r, c);
        const double b = dpsfm::SignedBlurDiameterMm(
            lens, focus_m * 1e3, z > 0 ? z * 1e3 : 1e12);
        radius.at<float>(r, c) =
            static_cast<float>(dpsfm::BlurRadiusPxFromDiameterMm(b, pitch_mm));
      }
    }
    cv::Mat left, right;
    dpsfm::DPRenderOptions render_options;
    render_options.compositing =
        options.compositing == "layers"
            ? dpsfm::DPRenderOptions::Compositing::kOcclusionLayers
            : dpsfm::DPRenderOptions::Compositing::kAdditive;
    dpsfm::RenderDPViews(
        render.image, render.depth, radius, psf, render_options, &left, &right);
    right *= options.right_gain;
    for (cv::Mat* view : {&left, &right}) {
      cv::Mat noise(view->size(), view->type());
      cv::randn(noise, 0.0, options.noise);
      *view += noise;
      cv::max(*view, 0.0, *view);
      cv::min(*view, 1.0, *view);
    }
    cv::imwrite((out / "dp/left" / (std::string(name) + ".png")).string(),
                To16Bit(left));
    cv::imwrite((out / "dp/right" / (std::string(name) + ".png")).string(),
                To16Bit(right));
    cv::Mat combined;
    cv::Mat(left + right).convertTo(combined, CV_8U, 255.0);
    const std::string image_name = std::string(name) + ".jpg";
    cv::imwrite((out / "images" / image_name).string(), combined);
    if (options.radial_k1 == 0) {
      cv::imwrite((out / "dense/images" / image_name).string(), combined);
    } else {
      cv::Mat undistorted;
      renders.back().image.convertTo(undistorted, CV_8U, 255.0);
      cv::imwrite((out / "dense/images" / image_name).string(), undistorted);
    }

    const cv::Mat depth_model = renders.back().depth / true_scale;
    const fs::path depth_dir = out / "dense/stereo/depth_maps";
    WriteDepthMap(depth_model,
                  options.depth_map_factor,
                  (depth_dir / (image_name + ".geometric.bin")).string());
    WriteDepthMap(depth_model,
                  options.depth_map_factor,
                  (depth_dir / (image_name + ".photometric.bin")).string());

    lens_csv << image_name << "," << options.focal_length_mm << ","
             << options.f_number << "," << lens.pixel_pitch_um << "\n";
    truth["views"][image_name]["focus_distance_m"] = focus_m;
    const Eigen::Vector3d center = views[i].Center();
    truth["views"][image_name]["center_m"] = {
        center.x(), center.y(), center.z()};
  }

  // Tracks: grid samples of every view, observed wherever they are visible.
  std::vector<std::vector<colmap::Point2D>> points2D(options.num_views);
  // The same observations in the original, distorted images (sparse/0).
  std::vector<std::vector<Eigen::Vector2d>> distorted2D(options.num_views);
  struct Track3D {
    Eigen::Vector3d xyz;
    std::vector<std::pair<int, int>> observations;  // (view, point2D idx)
  };
  std::vector<Track3D> tracks;
  for (int i = 0; i < options.num_views; ++i) {
    const Eigen::Matrix3d world_from_cam = views[i].rotation.transpose();
    for (int r = 20; r < options.height - 20; r += options.height / 24) {
      for (int c = 20; c < options.width - 20; c += options.width / 36) {
        const float z = renders[i].depth.at<float>(r, c);
        if (z <= 0) continue;
        const Eigen::Vector3d cam(
            (c - (options.width - 1) / 2.0) / focal_px * z,
            (r - (options.height - 1) / 2.0) / focal_px * z,
            z);
        Track3D track;
        track.xyz = world_from_cam * (cam - views[i].translation);
        for (int j = 0; j < options.num_views; ++j) {
          const Eigen::Vector3d pc =
              views[j].rotation * track.xyz + views[j].translation;
          if (pc.z() <= 0) continue;
          const double u =
              focal_px * pc.x() / pc.z() + (options.width - 1) / 2.0;
          const double v =
              focal_px * pc.y() / pc.z() + (options.height - 1) / 2.0;
          const int ui = static_cast<int>(std::lround(u));
          const int vi = static_cast<int>(std::lround(v));
          if (ui < 0 || vi < 0 || ui >= options.width || vi >= options.height) {
            continue;
          }
          const float zj = renders[j].depth.at<float>(vi, ui);
          if (std::abs(zj - pc.z()) > 0.01 * pc.z()) continue;  // occluded
          // COLMAP puts the top-left pixel centre at (0.5, 0.5).
          colmap::Point2D point;
          point.xy = Eigen::Vector2d(u + 0.5, v + 0.5);
          track.observations.emplace_back(j, points2D[j].size());
          points2D[j].push_back(point);
          distorted2D[j].push_back(views[j].Project(pc) +
                                   Eigen::Vector2d(0.5, 0.5));
        }
        if (track.observations.size() >= 2) tracks.push_back(track);
      }
    }
  }
  for (int i = 0; i < options.num_views; ++i) {
    colmap::Image image;
    image.SetImageId(i + 1);
    image.SetName(names[i] + ".jpg");
    image.SetCameraId(1);
    image.CamFromWorld() =
        colmap::Rigid3d(Eigen::Quaterniond(views[i].rotation),
                        views[i].translation / true_scale);
    image.SetPoints2D(points2D[i]);
    reconstruction.AddImage(image);
    reconstruction.RegisterImage(i + 1);
  }
  for (const Track3D& track : tracks) {
    colmap::Track colmap_track;
    for (const auto& obs : track.observations) {
      colmap_track.AddElement(obs.first + 1, obs.second);
    }
    reconstruction.AddPoint3D(
        track.xyz / true_scale, colmap_track, Eigen::Vector3ub(128, 128, 128));
  }
  reconstruction.WriteBinary((out / "dense/sparse").string());
  // sparse/0: the model of the original images, as the mapper leaves it.
  colmap::Camera original = colmap::Camera::CreateFromModelName(
      1, "SIMPLE_RADIAL", focal_px, options.width, options.height);
  original.params[3] = options.radial_k1;
  reconstruction.Camera(1) = original;
  for (int i = 0; i < options.num_views; ++i) {
    colmap::Image& image = reconstruction.Image(i + 1);
    for (size_t k = 0; k < distorted2D[i].size(); ++k) {
      image.Point2D(k).xy = distorted2D[i][k];
    }
  }
  reconstruction.WriteBinary((out / "sparse/0").string());
  {
    // The project database, as feature extraction leaves it (cameras and
    // images; no features are needed here).
    colmap::Database database((out / "database.db").string());
    database.WriteCamera(original, /*use_camera_id=*/true);
    for (int i = 0; i < options.num_views; ++i) {
      colmap::Image image;
      image.SetName(names[i] + ".jpg");
      image.SetCameraId(1);
      database.WriteImage(image);
    }
  }

  // fused.ply: every 4th depth pixel of every view, in model units.
  std::vector<colmap::PlyPoint> ply_points;
  for (int i = 0; i < options.num_views; ++i) {
    const Eigen::Matrix3d world_from_cam = views[i].rotation.transpose();
    for (int r = 0; r < options.height; r += 4) {
      for (int c = 0; c < options.width; c += 4) {
        const float z = renders[i].depth.at<float>(r, c);
        if (z <= 0) continue;
        const Eigen::Vector3d cam(
            (c - (options.width - 1) / 2.0) / focal_px * z,
            (r - (options.height - 1) / 2.0) / focal_px * z,
            z);
        const Eigen::Vector3d xyz =
            world_from_cam * (cam - views[i].translation) / true_scale;
        const Eigen::Vector3d normal = -(world_from_cam * cam).normalized();
        const cv::Vec3f bgr = renders[i].image.at<cv::Vec3f>(r, c);
        colmap::PlyPoint point;
        point.x = xyz.x();
        point.y = xyz.y();
        point.z = xyz.z();
        point.nx = normal.x();
        point.ny = normal.y();
        point.nz = normal.z();
        point.r = static_cast<uint8_t>(255 * bgr[2]);
        point.g = static_cast<uint8_t>(255 * bgr[1]);
        point.b = static_cast<uint8_t>(255 * bgr[0]);
        ply_points.push_back(point);
      }
    }
  }
  colmap::WriteBinaryPlyPoints((out / "dense/fused.ply").string(),
                               ply_points,
                               /*write_normal=*/true,
                               /*write_rgb=*/true);

  std::ofstream((out / "ground_truth.json").string()) << truth.dump(2) << "\n";
  std::cout << "Generated " << options.num_views << " views, " << tracks.size()
            << " tracks, true scale " << true_scale << " m per model unit, in "
            << options.output_path << std::endl;
  return EXIT_SUCCESS;
}

}  // namespace

int main(int argc, char** argv) {
  GeneratorOptions options;
  namespace po = boost::program_options;
  po::options_description desc("dpsfm_make_example options");
  desc.add_options()("help,h", "")("output_path",
                                   po::value(&options.output_path)->required(),
                                   "output folder")(
      "seed",
      po::value(&options.seed)->default_value(options.seed),
      "random seed")(
      "num_views",
      po::value(&options.num_views)->default_value(options.num_views),
      "")("width",
          po::value(&options.width)->default_value(options.width),
          "image width")(
      "height",
      po::value(&options.height)->default_value(options.height),
      "image height")("focal_length_mm",
                      po::value(&options.focal_length_mm)
                          ->default_value(options.focal_length_mm),
                      "")(
      "f_number",
      po::value(&options.f_number)->default_value(options.f_number),
      "")("sensor_width_mm",
          po::value(&options.sensor_width_mm)
              ->default_value(options.sensor_width_mm),
          "")("scale",
              po::value(&options.scale)->default_value(options.scale),
              "metres per model unit (0: random)")(
      "noise",
      po::value(&options.noise)->default_value(options.noise),
      "noise sigma on [0,1]")("depth_map_factor",
                              po::value(&options.depth_map_factor)
                                  ->default_value(options.depth_map_factor),
                              "")(
      "right_gain",
      po::value(&options.right_gain)->default_value(options.right_gain),
      "")("radial_k1",
          po::value(&options.radial_k1)->default_value(options.radial_k1),
          "SIMPLE_RADIAL k1 of the original images")(
      "compositing",
      po::value(&options.compositing)->default_value(options.compositing),
      "additive | layers");
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, desc), vm);
    if (vm.count("help")) {
      std::cout << desc << std::endl;
      return EXIT_SUCCESS;
    }
    po::notify(vm);
    if (options.num_views < 1 || options.width < 64 || options.height < 64 ||
        options.depth_map_factor < 1 ||
        (options.compositing != "additive" &&
         options.compositing != "layers")) {
      throw std::invalid_argument(
          "need num_views >= 1, width/height >= 64, depth_map_factor >= 1, "
          "compositing additive or layers");
    }
    return Run(options);
  } catch (const std::exception& error) {
    std::cerr << "ERROR: dpsfm_make_example: " << error.what() << std::endl;
    return EXIT_FAILURE;
  }
}
