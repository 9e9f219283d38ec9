#include "dpsfm/colmap/io/dp_images.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <future>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <opencv2/imgproc.hpp>

#include "colmap/util/string.h"
#include "dpsfm/colmap/io/png_decoder.h"
#include "dpsfm/colmap/io/text.h"
#include "dpsfm/colmap/util/durable_file.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;

}  // namespace

DPImageIndex::DPImageIndex(const WorkspaceLayout& layout)
    : left_(layout.left_path),
      right_(layout.right_path),
      sum_(layout.sum_path),
      has_right_(!layout.right_path.empty()) {}

std::string DPImageIndex::Lookup(const FileIndex& folder,
                                 const std::string& name,
                                 const std::string& what) {
  const std::string exact = folder.Exact(name);
  if (!exact.empty()) return exact;
  const std::vector<std::string>& stem = folder.SameStem(name);
  if (stem.empty()) {
    throw InputError("no " + what + " DP view for image " + name + " in " +
                     folder.root());
  }
  if (stem.size() > 1) {
    std::ostringstream message;
    message << "ambiguous " << what << " DP view for image " << name << ": ";
    for (size_t i = 0; i < stem.size(); ++i) {
      message << (i > 0 ? ", " : "") << stem[i];
    }
    throw InputError(message.str());
  }
  return stem.front();
}

std::string DPImageIndex::LeftPath(const std::string& image_name) const {
  return HasLeft(image_name) ? Lookup(left_, image_name, "left") : "";
}

bool DPImageIndex::HasLeft(const std::string& image_name) const {
  return !left_.Find(image_name).empty();
}

DPFramePaths DPImageIndex::Find(const std::string& image_name) const {
  DPFramePaths paths;
  paths.left = Lookup(left_, image_name, "left");
  if (has_right_) {
    paths.right = Lookup(right_, image_name, "right");
  } else {
    paths.sum = Lookup(sum_, image_name, "sum");
  }
  return paths;
}

namespace {

// Channels 0 and 2 of every pixel exchanged in place (RGB <-> BGR, RGBA <->
// BGRA). By hand because cv::cvtColor into its own input first clones the
// whole frame (36 MB at 3000 x 2000 in 16-bit colour, fresh pages while a
// read is at its peak) and takes 4x this loop's time.
template <typename T>
void SwapRedAndBlue(cv::Mat* pixels) {
  const int channels = pixels->channels();
  for (int y = 0; y < pixels->rows; ++y) {
    T* p = pixels->ptr<T>(y);
    for (int x = 0; x < pixels->cols; ++x, p += channels) std::swap(p[0], p[2]);
  }
}

// No format DP frames come in stores its pixels more than 4096 times
// smaller (deflate at most 1032:1, LZW about 2700:1): a header that claims
// more is corrupt, and is refused before its frame is allocated.
constexpr double kMaxCompressionRatio = 4096;

void CheckFrameFitsTheFile(int width,
                           int height,
                           int bytes_per_pixel,
                           size_t file_bytes,
                           const std::string& path) {
  const double frame_bytes =
      static_cast<double>(width) * height * bytes_per_pixel;
  if (frame_bytes > kMaxCompressionRatio * static_cast<double>(file_bytes) +
                        65536) {
    throw InputError("DP view's header claims " + std::to_string(width) +
                     " x " + std::to_string(height) +
                     " pixels, more than its " + std::to_string(file_bytes) +
                     " bytes can hold (corrupt file): " + path);
  }
}

// Decodes an image file's bytes with OpenImageIO, the library COLMAP 4 reads
// images with, so that any frame COLMAP reads, the plugin reads; plain PNGs
// with libdeflate instead (png_decoder.h), to the same bits in half the
// time. Returns the pixels as OpenCV's decoder would (8-bit, 16-bit or float;
// colour in BGR order), or an empty matrix. The bytes are decoded in memory
// where the format allows it; other formats are opened by name (a second
// read), as is a PNG whose pixel data libdeflate found corrupt, so that
// OpenImageIO decides what to make of it.
cv::Mat DecodeImage(std::string bytes, const std::string& path) {
  const size_t file_bytes = bytes.size();
  cv::Mat png;
  const PngDecoding decoding = DecodePng(&bytes, &png);
  if (decoding == PngDecoding::kDecoded) return png;
  OIIO::Filesystem::IOMemReader memory(bytes.data(), bytes.size());
  std::unique_ptr<OIIO::ImageInput> input =
      decoding == PngDecoding::kNotDecoded
          ? OIIO::ImageInput::open(path, nullptr, &memory)
          : nullptr;
  if (!input) input = OIIO::ImageInput::open(path);
  if (!input) {
    OIIO::geterror();  // clears OpenImageIO's per-thread error
    return cv::Mat();
  }
  const OIIO::ImageSpec& spec = input->spec();
  const int channels = spec.nchannels;
  if (channels < 1 || channels > 4 || spec.width <= 0 || spec.height <= 0) {
    return cv::Mat();
  }
  OIIO::TypeDesc format = OIIO::TypeDesc::FLOAT;
  int depth = CV_32F;
  if (spec.format == OIIO::TypeDesc::UINT8) {
    format = OIIO::TypeDesc::UINT8;
    depth = CV_8U;
  } else if (spec.format == OIIO::TypeDesc::UINT16) {
    format = OIIO::TypeDesc::UINT16;
    depth = CV_16U;
  }
  CheckFrameFitsTheFile(spec.width,
                        spec.height,
                        channels * static_cast<int>(CV_ELEM_SIZE1(depth)),
                        file_bytes,
                        path);
  cv::Mat pixels(spec.height, spec.width, CV_MAKETYPE(depth, channels));
  // 8- and 16-bit files are read as they are stored (TypeDesc::UNKNOWN):
  // asked for their own type by name, OpenImageIO decodes into a buffer of
  // its own and copies (68 MB for a 16-bit colour frame of 3000 x 2000).
  if (format == spec.format && spec.channelformats.empty()) {
    format = OIIO::TypeDesc::UNKNOWN;
  }
  if (!input->read_image(0, 0, 0, channels, format, pixels.data)) {
    input->geterror();
    return cv::Mat();
  }
  if (channels >= 3) {
    if (depth == CV_8U) {
      SwapRedAndBlue<uint8_t>(&pixels);
    } else if (depth == CV_16U) {
      SwapRedAndBlue<uint16_t>(&pixels);
    } else {
      SwapRedAndBlue<float>(&pixels);
    }
  }
  return pixels;
}

}  // namespace

