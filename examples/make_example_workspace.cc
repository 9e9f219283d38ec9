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
namespace po = boost::program_options;
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

// A DP view binned down to the DP frames' size, then its sensor noise.
void BinAndAddNoise(const GeneratorOptions& options,
                    const cv::Size& dp_size,
                    cv::RNG* noise_rng,
                    cv::Mat* view) {
  if (options.dp_factor > 1) {
    cv::resize(cv::Mat(*view), *view, dp_size, 0, 0, cv::INTER_AREA);
  }
  AddNoiseAndClamp(options.noise, noise_rng, view);
}

// "2.8" -> "2.8", "11" -> "11": the f-number as written in image names.
std::string FNumberTag(double f_number) {
  std::ostringstream tag;
  tag << f_number;
  return tag.str();
}

// The distance (metres) of a point whose blur radius is target_radius
// (pixels of the lens's pitch) under the focus focus_m: bisection, the blur
// being monotone in depth.
double DistanceOfBlur(const dpsfm::DPLensData& lens,
                      double focus_m,
                      double target_radius) {
  double lo = 0.2 * focus_m, hi = 20 * focus_m;
  for (int it = 0; it < 100; ++it) {
    const double mid = std::sqrt(lo * hi);
    const double r = dpsfm::PredictBlurRadiusPx(
        lens, lens.PixelPitchMm(), 1.0, focus_m, mid);
    (r < target_radius ? lo : hi) = mid;
  }
  return std::sqrt(lo * hi);
}

