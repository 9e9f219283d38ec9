// The user guide's first-hour walkthrough, run exactly as written: the
// shell block after "<!-- first-hour walkthrough -->" in docs/user-guide.md,
// with the build's programs on PATH, HOME in a temporary folder and
// DPSFM_REALDP_DIR at the real captures, as the guide tells a user to set
// them. What the guide promises of it is checked: the calibrator's verdict,
// the answer's last line, an interval that holds the true 0.37, and the
// figures the guide prints (GuideFigures), so that they cannot go stale.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/e2e/e2e_helpers.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

constexpr char kMarker[] = "<!-- first-hour walkthrough -->";

// The block's lines, or "" when the marker or the block is missing.
std::string WalkthroughBlock() {
  std::ifstream guide(std::string(DPSFM_SOURCE_DIR) + "/docs/user-guide.md");
  std::string line, block;
  bool marked = false, inside = false;
  while (std::getline(guide, line)) {
    if (!marked) {
      marked = line == kMarker;
      continue;
    }
    if (!inside) {
      if (line != "```sh") return "";
      inside = true;
      continue;
    }
    if (line == "```") return block;
    block += line + "\n";
  }
  return "";
}

// The figures the guide prints for the walkthrough's answer: the scale, its
// interval and the DP cue's ratio to the truth, and the precision each is
// printed to.
struct GuideFigures {
  double scale = 0, low = 0, high = 0, dp_cue_ratio = 0;
  double scale_digit = 0, interval_digit = 0, ratio_digit = 0;
  bool found = false;
};

// The unit of the last printed digit of `number` ("0.3696": 1e-4).
double LastDigit(const std::string& number) {
  const size_t dot = number.find('.');
  return dot == std::string::npos
             ? 1.0
             : std::pow(10.0, -static_cast<int>(number.size() - dot - 1));
}

GuideFigures ReadGuideFigures() {
  std::ifstream file(std::string(DPSFM_SOURCE_DIR) + "/docs/user-guide.md");
  std::stringstream text;
  text << file.rdbuf();
  // Line breaks and indentation as single blanks.
  const std::string guide =
      std::regex_replace(text.str(), std::regex("\\s+"), " ");
  GuideFigures f;
  std::smatch m;
  if (!std::regex_search(guide, m,
                         std::regex("Here: `Scale ([0-9.]+) \\.\\.\\. \\(95 % "
                                    "interval \\[([0-9.]+), ([0-9.]+)\\]"))) {
    return f;
  }
  f.scale = std::stod(m[1]);
  f.low = std::stod(m[2]);
  f.high = std::stod(m[3]);
  f.scale_digit = LastDigit(m[1]);
  f.interval_digit = LastDigit(m[2]);
  if (!std::regex_search(guide, m,
                         std::regex("the DP cue alone, ([0-9.]+) of the "
                                    "truth"))) {
    return f;
  }
  f.dp_cue_ratio = std::stod(m[1]);
  f.ratio_digit = LastDigit(m[1]);
  f.found = true;
  return f;
}

// The guide's figures against the run's report: each within half its last
// printed digit plus a tenth of the interval's half-width, the move a
// change may make to an answer (a larger move means the guide needs the
// new figures).
void ExpectTheGuidesFigures(const nlohmann::json& report) {
  const GuideFigures guide = ReadGuideFigures();
  ASSERT_TRUE(guide.found)
      << "docs/user-guide.md no longer prints the walkthrough's answer as "
         "\"Here: `Scale <s> ... (95 % interval [<low>, <high>]\" and \"the "
         "DP cue alone, <r> of the truth\"";
  const double scale = report.at("scale").get<double>();
  const double low = report.at("scale_ci_low").get<double>();
  const double high = report.at("scale_ci_high").get<double>();
  const double allowed = 0.1 * 0.5 * (high - low);
  EXPECT_NEAR(guide.scale, scale, 0.5 * guide.scale_digit + allowed);
  EXPECT_NEAR(guide.low, low, 0.5 * guide.interval_digit + allowed);
  EXPECT_NEAR(guide.high, high, 0.5 * guide.interval_digit + allowed);
  const nlohmann::json& dp = report.at("cues").at("dual_pixel");
  const double dp_scale = dp.at("scale").get<double>();
  const double dp_allowed =
      0.1 * 0.5 * (dp.at("ci")[1].get<double>() - dp.at("ci")[0].get<double>());
  EXPECT_NEAR(guide.dp_cue_ratio, dp_scale / 0.37,
              0.5 * guide.ratio_digit + dp_allowed / 0.37);
}

