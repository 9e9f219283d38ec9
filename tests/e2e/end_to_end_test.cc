// `colmap dp_scale_estimator` end to end on generated workspaces: the real
// binary estimates the scale of a scene whose truth is known, rescales every
// artefact by exactly that scale, leaves everything else byte-identical,
// refuses to rescale twice, and survives a kill during its commit.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "colmap/scene/database.h"
#include "colmap/scene/reconstruction.h"
#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "tests/e2e/e2e_helpers.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

// Largest accepted |1 - s_est / s_true| on the clean generated DSLR scene.
constexpr double kMaxScaleError = 0.03;

// fused.ply: binary little-endian, 27 bytes per vertex (xyz, normal, rgb).
void ExpectFusedPlyScaled(const std::string& before,
                          const std::string& after,
                          double scale) {
  const std::string a = ReadTextFile(before), b = ReadTextFile(after);
  ASSERT_EQ(a.size(), b.size());
  const size_t header_end = a.find("end_header\n") + 11;
  ASSERT_EQ(a.substr(0, header_end), b.substr(0, header_end));
  for (size_t offset = header_end; offset + 27 <= a.size(); offset += 27) {
    for (int k = 0; k < 3; ++k) {
      float x, y;
      std::memcpy(&x, a.data() + offset + 4 * k, 4);
      std::memcpy(&y, b.data() + offset + 4 * k, 4);
      ASSERT_NEAR(y, static_cast<float>(scale * x), 1e-6 * std::abs(scale * x));
    }
    ASSERT_EQ(a.substr(offset + 12, 15), b.substr(offset + 12, 15))
        << "normal or colour changed at byte " << offset;
  }
}

bool IsRescaledArtefact(const std::string& relative) {
  if (relative.back() == '/') return false;  // a directory entry
  return relative == "dense/sparse/images.bin" ||
         relative == "dense/sparse/points3D.bin" ||
         relative == "dense/sparse/frames.bin" ||
         relative == "dense/fused.ply" ||
         relative.find("dense/stereo/depth_maps/") == 0;
}

TEST(EndToEnd, DenseWorkspaceInPlace) {
  SceneCopy scene("dslr");
  const auto before = SnapshotTree(scene.root());
  const std::string original =
      CopyModel(scene / "dense/sparse", scene.temp() / "original");
  const std::string report_path = scene.temp() / "report.json";
  const CommandResult result =
      RunEstimator(With(DenseArgs(scene), {"--report_path", report_path}));
  ASSERT_EQ(result.exit_code, 0) << result.err;

  const nlohmann::json report = ReadJson(report_path);
  const nlohmann::json truth = ReadJson(scene / "ground_truth.json");
  const double scale = report.at("scale").get<double>();
  const double true_scale = truth.at("scale").get<double>();
  EXPECT_LT(std::abs(1 - scale / true_scale), kMaxScaleError)
      << "estimated " << scale << ", true " << true_scale;
  EXPECT_TRUE(report.at("scale_initial").is_number());
  EXPECT_GT(report.at("num_patches").get<int>(), 0);
  EXPECT_EQ(report.at("views").size(), 8u);
  for (const auto& view : report.at("views").items()) {
    EXPECT_TRUE(view.value().contains("used"));
    EXPECT_TRUE(view.value().contains("reason"));
    EXPECT_TRUE(view.value().contains("focus_distance_m"));
  }
  EXPECT_GT(report.at("seconds").get<double>(), 0);
  // The pictures next to the report are listed, none missing.
  EXPECT_GE(report.at("plots").at("written").size(), 2u);
  EXPECT_TRUE(report.at("plots").at("failures").empty());

  // Every metric artefact is the original times s; nothing else changed.
  ExpectModelScaled(original, scene / "dense/sparse", scale);
  const auto after = SnapshotTree(scene.root());
  std::set<std::string> rescaled;
  for (const auto& file : before) {
    ASSERT_TRUE(after.count(file.first)) << file.first << " disappeared";
    if (IsRescaledArtefact(file.first)) {
      EXPECT_NE(after.at(file.first), file.second) << file.first;
      rescaled.insert(file.first);
    } else {
      EXPECT_TRUE(after.at(file.first) == file.second)
          << file.first << " changed";
    }
  }
  // The model (with its frames on COLMAP 4; the trivial rigs hold no
  // translation), 8 x 2 depth maps and fused.ply.
  EXPECT_EQ(rescaled.size(), (kWriterWritesRigsAndFrames ? 3u : 2u) + 16u + 1u);
  for (const std::string& file : rescaled) {
    if (file.find("depth_maps/") != std::string::npos) {
      const std::string copy = scene.temp() / "depth_before.bin";
      WriteTextFile(copy, before.at(file));
      ExpectDepthMapScaled(copy, scene / file, scale);
    }
  }
  const std::string fused_before = scene.temp() / "fused_before.ply";
  WriteTextFile(fused_before, before.at("dense/fused.ply"));
  ExpectFusedPlyScaled(fused_before, scene / "dense/fused.ply", scale);
  // A record of what was applied.
  const nlohmann::json record = ReadJson(scene / "dense/dp_scale_record.json");
  EXPECT_EQ(after.size(), before.size() + 1);
  EXPECT_NE(record.dump().find("cumulative_scale"), std::string::npos);

  // A second run refuses and changes nothing; with --force it composes.
  const auto rescaled_tree = SnapshotTree(scene.root());
  ExpectRefusal(RunEstimator(DenseArgs(scene)),
                "already rescaled",
                rescaled_tree,
                scene.root());
  const std::string report2 = scene.temp() / "report2.json";
  const CommandResult forced = RunEstimator(
      With(DenseArgs(scene), {"--force", "1", "--report_path", report2}));
  ASSERT_EQ(forced.exit_code, 0) << forced.err;
  const double scale2 = ReadJson(report2).at("scale").get<double>();
  // The model is already metric: a second estimate is close to 1.
  EXPECT_LT(std::abs(scale2 - 1.0), kMaxScaleError);
  const nlohmann::json record2 = ReadJson(scene / "dense/dp_scale_record.json");
  EXPECT_NEAR(ReadJson(report2).at("cumulative_scale").get<double>(),
              scale * scale2,
              1e-9 * scale * scale2)
      << record2.dump(2);
}

