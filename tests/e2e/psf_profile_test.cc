// DP PSF profiles end to end: `colmap dp_psf_calibrator` on DP captures of a
// planar target rendered with a known split profile writes a profile file
// that recovers it; `colmap dp_scale_estimator` takes
// --DPScaleEstimator.psf_model translating_disk|calibrated|auto, reports
// what it used, and refuses bad profile options with one error line.
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "dpsfm/colmap/io/psf_profile.h"
#include "dpsfm/core/optics/lens_model.h"
#include "tests/core/synthetic_dp.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

// The binary with the dp-sfm commands: the patched colmap or dpsfm.
const std::string kDpsfm = DPSFM_DP_EXE;
const std::string kScenes = DPSFM_E2E_SCENES_DIR;

int CountErrorLines(const std::string& err, const std::string& expected) {
  int count = 0;
  for (const std::string& line : Lines(err)) {
    if (line.compare(0, 7, "ERROR: ") == 0) {
      ++count;
      EXPECT_NE(line.find(expected), std::string::npos)
          << line << "\nexpected: " << expected;
    }
  }
  return count;
}

// Calibration captures of a textured planar target at measured distances,
// rendered with `psf`: 50 mm f/2.8, DP pitch 10 um, focus 1.0 m.
void WriteCalibrationCaptures(const DPPsfModel& psf,
                              const std::vector<double>& target_distances_m,
                              const std::string& root) {
  fs::create_directories(root + "/dp/left");
  fs::create_directories(root + "/dp/right");
  std::ofstream csv(root + "/targets.csv");
  csv << "name,target_distance_m,focus_distance_m,focal_length_mm,f_number,"
         "pixel_pitch_um\n";
  DPLensData lens;
  lens.focal_length_mm = 50;
  lens.f_number = 2.8;
  lens.pixel_pitch_um = 10;
  // The distances are from the focal-plane mark: the thin lens (u + v =
  // D, 1/u + 1/v = 1/f) focused at 1.0 m from the sensor sits v in front
  // of it, and a target at D from the sensor is D - v from the lens.
  const double f = 50, focus = 1000;
  const double u_g = 0.5 * (focus + std::sqrt(focus * focus - 4 * focus * f));
  const double v = focus - u_g;
  for (size_t k = 0; k < target_distances_m.size(); ++k) {
    const double r = PredictBlurRadiusPx(
        lens, lens.PixelPitchMm(), 1e-3, u_g, 1000 * target_distances_m[k] - v);
    TextureOptions texture;
    texture.channels = 3;
    const cv::Mat sharp =
        MakeTexture(cv::Size(480, 360), 600 + static_cast<int>(k), texture);
    RenderOptions render;
    render.noise_sigma = 0.004;
    render.noise_seed = 700 + k;
    const DPPair pair = RenderDP(sharp, psf, r, render);
    const std::string name = "cal_" + std::to_string(k) + ".png";
    for (const auto& view : {std::make_pair("left", pair.left),
                             std::make_pair("right", pair.right)}) {
      cv::Mat u16;
      view.second.convertTo(u16, CV_16UC3, 65535.0);
      ASSERT_TRUE(cv::imwrite(root + "/dp/" + view.first + "/" + name, u16));
    }
    csv << name << "," << target_distances_m[k] << ",1.0,50,2.8,10\n";
  }
}

CommandResult RunCalibrator(const std::string& root,
                            const std::string& output) {
  return RunCommand({kDpsfm,
                     "dp_psf_calibrator",
                     "--dp_image_path",
                     root + "/dp",
                     "--targets_path",
                     root + "/targets.csv",
                     "--output_path",
                     output,
                     "--DPPsfCalibrator.patch_size",
                     "51",
                     "--DPPsfCalibrator.stride",
                     "30",
                     "--DPPsfCalibrator.max_radius_px",
                     "12",
                     // A simulated camera: its scenes come from the
                     // renderer of its calibration captures.
                     "--DPPsfCalibrator.transfer_uncertainty",
                     "0"});
}

double CentroidOf(double exponent) {
  SplitProfileParams params;
  params.split_exponent = exponent;
  return CentroidOffsetPerRadius(SplitProfilePsf(params), 8);
}

// Distances at +-3..10 px of blur around the 1.0 m focus.
const std::vector<double> kTargets = {0.80, 0.86, 0.92, 1.10, 1.25, 1.45};

TEST(DPPsfCalibrator, RecoversTheProfileOfTheCaptures) {
  TempDir dir;
  SplitProfileParams truth;
  truth.split_exponent = 0.45;
  WriteCalibrationCaptures(SplitProfilePsf(truth), kTargets, dir.path());
  const std::string profile_path = dir / "camera.dpsf";
  const CommandResult result = RunCalibrator(dir.path(), profile_path);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const PsfProfileFile profile = ReadPsfProfile(profile_path);
  ASSERT_EQ(profile.model, "measured_kernels");
  // Each column band's kernels carry the true profile's centroid offset.
  const DPPsfField field = profile.MakeField(profile_path);
  for (const auto& cell : field.cells) {
    const double ratio = CentroidOffsetPerRadius(*cell, 8) / CentroidOf(0.45);
    std::printf("cell centroid offset / truth: %.4f\n", ratio);
    EXPECT_NEAR(ratio, 1.0, 0.02);
  }
  EXPECT_GT(profile.uncertainty, 0);
  EXPECT_LT(profile.uncertainty, 0.05);
}

