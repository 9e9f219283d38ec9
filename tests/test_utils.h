// Helpers for end-to-end tests that run the real `colmap` binary.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "dpsfm/colmap/util/paths.h"

namespace dpsfm {
namespace test {

struct CommandResult {
  int exit_code = -1;
  bool signaled = false;  // killed by a signal (abort, segfault)
  std::string out;
  std::string err;
};

inline std::string ReadTextFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream buffer;
  buffer << file.rdbuf();
  return buffer.str();
}

inline std::string ShellQuote(const std::string& arg) {
  std::string quoted = "'";
  for (const char c : arg) {
    if (c == '\'') {
      quoted += "'\\''";
    } else {
      quoted += c;
    }
  }
  return quoted + "'";
}

// A fresh empty directory under the test temp dir, removed on destruction.
class TempDir {
 public:
  TempDir() {
    std::error_code error;
    path_ = MakeUniqueDirectory(std::filesystem::temp_directory_path(),
                                "dpsfm-test-", &error)
                .string();
    if (path_.empty()) {
      throw std::runtime_error("no temporary folder: " + error.message());
    }
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const {
    return (std::filesystem::path(path_) / name).string();
  }

 private:
  std::string path_;
};

// Runs a program with arguments (no shell interpretation of the arguments),
// capturing stdout and stderr.
inline CommandResult RunCommand(const std::vector<std::string>& args) {
  TempDir dir;
  std::string command;
  for (const std::string& arg : args) {
    command += ShellQuote(arg) + " ";
  }
  command += "</dev/null >" + ShellQuote(dir / "out") + " 2>" +
             ShellQuote(dir / "err");
  const int status = std::system(command.c_str());
  CommandResult result;
  if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
  }
  result.signaled = WIFSIGNALED(status);
  result.out = ReadTextFile(dir / "out");
  result.err = ReadTextFile(dir / "err");
  return result;
}

inline std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  std::string line;
  while (std::getline(stream, line)) {
    lines.push_back(line);
  }
  return lines;
}

// Every regular file under `root` (relative path -> contents), to prove a
// failed run left a workspace byte-for-byte unchanged.
inline std::map<std::string, std::string> SnapshotTree(
    const std::string& root) {
  std::map<std::string, std::string> files;
  for (std::filesystem::recursive_directory_iterator it(root), end; it != end;
       ++it) {
    if (std::filesystem::is_regular_file(it->path())) {
      files[std::filesystem::relative(it->path(), root).string()] =
          ReadTextFile(it->path().string());
    } else if (std::filesystem::is_directory(it->path())) {
      files[std::filesystem::relative(it->path(), root).string() + "/"] = "";
    }
  }
  return files;
}

inline void WriteTextFile(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(
      std::filesystem::path(path).parent_path());
  std::ofstream file(path, std::ios::binary);
  file << text;
}

// The Python with pycolmap 4.2.1 (COLMAP 4's reader, the oracle of the
// rescaling tests on current-format models) that scripts/install_deps.sh
// puts into $DPSFM_CACHE_DIR/venv/pycolmap-4.2.1; DPSFM_PYCOLMAP_PYTHON
// overrides.
inline std::string PycolmapPython() {
  if (const char* python = std::getenv("DPSFM_PYCOLMAP_PYTHON")) {
    return python;
  }
  std::string cache;
  if (const char* dir = std::getenv("DPSFM_CACHE_DIR")) {
    cache = dir;
  } else if (const char* xdg = std::getenv("XDG_CACHE_HOME")) {
    cache = std::string(xdg) + "/dp-sfm";
  } else {
    const char* home = std::getenv("HOME");
    cache = std::string(home ? home : "") + "/.cache/dp-sfm";
  }
  return cache + "/venv/pycolmap-4.2.1/bin/python";
}

// Runs tests/colmap/rescale/colmap4_oracle.py (make, convert, map, check; see
// there) with PycolmapPython().
inline CommandResult RunColmap4Oracle(std::vector<std::string> args) {
  args.insert(args.begin(),
              {PycolmapPython(),
               std::string(DPSFM_SOURCE_DIR) +
                   "/tests/colmap/rescale/colmap4_oracle.py"});
  return RunCommand(args);
}

// The oracle's `check` of `rescaled` against `original` and the scale
// (printed with round-trip precision), plus any further options.
inline CommandResult CheckWithColmap4(const std::string& original,
                                      const std::string& rescaled,
                                      double scale,
                                      std::vector<std::string> extra = {}) {
  char s[64];
  std::snprintf(s, sizeof(s), "%.17g", scale);
  std::vector<std::string> args = {"check", original, rescaled, s};
  args.insert(args.end(), extra.begin(), extra.end());
  return RunColmap4Oracle(args);
}

// Copies the regular files of `from` (not sub-folders) into `to`.
inline void CopyFolderFiles(const std::string& from, const std::string& to) {
  std::filesystem::create_directories(to);
  for (std::filesystem::directory_iterator it(from), end; it != end; ++it) {
    if (std::filesystem::is_regular_file(it->path())) {
      std::filesystem::copy_file(
          it->path(), std::filesystem::path(to) / it->path().filename());
    }
  }
}

// A folder of ../shared: the environment variable `env`, else
// ../shared/<name> beside the source tree, else /work/shared/<name>; the
// first that holds `marker` (a file or folder), or "" when none does.
inline std::string SharedDataDir(const char* env,
                                 const std::string& name,
                                 const std::string& marker) {
  std::vector<std::string> candidates;
  if (const char* value = std::getenv(env)) candidates.push_back(value);
  candidates.push_back(std::string(DPSFM_SOURCE_DIR) + "/../shared/" + name);
  candidates.push_back("/work/shared/" + name);
  for (const std::string& c : candidates) {
    if (std::filesystem::exists(std::filesystem::path(c) / marker)) {
      return std::filesystem::canonical(c).string();
    }
  }
  return "";
}

// The real DP captures (DPSFM_REALDP_DIR, ../shared/realdp).
inline std::string RealDpDir() {
  return SharedDataDir("DPSFM_REALDP_DIR", "realdp", "canon_r6m2_rf50");
}

// Files written by real cameras, for the metadata readers (DPSFM_EXIF_DIR,
// ../shared/exif).
inline std::string RealExifDir() {
  return SharedDataDir("DPSFM_EXIF_DIR", "exif", "README.md");
}

}  // namespace test
}  // namespace dpsfm
