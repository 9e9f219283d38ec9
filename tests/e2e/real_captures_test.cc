// The real DP captures of ../shared/realdp (Canon EOS R6 Mark II + RF 50 mm
// at f/4, measured depth), read in place, every command with its default
// geometry as a new user would run it: calibration of the camera's DP
// profile from the flat planes with the focus unknown, then the scale of a
// real scene through the real `colmap` binary, checked against the measured
// depth (the workspace's depth is it divided by a known factor).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/e2e/e2e_helpers.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

constexpr double kTrueScale = 0.37;
// The RF 50 mm's entrance pupil at ~1 m focus, in mm in front of the
// focal-plane mark (its prescription traced paraxially): scene depths are
// measured from it, so a profile for scenes takes the planes' distances
// from it (as make real and the user guide's first hour do).
const std::vector<std::string> kEntrancePupil = {
    "--DPPsfCalibrator.entrance_pupil_mm", "39.9"};

// The Canon R6 II captures (e2e_helpers.h, RealDpDir), or "".
std::string RealDir() {
  const std::string dir = RealDpDir();
  return dir.empty() ? dir : dir + "/canon_r6m2_rf50";
}

class RealCaptures : public ::testing::Test {
 protected:
  void SetUp() override {
    real_ = RealDir();
    ASSERT_FALSE(real_.empty())
        << "the real DP captures (../shared/realdp) are missing; set "
           "DPSFM_REALDP_DIR to the folder holding canon_r6m2_rf50/";
  }

  // A calibration folder with the flat planes; `rows` of targets.csv.
  std::string Calibration(const std::vector<std::string>& captures,
                          const std::string& focus) {
    const std::string dir = dir_ / "calibration";
    fs::create_directories(dir + "/dp/left");
    fs::create_directories(dir + "/dp/right");
    std::ofstream targets(dir + "/targets.csv");
    targets << "name,target_distance_m,focus_distance_m,focal_length_mm,"
               "f_number,pixel_pitch_um\n";
    for (const std::string& c : captures) {  // e.g. "0600/f4"
      const std::string name = c.substr(0, 4) + "_" + c.substr(5) + ".png";
      const fs::path from = fs::path(real_) / "flat/001" / c;
      fs::copy_file(from / "l.png",
                    dir + "/dp/left/" + name,
                    fs::copy_options::overwrite_existing);
      fs::copy_file(from / "r.png",
                    dir + "/dp/right/" + name,
                    fs::copy_options::overwrite_existing);
      targets << name << "," << std::stod(c.substr(0, 4)) / 1000 << "," << focus
              << ",49.57," << c.substr(6) << ",46.875\n";
    }
    return dir;
  }

  CommandResult Calibrate(const std::string& dir,
                          const std::string& out,
                          const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args = {kDpsfm,
                                     "dp_psf_calibrator",
                                     "--dp_image_path",
                                     dir + "/dp",
                                     "--targets_path",
                                     dir + "/targets.csv",
                                     "--output_path",
                                     out,
                                     "--DPPsfCalibrator.camera",
                                     "Canon / Canon EOS R6m2",
                                     "--DPPsfCalibrator.lens",
                                     "RF50mm F1.8 STM"};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunCommand(args);
  }

  std::string Workspace(const std::string& scene) {
    const std::string out = dir_ / scene;
    const CommandResult made = RunCommand({DPSFM_MAKE_REALDP_EXE,
                                           "--capture_path",
                                           real_ + "/" + scene,
                                           "--output_path",
                                           out,
                                           "--name",
                                           "view",
                                           "--true_scale",
                                           std::to_string(kTrueScale)});
    EXPECT_EQ(made.exit_code, 0) << made.err;
    return out;
  }

  CommandResult Estimate(const std::string& workspace,
                         const std::string& report,
                         std::vector<std::string> extra) {
    std::vector<std::string> args = {"--workspace_path",
                                     workspace + "/dense",
                                     "--dp_image_path",
                                     workspace + "/dp",
                                     "--lens_path",
                                     workspace + "/lens.csv",
                                     "--dry_run",
                                     "1",
                                     "--report_path",
                                     report};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunEstimator(args);
  }

