#include "dpsfm/colmap/io/psf_library.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "colmap/util/string.h"
#include "dpsfm/colmap/io/psf_profile.h"
#include "dpsfm/colmap/io/text.h"
#include "dpsfm/colmap/io/workspace.h"

namespace fs = std::filesystem;

namespace dpsfm {

namespace {

std::string Key(const std::string& text) {
  std::string key = Trim(text);
  colmap::StringToLower(&key);
  return key;
}

}  // namespace

std::string FindLibraryProfile(const std::string& library_dir,
                               const std::string& camera,
                               const std::string& lens,
                               std::vector<std::string>* skipped) {
  if (Key(camera).empty() || Key(lens).empty() ||
      !fs::is_directory(library_dir)) {
    return "";
  }
  std::vector<std::string> files;
  for (fs::directory_iterator it(library_dir), end; it != end; ++it) {
    if (fs::is_regular_file(it->path()) && it->path().extension() == ".dpsf") {
      files.push_back(it->path().string());
    }
  }
  std::sort(files.begin(), files.end());
  for (const std::string& file : files) {
    try {
      const PsfProfileFile profile = ReadPsfProfile(file);
      if (Key(profile.camera) == Key(camera) &&
          Key(profile.lens) == Key(lens)) {
        return file;
      }
    } catch (const InputError& e) {
      if (skipped) skipped->push_back(e.what());
    }
  }
  return "";
}

std::string DefaultProfileLibrary() {
  if (const char* env = std::getenv("DPSFM_PROFILE_LIBRARY")) return env;
  if (const char* data = std::getenv("XDG_DATA_HOME")) {
    return (fs::path(data) / "dp-sfm/profiles").string();
  }
  const char* home = std::getenv("HOME");
  return (fs::path(home ? home : ".") / ".local/share/dp-sfm/profiles")
      .string();
}

}  // namespace dpsfm
