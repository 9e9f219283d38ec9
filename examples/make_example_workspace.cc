// Generates a synthetic dual-pixel capture of a parametric scene with a known
// metric scale, written as a complete COLMAP workspace:
//
//   <out>/images/<name>.jpg          "original" images (DP left + right)
//   <out>/sparse/0/                  sparse model with tracks (model units)
//   <out>/dense/sparse/              the same model (PINHOLE, undistorted)
//   <out>/dense/images/<name>.jpg
//   <out>/dense/stereo/depth_maps/<name>.jpg.{geometric,photometric}.bin
//   <out>/dense/fused.ply            points from the depth maps
//   <out>/dp/left/<name>.png, <out>/dp/right/<name>.png   16-bit DP views
//   <out>/database.db, <out>/lens.csv, <out>/ground_truth.json
//
// Model units are metres / s_true: the estimator should recover s_true.
// Scenes: tabletop, facade, planes. Cameras: a full-frame DSLR (DP frames
// at the image size) or a phone (4.38 mm f/1.73, DP frames at half the
// image size). With --f_numbers, every tripod position is captured at
// several apertures (same pose and focus, one image per aperture).
// Everything is drawn from --seed.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colmap/mvs/depth_map.h"
#include "colmap/scene/database.h"
#include "colmap/scene/reconstruction.h"
#include "colmap/util/ply.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/dp_renderer.h"
#include "dpsfm/core/optics/lens_model.h"
#include "examples/aperture_renderer.h"
#include "synthetic_scene.h"

namespace fs = std::filesystem;
using dpsfm::examples::PinholeView;
using dpsfm::examples::RenderedView;
using dpsfm::examples::SyntheticScene;

