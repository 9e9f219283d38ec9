// The command is registered in COLMAP's binary, and bad input gives one clear
// error line, a non-zero exit, no abort, and an untouched workspace.
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

// The binary with the dp-sfm commands: the patched colmap or dpsfm.
const std::string kDpsfm = DPSFM_DP_EXE;

CommandResult RunEstimator(const std::vector<std::string>& args) {
  std::vector<std::string> command = {kDpsfm, "dp_scale_estimator"};
  command.insert(command.end(), args.begin(), args.end());
  return RunCommand(command);
}

// A failed run: exit status 1, not killed, exactly one error line, no
// crash report, and the error line contains `expected`.
void ExpectCleanError(const CommandResult& result,
                      const std::string& expected) {
  EXPECT_FALSE(result.signaled) << result.err;
  EXPECT_EQ(result.exit_code, 1) << result.err;
  const std::regex error_line("^(ERROR: |E[0-9]{8} ).*");
  // COLMAP 4 colours its log lines even off a terminal.
  const std::regex colour("\x1b\\[[0-9;]*m");
  int num_error_lines = 0;
  for (const std::string& coloured : Lines(result.err)) {
    const std::string line = std::regex_replace(coloured, colour, "");
    if (std::regex_match(line, error_line)) {
      ++num_error_lines;
      EXPECT_NE(line.find(expected), std::string::npos)
          << "error line: " << line << "\nexpected to contain: " << expected;
    }
  }
  EXPECT_EQ(num_error_lines, 1) << result.err;
  for (const char* crash : {"Check failed",
                            "terminate called",
                            "Aborted",
                            "stack trace",
                            "*** SIG"}) {
    EXPECT_EQ(result.err.find(crash), std::string::npos) << result.err;
  }
}

// A minimal dense workspace layout: enough for option validation.
struct WorkspaceFixture {
  TempDir dir;
  std::string workspace = dir / "dense";
  std::string dp = dir / "dp";
  WorkspaceFixture() {
    for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) {
      WriteTextFile(workspace + "/sparse/" + name, "# empty model\n");
    }
    std::filesystem::create_directories(workspace + "/stereo/depth_maps");
    WriteTextFile(dp + "/left/a.png", "not an image");
    WriteTextFile(dp + "/right/a.png", "not an image");
  }
};

TEST(CommandLine, RegisteredInColmapHelp) {
  const CommandResult result = RunCommand({kDpsfm, "help"});
  EXPECT_EQ(result.exit_code, 0);
  EXPECT_NE(result.out.find("  dp_scale_estimator\n"), std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("  dp_psf_calibrator\n"), std::string::npos)
      << result.out;
  // The help names the COLMAP the commands were built against.
  EXPECT_NE(result.out.find("COLMAP " +
                            std::to_string(DPSFM_COLMAP_VERSION_MAJOR) + "." +
                            std::to_string(DPSFM_COLMAP_VERSION_MINOR)),
            std::string::npos)
      << result.out;
}

TEST(CommandLine, HelpListsContractOptions) {
  const CommandResult result = RunEstimator({"--help"});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  const std::string text = result.out + result.err;
  for (const char* option : {"--workspace_path",
                             "--dp_image_path",
                             "--input_path",
                             "--image_path",
                             "--database_path",
                             "--lens_path",
                             "--DPScaleEstimator.focal_length_mm",
                             "--DPScaleEstimator.f_number",
                             "--DPScaleEstimator.pixel_pitch_um",
                             "--DPScaleEstimator.swap_dp_views",
                             "--input_type",
                             "--report_path",
                             "--dry_run",
                             "--output_path"}) {
    EXPECT_NE(text.find(option), std::string::npos) << option;
  }
}

TEST(CommandLine, MissingRequiredOption) {
  WorkspaceFixture fixture;
  ExpectCleanError(RunEstimator({"--workspace_path", fixture.workspace}),
                   "dp_image_path");
}

TEST(CommandLine, UnknownOption) {
  ExpectCleanError(RunEstimator({"--no_such_option", "1"}), "no_such_option");
}

