// Models written by current COLMAP (4.x: rigs.bin / frames.bin beside the
// rest), rescaled by this build, checked by two readers that share no code
// with the rescaler: this build's own COLMAP (3.x reads the composed poses
// of images.*) and COLMAP 4.2.1 through pycolmap from PyPI (it takes each
// image's pose from its frame's rig_from_world and its rig's
// sensor_from_rig). The models themselves are made by COLMAP 4.2.1's own
// synthesizer: rigs of two cameras (with sensor_from_rig poses), frames,
// points.
//
// pycolmap lives in a virtualenv that scripts/install_deps.sh makes
// ($DPSFM_CACHE_DIR/venv/pycolmap-4.2.1); DPSFM_PYCOLMAP_PYTHON overrides.
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <colmap/scene/reconstruction.h>
#include <gtest/gtest.h>

#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/rescale/rescale_plan.h"
#include "dpsfm/colmap/rescale/transaction.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/colmap/util/durable_file.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

class Colmap4Model : public ::testing::Test {
 protected:
  void SetUp() override {
    python_ = PycolmapPython();
    ASSERT_TRUE(fs::exists(python_))
        << "no Python with pycolmap 4.2.1 at " << python_
        << ": run scripts/install_deps.sh (or set DPSFM_PYCOLMAP_PYTHON)";
  }

  // A model by COLMAP 4.2.1 in `dir`.
  void Make(const std::string& dir, std::vector<std::string> options) {
    options.insert(options.begin(), {"make", dir});
    const CommandResult made = RunColmap4Oracle(options);
    ASSERT_EQ(made.exit_code, 0) << made.err;
    ASSERT_TRUE(fs::exists(dir + "/frames.bin") ||
                fs::exists(dir + "/frames.txt"));
  }

  std::string python_;
  TempDir dir_;
};

// Mean reprojection error per image under this build's COLMAP reader.
std::map<std::string, double> ImageErrors(const colmap::Reconstruction& r) {
  std::map<std::string, double> errors;
  for (const auto& entry : r.Images()) {
    const colmap::Image& image = entry.second;
    const colmap::Camera& camera = r.Camera(image.CameraId());
    double sum = 0;
    int n = 0;
    for (const colmap::Point2D& point : image.Points2D()) {
      if (!point.HasPoint3D()) continue;
      const Eigen::Vector3d xyz = r.Point3D(point.point3D_id).xyz;
      const Eigen::Vector3d cam = image.CamFromWorld() * xyz;
      const std::optional<Eigen::Vector2d> xy = ImgFromCam(camera, cam);
      if (!xy) continue;
      sum += (*xy - point.xy).norm();
      ++n;
    }
    errors[image.Name()] = n ? sum / n : 0;
  }
  return errors;
}

// The 3.x reader's view of the rescaled model: errors unchanged, centre
// distances and points times s.
void ExpectScaledByThisBuild(const std::string& original_dir,
                             const std::string& rescaled_dir,
                             double scale) {
  colmap::Reconstruction original, rescaled;
  original.Read(original_dir);
  rescaled.Read(rescaled_dir);
  ASSERT_EQ(original.NumImages(), rescaled.NumImages());
  const auto e0 = ImageErrors(original), e1 = ImageErrors(rescaled);
  for (const auto& entry : e0) {
    EXPECT_NEAR(
        e1.at(entry.first), entry.second, 1e-9 * std::max(entry.second, 1e-3))
        << entry.first;
  }
  std::vector<Eigen::Vector3d> c0, c1;
  for (const auto& entry : original.Images()) {
    c0.push_back(entry.second.ProjectionCenter());
    c1.push_back(rescaled.Image(entry.first).ProjectionCenter());
  }
  for (size_t i = 0; i < c0.size(); ++i) {
    for (size_t j = i + 1; j < c0.size(); ++j) {
      const double d0 = (c0[i] - c0[j]).norm();
      EXPECT_NEAR((c1[i] - c1[j]).norm(), scale * d0, 1e-9 * scale * d0);
    }
  }
  for (const auto& entry : original.Points3D()) {
    const Eigen::Vector3d want = scale * entry.second.xyz;
    EXPECT_NEAR((rescaled.Point3D(entry.first).xyz - want).norm(),
                0,
                1e-9 * want.norm());
  }
}