namespace {

struct GeneratorOptions {
  std::string output_path;
  int seed = 1;
  int num_views = 10;
  // tabletop | facade | planes.
  std::string scene = "tabletop";
  // dslr | phone: the defaults of every option below that is 0.
  std::string camera = "dslr";
  int width = 0;
  int height = 0;
  double focal_length_mm = 0;
  double f_number = 0;
  // Several apertures per tripod position ("2.8,5.6,11"): one image each,
  // named <pose>_f<N>. Overrides f_number.
  std::string f_numbers;
  double sensor_width_mm = 0;
  // DP frames are this many times smaller than the images.
  int dp_factor = 0;
  // Multiplies every length of the scene and of the camera rig: a phone
  // photographs the same scene from closer up.
  double scene_scale = 0;
  // Metres per model unit; 0 draws one at random from the seed.
  double scale = 0.0;
  // Gaussian noise sigma on [0, 1] intensities of each DP view.
  double noise = 0.002;
  // Depth maps are this many times smaller than the images (PatchMatch's
  // max_image_size makes them so).
  int depth_map_factor = 1;
  // Relative sigma of the depth maps' error: half of its variance
  // per-pixel, half smooth over ~16 depth-map pixels (as PatchMatch's
  // errors are partly correlated).
  double depth_noise = 0;
  // Fraction of depth-map pixels set to 0, in blobs (PatchMatch's filtered
  // holes).
  double depth_holes = 0;
  // Mean gain of the right view relative to the left one.
  double right_gain = 1.0;
  // Opposite horizontal gain ramps of the two views (vignetting of the
  // half apertures): the left view's gain goes from 1 + ramp/2 at the left
  // edge to 1 - ramp/2 at the right edge, the right view's the other way.
  double gain_ramp = 0.0;
  // Texture contrast: 1 full, 0 flat surfaces (no texture).
  double texture_contrast = 1.0;
  // Radial distortion k1 of the original images (COLMAP SIMPLE_RADIAL).
  // The DP views and sparse/0 are in the distorted geometry; dense/ is
  // undistorted (PINHOLE), as image_undistorter makes it.
  double radial_k1 = 0.0;
  // "additive" (seamless surfaces) or "layers" (occlusion-aware "over"
  // compositing, seams at blur-bin boundaries): see DPRenderOptions.
  std::string compositing = "additive";
  // The sensor's DP split profile (dpsfm::SplitProfilePsf); split exponent
  // 0 = the paper's translating disk. With psf_split_exponent_right > 0 the
  // profile changes across the frame: the views are blended column by
  // column from the profile with psf_split_exponent (left edge) to the one
  // with psf_split_exponent_right (right edge).
  double psf_split_exponent = 0;
  double psf_crosstalk = 0;
  double psf_rim_softness = 0;
  double psf_split_exponent_right = 0;
  // kernels: the views by convolution with the profile's kernels
  // (dpsfm::RenderDPViews); aperture: by following each pixel's light
  // through sample points of the aperture (aperture_renderer.h: no code
  // shared with the estimator's optics), with a split between the halves
  // that leaks aperture_crosstalk; the psf_* options then do not apply.
  std::string renderer = "kernels";
  int aperture_subsamples = 2;
  double aperture_crosstalk = 0.1;
  // Calibration captures of a planar textured target at known distances
  // made with the same camera and profile (calibration/dp, targets.csv), for
  // colmap dp_psf_calibrator. 0 = none.
  int calibration_captures = 0;
};

// The simulated sensor's DP PSF: one profile, or two blended across the
// frame.
struct SensorPsf {
  std::shared_ptr<const dpsfm::DPPsfModel> left_edge, right_edge;
  std::string description;
};

SensorPsf MakeSensorPsf(const GeneratorOptions& options) {
  SensorPsf sensor;
  const bool split = options.psf_split_exponent > 0 ||
                     options.psf_crosstalk > 0 || options.psf_rim_softness > 0;
  auto make = [&](double exponent) {
    dpsfm::SplitProfileParams params;
    params.split_exponent = exponent > 0 ? exponent : 1.0;
    params.crosstalk = options.psf_crosstalk;
    params.rim_softness = options.psf_rim_softness;
    return std::make_shared<const dpsfm::SplitProfilePsf>(params);
  };
  if (!split && options.psf_split_exponent_right <= 0) {
    sensor.left_edge = std::make_shared<const dpsfm::TranslatingDiskPsf>();
  } else {
    sensor.left_edge = make(options.psf_split_exponent);
  }
  if (options.renderer == "aperture") {
    std::ostringstream description;
    description << "aperture sampling (" << options.aperture_subsamples
                << " points per pixel of blur, crosstalk "
                << options.aperture_crosstalk << ")";
    sensor.description = description.str();
    return sensor;
  }
  sensor.description = sensor.left_edge->Name();
  if (options.psf_split_exponent_right > 0) {
    sensor.right_edge = make(options.psf_split_exponent_right);
    sensor.description += " -> " + sensor.right_edge->Name();
  }
  return sensor;
}

// DP views through the sensor's PSF, or through the aperture (the
// generator's renderer option).
void RenderSensorViews(const GeneratorOptions& options,
                       const SensorPsf& sensor,
                       const cv::Mat& image,
                       const cv::Mat& depth,
                       const cv::Mat& radius,
                       const dpsfm::DPRenderOptions& render_options,
                       cv::Mat* left,
                       cv::Mat* right) {
  if (options.renderer == "aperture") {
    dpsfm::examples::ApertureRenderOptions aperture;
    aperture.subsamples_per_pixel = options.aperture_subsamples;
    aperture.crosstalk = options.aperture_crosstalk;
    dpsfm::examples::RenderDPByApertureSampling(
        image, radius, aperture, left, right);
    return;
  }
  dpsfm::RenderDPViews(
      image, depth, radius, *sensor.left_edge, render_options, left, right);
  if (!sensor.right_edge) return;
  cv::Mat other_left, other_right;
  dpsfm::RenderDPViews(image,
                       depth,
                       radius,
                       *sensor.right_edge,
                       render_options,
                       &other_left,
                       &other_right);
  for (int c = 0; c < left->cols; ++c) {
    const double w = left->cols == 1 ? 0 : c / (left->cols - 1.0);
    left->col(c) = (1 - w) * left->col(c) + w * other_left.col(c);
    right->col(c) = (1 - w) * right->col(c) + w * other_right.col(c);
  }
}

// The signed blur radius (pixels of `pitch_mm`) of a point at depth_m
// (<= 0: at infinity) under the focus focus_m: the renderer's own thin lens
// for the aperture renderer, the core's for the kernels.
double BlurRadiusPx(const GeneratorOptions& options,
                    const dpsfm::DPLensData& lens,
                    double focus_m,
                    double depth_m,
                    double pitch_mm) {
  const double depth_mm = depth_m > 0 ? depth_m * 1e3 : 1e12;
  if (options.renderer == "aperture") {
    return dpsfm::examples::ThinLensBlurRadiusPx(
        lens.focal_length_mm, lens.f_number, pitch_mm, focus_m * 1e3, depth_mm);
  }
  return dpsfm::BlurRadiusPxFromDiameterMm(
      dpsfm::SignedBlurDiameterMm(lens, focus_m * 1e3, depth_mm), pitch_mm);
}

// Fills the options left at 0 with the camera's defaults.
void ApplyCameraDefaults(GeneratorOptions* options) {
  struct Defaults {
    int width, height;
    double focal_length_mm, f_number, sensor_width_mm;
    int dp_factor;
    double scene_scale;
  };
  Defaults defaults;
  if (options->camera == "dslr") {
    // A full-frame DSLR with a 50 mm lens, images downsized to 1200 px.
    defaults = {1200, 800, 50.0, 2.8, 36.0, 1, 1.0};
  } else if (options->camera == "phone") {
    // A Pixel 4-like phone: 4.38 mm f/1.73 on a 5.6 mm wide sensor, 4:3
    // images of 1600 px (3.5 um pixels), DP frames at half that.
    defaults = {1600, 1200, 4.38, 1.73, 5.6, 2, 0.3};
  } else {
    throw std::invalid_argument("unknown camera '" + options->camera +
                                "' (dslr or phone)");
  }
  if (options->width == 0) options->width = defaults.width;
  if (options->height == 0) options->height = defaults.height;
  if (options->focal_length_mm == 0) {
    options->focal_length_mm = defaults.focal_length_mm;
  }
  if (options->f_number == 0) options->f_number = defaults.f_number;
  if (options->sensor_width_mm == 0) {
    options->sensor_width_mm = defaults.sensor_width_mm;
  }
  if (options->dp_factor == 0) options->dp_factor = defaults.dp_factor;
  if (options->scene_scale == 0) options->scene_scale = defaults.scene_scale;
}

std::vector<double> ParseFNumbers(const std::string& list) {
  std::vector<double> values;
  std::stringstream stream(list);
  std::string item;
  while (std::getline(stream, item, ',')) {
    size_t end = 0;
    const double value = std::stod(item, &end);
    if (end != item.size() || !(value > 0)) {
      throw std::invalid_argument("bad f-number '" + item + "' in --f_numbers");
    }
    values.push_back(value);
  }
  if (values.empty()) throw std::invalid_argument("--f_numbers is empty");
  return values;
}

// A seed for an image's own random numbers (noise), from the run's seed and
// the image's name (FNV-1a): the same image gets the same noise whatever
// else the run generates.
uint64_t ImageSeed(int seed, const std::string& name) {
  uint64_t hash = 1469598103934665603ull ^ static_cast<uint64_t>(seed);
  for (const char c : name) {
    hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  }
  return hash;
}

// A smooth random field of unit variance over `size`, varying over about
// `cell` pixels.
cv::Mat SmoothNoise(const cv::Size& size, int cell, cv::RNG* rng) {
  cv::Mat coarse(size.height / cell + 3, size.width / cell + 3, CV_32FC1);
  rng->fill(coarse, cv::RNG::NORMAL, 0.0, 1.0);
  cv::Mat fine;
  cv::resize(coarse,
             fine,
             cv::Size(coarse.cols * cell, coarse.rows * cell),
             0,
             0,
             cv::INTER_CUBIC);
  fine = fine(cv::Rect(cell, cell, size.width, size.height)).clone();
  cv::Scalar mean, stddev;
  cv::meanStdDev(fine, mean, stddev);
  return (fine - mean[0]) / std::max(stddev[0], 1e-9);
}

// PatchMatch-like depth-map errors: relative noise, then holes (0) in
// blobs covering `hole_fraction` of the map.
void DegradeDepthMap(double relative_sigma,
                     double hole_fraction,
                     cv::RNG* rng,
                     cv::Mat* depth) {
  if (relative_sigma > 0) {
    cv::Mat white(depth->size(), CV_32FC1);
    rng->fill(white, cv::RNG::NORMAL, 0.0, 1.0);
    const cv::Mat error =
        (white + SmoothNoise(depth->size(), 16, rng)) * (1 / std::sqrt(2.0));
    for (int r = 0; r < depth->rows; ++r) {
      for (int c = 0; c < depth->cols; ++c) {
        float& z = depth->at<float>(r, c);
        if (z > 0) {
          z *= std::max(1 + relative_sigma * error.at<float>(r, c), 0.1);
        }
      }
    }
  }
  if (hole_fraction > 0) {
    const cv::Mat field = SmoothNoise(depth->size(), 12, rng);
    std::vector<float> values(field.begin<float>(), field.end<float>());
    const size_t k = std::min(
        values.size() - 1, static_cast<size_t>(hole_fraction * values.size()));
    std::nth_element(values.begin(), values.begin() + k, values.end());
    const float threshold = values[k];
    depth->setTo(0.0f, field < threshold);
  }
}

void WriteDepthMap(const cv::Mat& depth_model, const std::string& path) {
  double min_depth, max_depth;
  cv::minMaxLoc(depth_model, &min_depth, &max_depth);
  colmap::mvs::DepthMap map(depth_model.cols,
                            depth_model.rows,
                            static_cast<float>(min_depth),
                            static_cast<float>(max_depth));
  for (int r = 0; r < depth_model.rows; ++r) {
    for (int c = 0; c < depth_model.cols; ++c) {
      map.Set(r, c, depth_model.at<float>(r, c));
    }
  }
  map.Write(path);
}

cv::Mat To16Bit(const cv::Mat& image) {
  cv::Mat out;
  image.convertTo(out, CV_16U, 65535.0);
  return out;
}

// The gain of each column: 1 + slope * (x / (width - 1) - 0.5).
void ApplyColumnGain(double gain, double slope, cv::Mat* image) {
  for (int c = 0; c < image->cols; ++c) {
    const double t = image->cols == 1 ? 0 : c / (image->cols - 1.0) - 0.5;
    image->col(c) *= gain * (1 + slope * t);
  }
}

void AddNoiseAndClamp(double sigma, cv::RNG* rng, cv::Mat* image) {
  if (sigma > 0) {
    cv::Mat noise(image->size(), image->type());
    rng->fill(noise, cv::RNG::NORMAL, 0.0, sigma);
    *image += noise;
  }
  cv::max(*image, 0.0, *image);
  cv::min(*image, 1.0, *image);
}

// "2.8" -> "2.8", "11" -> "11": the f-number as written in image names.
std::string FNumberTag(double f_number) {
  std::ostringstream tag;
  tag << f_number;
  return tag.str();
}

// colmap dp_psf_calibrator's input: DP captures of a planar, fronto-parallel
// target with multi-scale texture, focused at 1 m (x scene_scale), at
// distances whose blur spans 0.3-0.85 of the automatic radius bound on both
// sides of the focus; calibration/targets.csv lists them with the lens data
// (pitch of the DP frames' pixels).
void WriteCalibrationCaptures(const GeneratorOptions& options,
                              const SensorPsf& sensor,
                              double pitch_mm,
                              const cv::Size& dp_size,
                              std::mt19937* rng,
                              const fs::path& out) {
  const fs::path root = out / "calibration";
  fs::create_directories(root / "dp/left");
  fs::create_directories(root / "dp/right");
  std::ofstream csv((root / "targets.csv").string());
  csv << "name,target_distance_m,focus_distance_m,focal_length_mm,f_number,"
         "pixel_pitch_um\n";
  dpsfm::DPLensData lens;
  lens.focal_length_mm = options.focal_length_mm;
  lens.f_number = options.f_number;
  lens.pixel_pitch_um = pitch_mm * 1e3 * options.dp_factor;
  const double focus_m = 1.0 * options.scene_scale;
  const double bound = dpsfm::DefaultPatchGeometry(dp_size).max_radius_px;
  const cv::Size size(options.width, options.height);
  const dpsfm::DPRenderOptions render_options;
  for (int k = 0; k < options.calibration_captures; ++k) {
    // Radius in DP-frame pixels, alternating sides of the focus.
    const double fraction =
        0.3 +
        0.55 * (k / 2) / std::max(1, (options.calibration_captures - 1) / 2);
    const double target_radius = (k % 2 ? 1 : -1) * fraction * bound;
    // Distance with that blur (bisection; the blur is monotone in depth).
    double lo = 0.2 * focus_m, hi = 20 * focus_m;
    for (int it = 0; it < 100; ++it) {
      const double mid = std::sqrt(lo * hi);
      const double r = dpsfm::PredictBlurRadiusPx(
          lens, lens.PixelPitchMm(), 1.0, focus_m, mid);
      (r < target_radius ? lo : hi) = mid;
    }
    const double distance_m = std::sqrt(lo * hi);
    const double radius_full =
        options.dp_factor *
        dpsfm::PredictBlurRadiusPx(
            lens, lens.PixelPitchMm(), 1.0, focus_m, distance_m);
    // Multi-scale value noise, like the scenes' textures.
    cv::Mat texture = cv::Mat::zeros(size, CV_32FC3);
    double amplitude = 1.0, total = 0;
    for (int cell = 64; cell >= 2; cell /= 2) {
      cv::Mat coarse(size.height / cell + 2, size.width / cell + 2, CV_32FC3);
      cv::RNG noise((*rng)());
      noise.fill(coarse, cv::RNG::UNIFORM, 0.0, 1.0);
      cv::Mat up;
      cv::resize(coarse,
                 up,
                 cv::Size(coarse.cols * cell, coarse.rows * cell),
                 0,
                 0,
                 cv::INTER_CUBIC);
      texture += amplitude * up(cv::Rect(0, 0, size.width, size.height));
      total += amplitude;
      amplitude *= 0.75;
    }
    texture = 0.1 + 0.8 * texture / total;
    const cv::Mat depth(size, CV_32FC1, cv::Scalar(distance_m));
    const cv::Mat radius(size, CV_32FC1, cv::Scalar(radius_full));
    cv::Mat left, right;
    RenderSensorViews(
        options, sensor, texture, depth, radius, render_options, &left, &right);
    cv::RNG noise_rng((*rng)());
    const std::string name = "cal_" + std::to_string(k) + ".png";
    for (cv::Mat* view : {&left, &right}) {
      if (options.dp_factor > 1) {
        cv::resize(cv::Mat(*view), *view, dp_size, 0, 0, cv::INTER_AREA);
      }
      AddNoiseAndClamp(options.noise, &noise_rng, view);
    }
    cv::imwrite((root / "dp/left" / name).string(), To16Bit(left));
    cv::imwrite((root / "dp/right" / name).string(), To16Bit(right));
    // targets.csv holds distances from the focal-plane mark (the sensor):
    // the thin lens focused at object distance u_g sits v = f u_g / (u_g -
    // f) in front of the sensor, the same v for the target.
    const double focus_sensor_m =
        dpsfm::SensorDistanceOfFocusMm(1000 * focus_m, lens.focal_length_mm) /
        1000;
    const double lens_to_sensor_m = focus_sensor_m - focus_m;
    csv << name << "," << std::setprecision(8) << distance_m + lens_to_sensor_m
        << "," << focus_sensor_m << "," << lens.focal_length_mm << ","
        << lens.f_number << "," << lens.pixel_pitch_um << "\n";
  }
}

// fused.ply: every 4th depth pixel of every pose, in model units.
void WriteFusedPly(const std::vector<PinholeView>& views,
                   const std::vector<RenderedView>& renders,
                   double true_scale,
                   const std::string& path) {
  std::vector<colmap::PlyPoint> ply_points;
  for (size_t i = 0; i < views.size(); ++i) {
    const PinholeView& view = views[i];
    const Eigen::Matrix3d world_from_cam = view.rotation.transpose();
    for (int r = 0; r < view.height; r += 4) {
      for (int c = 0; c < view.width; c += 4) {
        const float z = renders[i].depth.at<float>(r, c);
        if (z <= 0) continue;
        const Eigen::Vector3d cam(
            (c - (view.width - 1) / 2.0) / view.focal_px * z,
            (r - (view.height - 1) / 2.0) / view.focal_px * z,
            z);
        const Eigen::Vector3d xyz =
            world_from_cam * (cam - view.translation) / true_scale;
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
  colmap::WriteBinaryPlyPoints(path,
                               ply_points,
                               /*write_normal=*/true,
                               /*write_rgb=*/true);
}

int Run(const GeneratorOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double true_scale =
      options.scale > 0 ? options.scale
                        : std::exp(std::log(0.3) + unit(rng) * std::log(10.0));

  SyntheticScene scene = dpsfm::examples::RandomScene(options.scene, &rng);
  scene.Scale(options.scene_scale);
  scene.texture_contrast = options.texture_contrast;
  const double pitch_mm = options.sensor_width_mm / options.width;
  const double focal_px = options.focal_length_mm / pitch_mm;
  const bool multi_aperture = !options.f_numbers.empty();
  const std::vector<double> f_numbers =
      multi_aperture ? ParseFNumbers(options.f_numbers)
                     : std::vector<double>{options.f_number};
  const int num_apertures = static_cast<int>(f_numbers.size());
  const int num_images = options.num_views * num_apertures;
  const cv::Size dp_size(options.width / options.dp_factor,
                         options.height / options.dp_factor);

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

  // Cameras on the scene's arc, looking at its middle.
  std::vector<PinholeView> views =
      dpsfm::examples::PlaceViews(scene.rig,
                                  options.num_views,
                                  options.width,
                                  options.height,
                                  focal_px,
                                  &rng);
  for (PinholeView& view : views) view.k1 = options.radial_k1;

  const SensorPsf sensor = MakeSensorPsf(options);
  dpsfm::DPRenderOptions render_options;
  render_options.compositing =
      options.compositing == "layers"
          ? dpsfm::DPRenderOptions::Compositing::kOcclusionLayers
          : dpsfm::DPRenderOptions::Compositing::kAdditive;
  std::ofstream lens_csv((out / "lens.csv").string());
  lens_csv << "name,focal_length_mm,f_number,pixel_pitch_um\n"
           << std::setprecision(10);
  nlohmann::json truth;
  truth["scale"] = true_scale;
  truth["model_unit"] = "metres / scale";
  truth["scene"] = options.scene;
  truth["camera"] = options.camera;
  truth["dp_factor"] = options.dp_factor;
  truth["dp_psf"] = sensor.description;

  // Renders in the undistorted (dense) geometry: depth maps, tracks, fused.
  std::vector<RenderedView> renders;
  // Image names, per pose one per aperture.
  std::vector<std::vector<std::string>> names(options.num_views);
  for (int i = 0; i < options.num_views; ++i) {
    char pose_name[32];
    std::snprintf(pose_name, sizeof(pose_name), "DP_%04d", i + 1);
    // The original (possibly distorted) image, and the undistorted one.
    const RenderedView render = dpsfm::examples::RenderView(scene, views[i]);
    PinholeView pinhole = views[i];
    pinhole.k1 = 0;
    renders.push_back(options.radial_k1 == 0
                          ? render
                          : dpsfm::examples::RenderView(scene, pinhole));

    // Focus somewhere inside the scene's depth range, as a photographer
    // focusing on the subject would; the same for every aperture.
    std::vector<float> depths;
    for (int r = 0; r < render.depth.rows; r += 4) {
      for (int c = 0; c < render.depth.cols; c += 4) {
        if (render.depth.at<float>(r, c) > 0) {
          depths.push_back(render.depth.at<float>(r, c));
        }
      }
    }
    if (depths.empty()) {
      throw std::runtime_error(std::string("view ") + pose_name +
                               " sees nothing of the scene");
    }
    std::sort(depths.begin(), depths.end());
    const double focus_m =
        depths[static_cast<size_t>((0.3 + 0.4 * unit(rng)) * depths.size())];

    // The depth map PatchMatch would give, in model units.
    cv::Mat depth_model = renders.back().depth / true_scale;
    if (options.depth_map_factor > 1) {
      cv::resize(cv::Mat(depth_model),
                 depth_model,
                 cv::Size(options.width / options.depth_map_factor,
                          options.height / options.depth_map_factor),
                 0,
                 0,
                 cv::INTER_NEAREST);
    }
    cv::RNG depth_rng(ImageSeed(options.seed, std::string(pose_name) + "/z"));
    DegradeDepthMap(
        options.depth_noise, options.depth_holes, &depth_rng, &depth_model);

    for (const double f_number : f_numbers) {
      const std::string name =
          multi_aperture ? std::string(pose_name) + "_f" + FNumberTag(f_number)
                         : std::string(pose_name);
      names[i].push_back(name);
      dpsfm::DPLensData lens;
      lens.focal_length_mm = options.focal_length_mm;
      lens.f_number = f_number;
      lens.pixel_pitch_um = pitch_mm * 1e3;
      cv::Mat radius(render.depth.size(), CV_32FC1);
      for (int r = 0; r < radius.rows; ++r) {
        for (int c = 0; c < radius.cols; ++c) {
          const float z = render.depth.at<float>(r, c);
          radius.at<float>(r, c) = static_cast<float>(
              BlurRadiusPx(options, lens, focus_m, z, pitch_mm));
        }
      }
      cv::Mat left, right;
      RenderSensorViews(options,
                        sensor,
                        render.image,
                        render.depth,
                        radius,
                        render_options,
                        &left,
                        &right);
      ApplyColumnGain(1.0, -options.gain_ramp, &left);
      ApplyColumnGain(options.right_gain, options.gain_ramp, &right);
      cv::RNG noise_rng(ImageSeed(options.seed, name));
      // The ordinary image sums both halves at full resolution; the DP
      // frames are binned down to their own size.
      cv::Mat combined = left + right;
      AddNoiseAndClamp(options.noise * std::sqrt(2.0), &noise_rng, &combined);
      for (cv::Mat* view : {&left, &right}) {
        if (options.dp_factor > 1) {
          cv::resize(cv::Mat(*view), *view, dp_size, 0, 0, cv::INTER_AREA);
        }
        AddNoiseAndClamp(options.noise, &noise_rng, view);
      }
      cv::imwrite((out / "dp/left" / (name + ".png")).string(), To16Bit(left));
      cv::imwrite((out / "dp/right" / (name + ".png")).string(),
                  To16Bit(right));
      cv::Mat combined_8bit;
      combined.convertTo(combined_8bit, CV_8U, 255.0);
      const std::string image_name = name + ".jpg";
      cv::imwrite((out / "images" / image_name).string(), combined_8bit);
      if (options.radial_k1 == 0) {
        cv::imwrite((out / "dense/images" / image_name).string(),
                    combined_8bit);
      } else {
        cv::Mat undistorted;
        renders.back().image.convertTo(undistorted, CV_8U, 255.0);
        cv::imwrite((out / "dense/images" / image_name).string(), undistorted);
      }
      const fs::path depth_dir = out / "dense/stereo/depth_maps";
      for (const char* type : {".geometric.bin", ".photometric.bin"}) {
        WriteDepthMap(depth_model, (depth_dir / (image_name + type)).string());
      }

      lens_csv << image_name << "," << options.focal_length_mm << ","
               << f_number << "," << lens.pixel_pitch_um << "\n";
      nlohmann::json& entry = truth["views"][image_name];
      entry["focus_distance_m"] = focus_m;
      const Eigen::Vector3d center = views[i].Center();
      entry["center_m"] = {center.x(), center.y(), center.z()};
      entry["f_number"] = f_number;
      entry["pose"] = i + 1;
    }
  }

  // Tracks: grid samples of every pose, observed wherever they are visible,
  // in every image (aperture) of the poses that see them.
  std::vector<std::vector<colmap::Point2D>> points2D(num_images);
  // The same observations in the original, distorted images (sparse/0).
  std::vector<std::vector<Eigen::Vector2d>> distorted2D(num_images);
  struct Track3D {
    Eigen::Vector3d xyz;
    std::vector<std::pair<int, int>> observations;  // (image, point2D idx)
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
          for (int a = 0; a < num_apertures; ++a) {
            const int image = j * num_apertures + a;
            // COLMAP puts the top-left pixel centre at (0.5, 0.5).
            colmap::Point2D point;
            point.xy = Eigen::Vector2d(u + 0.5, v + 0.5);
            track.observations.emplace_back(image, points2D[image].size());
            points2D[image].push_back(point);
            distorted2D[image].push_back(views[j].Project(pc) +
                                         Eigen::Vector2d(0.5, 0.5));
          }
        }
        if (track.observations.size() >= 2) tracks.push_back(track);
      }
    }
  }

  colmap::Reconstruction reconstruction;
  dpsfm::AddCamera(&reconstruction,
                   colmap::Camera::CreateFromModelName(
                       1, "PINHOLE", focal_px, options.width, options.height));
  for (int i = 0; i < options.num_views; ++i) {
    for (int a = 0; a < num_apertures; ++a) {
      const int index = i * num_apertures + a;
      colmap::Image image;
      image.SetImageId(index + 1);
      image.SetName(names[i][a] + ".jpg");
      image.SetCameraId(1);
      image.SetPoints2D(points2D[index]);
      dpsfm::AddRegisteredImage(
          &reconstruction,
          image,
          colmap::Rigid3d(Eigen::Quaterniond(views[i].rotation),
                          views[i].translation / true_scale));
    }
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
  for (int index = 0; index < num_images; ++index) {
    colmap::Image& image = reconstruction.Image(index + 1);
    for (size_t k = 0; k < distorted2D[index].size(); ++k) {
      image.Point2D(k).xy = distorted2D[index][k];
    }
  }
  reconstruction.WriteBinary((out / "sparse/0").string());
  {
    // The project database, as feature extraction leaves it (cameras and
    // images; no features are needed here).
    const std::shared_ptr<colmap::Database> database =
        dpsfm::OpenDatabase((out / "database.db").string());
    database->WriteCamera(original, /*use_camera_id=*/true);
    for (int index = 0; index < num_images; ++index) {
      colmap::Image image;
      image.SetName(reconstruction.Image(index + 1).Name());
      image.SetCameraId(1);
      database->WriteImage(image);
    }
  }
  WriteFusedPly(views, renders, true_scale, (out / "dense/fused.ply").string());

  if (options.calibration_captures > 0) {
    WriteCalibrationCaptures(options, sensor, pitch_mm, dp_size, &rng, out);
  }
  std::ofstream((out / "ground_truth.json").string()) << truth.dump(2) << "\n";
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  std::cout << "Generated " << options.scene << " scene, " << options.camera
            << ": " << options.num_views << " poses x " << num_apertures
            << " aperture(s), " << options.width << "x" << options.height
            << " (DP " << dp_size.width << "x" << dp_size.height << "), "
            << tracks.size() << " tracks, true scale " << true_scale
            << " m per model unit, in " << options.output_path << " ("
            << std::fixed << std::setprecision(1) << seconds << " s)"
            << std::endl;
  return EXIT_SUCCESS;
}

}  // namespace

int main(int argc, char** argv) {
  GeneratorOptions options;
  namespace po = boost::program_options;
  po::options_description desc(
      "dpsfm_make_example options (0: the camera's default)");
  auto add = [&desc](const char* name, auto* value, const char* help) {
    desc.add_options()(name, po::value(value)->default_value(*value), help);
  };
  desc.add_options()("help,h", "this help")(
      "output_path",
      po::value(&options.output_path)->required(),
      "output folder");
  add("seed", &options.seed, "random seed: everything is drawn from it");
  add("num_views", &options.num_views, "tripod positions (poses)");
  add("scene", &options.scene, "tabletop | facade | planes");
  add("camera",
      &options.camera,
      "dslr (50 mm f/2.8, 36 mm sensor, 1200x800) | phone (4.38 mm f/1.73, 5.6 "
      "mm sensor, 1600x1200, DP frames at half size)");
  add("width", &options.width, "image width");
  add("height", &options.height, "image height");
  add("focal_length_mm", &options.focal_length_mm, "lens focal length");
  add("f_number", &options.f_number, "aperture");
  add("f_numbers",
      &options.f_numbers,
      "several apertures per pose, e.g. 2.8,5.6,11 (images <pose>_f<N>)");
  add("sensor_width_mm",
      &options.sensor_width_mm,
      "sensor width (pixel pitch = width_mm / width)");
  add("dp_factor",
      &options.dp_factor,
      "DP frames are this many times smaller than the images");
  add("scene_scale",
      &options.scene_scale,
      "multiplies the scene's and the rig's lengths (dslr 1, phone 0.3)");
  add("scale", &options.scale, "metres per model unit (0: random)");
  add("noise", &options.noise, "noise sigma on [0,1] of each DP view");
  add("depth_map_factor",
      &options.depth_map_factor,
      "depth maps are this many times smaller than the images");
  add("depth_noise",
      &options.depth_noise,
      "relative sigma of the depth maps' error");
  add("depth_holes",
      &options.depth_holes,
      "fraction of depth-map pixels missing (0), in blobs");
  add("right_gain", &options.right_gain, "gain of the right DP view");
  add("gain_ramp",
      &options.gain_ramp,
      "opposite horizontal gain ramps of the DP views (edge to edge)");
  add("texture_contrast",
      &options.texture_contrast,
      "1: full texture, 0: flat surfaces");
  add("radial_k1",
      &options.radial_k1,
      "SIMPLE_RADIAL k1 of the original images");
  add("compositing", &options.compositing, "additive | layers");
  add("psf_split_exponent",
      &options.psf_split_exponent,
      "DP split profile exponent (0: the translating disk)");
  add("psf_crosstalk", &options.psf_crosstalk, "DP split profile crosstalk");
  add("psf_rim_softness",
      &options.psf_rim_softness,
      "DP split profile rim softness (fraction of the radius)");
  add("psf_split_exponent_right",
      &options.psf_split_exponent_right,
      "split exponent at the right edge (profile changing across the frame)");
  add("renderer",
      &options.renderer,
      "kernels (the profile's kernels) | aperture (light through aperture "
      "points; shares no code with the estimator's optics)");
  add("aperture_subsamples",
      &options.aperture_subsamples,
      "aperture points landing per pixel of blur, along each axis (renderer "
      "aperture)");
  add("aperture_crosstalk",
      &options.aperture_crosstalk,
      "share of a half aperture's light in the other photodiode (renderer "
      "aperture)");
  add("calibration_captures",
      &options.calibration_captures,
      "planar-target captures for dp_psf_calibrator (calibration/)");
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, desc), vm);
    if (vm.count("help")) {
      std::cout << desc << std::endl;
      return EXIT_SUCCESS;
    }
    po::notify(vm);
    ApplyCameraDefaults(&options);
    if (options.num_views < 1 || options.width < 64 || options.height < 64 ||
        options.depth_map_factor < 1 || options.dp_factor < 1 ||
        options.dp_factor > 8 || options.focal_length_mm <= 0 ||
        options.f_number <= 0 || options.sensor_width_mm <= 0 ||
        options.scene_scale <= 0 || options.noise < 0 ||
        options.depth_noise < 0 || options.depth_holes < 0 ||
        options.depth_holes >= 1 || options.right_gain <= 0 ||
        std::abs(options.gain_ramp) >= 2 || options.texture_contrast < 0 ||
        (options.compositing != "additive" &&
         options.compositing != "layers") ||
        (options.renderer != "kernels" && options.renderer != "aperture") ||
        options.aperture_subsamples < 1 || !(options.aperture_crosstalk >= 0) ||
        !(options.aperture_crosstalk < 0.5)) {
      throw std::invalid_argument(
          "need num_views >= 1, width/height >= 64, depth_map_factor >= 1, "
          "dp_factor in 1..8, positive lens and scene numbers, noise >= 0, "
          "depth_holes in [0, 1), right_gain > 0, |gain_ramp| < 2, "
          "texture_contrast >= 0, compositing additive or layers, renderer "
          "kernels or aperture, aperture_subsamples >= 1, aperture_crosstalk "
          "in "
          "[0, 0.5)");
    }
    return Run(options);
  } catch (const std::exception& error) {
    std::cerr << "ERROR: dpsfm_make_example: " << error.what() << std::endl;
    return EXIT_FAILURE;
  }
}