// The calibration target's texture: multi-scale value noise, like the
// scenes' textures (one draw from rng per scale).
cv::Mat CalibrationTexture(const cv::Size& size, std::mt19937* rng) {
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
  return texture;
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
    const double distance_m = DistanceOfBlur(lens, focus_m, target_radius);
    const double radius_full =
        options.dp_factor *
        dpsfm::PredictBlurRadiusPx(
            lens, lens.PixelPitchMm(), 1.0, focus_m, distance_m);
    const cv::Mat texture = CalibrationTexture(size, rng);
    const cv::Mat depth(size, CV_32FC1, cv::Scalar(distance_m));
    const cv::Mat radius(size, CV_32FC1, cv::Scalar(radius_full));
    cv::Mat left, right;
    RenderSensorViews(
        options, sensor, texture, depth, radius, render_options, &left, &right);
    cv::RNG noise_rng((*rng)());
    const std::string name = "cal_" + std::to_string(k) + ".png";
    for (cv::Mat* view : {&left, &right}) {
      BinAndAddNoise(options, dp_size, &noise_rng, view);
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

// The camera-frame point of pixel (c, r) at depth z, in a centred pinhole
// camera of width x height pixels.
Eigen::Vector3d BackProject(
    int c, int r, float z, int width, int height, double focal_px) {
  return Eigen::Vector3d((c - (width - 1) / 2.0) / focal_px * z,
                         (r - (height - 1) / 2.0) / focal_px * z,
                         z);
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
        const Eigen::Vector3d cam =
            BackProject(c, r, z, view.width, view.height, view.focal_px);
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

// The numbers every step of a run shares: the true scale, the camera's
// pitch and focal length, the apertures and the DP frames' size.
struct RunSetup {
  double true_scale = 0;
  double pitch_mm = 0;
  double focal_px = 0;
  bool multi_aperture = false;
  std::vector<double> f_numbers;
  int num_apertures = 0;
  int num_images = 0;
  cv::Size dp_size;
  fs::path out;
};

// The scene's renders in the undistorted (dense) geometry (depth maps,
// tracks, fused points) and the image names, per pose one per aperture.
struct PoseRenders {
  std::vector<RenderedView> renders;
  std::vector<std::vector<std::string>> names;
};

// lens.csv and ground_truth.json, filled in as the images are written.
struct Records {
  std::ofstream lens_csv;
  nlohmann::json truth;
};

// A sparse point and its observations: (image, point2D index).
struct Track3D {
  Eigen::Vector3d xyz;
  std::vector<std::pair<int, int>> observations;
};

// The tracks and every image's observations, in the undistorted (dense)
// geometry and in the original, distorted images (sparse/0).
struct SparseTracks {
  std::vector<std::vector<colmap::Point2D>> points2D;
  std::vector<std::vector<Eigen::Vector2d>> distorted2D;
  std::vector<Track3D> tracks;
};

// The true scale (metres per model unit): the option's, or a draw from rng.
double DrawTrueScale(const GeneratorOptions& options, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  return options.scale > 0
             ? options.scale
             : std::exp(std::log(0.3) + unit(*rng) * std::log(10.0));
}

// The scene drawn from rng, scaled to the camera and with the option's
// texture contrast.
SyntheticScene MakeScene(const GeneratorOptions& options, std::mt19937* rng) {
  SyntheticScene scene = dpsfm::examples::RandomScene(options.scene, rng);
  scene.Scale(options.scene_scale);
  scene.texture_contrast = options.texture_contrast;
  return scene;
}

// The camera's numbers and the apertures, from the options.
RunSetup MakeRunSetup(const GeneratorOptions& options, double true_scale) {
  RunSetup setup;
  setup.true_scale = true_scale;
  setup.pitch_mm = options.sensor_width_mm / options.width;
  setup.focal_px = options.focal_length_mm / setup.pitch_mm;
  setup.multi_aperture = !options.f_numbers.empty();
  setup.f_numbers = setup.multi_aperture
                        ? ParseFNumbers(options.f_numbers)
                        : std::vector<double>{options.f_number};
  setup.num_apertures = static_cast<int>(setup.f_numbers.size());
  setup.num_images = options.num_views * setup.num_apertures;
  setup.dp_size = cv::Size(options.width / options.dp_factor,
                           options.height / options.dp_factor);
  setup.out = fs::path(options.output_path);
  return setup;
}

// The workspace's folders.
void CreateWorkspaceFolders(const fs::path& out) {
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
}

// Cameras on the scene's arc, looking at its middle, with the option's
// radial distortion.
std::vector<PinholeView> PlaceCameras(const GeneratorOptions& options,
                                      const SyntheticScene& scene,
                                      double focal_px,
                                      std::mt19937* rng) {
  std::vector<PinholeView> views =
      dpsfm::examples::PlaceViews(scene.rig,
                                  options.num_views,
                                  options.width,
                                  options.height,
                                  focal_px,
                                  rng);
  for (PinholeView& view : views) view.k1 = options.radial_k1;
  return views;
}

// The DP renderer's options: the compositing the options name.
dpsfm::DPRenderOptions MakeRenderOptions(const GeneratorOptions& options) {
  dpsfm::DPRenderOptions render_options;
  render_options.compositing =
      options.compositing == "layers"
          ? dpsfm::DPRenderOptions::Compositing::kOcclusionLayers
          : dpsfm::DPRenderOptions::Compositing::kAdditive;
  return render_options;
}

// Opens lens.csv with its header and starts the ground truth.
void StartRecords(const GeneratorOptions& options,
                  const RunSetup& setup,
                  const SensorPsf& sensor,
                  Records* records) {
  records->lens_csv.open((setup.out / "lens.csv").string());
  records->lens_csv << "name,focal_length_mm,f_number,pixel_pitch_um\n"
                    << std::setprecision(10);
  nlohmann::json& truth = records->truth;
  truth["scale"] = setup.true_scale;
  truth["model_unit"] = "metres / scale";
  truth["scene"] = options.scene;
  truth["camera"] = options.camera;
  truth["dp_factor"] = options.dp_factor;
  truth["dp_psf"] = sensor.description;
}

// "DP_0001" for the first pose.
std::string PoseName(int pose) {
  char pose_name[32];
  std::snprintf(pose_name, sizeof(pose_name), "DP_%04d", pose + 1);
  return pose_name;
}

// The undistorted render of a view whose original render is `render`.
RenderedView UndistortedRender(const GeneratorOptions& options,
                               const SyntheticScene& scene,
                               const PinholeView& view,
                               const RenderedView& render) {
  PinholeView pinhole = view;
  pinhole.k1 = 0;
  return options.radial_k1 == 0 ? render
                                : dpsfm::examples::RenderView(scene, pinhole);
}

// Focus somewhere inside the view's depth range, as a photographer focusing
// on the subject would (one draw from rng).
double DrawFocusDistance(const cv::Mat& depth,
                         const std::string& pose_name,
                         std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<float> depths;
  for (int r = 0; r < depth.rows; r += 4) {
    for (int c = 0; c < depth.cols; c += 4) {
      if (depth.at<float>(r, c) > 0) depths.push_back(depth.at<float>(r, c));
    }
  }
  if (depths.empty()) {
    throw std::runtime_error("view " + pose_name +
                             " sees nothing of the scene");
  }
  std::sort(depths.begin(), depths.end());
  return depths[static_cast<size_t>((0.3 + 0.4 * unit(*rng)) * depths.size())];
}

// The depth map PatchMatch would give, in model units: downsized and
// degraded with the pose's own random numbers.
cv::Mat PatchMatchDepthMap(const GeneratorOptions& options,
                           const RunSetup& setup,
                           const cv::Mat& depth,
                           const std::string& pose_name) {
  cv::Mat depth_model = depth / setup.true_scale;
  if (options.depth_map_factor > 1) {
    cv::resize(cv::Mat(depth_model),
               depth_model,
               cv::Size(options.width / options.depth_map_factor,
                        options.height / options.depth_map_factor),
               0,
               0,
               cv::INTER_NEAREST);
  }
  cv::RNG depth_rng(ImageSeed(options.seed, pose_name + "/z"));
  DegradeDepthMap(
      options.depth_noise, options.depth_holes, &depth_rng, &depth_model);
  return depth_model;
}

// The lens of the images made at `f_number`.
dpsfm::DPLensData ApertureLens(const GeneratorOptions& options,
                               const RunSetup& setup,
                               double f_number) {
  dpsfm::DPLensData lens;
  lens.focal_length_mm = options.focal_length_mm;
  lens.f_number = f_number;
  lens.pixel_pitch_um = setup.pitch_mm * 1e3;
  return lens;
}

// The signed blur radius of every pixel of `depth` (metres).
cv::Mat BlurRadiusMap(const GeneratorOptions& options,
                      const RunSetup& setup,
                      const dpsfm::DPLensData& lens,
                      double focus_m,
                      const cv::Mat& depth) {
  cv::Mat radius(depth.size(), CV_32FC1);
  for (int r = 0; r < radius.rows; ++r) {
    for (int c = 0; c < radius.cols; ++c) {
      const float z = depth.at<float>(r, c);
      radius.at<float>(r, c) = static_cast<float>(
          BlurRadiusPx(options, lens, focus_m, z, setup.pitch_mm));
    }
  }
  return radius;
}

// The image's DP views with their gains and noise, and the ordinary image
// (both halves summed at full resolution) with its own noise.
void RenderImage(const GeneratorOptions& options,
                 const RunSetup& setup,
                 const SensorPsf& sensor,
                 const dpsfm::DPRenderOptions& render_options,
                 const RenderedView& render,
                 const cv::Mat& radius,
                 const std::string& name,
                 cv::Mat* left,
                 cv::Mat* right,
                 cv::Mat* combined) {
  RenderSensorViews(options,
                    sensor,
                    render.image,
                    render.depth,
                    radius,
                    render_options,
                    left,
                    right);
  ApplyColumnGain(1.0, -options.gain_ramp, left);
  ApplyColumnGain(options.right_gain, options.gain_ramp, right);
  cv::RNG noise_rng(ImageSeed(options.seed, name));
  *combined = *left + *right;
  AddNoiseAndClamp(options.noise * std::sqrt(2.0), &noise_rng, combined);
  for (cv::Mat* view : {left, right}) {
    BinAndAddNoise(options, setup.dp_size, &noise_rng, view);
  }
}

// The image's files: DP views, original and undistorted image, depth maps.
void WriteImageFiles(const GeneratorOptions& options,
                     const RunSetup& setup,
                     const std::string& name,
                     const cv::Mat& left,
                     const cv::Mat& right,
                     const cv::Mat& combined,
                     const RenderedView& undistorted_render,
                     const cv::Mat& depth_model) {
  const fs::path& out = setup.out;
  cv::imwrite((out / "dp/left" / (name + ".png")).string(), To16Bit(left));
  cv::imwrite((out / "dp/right" / (name + ".png")).string(), To16Bit(right));
  cv::Mat combined_8bit;
  combined.convertTo(combined_8bit, CV_8U, 255.0);
  const std::string image_name = name + ".jpg";
  cv::imwrite((out / "images" / image_name).string(), combined_8bit);
  if (options.radial_k1 == 0) {
    cv::imwrite((out / "dense/images" / image_name).string(), combined_8bit);
  } else {
    cv::Mat undistorted;
    undistorted_render.image.convertTo(undistorted, CV_8U, 255.0);
    cv::imwrite((out / "dense/images" / image_name).string(), undistorted);
  }
  const fs::path depth_dir = out / "dense/stereo/depth_maps";
  for (const char* type : {".geometric.bin", ".photometric.bin"}) {
    WriteDepthMap(depth_model, (depth_dir / (image_name + type)).string());
  }
}

// The image's line of lens.csv and its entry in the ground truth.
void RecordImage(const GeneratorOptions& options,
                 const dpsfm::DPLensData& lens,
                 const PinholeView& view,
                 int pose,
                 const std::string& image_name,
                 double focus_m,
                 Records* records) {
  records->lens_csv << image_name << "," << options.focal_length_mm << ","
                    << lens.f_number << "," << lens.pixel_pitch_um << "\n";
  nlohmann::json& entry = records->truth["views"][image_name];
  entry["focus_distance_m"] = focus_m;
  const Eigen::Vector3d center = view.Center();
  entry["center_m"] = {center.x(), center.y(), center.z()};
  entry["f_number"] = lens.f_number;
  entry["pose"] = pose + 1;
}

// Renders every pose (original and undistorted geometry), focuses it (one
// draw each from rng) and writes its images, one per aperture.
PoseRenders RenderPoses(const GeneratorOptions& options,
                        const RunSetup& setup,
                        const SyntheticScene& scene,
                        const std::vector<PinholeView>& views,
                        const SensorPsf& sensor,
                        const dpsfm::DPRenderOptions& render_options,
                        std::mt19937* rng,
                        Records* records) {
  PoseRenders poses;
  poses.names.resize(options.num_views);
  for (int i = 0; i < options.num_views; ++i) {
    const std::string pose_name = PoseName(i);
    const RenderedView render = dpsfm::examples::RenderView(scene, views[i]);
    poses.renders.push_back(
        UndistortedRender(options, scene, views[i], render));
    const double focus_m = DrawFocusDistance(render.depth, pose_name, rng);
    const cv::Mat depth_model = PatchMatchDepthMap(
        options, setup, poses.renders.back().depth, pose_name);
    for (const double f_number : setup.f_numbers) {
      const std::string name = setup.multi_aperture
                                   ? pose_name + "_f" + FNumberTag(f_number)
                                   : pose_name;
      poses.names[i].push_back(name);
      const dpsfm::DPLensData lens = ApertureLens(options, setup, f_number);
      const cv::Mat radius =
          BlurRadiusMap(options, setup, lens, focus_m, render.depth);
      cv::Mat left, right, combined;
      RenderImage(options,
                  setup,
                  sensor,
                  render_options,
                  render,
                  radius,
                  name,
                  &left,
                  &right,
                  &combined);
      WriteImageFiles(options,
                      setup,
                      name,
                      left,
                      right,
                      combined,
                      poses.renders.back(),
                      depth_model);
      RecordImage(options, lens, views[i], i, name + ".jpg", focus_m, records);
    }
  }
  return poses;
}

// Adds the observations of `track` in view j (pose j, every aperture), if
// the view sees it unoccluded.
void ObserveInView(const GeneratorOptions& options,
                   const RunSetup& setup,
                   const PinholeView& view,
                   const RenderedView& render,
                   int j,
                   Track3D* track,
                   SparseTracks* sparse) {
  const double focal_px = setup.focal_px;
  const Eigen::Vector3d pc = view.rotation * track->xyz + view.translation;
  if (pc.z() <= 0) return;
  const double u = focal_px * pc.x() / pc.z() + (options.width - 1) / 2.0;
  const double v = focal_px * pc.y() / pc.z() + (options.height - 1) / 2.0;
  const int ui = static_cast<int>(std::lround(u));
  const int vi = static_cast<int>(std::lround(v));
  if (ui < 0 || vi < 0 || ui >= options.width || vi >= options.height) {
    return;
  }
  const float zj = render.depth.at<float>(vi, ui);
  if (std::abs(zj - pc.z()) > 0.01 * pc.z()) return;  // occluded
  for (int a = 0; a < setup.num_apertures; ++a) {
    const int image = j * setup.num_apertures + a;
    // COLMAP puts the top-left pixel centre at (0.5, 0.5).
    colmap::Point2D point;
    point.xy = Eigen::Vector2d(u + 0.5, v + 0.5);
    track->observations.emplace_back(image, sparse->points2D[image].size());
    sparse->points2D[image].push_back(point);
    sparse->distorted2D[image].push_back(view.Project(pc) +
                                         Eigen::Vector2d(0.5, 0.5));
  }
}

// Tracks: grid samples of every pose, observed wherever they are visible,
// in every image (aperture) of the poses that see them.
SparseTracks MakeTracks(const GeneratorOptions& options,
                        const RunSetup& setup,
                        const std::vector<PinholeView>& views,
                        const std::vector<RenderedView>& renders) {
  const double focal_px = setup.focal_px;
  SparseTracks sparse;
  sparse.points2D.resize(setup.num_images);
  sparse.distorted2D.resize(setup.num_images);
  for (int i = 0; i < options.num_views; ++i) {
    const Eigen::Matrix3d world_from_cam = views[i].rotation.transpose();
    for (int r = 20; r < options.height - 20; r += options.height / 24) {
      for (int c = 20; c < options.width - 20; c += options.width / 36) {
        const float z = renders[i].depth.at<float>(r, c);
        if (z <= 0) continue;
        const Eigen::Vector3d cam =
            BackProject(c, r, z, options.width, options.height, focal_px);
        Track3D track;
        track.xyz = world_from_cam * (cam - views[i].translation);
        for (int j = 0; j < options.num_views; ++j) {
          ObserveInView(
              options, setup, views[j], renders[j], j, &track, &sparse);
        }
        if (track.observations.size() >= 2) sparse.tracks.push_back(track);
      }
    }
  }
  return sparse;
}

// The model of the undistorted images (PINHOLE) in model units, as
// image_undistorter leaves it.
colmap::Reconstruction MakeDenseModel(const GeneratorOptions& options,
                                      const RunSetup& setup,
                                      const std::vector<PinholeView>& views,
                                      const PoseRenders& poses,
                                      const SparseTracks& sparse) {
  colmap::Reconstruction reconstruction;
  dpsfm::AddCamera(
      &reconstruction,
      colmap::Camera::CreateFromModelName(
          1, "PINHOLE", setup.focal_px, options.width, options.height));
  for (int i = 0; i < options.num_views; ++i) {
    for (int a = 0; a < setup.num_apertures; ++a) {
      const int index = i * setup.num_apertures + a;
      colmap::Image image;
      image.SetImageId(index + 1);
      image.SetName(poses.names[i][a] + ".jpg");
      image.SetCameraId(1);
      image.SetPoints2D(sparse.points2D[index]);
      dpsfm::AddRegisteredImage(
          &reconstruction,
          image,
          colmap::Rigid3d(Eigen::Quaterniond(views[i].rotation),
                          views[i].translation / setup.true_scale));
    }
  }
  for (const Track3D& track : sparse.tracks) {
    colmap::Track colmap_track;
    for (const auto& obs : track.observations) {
      colmap_track.AddElement(obs.first + 1, obs.second);
    }
    reconstruction.AddPoint3D(track.xyz / setup.true_scale,
                              colmap_track,
                              Eigen::Vector3ub(128, 128, 128));
  }
  return reconstruction;
}

// Turns the dense model into the model of the original images
// (SIMPLE_RADIAL, distorted observations), as the mapper leaves it; returns
// its camera.
colmap::Camera ToOriginalModel(const GeneratorOptions& options,
                               const RunSetup& setup,
                               const SparseTracks& sparse,
                               colmap::Reconstruction* reconstruction) {
  colmap::Camera original = colmap::Camera::CreateFromModelName(
      1, "SIMPLE_RADIAL", setup.focal_px, options.width, options.height);
  original.params[3] = options.radial_k1;
  reconstruction->Camera(1) = original;
  for (int index = 0; index < setup.num_images; ++index) {
    colmap::Image& image = reconstruction->Image(index + 1);
    for (size_t k = 0; k < sparse.distorted2D[index].size(); ++k) {
      image.Point2D(k).xy = sparse.distorted2D[index][k];
    }
  }
  return original;
}

// The project database, as feature extraction leaves it (cameras and
// images; no features are needed here).
void WriteDatabase(const RunSetup& setup,
                   const colmap::Camera& camera,
                   const colmap::Reconstruction& reconstruction) {
  const std::shared_ptr<colmap::Database> database =
      dpsfm::OpenDatabase((setup.out / "database.db").string());
  database->WriteCamera(camera, /*use_camera_id=*/true);
  for (int index = 0; index < setup.num_images; ++index) {
    colmap::Image image;
    image.SetName(reconstruction.Image(index + 1).Name());
    image.SetCameraId(1);
    database->WriteImage(image);
  }
}

// The models (dense/sparse, sparse/0) and the database.
void WriteModels(const GeneratorOptions& options,
                 const RunSetup& setup,
                 const std::vector<PinholeView>& views,
                 const PoseRenders& poses,
                 const SparseTracks& sparse) {
  colmap::Reconstruction reconstruction =
      MakeDenseModel(options, setup, views, poses, sparse);
  reconstruction.WriteBinary((setup.out / "dense/sparse").string());
  const colmap::Camera original =
      ToOriginalModel(options, setup, sparse, &reconstruction);
  reconstruction.WriteBinary((setup.out / "sparse/0").string());
  WriteDatabase(setup, original, reconstruction);
}

// The line that says what was generated, and how long it took.
void PrintSummary(const GeneratorOptions& options,
                  const RunSetup& setup,
                  size_t num_tracks,
                  std::chrono::steady_clock::time_point start) {
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  std::cout << "Generated " << options.scene << " scene, " << options.camera
            << ": " << options.num_views << " poses x " << setup.num_apertures
            << " aperture(s), " << options.width << "x" << options.height
            << " (DP " << setup.dp_size.width << "x" << setup.dp_size.height
            << "), " << num_tracks << " tracks, true scale " << setup.true_scale
            << " m per model unit, in " << options.output_path << " ("
            << std::fixed << std::setprecision(1) << seconds << " s)"
            << std::endl;
}

int Run(const GeneratorOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::mt19937 rng(options.seed);
  const double true_scale = DrawTrueScale(options, &rng);
  const SyntheticScene scene = MakeScene(options, &rng);
  const RunSetup setup = MakeRunSetup(options, true_scale);
  CreateWorkspaceFolders(setup.out);
  const std::vector<PinholeView> views =
      PlaceCameras(options, scene, setup.focal_px, &rng);
  const SensorPsf sensor = MakeSensorPsf(options);
  const dpsfm::DPRenderOptions render_options = MakeRenderOptions(options);
  Records records;
  StartRecords(options, setup, sensor, &records);
  const PoseRenders poses = RenderPoses(
      options, setup, scene, views, sensor, render_options, &rng, &records);
  const SparseTracks sparse = MakeTracks(options, setup, views, poses.renders);
  WriteModels(options, setup, views, poses, sparse);
  WriteFusedPly(views,
                poses.renders,
                true_scale,
                (setup.out / "dense/fused.ply").string());
  if (options.calibration_captures > 0) {
    WriteCalibrationCaptures(
        options, sensor, setup.pitch_mm, setup.dp_size, &rng, setup.out);
  }
  std::ofstream((setup.out / "ground_truth.json").string())
      << records.truth.dump(2) << "\n";
  PrintSummary(options, setup, sparse.tracks.size(), start);
  return EXIT_SUCCESS;
}

// Adds an option whose default is its current value.
template <typename T>
void AddOption(po::options_description* desc,
               const char* name,
               T* value,
               const char* help) {
  desc->add_options()(name, po::value(value)->default_value(*value), help);
}

// The output folder, the seed and what is drawn from it.
void AddRunOptions(po::options_description* desc, GeneratorOptions* options) {
  desc->add_options()("help,h", "this help")(
      "output_path",
      po::value(&options->output_path)->required(),
      "output folder");
  AddOption(
      desc, "seed", &options->seed, "random seed: everything is drawn from it");
  AddOption(desc, "num_views", &options->num_views, "tripod positions (poses)");
  AddOption(desc, "scene", &options->scene, "tabletop | facade | planes");
}

// The camera and lens (0: the camera's default), the scene's size and the
// true scale.
void AddCameraOptions(po::options_description* desc,
                      GeneratorOptions* options) {
  AddOption(
      desc,
      "camera",
      &options->camera,
      "dslr (50 mm f/2.8, 36 mm sensor, 1200x800) | phone (4.38 mm f/1.73, 5.6 "
      "mm sensor, 1600x1200, DP frames at half size)");
  AddOption(desc, "width", &options->width, "image width");
  AddOption(desc, "height", &options->height, "image height");
  AddOption(
      desc, "focal_length_mm", &options->focal_length_mm, "lens focal length");
  AddOption(desc, "f_number", &options->f_number, "aperture");
  AddOption(desc,
            "f_numbers",
            &options->f_numbers,
            "several apertures per pose, e.g. 2.8,5.6,11 (images <pose>_f<N>)");
  AddOption(desc,
            "sensor_width_mm",
            &options->sensor_width_mm,
            "sensor width (pixel pitch = width_mm / width)");
  AddOption(desc,
            "dp_factor",
            &options->dp_factor,
            "DP frames are this many times smaller than the images");
  AddOption(desc,
            "scene_scale",
            &options->scene_scale,
            "multiplies the scene's and the rig's lengths (dslr 1, phone 0.3)");
  AddOption(
      desc, "scale", &options->scale, "metres per model unit (0: random)");
}

// The sensor's noise and gains, and the imperfections of the depth maps,
// of the texture and of the lens.
void AddImperfectionOptions(po::options_description* desc,
                            GeneratorOptions* options) {
  AddOption(
      desc, "noise", &options->noise, "noise sigma on [0,1] of each DP view");
  AddOption(desc,
            "depth_map_factor",
            &options->depth_map_factor,
            "depth maps are this many times smaller than the images");
  AddOption(desc,
            "depth_noise",
            &options->depth_noise,
            "relative sigma of the depth maps' error");
  AddOption(desc,
            "depth_holes",
            &options->depth_holes,
            "fraction of depth-map pixels missing (0), in blobs");
  AddOption(
      desc, "right_gain", &options->right_gain, "gain of the right DP view");
  AddOption(desc,
            "gain_ramp",
            &options->gain_ramp,
            "opposite horizontal gain ramps of the DP views (edge to edge)");
  AddOption(desc,
            "texture_contrast",
            &options->texture_contrast,
            "1: full texture, 0: flat surfaces");
  AddOption(desc,
            "radial_k1",
            &options->radial_k1,
            "SIMPLE_RADIAL k1 of the original images");
}

// How the DP views are rendered (compositing, the DP profile, the renderer),
// and the calibration captures made with them.
void AddSensorOptions(po::options_description* desc,
                      GeneratorOptions* options) {
  AddOption(desc, "compositing", &options->compositing, "additive | layers");
  AddOption(desc,
            "psf_split_exponent",
            &options->psf_split_exponent,
            "DP split profile exponent (0: the translating disk)");
  AddOption(desc,
            "psf_crosstalk",
            &options->psf_crosstalk,
            "DP split profile crosstalk");
  AddOption(desc,
            "psf_rim_softness",
            &options->psf_rim_softness,
            "DP split profile rim softness (fraction of the radius)");
  AddOption(
      desc,
      "psf_split_exponent_right",
      &options->psf_split_exponent_right,
      "split exponent at the right edge (profile changing across the frame)");
  AddOption(
      desc,
      "renderer",
      &options->renderer,
      "kernels (the profile's kernels) | aperture (light through aperture "
      "points; shares no code with the estimator's optics)");
  AddOption(
      desc,
      "aperture_subsamples",
      &options->aperture_subsamples,
      "aperture points landing per pixel of blur, along each axis (renderer "
      "aperture)");
  AddOption(
      desc,
      "aperture_crosstalk",
      &options->aperture_crosstalk,
      "share of a half aperture's light in the other photodiode (renderer "
      "aperture)");
  AddOption(desc,
            "calibration_captures",
            &options->calibration_captures,
            "planar-target captures for dp_psf_calibrator (calibration/)");
}

// Throws unless the options (camera defaults applied) make a scene.
void CheckOptions(const GeneratorOptions& options) {
  if (options.num_views < 1 || options.width < 64 || options.height < 64 ||
      options.depth_map_factor < 1 || options.dp_factor < 1 ||
      options.dp_factor > 8 || options.focal_length_mm <= 0 ||
      options.f_number <= 0 || options.sensor_width_mm <= 0 ||
      options.scene_scale <= 0 || options.noise < 0 ||
      options.depth_noise < 0 || options.depth_holes < 0 ||
      options.depth_holes >= 1 || options.right_gain <= 0 ||
      std::abs(options.gain_ramp) >= 2 || options.texture_contrast < 0 ||
      (options.compositing != "additive" && options.compositing != "layers") ||
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
}

}  // namespace

int main(int argc, char** argv) {
  GeneratorOptions options;
  po::options_description desc(
      "dpsfm_make_example options (0: the camera's default)");
  AddRunOptions(&desc, &options);
  AddCameraOptions(&desc, &options);
  AddImperfectionOptions(&desc, &options);
  AddSensorOptions(&desc, &options);
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, desc), vm);
    if (vm.count("help")) {
      std::cout << desc << std::endl;
      return EXIT_SUCCESS;
    }
    po::notify(vm);
    ApplyCameraDefaults(&options);
    CheckOptions(options);
    return Run(options);
  } catch (const std::exception& error) {
    std::cerr << "ERROR: dpsfm_make_example: " << error.what() << std::endl;
    return EXIT_FAILURE;
  }
}
