// The command on what current COLMAP (4.x) and real file systems hand it:
// a dense workspace whose model COLMAP 4.2.1 wrote (rigs.bin, frames.bin;
// trivial rigs, or a two-camera rig), a model from COLMAP 4.2.1's
// global_mapper, each rescaled in place and read back by COLMAP 4.2.1
// (pycolmap) and by this build's own reader; a model
// folder with a file of unknown treatment; a read-only workspace; a
// truncated images.bin. Refusals come before the estimation, in one line,
// with the workspace unchanged.
#include <sys/mount.h>

#include <cerrno>
#include <cstring>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "tests/e2e/e2e_helpers.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

// The generated dense workspace with its model written again by COLMAP
// 4.2.1, as image undistorters of COLMAP 4 leave it: one trivial rig per
// camera and a frame per image, or the images split over the two cameras
// of one rig (lens data per image in lens.csv, DP frames per image). The
// 3.x model is kept aside as the original; COLMAP 4.2.1 reads the
// rescaled one back.
void RescaleColmap4Workspace(bool two_camera_rig) {
  ASSERT_TRUE(fs::exists(PycolmapPython()))
      << "no pycolmap 4.2.1 at " << PycolmapPython()
      << ": run scripts/install_deps.sh";
  SceneCopy scene("dslr");
  const std::string sparse = scene / "dense/sparse";
  const std::string original = scene.temp() / "original_model";
  std::vector<std::string> convert = {"convert", sparse, original};
  if (two_camera_rig) convert.push_back("--two_camera_rig");
  const CommandResult converted = RunColmap4Oracle(convert);
  ASSERT_EQ(converted.exit_code, 0) << converted.err;
  fs::remove_all(sparse);
  CopyFolderFiles(original, sparse);
  ASSERT_TRUE(fs::exists(sparse + "/frames.bin"));
  ASSERT_TRUE(fs::exists(sparse + "/rigs.bin"));

  const std::string report = scene.temp() / "report.json";
  const CommandResult run =
      RunEstimator(With(DenseArgs(scene), {"--report_path", report}));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json r = ReadJson(report);
  EXPECT_EQ(r.at("views").size(), 8u);
  const double scale = r.at("scale").get<double>();
  const CommandResult verdict = CheckWithColmap4(original, sparse, scale);
  EXPECT_EQ(verdict.exit_code, 0) << verdict.out << verdict.err;
  std::printf("%s", verdict.out.c_str());
  ExpectModelScaled(original, sparse, scale);
}

TEST(CurrentColmap, DenseWorkspaceFromColmap4IsRescaledWhole) {
  RescaleColmap4Workspace(false);
}

TEST(CurrentColmap, TwoCameraRigIsEstimatedAndRescaledWhole) {
  RescaleColmap4Workspace(true);
}

// A model made by COLMAP 4.2.1's global_mapper (GLOMAP) from the generated
// images (CPU SIFT, exhaustive matching), scaled in sparse mode from its
// triangulated points and rescaled in place: COLMAP 4.2.1 reads it back
// scaled whole, and its camera distances are metric (the generator's true
// camera centres, within 5 %).
TEST(CurrentColmap, GlobalMapperModelIsScaledToMetres) {
  ASSERT_TRUE(fs::exists(PycolmapPython()))
      << "no pycolmap 4.2.1 at " << PycolmapPython()
      << ": run scripts/install_deps.sh";
  SceneCopy scene("dslr");
  const std::string model = scene / "global";
  const CommandResult mapped =
      RunColmap4Oracle({"map", scene / "images", model, "--mapper", "global"});
  ASSERT_EQ(mapped.exit_code, 0) << mapped.out << mapped.err;
  std::printf("%s", mapped.out.c_str());
  const std::string original = scene.temp() / "global_original";
  CopyFolderFiles(model, original);
  const std::string report = scene.temp() / "report.json";
  const CommandResult run = RunEstimator({"--input_path",
                                          model,
                                          "--dp_image_path",
                                          scene / "dp",
                                          "--lens_path",
                                          scene / "lens.csv",
                                          "--report_path",
                                          report});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const double scale = ReadJson(report).at("scale").get<double>();
  const CommandResult verdict = CheckWithColmap4(
      original, model, scale, {"--truth", scene / "ground_truth.json"});
  EXPECT_EQ(verdict.exit_code, 0) << verdict.out << verdict.err;
  std::printf("%s", verdict.out.c_str());
  ExpectModelScaled(original, model, scale);
}

