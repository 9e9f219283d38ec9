// Finding and reading the DP views of a model's images.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/colmap/workspace.h"

namespace dpsfm {

// The DP view files that belong to one model image.
struct DPFramePaths {
  std::string left;
  std::string right;  // empty when the right view comes from sum - left
  std::string sum;
};

// Index of the DP view folders, built once. A model image `<name>` (relative
// path with sub-folders, as stored in the model) matches left/<name>; when
// that file is absent, the file with the same path minus extension (e.g.
// model IMG_1.JPG, DP view left/IMG_1.png).
class DPImageIndex {
 public:
  explicit DPImageIndex(const WorkspaceLayout& layout);

  // Throws InputError naming the image and the missing view.
  DPFramePaths Find(const std::string& image_name) const;
  // False if the image has no left view at all (lets the caller list every
  // missing image in one message).
  bool HasLeft(const std::string& image_name) const;

 private:
  struct Folder {
    std::string root;
    // relative path -> full path; relative path without extension -> paths.
    std::map<std::string, std::string> by_name;
    std::map<std::string, std::vector<std::string>> by_stem;
  };
  static Folder Scan(const std::string& root);
  static std::string Lookup(const Folder& folder,
                            const std::string& name,
                            const std::string& what);

  Folder left_;
  Folder right_;
  Folder sum_;
  bool has_right_ = false;
};

// Reads an 8- or 16-bit grey or colour PNG/TIFF/JPEG as CV_32FC1 or CV_32FC3
// in [0, 1] (16-bit divided by 65535, 8-bit by 255). Throws InputError for a
// missing, unreadable or unsupported file.
cv::Mat ReadImageAsFloat(const std::string& path);

struct DPFrames {
  cv::Mat left;
  cv::Mat right;
};

// Loads one image's DP views. With a sum frame, right = sum - left (Canon's
// DPRSplit gives A and A+B in the same units). `swap_views` exchanges left and
// right for sensors with the opposite naming.
DPFrames LoadDPFrames(const DPFramePaths& paths, bool swap_views);

// The integer factor k with frame size = camera size / k (phones give half
// size DP frames), or throws InputError naming the image and both sizes.
int DPFrameDownsampling(const cv::Size& frame_size,
                        int camera_width,
                        int camera_height,
                        const std::string& image_name);

}  // namespace dpsfm
