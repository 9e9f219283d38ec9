// The files under a folder, found by a model image's name: its exact
// relative path (sub-folders kept), else a file with the same path minus
// its extension (model IMG_1.JPG: IMG_1.png, IMG_1.CR3). Scanned once.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace dpsfm {

class FileIndex {
 public:
  // Every regular file under `root`; an empty root indexes nothing.
  explicit FileIndex(const std::string& root = "");

  const std::string& root() const { return root_; }

  // The file named `name` relative to the root, "" if none.
  std::string Exact(const std::string& name) const;
  // The files whose path minus extension is `name`'s, in name order.
  const std::vector<std::string>& SameStem(const std::string& name) const;
  // Exact, else the first of SameStem, else "".
  std::string Find(const std::string& name) const;

 private:
  std::string root_;
  std::map<std::string, std::string> by_name_;
  std::map<std::string, std::vector<std::string>> by_stem_;
};

}  // namespace dpsfm
