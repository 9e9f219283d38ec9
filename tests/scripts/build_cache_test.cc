// The COLMAP build cache: its key follows the patch series and the pinned
// source tarball is verified.
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

const std::string kRoot = DPSFM_SOURCE_DIR;

std::string CacheKey(const std::string& patch_dir, const std::string& kind) {
  const CommandResult result =
      RunCommand({"bash", kRoot + "/scripts/cache_key.sh", patch_dir, kind});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  std::string key = result.out;
  while (!key.empty() && (key.back() == '\n' || key.back() == ' ')) {
    key.pop_back();
  }
  return key;
}

// A copy of colmap_patches/ to edit.
std::string CopyPatches(const TempDir& dir) {
  const std::string copy = dir / "patches";
  boost::filesystem::create_directories(copy);
  for (boost::filesystem::directory_iterator it(kRoot + "/colmap_patches"), end;
       it != end;
       ++it) {
    boost::filesystem::copy_file(it->path(), copy / it->path().filename());
  }
  return copy;
}

TEST(BuildCache, KeyIsStable) {
  const std::string patches = kRoot + "/colmap_patches";
  const std::string key = CacheKey(patches, "build");
  EXPECT_EQ(key.size(), 16u);
  EXPECT_EQ(CacheKey(patches, "build"), key);
  TempDir dir;
  EXPECT_EQ(CacheKey(CopyPatches(dir), "build"), key);
}

TEST(BuildCache, KeyChangesWhenAPatchChanges) {
  TempDir dir;
  const std::string patches = CopyPatches(dir);
  const std::string source_key = CacheKey(patches, "source");
  const std::string build_key = CacheKey(patches, "build");
  boost::filesystem::directory_iterator first(patches);
  const std::string patch = first->path().string();
  WriteTextFile(patch, ReadTextFile(patch) + "\n");
  EXPECT_NE(CacheKey(patches, "source"), source_key);
  EXPECT_NE(CacheKey(patches, "build"), build_key);
}

TEST(BuildCache, KeyChangesWhenAPatchIsAdded) {
  TempDir dir;
  const std::string patches = CopyPatches(dir);
  const std::string build_key = CacheKey(patches, "build");
  WriteTextFile(patches + "/9999-extra.patch", "");
  EXPECT_NE(CacheKey(patches, "build"), build_key);
}

TEST(BuildCache, KeyChangesWithBuildOptions) {
  const std::string patches = kRoot + "/colmap_patches";
  const std::string release = CacheKey(patches, "build");
  const CommandResult debug = RunCommand({"env",
                                          "DPSFM_BUILD_TYPE=Debug",
                                          "bash",
                                          kRoot + "/scripts/cache_key.sh",
                                          patches,
                                          "build"});
  EXPECT_EQ(debug.exit_code, 0);
  EXPECT_NE(debug.out.substr(0, 16), release);
  // The source key does not depend on build options.
  const CommandResult debug_source =
      RunCommand({"env",
                  "DPSFM_BUILD_TYPE=Debug",
                  "bash",
                  kRoot + "/scripts/cache_key.sh",
                  patches,
                  "source"});
  EXPECT_EQ(debug_source.out.substr(0, 16), CacheKey(patches, "source"));
}

TEST(BuildCache, TarballWithWrongChecksumIsRefused) {
  TempDir cache;
  WriteTextFile(cache / "downloads/colmap_3.10.orig.tar.gz", "not colmap");
  const CommandResult result = RunCommand({"env",
                                           "DPSFM_CACHE_DIR=" + cache.path(),
                                           "bash",
                                           kRoot + "/scripts/fetch_colmap.sh"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.err.find("sha256 mismatch"), std::string::npos)
      << result.err;
  EXPECT_FALSE(boost::filesystem::exists(cache / "src"));
}

// build.sh's standard output is the build directory and nothing else, also
// when packages are missing and apt prints its progress (on a fresh machine
// that output once became the build directory's "name"). apt-get and
// dpkg-query are stand-ins here that report every package missing and
// print like apt does; the build itself is the suite's own, up to date.
TEST(BuildScripts, StdoutIsOnlyTheBuildDirectory) {
  TempDir dir;
  const std::string bin = dir / "bin";
  boost::filesystem::create_directories(bin);
  WriteTextFile(bin + "/dpkg-query", "#!/bin/sh\nexit 1\n");
  WriteTextFile(bin + "/apt-get",
                "#!/bin/sh\necho 'Reading package lists... Done'\n"
                "echo 'Setting up libfoo (1.0) ...'\nexit 0\n");
  for (const char* tool : {"/dpkg-query", "/apt-get"}) {
    boost::filesystem::permissions(bin + tool,
                                   boost::filesystem::owner_all |
                                       boost::filesystem::group_read |
                                       boost::filesystem::others_read);
  }
  const char* path = std::getenv("PATH");
  const CommandResult result =
      RunCommand({"env",
                  "PATH=" + bin + ":" + (path ? path : "/usr/bin:/bin"),
                  "bash",
                  kRoot + "/scripts/build.sh"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  // Proof that the stand-ins ran and printed.
  EXPECT_NE(result.err.find("Setting up libfoo"), std::string::npos)
      << result.err;
  ASSERT_FALSE(result.out.empty());
  EXPECT_EQ(result.out.find('\n'), result.out.size() - 1) << result.out;
  const std::string build_dir = result.out.substr(0, result.out.size() - 1);
  EXPECT_TRUE(boost::filesystem::exists(build_dir + "/CMakeCache.txt"))
      << build_dir;
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