  std::string real_;
  TempDir dir_;
};

// Two planes at f/4 and their f/20 references, focus unknown: the
// calibration fits a focus near the recorded 1 m, a split far weaker than
// the translating disk's 0.295 R, and writes a measured-kernel profile in
// linear light whose uncertainty owns how far it transfers to scenes. With
// it, the box scenes alone never answer with an interval that misses the
// truth, and with the recorded focus both cues answer together.
TEST_F(RealCaptures, CalibrateFromFlatPlanesThenEstimate) {
  const std::string dir =
      Calibration({"0600/f4", "1500/f4", "0600/f20", "1500/f20"}, "");
  fs::create_directories(dir_ / "library");
  const std::string profile = dir_ / "library/r6m2.dpsf";
  const CommandResult calibrated = Calibrate(dir, profile, kEntrancePupil);
  ASSERT_EQ(calibrated.exit_code, 0) << calibrated.err;
  const std::string text = ReadTextFile(profile);
  EXPECT_NE(text.find("model measured_kernels"), std::string::npos) << text;
  EXPECT_NE(text.find("\nlight linear"), std::string::npos) << text;
  // The stated uncertainty: the planes' own ~4 % and the 24 % transfer term
  // in quadrature.
  const size_t u = text.find("\nuncertainty ");
  ASSERT_NE(u, std::string::npos) << text;
  const double uncertainty = std::stod(text.substr(u + 13));
  EXPECT_GT(uncertainty, 0.24);
  EXPECT_LT(uncertainty, 0.27);
  EXPECT_NE(text.find("fit_uncertainty_terms "), std::string::npos) << text;
  EXPECT_TRUE(fs::exists(dir_ / "library/r6m2_left.npy"));
  // The fitted focus (from the focal-plane mark) and the strength.
  const size_t at = text.find("fit_focus_distance ");
  ASSERT_NE(at, std::string::npos);
  const double focus = std::stod(text.substr(at + 19));
  EXPECT_GT(focus, 0.85);
  EXPECT_LT(focus, 1.10);
  const size_t cells = text.find("fit_cell_centroid_offsets ");
  ASSERT_NE(cells, std::string::npos);
  std::istringstream offsets(text.substr(cells + 26));
  for (int c = 0; c < 3; ++c) {
    double kappa = 0;
    offsets >> kappa;
    EXPECT_GT(kappa, 0.03) << c;
    EXPECT_LT(kappa, 0.15) << c;  // the translating disk: 0.295
  }
  // The shape, measured against the f/20 references by deconvolution: its
  // strength is a second, independent measurement of the blur readings'.
  EXPECT_NE(text.find("fit_shape measured by deconvolution"), std::string::npos)
      << text;
  const std::string kShapeLine =
      "Measured shape: the deconvolved kernels' DP strength ";
  const size_t shape = calibrated.err.find(kShapeLine);
  ASSERT_NE(shape, std::string::npos) << calibrated.err;
  std::istringstream strengths(
      calibrated.err.substr(shape + kShapeLine.size()));
  double from_kernels = 0, from_readings = 0;
  std::string against;
  strengths >> from_kernels >> against >> from_readings;
  EXPECT_EQ(against, "against");
  std::printf("DP strength: kernels %.4f, blur readings %.4f\n",
              from_kernels,
              from_readings);
  EXPECT_NEAR(from_kernels / from_readings, 1.0, 0.1);

  // The DP data alone (no recorded focus in lens.csv): the two box scenes
  // with the calibrated profile. Every answer holds the truth; a refusal
  // must name the profile's uncertainty (with the transfer term a single
  // real view's interval is about 50 % wide: both refuse today).
  std::string box;
  int answered = 0;
  for (const std::string scene : {"box/001", "box/002"}) {
    const std::string workspace = Workspace(scene);
    if (box.empty()) box = workspace;
    const std::string report = dir_ / (scene.substr(4) + ".json");
    const CommandResult run = Estimate(workspace,
                                       report,
                                       {"--DPScaleEstimator.psf_model",
                                        "calibrated",
                                        "--DPScaleEstimator.psf_path",
                                        profile});
    if (run.exit_code != 0) {
      std::printf("%s calibrated: refused\n", scene.c_str());
      EXPECT_NE(run.err.find("uncertainty"), std::string::npos) << run.err;
      continue;
    }
    ++answered;
    const nlohmann::json r = ReadJson(report);
    const double ratio = r.at("scale").get<double>() / kTrueScale;
    std::printf("%s calibrated: r_s %.3f in [%.3f, %.3f]\n",
                scene.c_str(),
                ratio,
                r.at("scale_ci_low").get<double>() / kTrueScale,
                r.at("scale_ci_high").get<double>() / kTrueScale);
    EXPECT_NEAR(ratio, 1.0, 0.15) << scene;
    EXPECT_LE(r.at("scale_ci_low").get<double>(), kTrueScale) << scene;
    EXPECT_GE(r.at("scale_ci_high").get<double>(), kTrueScale) << scene;
    EXPECT_NE(r.at("psf").at("model").get<std::string>().find("measured"),
              std::string::npos);
  }
  std::printf("calibrated alone: %d of 2 answered\n", answered);

  // The same profile from the library, picked by the camera and lens of
  // lens.csv with the defaults; the recorded focus ("1 m") is checked
  // against the estimate.
  {
    std::ofstream lens(box + "/lens.csv");
    lens << "name,focal_length_mm,f_number,pixel_pitch_um,focus_distance_m,"
            "camera,lens\n"
         << "view.png,49.57,4,46.875,1.0,Canon / Canon EOS R6m2,"
            "rf50mm f1.8 stm\n";
  }
  const std::string library_report = dir_ / "library.json";
  const CommandResult from_library =
      Estimate(box,
               library_report,
               {"--DPScaleEstimator.psf_library", dir_ / "library"});
  ASSERT_EQ(from_library.exit_code, 0) << from_library.err;
  const nlohmann::json l = ReadJson(library_report);
  EXPECT_EQ(l.at("psf").at("source").get<std::string>().rfind("library", 0), 0u)
      << l.at("psf").at("source");
  // The same answer as with the profile given by path.
  const std::string by_path_report = dir_ / "by_path.json";
  ASSERT_EQ(Estimate(box,
                     by_path_report,
                     {"--DPScaleEstimator.psf_model",
                      "calibrated",
                      "--DPScaleEstimator.psf_path",
                      profile})
                .exit_code,
            0);
  EXPECT_DOUBLE_EQ(l.at("scale").get<double>(),
                   ReadJson(by_path_report).at("scale").get<double>());
  // The answer comes from both cues, and holds the truth.
  EXPECT_EQ(l.at("scale_source").get<std::string>(),
            "dual_pixel+recorded_focus");
  EXPECT_EQ(l.at("cues").at("agreement").get<std::string>(), "agree");
  EXPECT_LE(l.at("scale_ci_low").get<double>(), kTrueScale);
  EXPECT_GE(l.at("scale_ci_high").get<double>(), kTrueScale);
  ASSERT_TRUE(l.contains("focus_check")) << l.dump(2);
  const double focus_ratio =
      l.at("focus_check").at("scale_from_recorded_focus").get<double>() /
      kTrueScale;
  std::printf("box/001: recorded 1 m focus gives r_s %.3f (%s)\n",
              focus_ratio,
              l.at("focus_check").at("status").get<std::string>().c_str());
  EXPECT_NEAR(focus_ratio, 1.0, 0.3);
}

