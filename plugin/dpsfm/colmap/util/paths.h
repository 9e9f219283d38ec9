// Path and file-name tests the rescale and its plan share, and the one
// maker of unique folders (header-only: the tests' temporary folders use it
// too).
#pragma once

#include <filesystem>
#include <random>
#include <string>
#include <system_error>

namespace dpsfm {

inline bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// True if `path` is `dir` or below it (both absolute and normalised).
inline bool IsWithin(const std::filesystem::path& path,
                     const std::filesystem::path& dir) {
  const std::filesystem::path relative = path.lexically_relative(dir);
  if (relative.empty()) return false;
  return *relative.begin() != "..";
}

// True if something (a file, a folder, even a dangling link) is at `path`.
inline bool PathExists(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::exists(std::filesystem::symlink_status(path, ec));
}

// A new, empty folder under `parent` named `prefix` and six random
// characters; empty, with *error set, if none could be made. Written here
// because std::filesystem has no mkdtemp: create_directory reports a name
// that exists (returns false), and another name is drawn.
inline std::filesystem::path MakeUniqueDirectory(
    const std::filesystem::path& parent,
    const std::string& prefix,
    std::error_code* error) {
  static const char kChars[] = "abcdefghijklmnopqrstuvwxyz0123456789";
  thread_local std::mt19937_64 random(std::random_device{}());
  std::uniform_int_distribution<int> pick(0, sizeof(kChars) - 2);
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::string name = prefix;
    for (int k = 0; k < 6; ++k) name += kChars[pick(random)];
    const std::filesystem::path path = parent / name;
    if (std::filesystem::create_directory(path, *error)) return path;
    if (*error) return {};
  }
  *error = std::make_error_code(std::errc::file_exists);
  return {};
}

// Whether entries can be made in the folder `dir`, tried by making and
// removing one there (what a write will do, read-only mounts included,
// where permission bits alone can say yes); *why says why not.
inline bool CanCreateIn(const std::filesystem::path& dir, std::string* why) {
  std::error_code error;
  const std::filesystem::path probe =
      MakeUniqueDirectory(dir, ".dpsfm-write-check-", &error);
  if (probe.empty()) {
    *why = error.message();
    return false;
  }
  std::filesystem::remove(probe, error);
  return true;
}

}  // namespace dpsfm