TEST(EndToEnd, DryRunChangesNothing) {
  SceneCopy scene("dslr");
  const auto before = SnapshotTree(scene.root());
  const std::string report_path = scene.temp() / "report.json";
  const CommandResult result = RunEstimator(
      With(DenseArgs(scene), {"--dry_run", "1", "--report_path", report_path}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(SnapshotTree(scene.root()) == before);
  EXPECT_TRUE(ReadJson(report_path).at("scale").is_number());
}

TEST(EndToEnd, OutputPathWritesARescaledCopy) {
  SceneCopy scene("dslr");
  const auto before = SnapshotTree(scene.root());
  const std::string out = scene.temp() / "metric";
  const std::string report_path = scene.temp() / "report.json";
  const CommandResult result = RunEstimator(With(
      DenseArgs(scene), {"--output_path", out, "--report_path", report_path}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(SnapshotTree(scene.root()) == before) << "input changed";
  const double scale = ReadJson(report_path).at("scale").get<double>();
  ExpectModelScaled(scene / "dense/sparse", out + "/sparse", scale);
  ExpectDepthMapScaled(
      scene / "dense/stereo/depth_maps/DP_0001.jpg.geometric.bin",
      out + "/stereo/depth_maps/DP_0001.jpg.geometric.bin",
      scale);
}

TEST(EndToEnd, SparseModelOnly) {
  SceneCopy scene("dslr");
  const std::string original =
      CopyModel(scene / "sparse/0", scene.temp() / "original");
  const std::string report_path = scene.temp() / "report.json";
  const CommandResult result = RunEstimator({"--input_path",
                                             scene / "sparse/0",
                                             "--dp_image_path",
                                             scene / "dp",
                                             "--lens_path",
                                             scene / "lens.csv",
                                             "--report_path",
                                             report_path});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const double scale = ReadJson(report_path).at("scale").get<double>();
  const double true_scale =
      ReadJson(scene / "ground_truth.json").at("scale").get<double>();
  EXPECT_LT(std::abs(1 - scale / true_scale), kMaxScaleError)
      << "estimated " << scale << ", true " << true_scale;
  ExpectModelScaled(original, scene / "sparse/0", scale);
}

TEST(EndToEnd, DistortedCamerasDenseAndSparse) {
  SceneCopy scene("distorted");
  const double true_scale =
      ReadJson(scene / "ground_truth.json").at("scale").get<double>();
  const std::string report_path = scene.temp() / "report.json";
  // Dense: the database's original cameras map depths into the DP frames.
  CommandResult result = RunEstimator(With(DenseArgs(scene),
                                           {"--database_path",
                                            scene / "database.db",
                                            "--dry_run",
                                            "1",
                                            "--report_path",
                                            report_path}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("6 original cameras"), std::string::npos)
      << result.err;
  double scale = ReadJson(report_path).at("scale").get<double>();
  EXPECT_LT(std::abs(1 - scale / true_scale), kMaxScaleError);
  // Sparse: the model's own (distorted) 2D points are in frame geometry.
  result = RunEstimator({"--input_path",
                         scene / "sparse/0",
                         "--dp_image_path",
                         scene / "dp",
                         "--lens_path",
                         scene / "lens.csv",
                         "--dry_run",
                         "1",
                         "--report_path",
                         report_path});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  scale = ReadJson(report_path).at("scale").get<double>();
  EXPECT_LT(std::abs(1 - scale / true_scale), kMaxScaleError);
}

// The model image_undistorter ran on (--original_model_path) maps depths
// into the DP frames like the database's cameras, and takes precedence over
// them (a real database holds only feature extraction's initial guesses).
TEST(EndToEnd, DistortedCamerasFromTheOriginalModel) {
  SceneCopy scene("distorted");
  const double true_scale =
      ReadJson(scene / "ground_truth.json").at("scale").get<double>();
  const std::string report_path = scene.temp() / "report.json";
  CommandResult result = RunEstimator(With(DenseArgs(scene),
                                           {"--original_model_path",
                                            scene / "sparse/0",
                                            "--dry_run",
                                            "1",
                                            "--report_path",
                                            report_path}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const double scale = ReadJson(report_path).at("scale").get<double>();
  EXPECT_LT(std::abs(1 - scale / true_scale), kMaxScaleError);
  // A folder without a model, or a sparse run, is refused with the reason.
  const std::map<std::string, std::string> before = SnapshotTree(scene.root());
  ExpectRefusal(
      RunEstimator(With(DenseArgs(scene),
                        {"--original_model_path", scene / "dense/stereo"})),
      "--original_model_path has no model",
      before,
      scene.root());
  ExpectRefusal(RunEstimator({"--input_path",
                              scene / "sparse/0",
                              "--dp_image_path",
                              scene / "dp",
                              "--lens_path",
                              scene / "lens.csv",
                              "--original_model_path",
                              scene / "sparse/0"}),
                "is for a dense workspace",
                before,
                scene.root());
}

TEST(EndToEnd, RealColmapPipelineSparseMode) {
  // COLMAP's own SfM on the generated images gives a model of arbitrary
  // frame and scale; after dp_scale_estimator its camera distances must be
  // the true ones in metres.
  SceneCopy scene("dslr");
  const std::string db = scene.temp() / "pipeline.db";
  const std::string sparse = scene.temp() / "sparse";
  fs::create_directories(sparse);
  for (const std::vector<std::string>& step :
       std::vector<std::vector<std::string>>{
           {"feature_extractor",
            "--database_path",
            db,
            "--image_path",
            scene / "images",
            "--ImageReader.single_camera",
            "1",
            std::string("--") + kFeatureExtractionSection + ".use_gpu",
            "0"},
           {"exhaustive_matcher",
            "--database_path",
            db,
            std::string("--") + kFeatureMatchingSection + ".use_gpu",
            "0"},
           {"mapper",
            "--database_path",
            db,
            "--image_path",
            scene / "images",
            "--output_path",
            sparse}}) {
    std::vector<std::string> command = {kColmap};
    command.insert(command.end(), step.begin(), step.end());
    const CommandResult result = RunCommand(command);
    ASSERT_EQ(result.exit_code, 0) << step[0] << "\n" << result.err;
  }
  ASSERT_TRUE(fs::is_directory(sparse + "/0"));
  const CommandResult result = RunEstimator({"--input_path",
                                             sparse + "/0",
                                             "--dp_image_path",
                                             scene / "dp",
                                             "--lens_path",
                                             scene / "lens.csv",
                                             "--database_path",
                                             db});
  ASSERT_EQ(result.exit_code, 0) << result.err;

  const nlohmann::json truth = ReadJson(scene / "ground_truth.json");
  colmap::Reconstruction model;
  model.Read(sparse + "/0");
  std::vector<double> ratios;
  const std::vector<colmap::image_t> ids = model.RegImageIds();
  for (size_t i = 0; i < ids.size(); ++i) {
    for (size_t j = i + 1; j < ids.size(); ++j) {
      const colmap::Image& a = model.Image(ids[i]);
      const colmap::Image& b = model.Image(ids[j]);
      const auto& ta = truth["views"][a.Name()]["center_m"];
      const auto& tb = truth["views"][b.Name()]["center_m"];
      const Eigen::Vector3d true_a(ta[0], ta[1], ta[2]);
      const Eigen::Vector3d true_b(tb[0], tb[1], tb[2]);
      ratios.push_back((a.ProjectionCenter() - b.ProjectionCenter()).norm() /
                       (true_a - true_b).norm());
    }
  }
  ASSERT_GE(ids.size(), 6u);
  std::sort(ratios.begin(), ratios.end());
  EXPECT_LT(std::abs(1 - ratios[ratios.size() / 2]), kMaxScaleError)
      << "median metric/true camera distance " << ratios[ratios.size() / 2];
}

TEST(EndToEnd, KillDuringCommitThenRerunFinishes) {
  // Kill the process right after its 5th rename, then run again: every file
  // must end up fully rescaled exactly once.
  SceneCopy scene("dslr");
  const std::string original =
      CopyModel(scene / "dense/sparse", scene.temp() / "original");
  const std::string report_path = scene.temp() / "report.json";
  const CommandResult killed =
      RunEstimator(With(DenseArgs(scene), {"--report_path", report_path}),
                   {"DPSFM_FAULT_INJECT_COMMIT_AFTER=5"});
  EXPECT_EQ(killed.exit_code, 77) << killed.err;
  const CommandResult rerun = RunEstimator(DenseArgs(scene));
  ASSERT_EQ(rerun.exit_code, 0) << rerun.err;
  EXPECT_NE(rerun.err.find("Finished an interrupted rescale"),
            std::string::npos)
      << rerun.err;
  const nlohmann::json record = ReadJson(scene / "dense/dp_scale_record.json");
  ASSERT_EQ(record.at("entries").size(), 1u) << record.dump(2);
  const double scale = record.at("entries")[0].at("scale").get<double>();
  ExpectModelScaled(original, scene / "dense/sparse", scale);
  for (fs::recursive_directory_iterator it(scene.root()), end; it != end;
       ++it) {
    EXPECT_EQ(it->path().string().find(".dpsfm-staged"), std::string::npos)
        << it->path();
  }
}

// --- Bad input: exit 1, one error line that says what and which file, and a
// byte-identical workspace.

TEST(EndToEndErrors, MissingDPView) {
  SceneCopy scene("dslr");
  fs::remove(scene / "dp/left/DP_0003.png");
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(
      RunEstimator(DenseArgs(scene)), "DP_0003.jpg", before, scene.root());
}

TEST(EndToEndErrors, UnreadableDPView) {
  SceneCopy scene("dslr");
  WriteTextFile(scene / "dp/right/DP_0002.png", "not a png");
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(
      RunEstimator(DenseArgs(scene)), "DP_0002.png", before, scene.root());
}

TEST(EndToEndErrors, DPViewSizeMismatch) {
  // Both views cropped: they agree with each other but not with the camera.
  SceneCopy scene("dslr");
  for (const char* side : {"left", "right"}) {
    const std::string path =
        scene / (std::string("dp/") + side + "/DP_0004.png");
    const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
    cv::imwrite(path,
                image(cv::Rect(0, 0, image.cols - 7, image.rows)).clone());
  }
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(
      RunEstimator(DenseArgs(scene)), "DP_0004.jpg", before, scene.root());
}

TEST(EndToEndErrors, LeftRightSizeMismatch) {
  SceneCopy scene("dslr");
  const std::string path = scene / "dp/left/DP_0004.png";
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  cv::imwrite(path, image(cv::Rect(0, 0, image.cols - 7, image.rows)).clone());
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(
      RunEstimator(DenseArgs(scene)), "DP_0004.png", before, scene.root());
}

TEST(EndToEndErrors, TruncatedDepthMap) {
  SceneCopy scene("dslr");
  const std::string path =
      scene / "dense/stereo/depth_maps/DP_0005.jpg.geometric.bin";
  const std::string bytes = ReadTextFile(path);
  WriteTextFile(path, bytes.substr(0, bytes.size() / 2));
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(RunEstimator(DenseArgs(scene)), path, before, scene.root());
}

TEST(EndToEndErrors, NonFiniteDepthMap) {
  SceneCopy scene("dslr");
  const std::string path =
      scene / "dense/stereo/depth_maps/DP_0006.jpg.geometric.bin";
  std::string bytes = ReadTextFile(path);
  const float nan = std::nanf("");
  std::memcpy(&bytes[bytes.size() - 400], &nan, sizeof(nan));
  WriteTextFile(path, bytes);
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(
      RunEstimator(DenseArgs(scene)), "non-finite", before, scene.root());
}

TEST(EndToEndErrors, LensDataMissing) {
  SceneCopy scene("dslr");
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(RunEstimator({"--workspace_path",
                              scene / "dense",
                              "--dp_image_path",
                              scene / "dp"}),
                "--DPScaleEstimator.focal_length_mm",
                before,
                scene.root());
}

TEST(EndToEndErrors, ModelWithoutRegisteredImages) {
  SceneCopy scene("dslr");
  colmap::Reconstruction empty;
  colmap::Reconstruction model;
  model.Read(scene / "dense/sparse");
  for (const auto& camera : model.Cameras()) {
    dpsfm::AddCamera(&empty, camera.second);
  }
  fs::remove_all(scene / "dense/sparse");
  fs::create_directories(scene / "dense/sparse");
  empty.WriteBinary(scene / "dense/sparse");
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(RunEstimator(DenseArgs(scene)),
                "no registered images",
                before,
                scene.root());
}

TEST(EndToEndErrors, PanFocusCaptureIsRefusedWithAReason) {
  ExpectSceneRefused("pan_focus", "too little blur");
}

// A project database holding the model's cameras and images (or, with
// `rename`, images of another project).
void WriteDatabase(const std::string& model_dir,
                   const std::string& path,
                   bool rename) {
  colmap::Reconstruction model;
  model.Read(model_dir);
  const std::shared_ptr<colmap::Database> database = dpsfm::OpenDatabase(path);
  for (const auto& camera : model.Cameras()) {
    database->WriteCamera(camera.second, /*use_camera_id=*/true);
  }
  for (const auto& image : model.Images()) {
    colmap::Image copy;
    copy.SetName(rename ? "other_" + image.second.Name() : image.second.Name());
    copy.SetCameraId(image.second.CameraId());
    database->WriteImage(copy);
  }
  database->Close();
}

TEST(EndToEnd, DatabaseIsOnlyRead) {
  SceneCopy scene("dslr");
  const std::string database = scene.temp() / "project.db";
  WriteDatabase(scene / "sparse/0", database, false);
  const auto before = SnapshotTree(scene.temp().path());
  const CommandResult result = RunEstimator(
      With(DenseArgs(scene), {"--database_path", database, "--dry_run", "1"}));
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("Database: 8 images; 0 model images missing"),
            std::string::npos)
      << result.err;
  // Not a byte changed, and no -wal / -shm files appeared.
  EXPECT_TRUE(SnapshotTree(scene.temp().path()) == before);
}

TEST(EndToEndErrors, DatabaseOfAnotherProject) {
  SceneCopy scene("dslr");
  const std::string database = scene.temp() / "other.db";
  WriteDatabase(scene / "sparse/0", database, true);
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(
      RunEstimator(With(DenseArgs(scene), {"--database_path", database})),
      "none of the model's 8 images is in the database",
      before,
      scene.root());
}

TEST(EndToEndErrors, NotADatabase) {
  SceneCopy scene("dslr");
  const std::string database = scene.temp() / "notes.db";
  WriteTextFile(database, "these are my notes, not a database");
  const auto before = SnapshotTree(scene.root());
  ExpectRefusal(
      RunEstimator(With(DenseArgs(scene), {"--database_path", database})),
      database,
      before,
      scene.root());
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