// Runs `block` with the programs in `bin` first on PATH and checks what the
// guide promises of it. `dir` holds bin/ and home/.
void RunWalkthrough(const std::string& block,
                    const TempDir& dir,
                    const std::string& real) {
  const std::string home = dir / "home";
  const std::string bin = dir / "bin";
  fs::create_directories(home);
  fs::create_symlink(DPSFM_MAKE_REALDP_EXE,
                     bin + "/dpsfm_make_realdp_workspace");
  const std::string script = dir / "walkthrough.sh";
  WriteTextFile(script, "set -euo pipefail\n" + block);
  const char* path = std::getenv("PATH");
  const CommandResult run =
      RunCommand({"env",
                  "HOME=" + home,
                  "PATH=" + bin + ":" + (path ? path : "/usr/bin:/bin"),
                  "DPSFM_REALDP_DIR=" + real,
                  // A colour terminal's TERM, with the log in a pipe.
                  "TERM=xterm-256color",
                  "bash",
                  script});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;

  EXPECT_NE(run.err.find("Verdict: DP strength"), std::string::npos) << run.err;
  // The last line is the answer, with its interval and source.
  const std::vector<std::string> lines = Lines(run.err);
  ASSERT_FALSE(lines.empty());
  const std::string& last = lines.back();
  EXPECT_NE(last.find("Scale "), std::string::npos) << last;
  EXPECT_NE(last.find("95 % interval ["), std::string::npos) << last;
  EXPECT_NE(last.find("the model is now in metres"), std::string::npos) << last;
  EXPECT_NE(run.err.find("8-bit DP frames"), std::string::npos);

  const std::string work = home + "/dp-first-hour";
  const nlohmann::json report = ReadJson(work + "/box002/report.json");
  ASSERT_TRUE(report.at("success").get<bool>());
  const double low = report.at("scale_ci_low").get<double>();
  const double high = report.at("scale_ci_high").get<double>();
  EXPECT_LE(low, 0.37) << report.at("scale");
  EXPECT_GE(high, 0.37) << report.at("scale");
  ExpectTheGuidesFigures(report);
  // The log is not a terminal: no colour codes in it.
  EXPECT_EQ(run.err.find("\x1b["), std::string::npos) << run.err;
  // The search bound is the view's own, and shown: first 4.78 px (the
  // blur the profile's kernels were measured at), grown to twice that.
  const nlohmann::json& bound = report.at("search_bound");
  EXPECT_GT(bound.at("px").get<double>(),
            bound.at("initial_px").get<double>())
      << bound;
  EXPECT_NE(run.err.find("Blur-search bound grown from 4.7"),
            std::string::npos)
      << run.err;
  const bool warned =
      run.err.find("beyond the blur-search bound") != std::string::npos;
  EXPECT_EQ(warned, bound.at("limits_answer").get<bool>()) << bound;
  if (warned) {
    // At twice the blur the profile covered, the advice is a calibration
    // with more blur, never a larger bound (its kernels would be guesses).
    EXPECT_NE(run.err.find("a calibration capture farther from the focus"),
              std::string::npos)
        << run.err;
    EXPECT_EQ(run.err.find("--DPScaleEstimator.max_radius_px"),
              std::string::npos)
        << run.err;
  }
  // Stages that did not run are null, never 0.
  const nlohmann::json& intensity = report.at("intensity");
  if (!intensity.at("ran").get<bool>()) {
    EXPECT_TRUE(intensity.at("scale").is_null()) << intensity;
    EXPECT_TRUE(intensity.at("ci").is_null()) << intensity;
  }
  EXPECT_TRUE(report.at("psf").at("fit").is_null()) << report.at("psf");
  EXPECT_TRUE(fs::exists(work + "/box002/dense/dp_scale_record.json"));
  EXPECT_TRUE(fs::exists(work + "/r6m2_rf50_f4_left.npy"));
}

TEST(Walkthrough, RunsAsWrittenInTheUserGuide) {
  const std::string block = WalkthroughBlock();
  ASSERT_FALSE(block.empty())
      << "no ```sh block after " << kMarker << " in docs/user-guide.md";
  if (fs::path(kDpsfm).filename() != "colmap") {
    GTEST_SKIP() << "the installed route has no colmap with the dp-sfm "
                    "commands: Walkthrough.RunsWithDpsfm runs the guide";
  }
  const std::string real = RealDpDir();
  ASSERT_FALSE(real.empty()) << "the real DP captures are missing";
  TempDir dir;
  fs::create_directories(dir / "bin");
  fs::create_symlink(kDpsfm, dir / "bin/colmap");
  RunWalkthrough(block, dir, real);
}

// The same walkthrough on the installed route, as the guide says to run it
// there: `dpsfm` for `colmap` in the dp-sfm commands, beside a `colmap` that
// refuses them (so none of them can reach COLMAP's binary unnoticed).
TEST(Walkthrough, RunsWithDpsfm) {
  std::string block = WalkthroughBlock();
  ASSERT_FALSE(block.empty());
  int replaced = 0;
  for (size_t at = block.find("colmap dp_"); at != std::string::npos;
       at = block.find("colmap dp_", at)) {
    block.replace(at, 6, "dpsfm");
    ++replaced;
  }
  ASSERT_EQ(replaced, 2) << block;
  const std::string real = RealDpDir();
  ASSERT_FALSE(real.empty()) << "the real DP captures are missing";
  TempDir dir;
  const std::string bin = dir / "bin";
  fs::create_directories(bin);
  fs::create_symlink(DPSFM_THIN_EXE, bin + "/dpsfm");
  WriteTextFile(bin + "/colmap",
                "#!/bin/sh\ncase \"$1\" in dp_*) echo \"$1 reached colmap\" "
                ">&2; exit 97 ;; esac\nexec \"" + kColmap + "\" \"$@\"\n");
  fs::permissions(bin + "/colmap", fs::perms::owner_all);
  RunWalkthrough(block, dir, real);
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
