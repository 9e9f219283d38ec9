// Pinned sources, fetched, verified and patched by CMake
// (cmake/FetchSource.cmake, cmake/PrepareSource.cmake, cmake/ColmapRelease.cmake).
// Each test makes its own small source archive and patch, and checks CMake's
// verdicts against checksums computed by coreutils (sha256sum), not by the
// code under test.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

const std::string kRoot = DPSFM_SOURCE_DIR;

std::string Trimmed(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) {
    text.pop_back();
  }
  return text;
}

// CMake wraps its messages' lines: the text with each line break and the
// indentation after it as one space.
std::string OneLine(const std::string& text) {
  std::string line;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\n') {
      line += text[i];
      continue;
    }
    while (i + 1 < text.size() && text[i + 1] == ' ') ++i;
    line += ' ';
  }
  return line;
}

// sha256sum of a file.
std::string FileSha256(const std::string& path) {
  const CommandResult result = RunCommand({"sha256sum", path});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  return result.out.substr(0, 64);
}

// The checksum of a tree's files as the pins are written: the sha256 of
// `sha256sum` over every regular file, in byte order of the paths.
std::string TreeSha256(const std::string& dir) {
  const CommandResult result = RunCommand(
      {"bash",
       "-c",
       "cd \"$1\" && find . -type f -print0 | LC_ALL=C sort -z | "
       "xargs -0 sha256sum | sha256sum | cut -c1-64",
       "_",
       dir});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  return Trimmed(result.out);
}

// A small source tree, demo-1.0/, with nested and hidden files.
void WriteDemoTree(const std::string& parent) {
  WriteTextFile(parent + "/demo-1.0/CMakeLists.txt", "# demo\n");
  WriteTextFile(parent + "/demo-1.0/src/greeting.txt", "hello\n");
  WriteTextFile(parent + "/demo-1.0/.hidden", "dot\n");
  WriteTextFile(parent + "/demo-1.0/src/b/Z.txt", "upper\n");
  WriteTextFile(parent + "/demo-1.0/src/a.txt", "lower\n");
}

// tar.gz of parent/demo-1.0; `level` changes the bytes, not the files.
std::string MakeArchive(const std::string& parent,
                        const std::string& archive,
                        int level) {
  const CommandResult tar = RunCommand(
      {"bash",
       "-c",
       "tar -C \"$1\" -cf - demo-1.0 | gzip -n -" + std::to_string(level) +
           " > \"$2\"",
       "_",
       parent,
       archive});
  EXPECT_EQ(tar.exit_code, 0) << tar.err;
  return archive;
}

const char kPatch[] =
    "--- a/src/greeting.txt\n"
    "+++ b/src/greeting.txt\n"
    "@@ -1 +1 @@\n"
    "-hello\n"
    "+hello, patched\n";

// A project that declares `demo` with dpsfm_declare_source and populates it.
struct DemoProject {
  explicit DemoProject(const TempDir& dir)
      : source(dir / "project"), build(dir / "build"), mirror(dir / "mirror") {
    std::filesystem::create_directories(mirror);
  }

  void Write(const std::string& declare_args) const {
    WriteTextFile(source + "/CMakeLists.txt",
                  "cmake_minimum_required(VERSION 3.16)\n"
                  "project(demo_fetch NONE)\n"
                  "include(" +
                      kRoot +
                      "/cmake/FetchSource.cmake)\n"
                      "dpsfm_declare_source(demo " +
                      declare_args +
                      ")\n"
                      "FetchContent_GetProperties(demo)\n"
                      "if(NOT demo_POPULATED)\n"
                      "  FetchContent_Populate(demo)\n"
                      "endif()\n"
                      "message(STATUS \"demo at ${demo_SOURCE_DIR}\")\n");
  }

  CommandResult Configure() const {
    return RunCommand({"cmake",
                       "-S",
                       source,
                       "-B",
                       build,
                       "-DDPSFM_SOURCES_DIR=" + mirror});
  }

  // The populated tree, from the configure output.
  static std::string SourceDir(const CommandResult& result) {
    const size_t at = result.out.find("-- demo at ");
    if (at == std::string::npos) return "";
    const size_t start = at + std::string("-- demo at ").size();
    return result.out.substr(start, result.out.find('\n', start) - start);
  }

  std::string source, build, mirror;
};

