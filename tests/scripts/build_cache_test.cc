// The COLMAP build cache: its key follows the patch series and the pinned
// source tarball is verified.
#include <cstdlib>
#include <map>
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
  std::filesystem::create_directories(copy);
  for (std::filesystem::directory_iterator it(kRoot + "/colmap_patches"), end;
       it != end;
       ++it) {
    std::filesystem::copy_file(it->path(), copy / it->path().filename());
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
  std::filesystem::directory_iterator first(patches);
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

// Each COLMAP version is its own cache entry, so switching rebuilds nothing.
TEST(BuildCache, KeyDiffersPerColmapVersion) {
  const std::string patches = kRoot + "/colmap_patches";
  std::map<std::string, std::string> keys;
  for (const std::string version : {"4.1.1", "3.10"}) {
    const CommandResult result = RunCommand({"env",
                                             "DPSFM_COLMAP_VERSION=" + version,
                                             "bash",
                                             kRoot + "/scripts/cache_key.sh",
                                             patches,
                                             "build"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    keys[version] = result.out;
  }
  EXPECT_NE(keys["4.1.1"], keys["3.10"]);
}

TEST(BuildCache, UnknownColmapVersionIsRefused) {
  const CommandResult result = RunCommand({"env",
                                           "DPSFM_COLMAP_VERSION=3.9",
                                           "bash",
                                           kRoot + "/scripts/cache_key.sh"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.err.find("DPSFM_COLMAP_VERSION=3.9 is not a version"),
            std::string::npos)
      << result.err;
}

TEST(BuildCache, TarballWithWrongChecksumIsRefused) {
  TempDir cache;
  WriteTextFile(cache / "downloads/colmap_3.10.orig.tar.gz", "not colmap");
  const CommandResult result = RunCommand({"env",
                                           "DPSFM_COLMAP_VERSION=3.10",
                                           "DPSFM_CACHE_DIR=" + cache.path(),
                                           "bash",
                                           kRoot + "/scripts/fetch_colmap.sh"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.err.find("sha256 mismatch"), std::string::npos)
      << result.err;
  EXPECT_FALSE(std::filesystem::exists(cache / "src/colmap-3.10"));
}

// COLMAP 4's source: a mirror file with another checksum is not used, and an
// archive whose files are not COLMAP 4.1.1's (as a download of the wrong tag
// would be) is refused and deleted, leaving no source tree behind.
TEST(BuildCache, ArchiveWithOtherFilesIsRefused) {
  TempDir dir;
  const std::string cache = dir / "cache";
  const std::string mirror = dir / "mirror";
  WriteTextFile(mirror + "/colmap-4.1.1.tar.gz", "not the pinned archive");
  WriteTextFile(dir / "colmap-4.1.1/CMakeLists.txt", "project(other)\n");
  std::filesystem::create_directories(cache + "/downloads");
  const CommandResult tar =
      RunCommand({"tar",
                  "-czf",
                  cache + "/downloads/colmap-4.1.1.tar.gz",
                  "-C",
                  dir.path(),
                  "colmap-4.1.1"});
  ASSERT_EQ(tar.exit_code, 0) << tar.err;
  const CommandResult result = RunCommand({"env",
                                           "DPSFM_COLMAP_VERSION=4.1.1",
                                           "DPSFM_CACHE_DIR=" + cache,
                                           "DPSFM_SOURCES_DIR=" + mirror,
                                           "bash",
                                           kRoot + "/scripts/fetch_colmap.sh"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.err.find("does not have the pinned sha256"),
            std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("are not those of colmap-4.1.1"), std::string::npos)
      << result.err;
  EXPECT_FALSE(
      std::filesystem::exists(cache + "/downloads/colmap-4.1.1.tar.gz"));
  for (std::filesystem::directory_iterator it(cache + "/src"), end; it != end;
       ++it) {
    ADD_FAILURE() << "left behind: " << it->path();
  }
}

// build.sh's standard output is the build directory and nothing else, also
// when packages are missing and apt prints its progress (on a fresh machine
// that output once became the build directory's "name"). apt-get and
// dpkg-query are stand-ins here that report every package missing and
// print like apt does; the build itself is the suite's own, up to date.
TEST(BuildScripts, StdoutIsOnlyTheBuildDirectory) {
  TempDir dir;
  const std::string bin = dir / "bin";
  std::filesystem::create_directories(bin);
  WriteTextFile(bin + "/dpkg-query", "#!/bin/sh\nexit 1\n");
  WriteTextFile(bin + "/apt-get",
                "#!/bin/sh\necho 'Reading package lists... Done'\n"
                "echo 'Setting up libfoo (1.0) ...'\nexit 0\n");
  for (const char* tool : {"/dpkg-query", "/apt-get"}) {
    std::filesystem::permissions(bin + tool,
                                 std::filesystem::perms::owner_all |
                                     std::filesystem::perms::group_read |
                                     std::filesystem::perms::others_read);
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
  EXPECT_TRUE(std::filesystem::exists(build_dir + "/CMakeCache.txt"))
      << build_dir;
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