// Two rigs of two cameras, binary and text, rescaled in place: both
// readers agree that the whole model, poses of rigs and frames included,
// is s times the original.
TEST_F(Colmap4Model, RigsAndFramesAreRescaledWithTheRest) {
  const double scale = 0.558;
  for (const bool text : {false, true}) {
    SCOPED_TRACE(text ? "text" : "binary");
    const std::string original = dir_ / (text ? "t_original" : "b_original");
    const std::string ws = dir_ / (text ? "t_ws" : "b_ws");
    Make(original,
         text ? std::vector<std::string>{"--text", "--seed", "2"}
              : std::vector<std::string>{});
    CopyFolderFiles(original, ws);
    const std::vector<Artefact> artefacts = ListArtefactsToRescale(ws);
    std::vector<std::string> names;
    for (const Artefact& a : artefacts) {
      names.push_back(fs::path(a.path).filename().string());
    }
    const std::vector<std::string> expected =
        text ? std::vector<std::string>{"images.txt",
                                        "points3D.txt",
                                        "rigs.txt",
                                        "frames.txt"}
             : std::vector<std::string>{
                   "images.bin", "points3D.bin", "rigs.bin", "frames.bin"};
    EXPECT_EQ(names, expected);
    RescaleWorkspaceInPlace(ws, scale, RescaleWorkspaceOptions());
    const CommandResult verdict = CheckWithColmap4(original, ws, scale);
    EXPECT_EQ(verdict.exit_code, 0) << verdict.out << verdict.err;
    std::printf("%s", verdict.out.c_str());
    ExpectScaledByThisBuild(original, ws, scale);
  }
}

// The oracle can fail: the old rescaler's output (images.* and points3D.*
// only) reads back in COLMAP 4.2.1 with unscaled camera distances.
TEST_F(Colmap4Model, OracleCatchesUnscaledFrames) {
  const std::string original = dir_ / "original";
  const std::string ws = dir_ / "old";
  Make(original, {});
  CopyFolderFiles(original, ws);
  for (const char* name : {"images.bin", "points3D.bin"}) {
    const std::string path = ws + "/" + name;
    std::string bytes = ReadFileBytes(path);
    RescaleContents(std::string(name) == "images.bin"
                        ? ArtefactType::kImagesBinary
                        : ArtefactType::kPoints3DBinary,
                    0.558,
                    path,
                    &bytes);
    WriteFileDurably(path, bytes);
  }
  const CommandResult verdict = CheckWithColmap4(original, ws, 0.558);
  EXPECT_NE(verdict.exit_code, 0) << verdict.out;
  EXPECT_NE(verdict.out.find("camera-centre distances are not"),
            std::string::npos)
      << verdict.out;
}

// Several single cameras (COLMAP 4 gives each a trivial rig) and a model
// folder holding both formats: every file rescaled, the two formats agree.
TEST_F(Colmap4Model, TrivialRigsAndBothFormats) {
  const std::string original = dir_ / "original";
  Make(original, {"--rigs", "3", "--cameras_per_rig", "1", "--frames", "3"});
  const std::string ws = dir_ / "ws";
  CopyFolderFiles(original, ws);
  const CommandResult text =
      RunColmap4Oracle({"convert", original, ws, "--text"});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_EQ(ListArtefactsToRescale(ws).size(), 8u);
  const double scale = 3.25;
  RescaleWorkspaceInPlace(ws, scale, RescaleWorkspaceOptions());
  // COLMAP 4 reads .bin first; check the text files on their own too.
  const std::string text_only = dir_ / "text_only";
  fs::create_directories(text_only);
  for (const char* name : {"cameras.txt",
                           "images.txt",
                           "points3D.txt",
                           "rigs.txt",
                           "frames.txt"}) {
    fs::copy_file(ws + "/" + name, text_only + "/" + name);
  }
  for (const std::string& rescaled : {ws, text_only}) {
    const CommandResult verdict = CheckWithColmap4(original, rescaled, scale);
    EXPECT_EQ(verdict.exit_code, 0) << rescaled << verdict.out << verdict.err;
  }
}

// A model folder with a file the rescaler cannot treat is refused before
// anything is written, in one line that names it.
TEST_F(Colmap4Model, UnknownFileInTheModelFolderIsRefused) {
  const std::string ws = dir_ / "ws";
  Make(ws, {});
  WriteTextFile(ws + "/cameras.nvm", "NVM_V3\n");
  const auto before = SnapshotTree(ws);
  try {
    RescaleWorkspaceInPlace(ws, 2.0, RescaleWorkspaceOptions());
    FAIL() << "rescaled a folder holding cameras.nvm";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("cameras.nvm"), std::string::npos) << message;
    EXPECT_NE(message.find("does not know how to treat"), std::string::npos)
        << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_EQ(SnapshotTree(ws), before);
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