// A model as COLMAP 3.x writes it (cameras, images and points, no rigs.bin
// or frames.bin; COLMAP 4 writes images.bin as 3.x did) is rescaled whole
// and stays in that layout: on a COLMAP 4 build, its reader makes the
// trivial rigs and frames itself, and the rescaler adds none to the folder.
TEST(CurrentColmap, ModelWithoutRigsAndFramesIsRescaledWhole) {
  SceneCopy scene("dslr");
  const std::string sparse = scene / "dense/sparse";
  fs::remove(sparse + "/rigs.bin");
  fs::remove(sparse + "/frames.bin");
  const std::string original = scene.temp() / "original_model";
  CopyFolderFiles(sparse, original);
  const std::string report = scene.temp() / "report.json";
  const CommandResult run =
      RunEstimator(With(DenseArgs(scene), {"--report_path", report}));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const double scale = ReadJson(report).at("scale").get<double>();
  EXPECT_GT(scale, 0.0);
  std::set<std::string> files;
  for (fs::directory_iterator it(sparse), end; it != end; ++it) {
    files.insert(it->path().filename().string());
  }
  EXPECT_EQ(
      files,
      (std::set<std::string>{"cameras.bin", "images.bin", "points3D.bin"}));
  ExpectModelScaled(original, sparse, scale);
}

TEST(CurrentColmap, UnknownFileInTheModelFolderIsRefusedBeforeEstimating) {
  SceneCopy scene("dslr");
  WriteTextFile(scene / "dense/sparse/cameras.nvm", "NVM_V3\n");
  const auto before = SnapshotTree(scene.root());
  const CommandResult run = RunEstimator(DenseArgs(scene));
  ExpectRefusal(run, "cameras.nvm", before, scene.root());
  // Refused before any view was read.
  EXPECT_EQ(run.err.find("Per-patch DP blur estimation"), std::string::npos)
      << run.err;
  // A dry run rescales nothing, so it does not care.
  const CommandResult dry =
      RunEstimator(With(DenseArgs(scene), {"--dry_run", "1"}));
  EXPECT_EQ(dry.exit_code, 0) << dry.err;
}

TEST(CurrentColmap, TruncatedImagesBinIsNamed) {
  SceneCopy scene("dslr");
  const std::string path = scene / "dense/sparse/images.bin";
  const std::string bytes = ReadTextFile(path);
  WriteTextFile(path, bytes.substr(0, bytes.size() - 100));
  const auto before = SnapshotTree(scene.root());
  const CommandResult run = RunEstimator(DenseArgs(scene));
  // The plugin's model check names the file, the record and the cut.
  ExpectRefusal(run, path + ": image ", before, scene.root());
  EXPECT_NE(run.err.find("it is truncated"), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find("bad_alloc"), std::string::npos) << run.err;
}

// A read-only bind mount of the workspace (root ignores permission bits,
// not a read-only mount).
class ReadOnlyMount {
 public:
  explicit ReadOnlyMount(const std::string& dir) : dir_(dir) {
    if (::mount(dir.c_str(), dir.c_str(), nullptr, MS_BIND, nullptr) != 0) {
      error_ = std::strerror(errno);
      return;
    }
    if (::mount(nullptr,
                dir.c_str(),
                nullptr,
                MS_BIND | MS_REMOUNT | MS_RDONLY,
                nullptr) != 0) {
      error_ = std::strerror(errno);
      ::umount(dir.c_str());
      return;
    }
    mounted_ = true;
  }
  ~ReadOnlyMount() {
    if (mounted_) ::umount(dir_.c_str());
  }
  bool mounted() const { return mounted_; }
  const std::string& error() const { return error_; }

 private:
  std::string dir_, error_;
  bool mounted_ = false;
};

TEST(CurrentColmap, ReadOnlyWorkspaceIsRefusedBeforeEstimating) {
  SceneCopy scene("dslr");
  const std::string dense = scene / "dense";
  const auto before = SnapshotTree(scene.root());
  CommandResult run, dry;
  {
    ReadOnlyMount read_only(dense);
    if (!read_only.mounted() && ::geteuid() != 0) {
      GTEST_SKIP() << "needs root for a read-only mount: " << read_only.error();
    }
    ASSERT_TRUE(read_only.mounted()) << read_only.error();
    run = RunEstimator(DenseArgs(scene));
    dry = RunEstimator(With(DenseArgs(scene), {"--dry_run", "1"}));
  }
  ExpectRefusal(run, "is not writable", before, scene.root());
  EXPECT_NE(run.err.find("--output_path"), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find("Per-patch DP blur estimation"), std::string::npos)
      << run.err;
  EXPECT_EQ(dry.exit_code, 0) << dry.err;
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