DPFrameFile ReadDPFrameFile(const std::string& path) {
  if (!fs::is_regular_file(path)) {
    throw InputError("DP view does not exist: " + path);
  }
  DPFrameFile file;
  cv::Mat raw;
  {
    // Read once: the pixels and what the file declares about its encoding
    // come from the same bytes, released before the conversion below.
    std::string bytes = ReadFileBytes(path);
    file.declared = ParseDeclaredEncoding(bytes);
    if (!bytes.empty()) raw = DecodeImage(std::move(bytes), path);
  }
  if (raw.empty()) {
    throw InputError("cannot read DP view (corrupt or unsupported format): " +
                     path);
  }
  switch (raw.depth()) {
    case CV_8U:
      file.bits = 8;
      break;
    case CV_16U:
      file.bits = 16;
      break;
    default:
      file.bits = 32;  // floating point (EXR, float TIFF)
      break;
  }
  std::string extension = fs::path(path).extension().string();
  colmap::StringToLower(&extension);
  file.lossy = extension == ".jpg" || extension == ".jpeg";
  switch (raw.channels()) {
    case 1:
    case 3:
      file.pixels = raw;
      break;
    case 4:
      cv::cvtColor(raw, file.pixels, cv::COLOR_BGRA2BGR);
      break;
    case 2:
      // Grey + alpha.
      cv::extractChannel(raw, file.pixels, 0);
      break;
    default:
      throw InputError("DP view has an unsupported channel count: " + path);
  }
  return file;
}

cv::Mat DPFrameValues(const DPFrameFile& file, const cv::Range& rows) {
  const double unit = file.bits == 8 ? 255.0 : file.bits == 16 ? 65535.0 : 1.0;
  cv::Mat values;
  file.pixels.rowRange(rows).convertTo(
      values, CV_MAKETYPE(CV_32F, file.pixels.channels()), 1.0 / unit);
  return values;
}

namespace {

// A file's view in linear light, reduced when `reduction` says so, and the
// file's pixels released. Where the reduction allows it (strip_rows), a
// strip of rows at a time: a 3000 x 2000 colour view is then never held in
// float at full size (72 MB), only its pixels as decoded and the reduced
// view; each strip's values are those of the whole frame's, to the bit.
cv::Mat LinearView(DPFrameFile* file,
                   DPEncoding encoding,
                   const FrameReduction* reduction) {
  const bool reduce = reduction != nullptr && reduction->reduce;
  const cv::Size size = file->pixels.size();
  const int k =
      reduce && reduction->strip_rows ? reduction->strip_rows(size) : 0;
  cv::Mat view;
  if (k > 0) {
    const int strip = 64 * k;  // 64 reduced rows
    for (int y = 0; y < size.height; y += strip) {
      const cv::Range rows(y, std::min(size.height, y + strip));
      cv::Mat values = DPFrameValues(*file, rows);
      DecodeToLinearLight(encoding, &values);
      const cv::Mat part = reduction->reduce(values, size);
      if (part.rows * k != rows.size()) {
        throw std::logic_error("a frame reduction by " + std::to_string(k) +
                               " gave " + std::to_string(part.rows) +
                               " rows for " + std::to_string(rows.size()));
      }
      if (view.empty()) view.create(size.height / k, part.cols, part.type());
      part.copyTo(view.rowRange(y / k, y / k + part.rows));
    }
    file->pixels.release();
    return view;
  }
  view = DPFrameValues(*file);
  file->pixels.release();
  DecodeToLinearLight(encoding, &view);
  return reduce ? reduction->reduce(view, size) : view;
}

}  // namespace

