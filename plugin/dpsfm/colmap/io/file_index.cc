#include "dpsfm/colmap/io/file_index.h"

#include <algorithm>
#include <filesystem>

#include "dpsfm/colmap/io/text.h"

namespace fs = std::filesystem;

namespace dpsfm {

FileIndex::FileIndex(const std::string& root) : root_(root) {
  if (root.empty()) return;
  for (fs::recursive_directory_iterator it(root), end; it != end; ++it) {
    if (!fs::is_regular_file(it->path())) continue;
    const std::string relative =
        fs::relative(it->path(), root).generic_string();
    by_name_[relative] = it->path().string();
    by_stem_[StripExtension(relative)].push_back(it->path().string());
  }
  for (auto& stem : by_stem_) std::sort(stem.second.begin(), stem.second.end());
}

std::string FileIndex::Exact(const std::string& name) const {
  const auto found = by_name_.find(name);
  return found == by_name_.end() ? "" : found->second;
}

const std::vector<std::string>& FileIndex::SameStem(
    const std::string& name) const {
  static const std::vector<std::string> kNone;
  const auto found = by_stem_.find(StripExtension(name));
  return found == by_stem_.end() ? kNone : found->second;
}

std::string FileIndex::Find(const std::string& name) const {
  const std::string exact = Exact(name);
  if (!exact.empty()) return exact;
  const std::vector<std::string>& same = SameStem(name);
  return same.empty() ? "" : same.front();
}

}  // namespace dpsfm