TEST(DPPsfCalibrator, RefusesCapturesWithoutBlur) {
  TempDir dir;
  WriteCalibrationCaptures(TranslatingDiskPsf(), {1.0, 1.01, 0.99}, dir.path());
  const CommandResult result = RunCalibrator(dir.path(), dir / "p.dpsf");
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_EQ(CountErrorLines(result.err, "shows visible blur"), 1) << result.err;
  EXPECT_FALSE(fs::exists(dir / "p.dpsf"));
}

// Each invalid option is refused in one line naming it and its value,
// before any capture is read.
TEST(DPPsfCalibrator, RefusesInvalidOptions) {
  TempDir dir;
  for (const auto& bad : std::vector<std::pair<std::string, std::string>>{
           {"grid_cols", "0"},
           {"num_bootstrap", "5"},
           {"min_texture_snr", "-1"},
           {"num_threads", "0"}}) {
    const CommandResult result = RunCommand({kDpsfm,
                                             "dp_psf_calibrator",
                                             "--dp_image_path",
                                             dir / "missing",
                                             "--targets_path",
                                             dir / "missing.csv",
                                             "--output_path",
                                             dir / "p.dpsf",
                                             "--DPPsfCalibrator." + bad.first,
                                             bad.second});
    EXPECT_EQ(result.exit_code, 1) << result.err;
    EXPECT_EQ(CountErrorLines(result.err,
                              "invalid --DPPsfCalibrator option: " + bad.first),
              1)
        << result.err;
    EXPECT_NE(result.err.find("(got " + bad.second + ")"), std::string::npos)
        << result.err;
  }
}

std::vector<std::string> DryRun(const std::string& report,
                                const std::vector<std::string>& more) {
  const std::string scene = kScenes + "/dslr";
  std::vector<std::string> args = {kDpsfm,
                                   "dp_scale_estimator",
                                   "--workspace_path",
                                   scene + "/dense",
                                   "--dp_image_path",
                                   scene + "/dp",
                                   "--lens_path",
                                   scene + "/lens.csv",
                                   "--dry_run",
                                   "1",
                                   "--report_path",
                                   report};
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

double TrueScale() {
  std::ifstream file(kScenes + "/dslr/ground_truth.json");
  return nlohmann::json::parse(file)["scale"].get<double>();
}

// The generated scene is made with the translating disk: every mode gets
// its scale within 3 %, and the report says which profile was used.
TEST(DPScaleEstimatorPsf, EveryModeOnTheGeneratedScene) {
  TempDir dir;
  WriteCalibrationCaptures(TranslatingDiskPsf(), kTargets, dir.path());
  const CommandResult calibration =
      RunCalibrator(dir.path(), dir / "disk.dpsf");
  ASSERT_EQ(calibration.exit_code, 0) << calibration.err;
  const double truth = TrueScale();
  const std::vector<std::vector<std::string>> modes = {
      {"--DPScaleEstimator.psf_model", "translating_disk"},
      {"--DPScaleEstimator.psf_model", "auto"},
      {"--DPScaleEstimator.psf_model",
       "calibrated",
       "--DPScaleEstimator.psf_path",
       dir / "disk.dpsf"}};
  for (const auto& mode : modes) {
    const std::string report = dir / ("report_" + mode[1] + ".json");
    const CommandResult run = RunCommand(DryRun(report, mode));
    ASSERT_EQ(run.exit_code, 0) << mode[1] << "\n" << run.err;
    std::ifstream file(report);
    const nlohmann::json json = nlohmann::json::parse(file);
    const double scale = json["scale"].get<double>();
    std::printf("%s: r_s %.4f (%s)\n",
                mode[1].c_str(),
                scale / truth,
                json["psf"]["status"].get<std::string>().c_str());
    EXPECT_NEAR(scale / truth, 1.0, 0.03) << mode[1];
    const std::string model = json["psf"]["model"].get<std::string>();
    if (mode[1] == "calibrated") {
      EXPECT_NE(model.find("measured_kernels"), std::string::npos) << model;
    } else {
      EXPECT_NE(model.find("translating_disk"), std::string::npos) << model;
    }
    // auto fits the profile, translating_disk is checked against the data
    // (here they agree), a calibrated profile is taken as it is.
    const std::string status = json["psf"]["status"].get<std::string>();
    EXPECT_EQ(status.empty(), mode[1] == "calibrated") << status;
    if (mode[1] == "translating_disk") {
      EXPECT_NE(status.find("agree with the translating disk"),
                std::string::npos)
          << status;
    }
  }
}

TEST(DPScaleEstimatorPsf, RefusesBadProfileOptions) {
  TempDir dir;
  {
    std::ofstream bad(dir / "bad.dpsf");
    bad << "format 1\nmodel split_profile\nsplit_exponent banana\n";
  }
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--DPScaleEstimator.psf_model", "gaussian"}, "unknown"},
      {{"--DPScaleEstimator.psf_model", "calibrated"}, "needs"},
      {{"--DPScaleEstimator.psf_model",
        "auto",
        "--DPScaleEstimator.psf_path",
        dir / "bad.dpsf"},
       "only used with"},
      {{"--DPScaleEstimator.psf_model",
        "calibrated",
        "--DPScaleEstimator.psf_path",
        dir / "bad.dpsf"},
       "bad.dpsf:3"},
      {{"--DPScaleEstimator.psf_model",
        "calibrated",
        "--DPScaleEstimator.psf_path",
        dir / "missing.dpsf"},
       "cannot read"}};
  for (const auto& c : cases) {
    const CommandResult run = RunCommand(DryRun(dir / "r.json", c.first));
    EXPECT_EQ(run.exit_code, 1) << c.second << "\n" << run.err;
    EXPECT_EQ(CountErrorLines(run.err, c.second), 1) << run.err;
  }
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
