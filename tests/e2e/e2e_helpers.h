// Helpers of the end-to-end tests on generated scenes: the real binary,
// private copies of the scenes the e2e_generate_scenes fixture made, and
// the checks every refusal must pass.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "colmap/scene/reconstruction.h"
#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {

// The binary with the dp-sfm commands: the patched `colmap` (checkout
// route) or `dpsfm` (installed route).
const std::string kDpsfm = DPSFM_DP_EXE;
// COLMAP's own commands (feature_extractor, mapper, image_deleter).
const std::string kColmap = DPSFM_COLMAP_EXE;
const std::string kScenes = DPSFM_E2E_SCENES_DIR;

// The model in after_dir is the one in before_dir scaled by `scale`, as this
// build's own COLMAP reads both: every image's pose (on COLMAP 4 composed
// from its frame and its rig's sensor pose, so rigs and frames are checked
// with it), every 3D point, and nothing else changed in number.
inline void ExpectModelScaled(const std::string& before_dir,
                              const std::string& after_dir,
                              double scale) {
  colmap::Reconstruction before, after;
  before.Read(before_dir);
  after.Read(after_dir);
  ASSERT_EQ(before.NumRegImages(), after.NumRegImages());
  for (const auto& image : before.Images()) {
    const colmap::Image& scaled = after.Image(image.first);
    EXPECT_EQ(scaled.Name(), image.second.Name());
    EXPECT_TRUE(
        dpsfm::RotationOf(scaled.CamFromWorld())
            .isApprox(dpsfm::RotationOf(image.second.CamFromWorld()), 1e-15));
    EXPECT_TRUE(
        dpsfm::TranslationOf(scaled.CamFromWorld())
            .isApprox(scale * dpsfm::TranslationOf(image.second.CamFromWorld()),
                      1e-12));
  }
  ASSERT_EQ(before.NumPoints3D(), after.NumPoints3D());
  for (const auto& point : before.Points3D()) {
    EXPECT_TRUE(after.Point3D(point.first)
                    .xyz.isApprox(scale * point.second.xyz, 1e-12));
  }
}

// The depth map at after_path is the one at before_path with every valid
// (> 0) depth multiplied by `scale` and every other value kept.
inline void ExpectDepthMapScaled(const std::string& before_path,
                                 const std::string& after_path,
                                 double scale) {
  const cv::Mat before = ReadColmapDepthMap(before_path);
  const cv::Mat after = ReadColmapDepthMap(after_path);
  ASSERT_EQ(before.size(), after.size());
  for (int r = 0; r < before.rows; ++r) {
    for (int c = 0; c < before.cols; ++c) {
      const float d = before.at<float>(r, c);
      const float expected = d > 0 ? static_cast<float>(scale * d) : d;
      ASSERT_NEAR(after.at<float>(r, c), expected, 1e-6 * std::abs(expected))
          << after_path << " at " << c << "," << r;
    }
  }
}

inline nlohmann::json ReadJson(const std::string& path) {
  std::ifstream file(path);
  EXPECT_TRUE(file.good()) << path;
  return nlohmann::json::parse(file);
}

// A private copy of a generated scene.
class SceneCopy {
 public:
  explicit SceneCopy(const std::string& scene) {
    const std::string source = kScenes + "/" + scene;
    if (!std::filesystem::is_directory(source)) {
      ADD_FAILURE() << "generated scene missing: " << source
                    << " (run the whole suite with ctest; the "
                       "e2e_generate_scenes fixture makes it)";
      return;
    }
    root_ = dir_ / scene;
    std::filesystem::create_directories(root_);
    for (std::filesystem::recursive_directory_iterator it(source), end;
         it != end;
         ++it) {
      const std::filesystem::path target =
          std::filesystem::path(root_) /
          std::filesystem::relative(it->path(), source);
      if (std::filesystem::is_directory(it->path())) {
        std::filesystem::create_directories(target);
      } else {
        std::filesystem::copy_file(it->path(), target);
      }
    }
  }
  const std::string& root() const { return root_; }
  std::string operator/(const std::string& name) const {
    return (std::filesystem::path(root_) / name).string();
  }
  const TempDir& temp() const { return dir_; }

 private:
  TempDir dir_;
  std::string root_;
};

// A copy of a binary model, to compare with after the run.
inline std::string CopyModel(const std::string& model_dir,
                             const std::string& copy) {
  std::filesystem::create_directories(copy);
  for (const char* name : {"images.bin", "points3D.bin", "cameras.bin"}) {
    std::filesystem::copy_file(std::filesystem::path(model_dir) / name,
                               std::filesystem::path(copy) / name);
  }
  return copy;
}

inline CommandResult RunEstimator(const std::vector<std::string>& args,
                                  const std::vector<std::string>& env = {}) {
  std::vector<std::string> command;
  if (!env.empty()) {
    command.push_back("env");
    command.insert(command.end(), env.begin(), env.end());
  }
  command.push_back(kDpsfm);
  command.push_back("dp_scale_estimator");
  command.insert(command.end(), args.begin(), args.end());
  return RunCommand(command);
}

inline std::vector<std::string> DenseArgs(const SceneCopy& scene) {
  return {"--workspace_path",
          scene / "dense",
          "--dp_image_path",
          scene / "dp",
          "--lens_path",
          scene / "lens.csv"};
}

inline std::vector<std::string> With(std::vector<std::string> args,
                                     const std::vector<std::string>& more) {
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

// One error line naming `expected`, exit 1, and the tree untouched.
inline void ExpectRefusal(const CommandResult& result,
                          const std::string& expected,
                          const std::map<std::string, std::string>& before,
                          const std::string& root) {
  EXPECT_FALSE(result.signaled) << result.err;
  EXPECT_EQ(result.exit_code, 1) << result.err;
  const std::vector<std::string> lines = Lines(result.err);
  int error_lines = 0;
  for (const std::string& line : lines) {
    if (line.compare(0, 7, "ERROR: ") == 0) {
      ++error_lines;
      EXPECT_NE(line.find(expected), std::string::npos)
          << line << "\nexpected: " << expected;
    }
  }
  EXPECT_EQ(error_lines, 1) << result.err;
  EXPECT_TRUE(SnapshotTree(root) == before) << "the workspace changed";
}

// A dense run on a private copy of the generated scene `name` is refused
// with an error line naming `expected`.
inline void ExpectSceneRefused(const std::string& name,
                               const std::string& expected) {
  SceneCopy scene(name);
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(RunEstimator(DenseArgs(scene)), expected, before, scene.root());
}

}  // namespace test
}  // namespace dpsfm