TEST(PrepareSource, TreeChecksumIsThatOfSha256sum) {
  TempDir dir;
  WriteDemoTree(dir.path());
  const std::string tree = dir / "demo-1.0";
  // A symbolic link is not a file of the tree (find -type f).
  std::filesystem::create_symlink("src/a.txt", tree + "/link.txt");
  WriteTextFile(dir / "tree.cmake",
                "include(" + kRoot +
                    "/cmake/PrepareSource.cmake)\n"
                    "dpsfm_tree_sha256(\"${DIR}\" sha)\n"
                    "message(\"${sha}\")\n");
  const CommandResult result =
      RunCommand({"cmake", "-DDIR=" + tree, "-P", dir / "tree.cmake"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(Trimmed(result.err), TreeSha256(tree));
  // Any change of a file's content or name changes it.
  WriteTextFile(tree + "/src/a.txt", "lower!\n");
  const CommandResult changed =
      RunCommand({"cmake", "-DDIR=" + tree, "-P", dir / "tree.cmake"});
  EXPECT_NE(Trimmed(changed.err), Trimmed(result.err));
  EXPECT_EQ(Trimmed(changed.err), TreeSha256(tree));
}

TEST(PrepareSource, OtherFilesAreRefusedAndNotPatched) {
  TempDir dir;
  WriteDemoTree(dir.path());
  const std::string tree = dir / "demo-1.0";
  const std::string pinned = TreeSha256(tree);
  WriteTextFile(dir / "fix.patch", kPatch);
  WriteTextFile(tree + "/extra.txt", "not in the release\n");
  const CommandResult result =
      RunCommand({"cmake",
                  "-DNAME=demo",
                  "-DSOURCE_DIR=" + tree,
                  "-DTREE_SHA256=" + pinned,
                  "-DPATCHES=" + (dir / "fix.patch"),
                  "-P",
                  kRoot + "/cmake/PrepareSource.cmake"});
  EXPECT_NE(result.exit_code, 0);
  const std::string err = OneLine(result.err);
  EXPECT_NE(err.find("the files fetched for demo are not demo's (their "
                     "sha256 is " +
                     TreeSha256(tree) + ", pinned " + pinned + ")"),
            std::string::npos)
      << result.err;
  EXPECT_EQ(ReadTextFile(tree + "/src/greeting.txt"), "hello\n");
  EXPECT_FALSE(std::filesystem::exists(tree + "/.dpsfm-prepared"));
}

TEST(PrepareSource, APatchThatDoesNotApplyIsNamed) {
  TempDir dir;
  WriteDemoTree(dir.path());
  const std::string tree = dir / "demo-1.0";
  WriteTextFile(dir / "0001-fix.patch", kPatch);
  std::string stale = kPatch;
  stale.replace(stale.find("-hello"), 6, "-howdy");
  WriteTextFile(dir / "0002-stale.patch", stale);
  const CommandResult result =
      RunCommand({"cmake",
                  "-DNAME=demo",
                  "-DSOURCE_DIR=" + tree,
                  "-DPATCHES=" + (dir / "0001-fix.patch") + "|" +
                      (dir / "0002-stale.patch"),
                  "-P",
                  kRoot + "/cmake/PrepareSource.cmake"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(OneLine(result.err).find(
                "patch 0002-stale.patch does not apply to demo"),
            std::string::npos)
      << result.err;
  EXPECT_FALSE(std::filesystem::exists(tree + "/.dpsfm-prepared"));
}

// From the mirror when its sha256 matches, patched; a second configure uses
// the prepared tree without the archive; another patch series prepares
// another tree and drops the old one.
TEST(FetchSource, MirrorVerifiedPatchedThenReused) {
  TempDir dir;
  WriteDemoTree(dir / "upstream");
  const DemoProject project(dir);
  const std::string archive =
      MakeArchive(dir / "upstream", project.mirror + "/demo-1.0.tar.gz", 6);
  const std::string tree_sha = TreeSha256(dir / "upstream/demo-1.0");
  WriteTextFile(dir / "fix.patch", kPatch);
  const std::string pins = "ARCHIVE demo-1.0.tar.gz SHA256 " +
                           FileSha256(archive) + " TREE_SHA256 " + tree_sha +
                           " URL file:///nonexistent/demo-1.0.tar.gz";
  project.Write(pins + " PATCHES " + (dir / "fix.patch"));

  const CommandResult first = project.Configure();
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err;
  EXPECT_NE(first.out.find("demo from " + project.mirror), std::string::npos)
      << first.out;
  const std::string tree = DemoProject::SourceDir(first);
  ASSERT_FALSE(tree.empty()) << first.out;
  EXPECT_EQ(ReadTextFile(tree + "/src/greeting.txt"), "hello, patched\n");
  EXPECT_TRUE(std::filesystem::exists(tree + "/.dpsfm-prepared"));

  std::filesystem::remove(archive);
  const CommandResult second = project.Configure();
  ASSERT_EQ(second.exit_code, 0) << second.out << second.err;
  EXPECT_NE(second.out.find("(prepared)"), std::string::npos) << second.out;
  EXPECT_EQ(DemoProject::SourceDir(second), tree);

  MakeArchive(dir / "upstream", archive, 6);
  std::string other = kPatch;
  other.replace(other.find("patched"), 7, "twice patched");
  WriteTextFile(dir / "fix.patch", other);
  const CommandResult third = project.Configure();
  ASSERT_EQ(third.exit_code, 0) << third.out << third.err;
  const std::string new_tree = DemoProject::SourceDir(third);
  EXPECT_NE(new_tree, tree);
  EXPECT_EQ(ReadTextFile(new_tree + "/src/greeting.txt"),
            "hello, twice patched\n");
  EXPECT_FALSE(std::filesystem::exists(tree));
}

// A mirror file with other bytes is not used; the release's own archive (other
// bytes, the same files) is accepted by the files' checksum.
TEST(FetchSource, OtherMirrorBytesFallBackToTheReleaseCheckedByItsFiles) {
  TempDir dir;
  WriteDemoTree(dir / "upstream");
  const DemoProject project(dir);
  const std::string pinned_archive =
      MakeArchive(dir / "upstream", dir / "pinned.tar.gz", 6);
  WriteTextFile(project.mirror + "/demo-1.0.tar.gz", "not the archive");
  const std::string release =
      MakeArchive(dir / "upstream", dir / "release.tar.gz", 1);
  ASSERT_NE(FileSha256(release), FileSha256(pinned_archive));
  project.Write("ARCHIVE demo-1.0.tar.gz SHA256 " +
                FileSha256(pinned_archive) + " TREE_SHA256 " +
                TreeSha256(dir / "upstream/demo-1.0") + " URL file://" +
                release);
  const CommandResult result = project.Configure();
  ASSERT_EQ(result.exit_code, 0) << result.out << result.err;
  EXPECT_NE(OneLine(result.err).find("does not have the pinned sha256"),
            std::string::npos)
      << result.err;
  EXPECT_NE(result.out.find("demo from file://" + release), std::string::npos)
      << result.out;
  EXPECT_EQ(ReadTextFile(DemoProject::SourceDir(result) + "/src/greeting.txt"),
            "hello\n");
}

// A download whose files are not the pinned ones (a wrong tag) is refused and
// leaves no prepared tree behind.
TEST(FetchSource, ADownloadWithOtherFilesIsRefused) {
  TempDir dir;
  WriteDemoTree(dir / "upstream");
  const std::string tree_sha = TreeSha256(dir / "upstream/demo-1.0");
  WriteTextFile(dir / "upstream/demo-1.0/src/greeting.txt", "hello 2.0\n");
  const DemoProject project(dir);
  const std::string release =
      MakeArchive(dir / "upstream", dir / "release.tar.gz", 6);
  project.Write("ARCHIVE demo-1.0.tar.gz SHA256 " + std::string(64, '0') +
                " TREE_SHA256 " + tree_sha + " URL file://" + release);
  const CommandResult result = project.Configure();
  EXPECT_NE(result.exit_code, 0);
  const std::string all = OneLine(result.out + result.err);
  EXPECT_NE(all.find("the files fetched for demo are not demo's"),
            std::string::npos)
      << all;
  for (std::filesystem::recursive_directory_iterator it(project.build), end;
       it != end;
       ++it) {
    EXPECT_NE(it->path().filename(), ".dpsfm-prepared") << it->path();
  }
}

// The pins of cmake/ColmapRelease.cmake are those of the mirror's archives
// (../shared/sources), where it is at hand.
TEST(ColmapRelease, PinsMatchTheMirror) {
  const std::string pins = ReadTextFile(kRoot + "/cmake/ColmapRelease.cmake");
  const std::string mirror = kRoot + "/../shared/sources";
  if (!std::filesystem::exists(mirror)) {
    GTEST_SKIP() << "no source mirror at " << mirror;
  }
  int checked = 0;
  for (const std::string archive : {"colmap-4.1.1.tar.gz",
                                    "PoseLib-a69263d.tar.gz",
                                    "colmap-main-5d968cf.tar.gz"}) {
    if (!std::filesystem::exists(mirror + "/" + archive)) continue;
    const size_t at = pins.find("ARCHIVE " + archive);
    ASSERT_NE(at, std::string::npos) << archive;
    const size_t sha = pins.find("SHA256 ", at) + 7;
    EXPECT_EQ(pins.substr(sha, 64), FileSha256(mirror + "/" + archive))
        << archive;
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(ColmapRelease, AnotherReleaseIsRefusedNamingThoseItFetches) {
  TempDir dir;
  const CommandResult result = RunCommand({"cmake",
                                           "-S",
                                           kRoot,
                                           "-B",
                                           dir / "build",
                                           "-DDPSFM_COLMAP_RELEASE=3.9",
                                           "-DDPSFM_TESTS_ENABLED=OFF",
                                           "-DDPSFM_BENCHMARKS_ENABLED=OFF"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(OneLine(result.err).find("DPSFM_COLMAP_RELEASE=3.9 is not a "
                                     "COLMAP release dp-sfm fetches (4.1.1, "
                                     "3.10;"),
            std::string::npos)
      << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "build/_deps"));
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
