// `colmap dp_scale_estimator` on the generator's harder captures: a phone
// with DP frames at half the image size, several apertures per tripod
// position, PatchMatch-like depth maps with noise and holes, and a scene
// without texture, which must be refused. And the generator itself: the
// same seed gives the same files.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "colmap/mvs/depth_map.h"
#include "colmap/scene/reconstruction.h"
#include "tests/e2e/e2e_helpers.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

// The generator's sensor stated as a profile file: the translating disk,
// trusted at +-1 % (as a library entry for the paper's camera would be).
std::vector<std::string> GivenDiskProfile(const SceneCopy& scene) {
  const std::string path = scene.temp() / "disk.dpsf";
  std::ofstream file(path);
  file << "format 1\nmodel translating_disk\nuncertainty 0.01\n";
  return {"--DPScaleEstimator.psf_model",
          "calibrated",
          "--DPScaleEstimator.psf_path",
          path};
}

// The arguments of a dry run on `workspace` (a workspace of `scene`) with
// the scene's DP views and lens.csv, then `extra`.
std::vector<std::string> DryRunArgs(const SceneCopy& scene,
                                    const std::string& workspace,
                                    const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"--workspace_path",
                                   workspace,
                                   "--dp_image_path",
                                   scene / "dp",
                                   "--lens_path",
                                   scene / "lens.csv",
                                   "--dry_run",
                                   "1"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

// A dry run on the scene's dense workspace whose blur is too small to see
// the DP profile: refused, saying the profile is unknown and how to
// calibrate it (and, for an explicit translating disk, that it could not
// be checked), not answered on a guessed or unchecked model.
void ExpectProfileUnknown(const SceneCopy& scene,
                          const std::vector<std::string>& extra,
                          const std::string& also) {
  const CommandResult run =
      RunEstimator(DryRunArgs(scene, scene / "dense", extra));
  EXPECT_NE(run.exit_code, 0);
  for (const std::string& text : {std::string("DP profile is unknown"),
                                  std::string("dp_psf_calibrator"),
                                  also}) {
    EXPECT_NE(run.err.find(text), std::string::npos) << text << "\n" << run.err;
  }
}

// --DPScaleEstimator.psf_model translating_disk where the data cannot
// check it.
void ExpectUncheckedDiskRefused(const SceneCopy& scene) {
  ExpectProfileUnknown(scene,
                       {"--DPScaleEstimator.psf_model", "translating_disk"},
                       "could not check the translating disk");
}

namespace fs = std::filesystem;

const std::string kMakeExample = DPSFM_MAKE_EXAMPLE_EXE;

// Largest accepted |1 - s_est / s_true| on these scenes.
constexpr double kMaxScaleError = 0.03;

// |1 - r_s| of a dry run on `workspace` (a dense workspace of `scene`).
double ScaleError(const SceneCopy& scene,
                  const std::string& workspace,
                  const std::string& report_path,
                  const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {"--report_path", report_path};
  args.insert(args.end(), extra.begin(), extra.end());
  const CommandResult result = RunEstimator(DryRunArgs(scene, workspace, args));
  EXPECT_EQ(result.exit_code, 0) << result.err;
  if (result.exit_code != 0) return 1;
  const double scale = ReadJson(report_path).at("scale").get<double>();
  return std::abs(
      1 -
      scale / ReadJson(scene / "ground_truth.json").at("scale").get<double>());
}

TEST(GeneratedScenes, PhoneWithHalfSizeDPFrames) {
  SceneCopy scene("phone");
  colmap::Reconstruction model;
  model.Read(scene / "dense/sparse");
  const colmap::Camera& camera = model.Cameras().begin()->second;
  const cv::Mat left = cv::imread(scene / "dp/left/DP_0001.png",
                                  cv::IMREAD_ANYDEPTH | cv::IMREAD_COLOR);
  ASSERT_FALSE(left.empty());
  EXPECT_EQ(left.cols * 2, static_cast<int>(camera.width));
  EXPECT_EQ(left.rows * 2, static_cast<int>(camera.height));

  // The phone's blur stays under 2 px: the default (auto) cannot see the
  // DP profile and must not answer on a guessed one, nor can the
  // translating disk chosen unchecked; given the sensor's profile (the
  // generator's translating disk, as a profile file) it answers.
  ExpectProfileUnknown(scene, {}, "");
  const std::string report_path = scene.temp() / "report.json";
  ExpectUncheckedDiskRefused(scene);
  const double error =
      ScaleError(scene, scene / "dense", report_path, GivenDiskProfile(scene));
  EXPECT_LT(error, kMaxScaleError);
  // lens.csv gives the image pixels' pitch; a DP-frame pixel covers 2 x 2.
  const nlohmann::json report = ReadJson(report_path);
  for (const auto& view : report.at("views").items()) {
    EXPECT_NEAR(view.value().at("lens").at("dp_pixel_pitch_um").get<double>(),
                2 * 5.6 / 1200 * 1e3,
                1e-7)
        << view.key();
    EXPECT_NEAR(view.value().at("lens").at("focal_length_mm").get<double>(),
                4.38,
                1e-9);
  }
}

TEST(GeneratedScenes, AllAperturesTogetherAtLeastAsGoodAsTheWorstAlone) {
  SceneCopy scene("multi_aperture");
  colmap::Reconstruction model;
  model.Read(scene / "dense/sparse");
  ASSERT_EQ(model.NumRegImages(), 8u);
  // Each aperture alone: a workspace whose model lacks the other
  // aperture's images (COLMAP's image_deleter), same depth maps.
  std::vector<double> single_errors;
  for (const std::string f_number : {"2.8", "5.6"}) {
    const std::string subset = scene.temp() / ("f" + f_number);
    fs::create_directories(subset + "/sparse");
    std::string deleted;
    for (const auto& image : model.Images()) {
      const std::string& name = image.second.Name();
      if (name.find("_f" + f_number + ".") == std::string::npos) {
        deleted += name + "\n";
      }
    }
    WriteTextFile(subset + "/delete.txt", deleted);
    const CommandResult deleter = RunCommand({kColmap,
                                              "image_deleter",
                                              "--input_path",
                                              scene / "dense/sparse",
                                              "--output_path",
                                              subset + "/sparse",
                                              "--image_names_path",
                                              subset + "/delete.txt"});
    ASSERT_EQ(deleter.exit_code, 0) << deleter.err;
    fs::create_symlink(scene / "dense/stereo", subset + "/stereo");
    single_errors.push_back(ScaleError(scene, subset, subset + "/report.json"));
    EXPECT_EQ(ReadJson(subset + "/report.json").at("views").size(), 4u);
  }
  const double together =
      ScaleError(scene, scene / "dense", scene.temp() / "report.json");
  const double worst_single =
      *std::max_element(single_errors.begin(), single_errors.end());
  EXPECT_LE(together, worst_single + 0.005)
      << "f/2.8 alone " << single_errors[0] << ", f/5.6 alone "
      << single_errors[1];
  EXPECT_LT(together, kMaxScaleError);
}

TEST(GeneratedScenes, DepthMapsWithNoiseAndHoles) {
  SceneCopy scene("depth_artefacts");
  // The generator made what the test claims: half-size maps, ~20 % holes.
  colmap::mvs::DepthMap depth;
  depth.Read(scene / "dense/stereo/depth_maps/DP_0001.jpg.geometric.bin");
  EXPECT_EQ(depth.GetWidth(), 400u);
  size_t holes = 0;
  for (size_t r = 0; r < depth.GetHeight(); ++r) {
    for (size_t c = 0; c < depth.GetWidth(); ++c) {
      if (depth.Get(r, c) == 0) ++holes;
    }
  }
  const double hole_fraction =
      static_cast<double>(holes) / (depth.GetWidth() * depth.GetHeight());
  EXPECT_GT(hole_fraction, 0.15);
  EXPECT_LT(hole_fraction, 0.3);
  // With each view's own search bound (once 5.5 px here, refusing as
  // "could not check the translating disk"), enough patches show blur to
  // check the disk, the generator's profile: the check passes and the
  // answer holds.
  EXPECT_LT(ScaleError(scene,
                       scene / "dense",
                       scene.temp() / "checked.json",
                       {"--DPScaleEstimator.psf_model", "translating_disk"}),
            kMaxScaleError);
  EXPECT_LT(ScaleError(scene,
                       scene / "dense",
                       scene.temp() / "report.json",
                       GivenDiskProfile(scene)),
            kMaxScaleError);
}

TEST(GeneratedScenes, TexturelessSceneIsRefused) {
  // The error line says why: no patch has texture above the noise.
  ExpectSceneRefused("textureless", "texture too weak for the noise");
}

TEST(GeneratedScenes, GeneratorIsDeterministic) {
  TempDir dir;
  std::vector<std::map<std::string, std::string>> trees;
  for (const char* name : {"a", "b"}) {
    const CommandResult result =
        RunCommand({kMakeExample, "--output_path", dir / name, "--seed",
                    "5",          "--num_views",   "2",        "--width",
                    "240",        "--height",      "160",      "--scene",
                    "planes",     "--f_numbers",   "2,4",      "--depth_noise",
                    "0.02",       "--depth_holes", "0.1",      "--gain_ramp",
                    "0.2"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    auto tree = SnapshotTree(dir / name);
    tree.erase("database.db");  // SQLite pages need not be byte-identical
    trees.push_back(tree);
  }
  EXPECT_EQ(trees[0].size(), trees[1].size());
  for (const auto& file : trees[0]) {
    EXPECT_TRUE(trees[1].count(file.first) &&
                trees[1].at(file.first) == file.second)
        << file.first << " differs between two runs with the same seed";
  }
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