DPEncoding DecideEncoding(DPEncoding requested,
                          const DPFrameFile& file,
                          std::string* reason) {
  if (requested != DPEncoding::kAuto) {
    *reason = "--DPScaleEstimator.dp_encoding";
    return requested;
  }
  if (file.declared.encoding != DPEncoding::kAuto) {
    *reason = file.declared.evidence;
    return file.declared.encoding;
  }
  *reason = std::to_string(file.bits) + "-bit file";
  return file.bits <= 8 ? DPEncoding::kSrgb : DPEncoding::kLinear;
}

DPFrames LoadDPFrames(const DPFramePaths& paths,
                      bool swap_views,
                      DPEncoding encoding,
                      const FrameReduction& reduction,
                      bool decode_together) {
  const bool from_sum = paths.right.empty();
  const std::string& other_path = from_sum ? paths.sum : paths.right;
  DPFrames frames;
  // The left view first, brought to linear light by its own encoding (the
  // other file must agree, below) and reduced before the other is read (or
  // while it is decoded, with decode_together); with a sum frame it is
  // needed at full size for the subtraction. The other file's errors come
  // after the left's either way.
  std::future<DPFrameFile> other;
  if (decode_together) {
    other = std::async(std::launch::async, ReadDPFrameFile, other_path);
  }
  DPFrameFile first = ReadDPFrameFile(paths.left);
  frames.encoding = DecideEncoding(encoding, first, &frames.encoding_reason);
  frames.frame_size = first.pixels.size();
  const int channels = first.pixels.channels();
  frames.bits = first.bits;
  frames.lossy = first.lossy;
  frames.left =
      LinearView(&first, frames.encoding, from_sum ? nullptr : &reduction);
  DPFrameFile second =
      decode_together ? other.get() : ReadDPFrameFile(other_path);
  if (second.pixels.size() != frames.frame_size ||
      second.pixels.channels() != channels) {
    std::ostringstream message;
    message << "DP views differ in size or channels: " << paths.left << " is "
            << frames.frame_size.width << "x" << frames.frame_size.height << "x"
            << channels << ", " << other_path << " is " << second.pixels.cols
            << "x" << second.pixels.rows << "x" << second.pixels.channels();
    throw InputError(message.str());
  }
  std::string other_reason;
  const DPEncoding other_encoding =
      DecideEncoding(encoding, second, &other_reason);
  if (other_encoding != frames.encoding) {
    throw InputError("DP views encode light differently: " + paths.left +
                     " is " + DPEncodingName(frames.encoding) + " (" +
                     frames.encoding_reason + "), " + other_path + " is " +
                     DPEncodingName(other_encoding) + " (" + other_reason +
                     "); export both views the same way, or set "
                     "--DPScaleEstimator.dp_encoding");
  }
  frames.bits = std::min(frames.bits, second.bits);
  frames.lossy = frames.lossy || second.lossy;
  if (from_sum) {
    // right = sum - left. A "sum" frame darker than the left view means the
    // files are not A and A+B.
    frames.right = LinearView(&second, frames.encoding, nullptr) - frames.left;
    const double mean_right = cv::mean(frames.right)[0];
    if (mean_right < 0.05 * cv::mean(frames.left)[0]) {
      throw InputError("sum frame " + paths.sum +
                       " is not brighter than its left view " + paths.left +
                       "; expected A+B and A frames in the same units");
    }
    cv::max(frames.right, 0.0, frames.right);
    if (reduction.reduce) {
      frames.left = reduction.reduce(frames.left, frames.frame_size);
      frames.right = reduction.reduce(frames.right, frames.frame_size);
    }
  } else {
    frames.right = LinearView(&second, frames.encoding, &reduction);
  }
  if (swap_views) {
    std::swap(frames.left, frames.right);
  }
  return frames;
}

int DPFrameDownsampling(const cv::Size& frame_size,
                        int camera_width,
                        int camera_height,
                        const std::string& image_name) {
  if (frame_size.width > 0 && frame_size.height > 0) {
    for (int k = 1; k <= 8; ++k) {
      // Allow rounding either way of an odd camera size.
      if (std::abs(frame_size.width * k - camera_width) < k &&
          std::abs(frame_size.height * k - camera_height) < k) {
        return k;
      }
    }
  }
  std::ostringstream message;
  message << "DP views of image " << image_name << " are " << frame_size.width
          << "x" << frame_size.height << ", but the model's camera is "
          << camera_width << "x" << camera_height
          << " (expected the same size or an integer fraction of it)";
  throw InputError(message.str());
}

}  // namespace dpsfm
