// What the camera recorded, read from its own files by the real binary:
// the generated DSLR scene's original JPEGs are given the metadata of a
// real Canon EOS R6 (its CR3 in ../shared/exif, EXIF and maker notes,
// written into each JPEG with Exiv2), with the focus window of the R6's
// FileInfo record set around each view's true focus. The estimator takes
// the recorded focus from them with no focus in lens.csv and names its
// source; dp_lens_data lists it as a lens.csv; the run on that lens.csv
// alone gives the same answer.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

// Exiv2 0.27's factory returns std::auto_ptr (deprecated in C++11).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/e2e/e2e_helpers.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

// The R6's metadata, with the focus window [lower, upper] cm and the
// scene's lens in place of the R6's (its FocalPlaneXResolution stays: the
// scene's lens.csv gives the pitch, which wins).
Exiv2::ExifData R6Metadata(int lower_cm, int upper_cm) {
  Exiv2::LogMsg::setLevel(Exiv2::LogMsg::mute);
  Exiv2::enableBMFF(true);
  auto cr3 = Exiv2::ImageFactory::open(RealExifDir() + "/Canon-R6-pruned.CR3");
  cr3->readMetadata();
  Exiv2::ExifData exif = cr3->exifData();
  exif["Exif.Photo.FocalLength"] = Exiv2::URational(50, 1);
  exif["Exif.Photo.FNumber"] = Exiv2::URational(28, 10);
  exif["Exif.CanonFi.FocusDistanceUpper"] = static_cast<int16_t>(upper_cm);
  exif["Exif.CanonFi.FocusDistanceLower"] = static_cast<int16_t>(lower_cm);
  return exif;
}

void WriteMetadata(const std::string& jpeg, const Exiv2::ExifData& exif) {
  auto image = Exiv2::ImageFactory::open(jpeg);
  image->readMetadata();
  image->setExifData(exif);
  image->writeMetadata();
}

class CameraMetadata : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(RealExifDir().empty())
        << "the real cameras' files (../shared/exif) are missing; set "
           "DPSFM_EXIF_DIR to the folder holding Canon-R6-pruned.CR3";
    const nlohmann::json truth = ReadJson(scene_ / "ground_truth.json");
    for (const auto& view : truth.at("views").items()) {
      // The window 3 % either side of the true focus, in whole cm as the
      // camera records it.
      const double cm = 100 * view.value().at("focus_distance_m").get<double>();
      const int lower = static_cast<int>(std::floor(0.97 * cm));
      const int upper = static_cast<int>(std::ceil(1.03 * cm));
      windows_.push_back({view.key(), lower, upper});
      WriteMetadata(scene_ / ("images/" + view.key()),
                    R6Metadata(lower, upper));
    }
    true_scale_ = truth.at("scale").get<double>();
  }

  struct Window {
    std::string image;
    int lower_cm, upper_cm;
  };
  SceneCopy scene_{"dslr"};
  std::vector<Window> windows_;
  double true_scale_ = 0;
};

TEST_F(CameraMetadata, RecordedFocusFromTheImagesEqualsItTypedInLensCsv) {
  ASSERT_FALSE(windows_.empty());
  // lens.csv as generated: focal length, f-number and pitch, no focus.
  const std::string from_files = scene_ / "from_files.json";
  const CommandResult run = RunEstimator(
      With(DenseArgs(scene_),
           {"--image_path", scene_ / "images", "--dry_run", "1",
            "--report_path", from_files}));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json r = ReadJson(from_files);
  for (const Window& w : windows_) {
    const nlohmann::json& view = r.at("views").at(w.image);
    const nlohmann::json& sources = view.at("lens").at("sources");
    EXPECT_EQ(sources.at("focus_distance_m").get<std::string>(),
              w.image + " Exif.CanonFi.FocusDistanceUpper/Lower");
    EXPECT_EQ(sources.at("focal_length_mm").get<std::string>().rfind(
                  "lens.csv", 0),
              0u);  // lens.csv wins over the files
  }
  EXPECT_TRUE(r.at("cues").at("recorded_focus").at("valid").get<bool>());
  EXPECT_LE(r.at("scale_ci_low").get<double>(), true_scale_);
  EXPECT_GE(r.at("scale_ci_high").get<double>(), true_scale_);

  // dp_lens_data lists the same, as a lens.csv.
  const std::string listed = scene_ / "listed.csv";
  const CommandResult list = RunCommand({kDpsfm,
                                         "dp_lens_data",
                                         "--workspace_path",
                                         scene_ / "dense",
                                         "--image_path",
                                         scene_ / "images",
                                         "--lens_path",
                                         scene_ / "lens.csv",
                                         "--output_path",
                                         listed});
  ASSERT_EQ(list.exit_code, 0) << list.err;
  std::ifstream csv(listed);
  std::string text((std::istreambuf_iterator<char>(csv)),
                   std::istreambuf_iterator<char>());
  for (const Window& w : windows_) {
    std::ostringstream window;
    window << w.lower_cm / 100.0 << "-" << w.upper_cm / 100.0 << " m";
    EXPECT_NE(text.find(w.image + ",50,2.8,30," + window.str()),
              std::string::npos)
        << window.str() << " in\n"
        << text;
  }
  EXPECT_NE(text.find("focus_distance_m: DP_0001.jpg "
                      "Exif.CanonFi.FocusDistanceUpper/Lower"),
            std::string::npos)
      << text;
  // Never over an existing file.
  const CommandResult again = RunCommand({kDpsfm,
                                          "dp_lens_data",
                                          "--image_path",
                                          scene_ / "images",
                                          "--output_path",
                                          listed});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.err.find("exists"), std::string::npos) << again.err;

  // The listed lens.csv alone (no images): the same answer.
  const std::string from_csv = scene_ / "from_csv.json";
  const CommandResult typed = RunEstimator(
      {"--workspace_path", scene_ / "dense", "--dp_image_path",
       scene_ / "dp", "--lens_path", listed, "--dry_run", "1",
       "--report_path", from_csv});
  ASSERT_EQ(typed.exit_code, 0) << typed.err;
  const nlohmann::json t = ReadJson(from_csv);
  const double scale = r.at("scale").get<double>();
  EXPECT_NEAR(t.at("scale").get<double>(), scale, 1e-9 * scale);
  EXPECT_NEAR(t.at("scale_ci_low").get<double>(),
              r.at("scale_ci_low").get<double>(), 1e-9 * scale);
  EXPECT_NEAR(t.at("scale_ci_high").get<double>(),
              r.at("scale_ci_high").get<double>(), 1e-9 * scale);
}

// --DPScaleEstimator.use_recorded_focus 0: the files' focus is not used,
// and the log says which was left.
TEST_F(CameraMetadata, UseRecordedFocusOffIgnoresIt) {
  const std::string report = scene_ / "off.json";
  const CommandResult run = RunEstimator(
      With(DenseArgs(scene_),
           {"--image_path", scene_ / "images", "--dry_run", "1",
            "--report_path", report, "--DPScaleEstimator.use_recorded_focus",
            "0"}));
  const nlohmann::json r = ReadJson(report);
  for (const Window& w : windows_) {
    EXPECT_FALSE(r.at("views").at(w.image).at("lens").at("sources").contains(
        "focus_distance_m"));
  }
  EXPECT_NE(run.err.find("use_recorded_focus is off"), std::string::npos)
      << run.err;
}

}  // namespace
}  // namespace test
}  // namespace dpsfm

#pragma GCC diagnostic pop
