// The Python recipe (examples/python/scale_with_dp.py) run as a pipeline
// shop would run it: a model pycolmap 4.2.1 wrote, the scale step through
// the built DP executable, the metric model read back with pycolmap.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/e2e/e2e_helpers.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

const std::string kRecipe =
    std::string(DPSFM_SOURCE_DIR) + "/examples/python/scale_with_dp.py";

// Reads the model in argv[1] with pycolmap and writes it into argv[2].
constexpr char kRewrite[] = R"(import sys, pycolmap
pycolmap.Reconstruction(sys.argv[1]).write(sys.argv[2])
print(pycolmap.__version__))";

// Exit 0 when pycolmap reads the model in argv[2] as the one in argv[1]
// times argv[3]: every 3D point and every camera centre within 1e-9
// relative, none missing.
constexpr char kCheckScaled[] = R"(import sys
import numpy as np
import pycolmap
before = pycolmap.Reconstruction(sys.argv[1])
after = pycolmap.Reconstruction(sys.argv[2])
s = float(sys.argv[3])
pairs = [(p.xyz, after.points3D[i].xyz) for i, p in before.points3D.items()]
pairs += [(im.projection_center(), after.images[i].projection_center())
          for i, im in before.images.items()]
worst = max(np.linalg.norm(b - s * a) / np.linalg.norm(s * a) for a, b in pairs)
print(f"{len(pairs)} points and camera centres, worst deviation {worst:.3g}")
same_size = (len(after.points3D) == len(before.points3D) and
             len(after.images) == len(before.images))
sys.exit(0 if same_size and worst <= 1e-9 else 1))";

CommandResult RunPython(std::vector<std::string> args) {
  args.insert(args.begin(), PycolmapPython());
  return RunCommand(args);
}

TEST(PythonRecipe, PycolmapModelIsScaledAndReadBackMetric) {
  if (!fs::exists(PycolmapPython())) {
    GTEST_SKIP() << "no pycolmap 4.2.1 at " << PycolmapPython()
                 << " (scripts/install_deps.sh makes it; "
                    "DPSFM_PYCOLMAP_PYTHON overrides)";
  }
  SceneCopy scene("dslr");
  const std::string sparse = scene / "dense/sparse";
  // The model as pycolmap 4.2.1 writes it: from a COLMAP 3.x layout (no
  // rigs.bin, frames.bin), so those two files exist only if pycolmap wrote
  // the model in the current format.
  fs::remove(sparse + "/rigs.bin");
  fs::remove(sparse + "/frames.bin");
  const std::string written = scene.temp() / "pycolmap_model";
  fs::create_directories(written);
  const CommandResult rewrite = RunPython({"-c", kRewrite, sparse, written});
  ASSERT_EQ(rewrite.exit_code, 0) << rewrite.err;
  EXPECT_EQ(rewrite.out, "4.2.1\n");
  fs::remove_all(sparse);
  CopyFolderFiles(written, sparse);
  ASSERT_TRUE(fs::exists(sparse + "/rigs.bin"));
  ASSERT_TRUE(fs::exists(sparse + "/frames.bin"));
  const std::string before = scene.temp() / "before";
  CopyFolderFiles(sparse, before);

  const std::string report_path = scene.temp() / "dp_scale.json";
  const std::vector<std::string> recipe = {kRecipe,
                                           "--exe",
                                           kDpsfm,
                                           "--workspace_path",
                                           scene / "dense",
                                           "--dp_image_path",
                                           scene / "dp",
                                           "--lens_path",
                                           scene / "lens.csv",
                                           "--report_path",
                                           report_path};
  const CommandResult run = RunPython(recipe);
  std::printf("%s", run.out.c_str());
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;

  // What it printed is the report's scale and interval (9 digits).
  const std::vector<std::string> lines = Lines(run.out);
  ASSERT_EQ(lines.size(), 2u) << run.out;
  double printed = 0, printed_low = 0, printed_high = 0;
  ASSERT_EQ(std::sscanf(lines[0].c_str(),
                        "scale %lf metres per model unit, 95 %% interval "
                        "[%lf, %lf]",
                        &printed,
                        &printed_low,
                        &printed_high),
            3)
      << lines[0];
  const nlohmann::json report = ReadJson(report_path);
  ASSERT_TRUE(report.at("success").get<bool>());
  const double scale = report.at("scale").get<double>();
  const double low = report.at("scale_ci_low").get<double>();
  const double high = report.at("scale_ci_high").get<double>();
  EXPECT_NEAR(printed, scale, 1e-8 * scale);
  EXPECT_NEAR(printed_low, low, 1e-8 * low);
  EXPECT_NEAR(printed_high, high, 1e-8 * high);
  // The interval holds the generator's true scale.
  const double truth =
      ReadJson(scene / "ground_truth.json").at("scale").get<double>();
  EXPECT_LE(low, truth);
  EXPECT_GE(high, truth);
  EXPECT_NE(lines[1].find("(pycolmap 4.2.1): 8 images, "), std::string::npos)
      << lines[1];
  // The extent of the camera centres it printed is the true one in metres
  // (5 %, and the printed 3 decimals).
  double extent[3] = {0, 0, 0};
  const size_t within = lines[1].find("camera centres within ");
  ASSERT_NE(within, std::string::npos) << lines[1];
  ASSERT_EQ(std::sscanf(lines[1].c_str() + within,
                        "camera centres within %lf x %lf x %lf m",
                        &extent[0],
                        &extent[1],
                        &extent[2]),
            3)
      << lines[1];
  const nlohmann::json views =
      ReadJson(scene / "ground_truth.json").at("views");
  for (int axis = 0; axis < 3; ++axis) {
    double lowest = 1e300, highest = -1e300;
    for (const auto& view : views) {
      const double c = view.at("center_m").at(axis).get<double>();
      lowest = std::min(lowest, c);
      highest = std::max(highest, c);
    }
    EXPECT_NEAR(
        extent[axis], highest - lowest, 0.05 * (highest - lowest) + 0.0005)
        << "axis " << axis;
  }

  // pycolmap reads the model back as the one it wrote times the scale; a
  // model left as it was fails that check.
  char s[64];
  std::snprintf(s, sizeof(s), "%.17g", scale);
  const CommandResult scaled =
      RunPython({"-c", kCheckScaled, before, sparse, s});
  EXPECT_EQ(scaled.exit_code, 0) << scaled.out << scaled.err;
  std::printf("%s", scaled.out.c_str());
  const CommandResult unscaled =
      RunPython({"-c", kCheckScaled, before, before, s});
  EXPECT_EQ(unscaled.exit_code, 1) << unscaled.out << unscaled.err;

  // A failed run (a second one on the rescaled workspace is refused): its
  // exit code and its ERROR line, nothing on stdout.
  const CommandResult again = RunPython(recipe);
  EXPECT_EQ(again.exit_code, 1) << again.err;
  EXPECT_EQ(again.out, "");
  EXPECT_EQ(again.err.rfind("ERROR: dp_scale_estimator: workspace ", 0), 0u)
      << again.err;
  EXPECT_NE(again.err.find("was already rescaled"), std::string::npos)
      << again.err;
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
