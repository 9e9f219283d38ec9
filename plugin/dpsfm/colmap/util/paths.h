// Path and file-name tests the rescale and its plan share.
#pragma once

#include <filesystem>
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

}  // namespace dpsfm
