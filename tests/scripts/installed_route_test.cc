// The installed route's version gate: dp-sfm configured without
// COLMAP_SOURCE_DIR against a prefix whose COLMAP package reports another
// version stops in one line naming it (3.x with the checkout route as the
// way out); with no package at all it says what to pass.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

const std::string kRoot = DPSFM_SOURCE_DIR;

// A prefix holding only share/colmap/colmap-config.cmake that reports
// `version` (what find_package reads first; nothing else is needed to reach
// the gate).
std::string FakeColmapPrefix(const TempDir& dir, const std::string& version) {
  const std::string prefix = dir / "prefix";
  std::filesystem::create_directories(prefix + "/share/colmap");
  WriteTextFile(prefix + "/share/colmap/colmap-config.cmake",
                "set(COLMAP_FOUND TRUE)\nset(COLMAP_VERSION " + version +
                    ")\n");
  return prefix;
}

CommandResult Configure(const TempDir& dir, const std::string& prefix) {
  return RunCommand({"cmake",
                     "-S",
                     kRoot,
                     "-B",
                     dir / "build",
                     "-DCMAKE_PREFIX_PATH=" + prefix,
                     "-DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF",
                     "-DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF"});
}

// The configure's error text, glued back from CMake's wrapped lines.
std::string ErrorText(const CommandResult& result) {
  std::string text;
  for (const std::string& line : Lines(result.err)) {
    const size_t start = line.find_first_not_of(' ');
    text += start == std::string::npos ? "\n" : line.substr(start) + " ";
  }
  return text;
}

TEST(InstalledRoute, RefusesColmap3PointingToTheCheckoutRoute) {
  TempDir dir;
  const CommandResult result = Configure(dir, FakeColmapPrefix(dir, "3.10"));
  EXPECT_NE(result.exit_code, 0);
  const std::string text = ErrorText(result);
  EXPECT_NE(text.find("dp-sfm: COLMAP 3.10 found at " + (dir / "prefix") +
                      "/share/colmap"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("-DCOLMAP_SOURCE_DIR"), std::string::npos) << text;
}

TEST(InstalledRoute, RefusesAnotherColmap4NamingTheVersion) {
  for (const std::string version : {"4.0.4", "4.3.0"}) {
    TempDir dir;
    const CommandResult result =
        Configure(dir, FakeColmapPrefix(dir, version));
    EXPECT_NE(result.exit_code, 0);
    const std::string text = ErrorText(result);
    EXPECT_NE(text.find("dp-sfm: COLMAP " + version + " found at"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("builds against COLMAP 4.1.x or 4.2.x"),
              std::string::npos)
        << text;
  }
}

TEST(InstalledRoute, NoColmapSaysWhatToPass) {
  TempDir dir;
  std::filesystem::create_directories(dir / "empty");
  const CommandResult result = Configure(dir, dir / "empty");
  EXPECT_NE(result.exit_code, 0);
  const std::string text = ErrorText(result);
  EXPECT_NE(text.find("dp-sfm: no installed COLMAP found"), std::string::npos)
      << text;
  EXPECT_NE(text.find("-DCMAKE_PREFIX_PATH="), std::string::npos) << text;
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