// With nothing calibrated the defaults must not answer confidently wrong:
// either refuse or give an interval that holds the truth.
TEST_F(RealCaptures, DefaultsNeverMissTheTruth) {
  for (const std::string scene : {"box/001", "casual/orbbec/001"}) {
    const std::string ws = Workspace(scene);
    const std::string report = dir_ / "defaults.json";
    const CommandResult run = Estimate(ws, report, {});
    if (run.exit_code != 0) {
      EXPECT_NE(run.err.find("no scale"), std::string::npos) << run.err;
      continue;
    }
    const nlohmann::json r = ReadJson(report);
    EXPECT_LE(r.at("scale_ci_low").get<double>(), kTrueScale) << scene;
    EXPECT_GE(r.at("scale_ci_high").get<double>(), kTrueScale) << scene;
  }
}

// Nothing calibrated, but the focus recorded (the nominal "1 m", from the
// focal-plane mark, as lens.csv's focus_distance_m). box/002's DP profile
// is unknown (the fit says so), so the recorded focus is the only cue: at
// the default 15 % a camera's record is worth, its interval is just over
// the limit and the run refuses, naming the cue; a distance measured to 5 %
// pins the scale with an interval that holds the truth; with the cue off
// the same run refuses as the profile leaves it.
TEST_F(RealCaptures, RecordedFocusPinsTheScaleWhenTheProfileIsUnknown) {
  const std::string ws = Workspace("box/002");
  {
    std::ofstream lens(ws + "/lens.csv");
    lens << "name,focal_length_mm,f_number,pixel_pitch_um,focus_distance_m\n"
         << "view.png,49.57,4,46.875,1.0\n";
  }
  const CommandResult defaults = Estimate(ws, dir_ / "defaults.json", {});
  if (defaults.exit_code == 0) {
    const nlohmann::json r = ReadJson(dir_ / "defaults.json");
    EXPECT_LE(r.at("scale_ci_low").get<double>(), kTrueScale);
    EXPECT_GE(r.at("scale_ci_high").get<double>(), kTrueScale);
  } else {
    EXPECT_NE(defaults.err.find("with the recorded focus"), std::string::npos)
        << defaults.err;
  }
  const std::string report = dir_ / "pinned.json";
  const CommandResult run = Estimate(
      ws, report, {"--DPScaleEstimator.recorded_focus_tolerance", "0.05"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json r = ReadJson(report);
  std::printf(
      "box/002 defaults, focus measured to 5 %%: r_s %.3f in [%.3f, "
      "%.3f]\n",
      r.at("scale").get<double>() / kTrueScale,
      r.at("scale_ci_low").get<double>() / kTrueScale,
      r.at("scale_ci_high").get<double>() / kTrueScale);
  EXPECT_EQ(r.at("scale_source").get<std::string>(), "recorded_focus");
  EXPECT_LE(r.at("scale_ci_low").get<double>(), kTrueScale);
  EXPECT_GE(r.at("scale_ci_high").get<double>(), kTrueScale);
  EXPECT_GT(r.at("pinned_profile_strength").get<double>(), 0);
  EXPECT_NE(run.err.find("recorded focus alone"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("from the recorded focus)"), std::string::npos)
      << run.err;  // the final line names the source

  const CommandResult off = Estimate(
      ws, dir_ / "off.json", {"--DPScaleEstimator.pin_to_recorded_focus", "0"});
  EXPECT_NE(off.exit_code, 0);
  EXPECT_NE(off.err.find("DP profile is unknown"), std::string::npos)
      << off.err;
}

// The same captures as 8-bit sRGB files and as 16-bit linear light (their
// inverse sRGB, as DPRSplit would give): the frames reach the blur search
// in the same linear light, so the answers agree, and the report says how
// each was read.
TEST_F(RealCaptures, BothEncodingsGiveTheSameAnswer) {
  const std::string srgb = Workspace("box/002");
  const std::string linear = dir_ / "box_002_linear16";
  const CommandResult made = RunCommand({DPSFM_MAKE_REALDP_EXE,
                                         "--capture_path",
                                         real_ + "/box/002",
                                         "--output_path",
                                         linear,
                                         "--name",
                                         "view",
                                         "--true_scale",
                                         std::to_string(kTrueScale),
                                         "--recorded_focus_m",
                                         "1.0",
                                         "--linear16",
                                         "1"});
  ASSERT_EQ(made.exit_code, 0) << made.err;
  {
    std::ofstream lens(srgb + "/lens.csv");
    lens << "name,focal_length_mm,f_number,pixel_pitch_um,focus_distance_m\n"
         << "view.png,49.57,4,46.875,1.0\n";
  }
  const std::vector<std::string> args = {
      "--DPScaleEstimator.recorded_focus_tolerance", "0.05"};
  ASSERT_EQ(Estimate(srgb, dir_ / "srgb.json", args).exit_code, 0);
  ASSERT_EQ(Estimate(linear, dir_ / "linear.json", args).exit_code, 0);
  const nlohmann::json a = ReadJson(dir_ / "srgb.json");
  const nlohmann::json b = ReadJson(dir_ / "linear.json");
  const nlohmann::json fa = a.at("views").at("view.png").at("frames");
  const nlohmann::json fb = b.at("views").at("view.png").at("frames");
  EXPECT_EQ(fa.at("encoding"), "srgb");
  EXPECT_EQ(fa.at("bits"), 8);
  EXPECT_EQ(fb.at("encoding"), "linear");
  EXPECT_EQ(fb.at("bits"), 16);
  const double sa = a.at("scale").get<double>(),
               sb = b.at("scale").get<double>();
  std::printf("box/002: 8-bit sRGB %.4f, 16-bit linear %.4f\n", sa, sb);
  EXPECT_NEAR(sa / sb, 1.0, 0.01);
  EXPECT_LE(b.at("scale_ci_low").get<double>(), sa);
  EXPECT_GE(b.at("scale_ci_high").get<double>(), sa);
  // Told the 16-bit frames are sRGB, the run reads them so, and the report
  // records the override (answer or refusal alike).
  Estimate(
      linear, dir_ / "told.json", {"--DPScaleEstimator.dp_encoding", "srgb"});
  const nlohmann::json told =
      ReadJson(dir_ / "told.json").at("views").at("view.png").at("frames");
  EXPECT_EQ(told.at("encoding"), "srgb");
  EXPECT_EQ(told.at("decided_by"), "--DPScaleEstimator.dp_encoding");
}

// All seven scenes, in every mode a user has: the defaults and the
// calibrated profile, each without and with the recorded "1 m" focus. No
// answer may be confidently wrong (more than 10 % off with an interval
// that misses the truth). With the calibrator's transfer term set to 0 (the
// planes' own 4 % uncertainty) this fails on three scenes (0.80-0.86 with
// intervals ending below 0.97); docs/psf-profiles.md, "Transfer".
TEST_F(RealCaptures, NoConfidentlyWrongAnswerOnAnyScene) {
  const std::string dir =
      Calibration({"0600/f4", "1500/f4", "0600/f20", "1500/f20"}, "");
  const std::string profile = dir_ / "r6m2.dpsf";
  ASSERT_EQ(Calibrate(dir, profile, kEntrancePupil).exit_code, 0);
  // Every profile a user may choose: the defaults, the calibrated profile,
  // and the paper's translating disk (unchecked, it read these scenes
  // 2.2-2.8x off with intervals a few per cent wide).
  const std::vector<std::pair<std::string, std::vector<std::string>>> profiles =
      {{"defaults", {}},
       {"calibrated",
        {"--DPScaleEstimator.psf_model",
         "calibrated",
         "--DPScaleEstimator.psf_path",
         profile}},
       {"translating_disk",
        {"--DPScaleEstimator.psf_model", "translating_disk"}}};
  int answered = 0, runs = 0;
  for (const std::string scene : {"casual/orbbec/001",
                                  "casual/orbbec/002",
                                  "casual/orbbec/003",
                                  "casual/iphone/001",
                                  "casual/iphone/002",
                                  "box/001",
                                  "box/002"}) {
    const std::string ws = Workspace(scene);
    for (const bool focus : {false, true}) {
      for (const auto& [name, args] : profiles) {
        {
          std::ofstream lens(ws + "/lens.csv");
          lens << "name,focal_length_mm,f_number,pixel_pitch_um"
               << (focus ? ",focus_distance_m" : "") << "\n"
               << "view.png,49.57,4,46.875" << (focus ? ",1.0" : "") << "\n";
        }
        const std::string report = dir_ / "mode.json";
        fs::remove(report);
        const CommandResult run = Estimate(ws, report, args);
        ++runs;
        const std::string mode = name + (focus ? " + focus" : "");
        if (run.exit_code != 0) {
          EXPECT_NE(run.err.find("no scale"), std::string::npos) << run.err;
          std::printf("%s, %s: refused\n", scene.c_str(), mode.c_str());
          continue;
        }
        ++answered;
        const nlohmann::json r = ReadJson(report);
        const double rs = r.at("scale").get<double>() / kTrueScale;
        const double lo = r.at("scale_ci_low").get<double>() / kTrueScale;
        const double hi = r.at("scale_ci_high").get<double>() / kTrueScale;
        std::printf("%s, %s: r_s %.3f in [%.3f, %.3f]\n",
                    scene.c_str(),
                    mode.c_str(),
                    rs,
                    lo,
                    hi);
        EXPECT_TRUE(std::abs(rs - 1) <= 0.10 || (lo <= 1 && hi >= 1))
            << scene << ", " << mode << ": confidently wrong";
      }
    }
  }
  std::printf("%d of %d runs answered\n", answered, runs);
}

// Advice that, followed, does not make the answer worse. A run whose
// patches lie beyond the search bound says what to do: a larger bound
// while the profile can describe the blur there, a calibration with more
// blur once the bound is twice what the profile's calibration covered
// (beyond it the kernels are magnified guesses: on box/002 a 16 px bound
// read the near boxes' ~7 px of blur as 12 px and moved the DP cue a third
// low). Each option a run advises is followed, and the answer must still
// hold the truth where it did, and the DP cue must not move by more than
// its own half-width.
TEST_F(RealCaptures, SearchBoundAdviceDoesNotMakeTheAnswerWorse) {
  const std::string dir =
      Calibration({"0600/f4", "1500/f4", "0600/f20", "1500/f20"}, "");
  const std::string profile = dir_ / "r6m2.dpsf";
  ASSERT_EQ(Calibrate(dir, profile, kEntrancePupil).exit_code, 0);
  const std::vector<std::string> calibrated = {"--DPScaleEstimator.psf_model",
                                               "calibrated",
                                               "--DPScaleEstimator.psf_path",
                                               profile};
  int advised = 0;
  for (const std::string scene :
       {"box/002", "casual/orbbec/001", "casual/iphone/001"}) {
    const std::string ws = Workspace(scene);
    {
      std::ofstream lens(ws + "/lens.csv");
      lens << "name,focal_length_mm,f_number,pixel_pitch_um,focus_distance_m\n"
           << "view.png,49.57,4,46.875,1.0\n";
    }
    const std::string report = dir_ / "advice_base.json";
    const CommandResult base = Estimate(ws, report, calibrated);
    const nlohmann::json b = ReadJson(report);
    const std::string option = "--DPScaleEstimator.max_radius_px ";
    const size_t at = base.err.find(option);
    // The bound the run ended with is twice the profile's covered blur:
    // it must never be advised to search farther.
    const nlohmann::json& bound = b.at("search_bound");
    const double covered = bound.at("profile_covered_px").get<double>();
    if (bound.at("px").get<double>() >= 2 * covered - 0.5) {
      EXPECT_EQ(at, std::string::npos) << scene << ": " << base.err;
      if (bound.at("patches_beyond_bound").get<int>() >=
          0.05 * bound.at("patches_searched").get<int>()) {
        EXPECT_NE(base.err.find("calibrat"), std::string::npos) << base.err;
      }
    }
    if (at == std::string::npos) continue;
    ++advised;
    const std::string value =
        base.err.substr(at + option.size(),
                        base.err.find_first_not_of("0123456789.",
                                                   at + option.size()) -
                            at - option.size());
    std::vector<std::string> args = calibrated;
    args.insert(args.end(), {"--DPScaleEstimator.max_radius_px", value});
    const std::string followed_report = dir_ / "advice_followed.json";
    Estimate(ws, followed_report, args);
    const nlohmann::json f = ReadJson(followed_report);
    const nlohmann::json& dp = b.at("cues").at("dual_pixel");
    const nlohmann::json& dp_f = f.at("cues").at("dual_pixel");
    if (dp.value("valid", false) && dp_f.value("valid", false)) {
      const double half =
          0.5 * (dp.at("ci")[1].get<double>() - dp.at("ci")[0].get<double>());
      EXPECT_LE(std::abs(dp_f.at("scale").get<double>() -
                         dp.at("scale").get<double>()),
                half)
          << scene << " with " << option << value;
    }
    if (b.at("success").get<bool>() && f.at("success").get<bool>() &&
        b.at("scale_ci_low").get<double>() <= kTrueScale &&
        b.at("scale_ci_high").get<double>() >= kTrueScale) {
      EXPECT_LE(f.at("scale_ci_low").get<double>(), kTrueScale) << scene;
      EXPECT_GE(f.at("scale_ci_high").get<double>(), kTrueScale) << scene;
    }
  }
  std::printf("runs that advised a larger bound: %d\n", advised);
}

// The planes' distances are from the focal-plane mark; scene depths are
// from the entrance pupil, which the RF 50 mm puts ~40 mm in front of the
// mark at ~1 m (its patent prescription, traced paraxially, whole-group
// focus) where the thin lens puts the lens 52.5 mm in front. Given the
// pupil, both planes lie 12.6 mm farther from the depths' origin; the
// inverse-depth span of 0.6 and 1.5 m shrinks by 3.2 %, so the same blur
// readings give a strength about that much larger. The profile records
// the origin; a pupil given in the wrong unit is refused.
TEST_F(RealCaptures, EntrancePupilMovesTheStrengthAsTheGeometrySays) {
  const std::string dir =
      Calibration({"0600/f4", "1500/f4", "0600/f20", "1500/f20"}, "");
  const std::string thin = dir_ / "thin.dpsf", pupil = dir_ / "pupil.dpsf";
  ASSERT_EQ(Calibrate(dir, thin).exit_code, 0);
  const CommandResult given =
      Calibrate(dir, pupil, {"--DPPsfCalibrator.entrance_pupil_mm", "39.9"});
  ASSERT_EQ(given.exit_code, 0) << given.err;
  auto strength = [](const std::string& path) {
    const std::string text = ReadTextFile(path);
    const size_t at = text.find("; strength ");
    EXPECT_NE(at, std::string::npos) << path;
    return at == std::string::npos ? 0.0 : std::stod(text.substr(at + 11));
  };
  const double ratio = strength(pupil) / strength(thin);
  std::printf("strength with the pupil / thin lens: %.4f\n", ratio);
  EXPECT_GT(ratio, 1.01);
  EXPECT_LT(ratio, 1.07);
  EXPECT_NE(
      ReadTextFile(pupil).find("fit_distance_origin entrance pupil, 39.9 mm"),
      std::string::npos);
  const CommandResult metres = Calibrate(
      dir, dir_ / "bad.dpsf", {"--DPPsfCalibrator.entrance_pupil_mm", "600"});
  EXPECT_NE(metres.exit_code, 0);
  EXPECT_NE(metres.err.find("entrance_pupil_mm"), std::string::npos)
      << metres.err;
}

// One f/4 plane with the focus unknown does not determine the profile: the
// calibrator says so instead of writing one.
TEST_F(RealCaptures, OnePlaneWithUnknownFocusIsRefused) {
  const std::string dir = Calibration({"0600/f4", "0600/f20"}, "");
  const std::string profile = dir_ / "one.dpsf";
  const CommandResult run = Calibrate(dir, profile);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("two or more"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(profile));
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
