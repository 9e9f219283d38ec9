// Finding and reading the DP views of a model's images.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/colmap/io/file_index.h"
#include "dpsfm/colmap/io/image_metadata.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/core/optics/encoding.h"

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
  // The left view's file, "" when there is none.
  std::string LeftPath(const std::string& image_name) const;

 private:
  static std::string Lookup(const FileIndex& folder,
                            const std::string& name,
                            const std::string& what);

  FileIndex left_;
  FileIndex right_;
  FileIndex sum_;
  bool has_right_ = false;
};

// One DP frame file as encoded, decoded by OpenImageIO (as COLMAP 4 reads
// images): `pixels` as decoded, CV_8U, CV_16U or CV_32F with one or three
// channels, colour in B, G, R order (an alpha channel dropped). Throws
// InputError for a missing, unreadable or unsupported file.
struct DPFrameFile {
  cv::Mat pixels;
  int bits = 0;               // 8, 16 or 32 (float) per channel
  bool lossy = false;         // JPEG
  DeclaredEncoding declared;  // ParseDeclaredEncoding of the same bytes
};
DPFrameFile ReadDPFrameFile(const std::string& path);

// Rows `rows` of a file's pixels as CV_32FC1 or CV_32FC3: 16-bit values
// divided by 65535, 8-bit by 255, floating-point ones as stored.
cv::Mat DPFrameValues(const DPFrameFile& file,
                      const cv::Range& rows = cv::Range::all());

// How a frame's values encode light (docs/user-guide.md, "Capturing"): the
// requested encoding when it is not kAuto; otherwise what the file declares
// (DPFrameFile::declared: PNG sRGB / iCCP / gAMA chunks, EXIF ColorSpace
// sRGB), else its bit depth: 8-bit files are sRGB (exports, phone
// captures), 16-bit and floating-point ones linear (DPRSplit output, raw).
// `reason` says which rule decided.
DPEncoding DecideEncoding(DPEncoding requested,
                          const DPFrameFile& file,
                          std::string* reason);

struct DPFrames {
  // Linear light, [0, 1]; reduced when LoadDPFrames was given a reduction.
  cv::Mat left;
  cv::Mat right;
  cv::Size frame_size;  // as decoded
  // What the files were, and why.
  DPEncoding encoding = DPEncoding::kLinear;
  std::string encoding_reason;
  int bits = 0;
  bool lossy = false;
};

// A reduction of each view to the working resolution as soon as it is in
// linear light (DPScaleEstimator::ReduceFrame, ReduceFrameStripRows).
struct FrameReduction {
  // Reduces rows of a frame of `frame_size`: all of them, or a strip (null:
  // no reduction).
  std::function<cv::Mat(const cv::Mat& rows, const cv::Size& frame_size)>
      reduce;
  // For frames of a size, k > 0 when `reduce` of any strip of a multiple of
  // k rows gives those rows' share of the reduced frame (null or 0: whole
  // frames only). Then a view is converted, brought to linear light and
  // reduced a strip at a time, never held in float at full size.
  std::function<int(const cv::Size& frame_size)> strip_rows;
};

// Loads one image's DP views and brings them to linear light. With a sum
// frame, right = sum - left in linear light (Canon's DPRSplit gives A and
// A+B in the same units). `swap_views` exchanges left and right for sensors
// with the opposite naming. Throws InputError when the two files differ in
// size, channels or encoding. A reduction (FrameReduction) replaces each
// view as soon as it is in linear light (a sum frame's right view after
// the subtraction), so a read holds one decoded frame at a time, as
// LoadView does with DPScaleEstimator::ReduceFrame. With `decode_together`
// the second file is read and decoded on a thread of its own while the
// first is brought to linear light: two decoded frames are held at once,
// for about half the read's time where a core is free.
DPFrames LoadDPFrames(const DPFramePaths& paths,
                      bool swap_views,
                      DPEncoding encoding = DPEncoding::kAuto,
                      const FrameReduction& reduction = {},
                      bool decode_together = false);

// The integer factor k with frame size = camera size / k (phones give half
// size DP frames), or throws InputError naming the image and both sizes.
int DPFrameDownsampling(const cv::Size& frame_size,
                        int camera_width,
                        int camera_height,
                        const std::string& image_name);

}  // namespace dpsfm