TEST(CommandLine, BadBooleanValue) {
  WorkspaceFixture fixture;
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--dp_image_path",
                                 fixture.dp,
                                 "--dry_run",
                                 "maybe"}),
                   "dry_run");
}

TEST(CommandLine, NeitherWorkspaceNorModel) {
  WorkspaceFixture fixture;
  ExpectCleanError(RunEstimator({"--dp_image_path", fixture.dp}),
                   "--workspace_path");
}

TEST(CommandLine, BothWorkspaceAndModel) {
  WorkspaceFixture fixture;
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--input_path",
                                 fixture.workspace + "/sparse",
                                 "--dp_image_path",
                                 fixture.dp}),
                   "exactly one");
}

TEST(CommandLine, MissingWorkspace) {
  WorkspaceFixture fixture;
  const std::string missing = fixture.dir / "no_such_dir";
  ExpectCleanError(
      RunEstimator(
          {"--workspace_path", missing, "--dp_image_path", fixture.dp}),
      missing);
}

TEST(CommandLine, WorkspaceWithoutModel) {
  WorkspaceFixture fixture;
  std::filesystem::remove(fixture.workspace + "/sparse/images.txt");
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--dp_image_path",
                                 fixture.dp}),
                   "no model");
}

TEST(CommandLine, WorkspaceWithoutDepthMaps) {
  WorkspaceFixture fixture;
  std::filesystem::remove_all(fixture.workspace + "/stereo");
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--dp_image_path",
                                 fixture.dp}),
                   "depth maps");
}

TEST(CommandLine, DPFolderWithoutRightOrSum) {
  WorkspaceFixture fixture;
  std::filesystem::remove_all(fixture.dp + "/right");
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--dp_image_path",
                                 fixture.dp}),
                   "neither right/ nor sum/");
}

TEST(CommandLine, BadInputType) {
  WorkspaceFixture fixture;
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--dp_image_path",
                                 fixture.dp,
                                 "--input_type",
                                 "fused"}),
                   "--input_type");
}

TEST(CommandLine, NonPositiveLensValues) {
  WorkspaceFixture fixture;
  for (const char* option : {"f_number", "focal_length_mm", "pixel_pitch_um"}) {
    ExpectCleanError(RunEstimator({"--workspace_path",
                                   fixture.workspace,
                                   "--dp_image_path",
                                   fixture.dp,
                                   std::string("--DPScaleEstimator.") + option,
                                   "-2"}),
                     option);
  }
}

TEST(CommandLine, NonNumericLensValue) {
  WorkspaceFixture fixture;
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--dp_image_path",
                                 fixture.dp,
                                 "--DPScaleEstimator.f_number",
                                 "wide"}),
                   "f_number");
}

TEST(CommandLine, MissingDatabaseIsNotCreated) {
  WorkspaceFixture fixture;
  const std::string database = fixture.dir / "project.db";
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--dp_image_path",
                                 fixture.dp,
                                 "--database_path",
                                 database}),
                   database);
  EXPECT_FALSE(std::filesystem::exists(database));
}

TEST(CommandLine, MissingLensFile) {
  WorkspaceFixture fixture;
  const std::string lens = fixture.dir / "lens.csv";
  ExpectCleanError(RunEstimator({"--workspace_path",
                                 fixture.workspace,
                                 "--dp_image_path",
                                 fixture.dp,
                                 "--lens_path",
                                 lens}),
                   lens);
}

TEST(CommandLine, FailedRunLeavesWorkspaceUnchanged) {
  WorkspaceFixture fixture;
  const auto before = SnapshotTree(fixture.dir.path());
  const CommandResult result = RunEstimator({"--workspace_path",
                                             fixture.workspace,
                                             "--dp_image_path",
                                             fixture.dp,
                                             "--report_path",
                                             fixture.dir / "report.json"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_FALSE(result.signaled);
  EXPECT_EQ(SnapshotTree(fixture.dir.path()), before);
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
