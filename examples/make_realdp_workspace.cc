// Makes a complete single-view scale problem from a real DP capture with
// measured depth (the layout of ../shared/realdp: l.png, r.png, d.png): a
// COLMAP dense workspace with one PINHOLE view whose geometric depth map is
// the measured depth divided by a known factor (the "up to scale" depth),
// the DP views under dp/left and dp/right, a lens.csv, and truth.json with
// the factor the estimator must recover (metres per model unit).
//
//   dpsfm_make_realdp_workspace --capture_path CAPTURE --output_path OUT
//       [--true_scale 0.37] [--focal_length_mm 49.57] [--f_number 4]
//       [--pixel_pitch_um 46.875] [--name scene] [--recorded_focus_m 1.0]
//       [--linear16 1] [--frames_only 1]
//
// --linear16 writes the DP views as 16-bit linear light (the sRGB decoding
// curve applied to the 8-bit files, as DPRSplit output would be) instead of
// copying them; --frames_only writes only dp/left and dp/right (calibration
// captures have no depth).
//
// Depth files: 16-bit single channel = millimetres (0 = none); 8-bit RGB(A)
// = metres x 255 / 10 in the first channel (the DP119 "box" scenes), at any
// resolution (area-resized to the frame; patches straddling depth edges are
// the estimator's to reject).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colmap/mvs/depth_map.h"
#include "colmap/scene/reconstruction.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/core/optics/encoding.h"

namespace fs = std::filesystem;
namespace po = boost::program_options;

namespace {

// Measured depth in metres at the frame's size; 0 where unknown.
cv::Mat ReadDepthMetres(const std::string& path, const cv::Size& frame) {
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty()) throw std::runtime_error("cannot read " + path);
  cv::Mat metres;
  if (raw.depth() == CV_16U && raw.channels() == 1) {
    raw.convertTo(metres, CV_32FC1, 1e-3);
  } else if (raw.depth() == CV_8U) {
    cv::Mat first;
    cv::extractChannel(raw, first, raw.channels() >= 3 ? 2 : 0);  // BGR(A)
    first.convertTo(metres, CV_32FC1, 10.0 / 255.0);
  } else {
    throw std::runtime_error(path + ": unknown depth encoding");
  }
  if (metres.size() != frame) {
    // Area averaging mixes depths only across edges; the mask keeps holes
    // from pulling neighbours towards 0.
    cv::Mat valid = metres > 0;
    valid.convertTo(valid, CV_32FC1, 1.0 / 255);
    cv::Mat sum, weight;
    cv::resize(metres, sum, frame, 0, 0, cv::INTER_AREA);
    cv::resize(valid, weight, frame, 0, 0, cv::INTER_AREA);
    metres = cv::Mat::zeros(frame, CV_32FC1);
    for (int r = 0; r < frame.height; ++r) {
      for (int c = 0; c < frame.width; ++c) {
        const float w = weight.at<float>(r, c);
        if (w > 0.99f) metres.at<float>(r, c) = sum.at<float>(r, c) / w;
      }
    }
  }
  return metres;
}

// The command line.
struct Arguments {
  std::string capture, output, name = "view";
  double true_scale = 0.37, focal_mm = 49.57, f_number = 4, pitch_um = 46.875;
  double recorded_focus_m = 0;
  bool linear16 = false, frames_only = false;
};

// The model depth map's range (model units) and its number of valid pixels.
struct DepthRange {
  double lo = 1e30, hi = 0;
  int valid = 0;
};

// The options, in the order --help lists them.
void AddOptions(po::options_description* desc, Arguments* args) {
  desc->add_options()("help,h", "print this help")(
      "capture_path",
      po::value(&args->capture)->required(),
      "folder with l.png, r.png, d.png")("output_path",
                                         po::value(&args->output)->required(),
                                         "workspace to create")(
      "true_scale", po::value(&args->true_scale), "metres per model unit")(
      "focal_length_mm", po::value(&args->focal_mm), "lens focal length")(
      "f_number", po::value(&args->f_number), "aperture")(
      "pixel_pitch_um", po::value(&args->pitch_um), "DP frame pixel pitch")(
      "name", po::value(&args->name), "image name (without extension)")(
      "recorded_focus_m",
      po::value(&args->recorded_focus_m),
      "focus distance the camera recorded (lens.csv; 0: none)")(
      "linear16",
      po::value(&args->linear16),
      "write the DP views as 16-bit linear light (the inverse sRGB of the "
      "8-bit files)")("frames_only",
                      po::value(&args->frames_only),
                      "write only dp/left and dp/right");
}

// --help: what the program makes, its usage and the options.
void PrintHelp(const po::options_description& desc) {
  std::cout << "dpsfm_make_realdp_workspace\n\n"
               "  Makes a COLMAP dense workspace from one DP capture with "
               "measured depth\n"
               "  (a folder with l.png, r.png and d.png, the layout of "
               "../shared/realdp):\n"
               "  one PINHOLE view whose depth map is the measured depth "
               "divided by\n"
               "  --true_scale (the \"up to scale\" depth a reconstruction "
               "would have),\n"
               "  the DP views in dp/left and dp/right, a lens.csv and "
               "truth.json.\n"
               "  colmap dp_scale_estimator must then recover --true_scale "
               "(docs/user-guide.md,\n"
               "  \"A first hour\"). d.png: 16-bit = millimetres, 8-bit = "
               "metres x 255 / 10.\n\n"
               "Usage:\n"
               "  dpsfm_make_realdp_workspace --capture_path CAPTURE "
               "--output_path OUT\n"
               "      [--true_scale 0.37] [--recorded_focus_m 1.0] "
               "[--frames_only 1]\n\n"
            << desc << "\n";
}

// The capture's DP views, l.png and r.png, of equal size.
void ReadViews(const std::string& capture, cv::Mat* left, cv::Mat* right) {
  const fs::path in(capture);
  *left = cv::imread((in / "l.png").string(), cv::IMREAD_UNCHANGED);
  *right = cv::imread((in / "r.png").string(), cv::IMREAD_UNCHANGED);
  if (left->empty() || right->empty() || left->size() != right->size()) {
    throw std::runtime_error("cannot read l.png / r.png of equal size in " +
                             capture);
  }
}

// dp/<side>/<image_name>: the view as read, or as 16-bit linear light.
void WriteView(const cv::Mat& view,
               const char* side,
               const fs::path& out,
               const std::string& image_name,
               bool linear16) {
  const std::string path = (out / "dp" / side / image_name).string();
  if (!linear16) {
    cv::imwrite(path, view);
    return;
  }
  if (view.depth() != CV_8U) {
    throw std::runtime_error("--linear16 needs 8-bit sRGB views");
  }
  cv::Mat light;
  view.convertTo(light, CV_32F, 1.0 / 255);
  dpsfm::DecodeToLinearLight(dpsfm::DPEncoding::kSrgb, &light);
  cv::Mat u16;
  light.convertTo(u16, CV_16U, 65535.0);
  cv::imwrite(path, u16);
}

// The geometric depth map of model depths z' = z / s at `path`; returns
// their range.
DepthRange WriteModelDepthMap(const cv::Mat& metres,
                              const Arguments& args,
                              const std::string& path) {
  DepthRange range;
  colmap::mvs::DepthMap map(metres.cols, metres.rows, 0, 1);
  for (int r = 0; r < metres.rows; ++r) {
    for (int c = 0; c < metres.cols; ++c) {
      const float z = metres.at<float>(r, c);
      // Time-of-flight dropouts read a few mm; nothing is in focus nearer
      // than 0.2 m with these lenses.
      const float model =
          z > 0.2f ? static_cast<float>(z / args.true_scale) : 0.f;
      map.Set(r, c, model);
      if (model > 0) {
        range.lo = std::min(range.lo, static_cast<double>(model));
        range.hi = std::max(range.hi, static_cast<double>(model));
        ++range.valid;
      }
    }
  }
  if (range.valid == 0) {
    throw std::runtime_error("no valid depth in " + args.capture);
  }
  colmap::mvs::DepthMap ranged(metres.cols, metres.rows, range.lo, range.hi);
  for (int r = 0; r < metres.rows; ++r) {
    for (int c = 0; c < metres.cols; ++c) ranged.Set(r, c, map.Get(r, c));
  }
  ranged.Write(path);
  return range;
}

// dense/sparse: one PINHOLE camera and its view at the origin.
void WriteModel(const Arguments& args,
                const fs::path& out,
                const std::string& image_name,
                const cv::Size& size) {
  const double focal_px = args.focal_mm / (args.pitch_um * 1e-3);
  colmap::Reconstruction reconstruction;
  dpsfm::AddCamera(&reconstruction,
                   colmap::Camera::CreateFromModelName(
                       1, "PINHOLE", focal_px, size.width, size.height));
  colmap::Image image;
  image.SetImageId(1);
  image.SetName(image_name);
  image.SetCameraId(1);
  dpsfm::AddRegisteredImage(&reconstruction, image, colmap::Rigid3d());
  reconstruction.WriteBinary((out / "dense/sparse").string());
}

// lens.csv: the view's lens, with the recorded focus if there is one.
void WriteLensCsv(const Arguments& args,
                  const fs::path& out,
                  const std::string& image_name) {
  std::ofstream lens((out / "lens.csv").string());
  lens << "name,focal_length_mm,f_number,pixel_pitch_um"
       << (args.recorded_focus_m > 0 ? ",focus_distance_m" : "") << "\n"
       << image_name << "," << args.focal_mm << "," << args.f_number << ","
       << args.pitch_um;
  if (args.recorded_focus_m > 0) lens << "," << args.recorded_focus_m;
  lens << "\n";
}

// truth.json: the scale to recover and the measured depth's range.
void WriteTruth(const Arguments& args,
                const fs::path& out,
                const DepthRange& range,
                size_t num_pixels) {
  nlohmann::json truth = {
      {"true_scale", args.true_scale},
      {"capture", args.capture},
      {"depth_range_m",
       {range.lo * args.true_scale, range.hi * args.true_scale}},
      {"valid_depth_fraction", static_cast<double>(range.valid) / num_pixels}};
  std::ofstream((out / "truth.json").string()) << truth.dump(2) << "\n";
}

// Writes the workspace (or only the DP views, with --frames_only).
void MakeWorkspace(const Arguments& args) {
  if (!(args.true_scale > 0)) {
    throw std::runtime_error("true_scale must be > 0");
  }
  const fs::path in(args.capture), out(args.output);
  cv::Mat left, right;
  ReadViews(args.capture, &left, &right);
  const std::string image_name = args.name + ".png";
  fs::create_directories(out / "dp/left");
  fs::create_directories(out / "dp/right");
  WriteView(left, "left", out, image_name, args.linear16);
  WriteView(right, "right", out, image_name, args.linear16);
  if (args.frames_only) return;
  const cv::Mat metres = ReadDepthMetres((in / "d.png").string(), left.size());
  for (const char* dir :
       {"dense/sparse", "dense/images", "dense/stereo/depth_maps"}) {
    fs::create_directories(out / dir);
  }
  cv::Mat sum;
  cv::addWeighted(left, 0.5, right, 0.5, 0, sum);
  cv::imwrite((out / "dense/images" / image_name).string(), sum);
  const DepthRange range = WriteModelDepthMap(
      metres,
      args,
      (out / "dense/stereo/depth_maps" / (image_name + ".geometric.bin"))
          .string());
  WriteModel(args, out, image_name, left.size());
  WriteLensCsv(args, out, image_name);
  WriteTruth(args, out, range, left.total());
  std::cout << "workspace " << args.output << ": " << image_name << ", depth "
            << range.lo * args.true_scale << "-" << range.hi * args.true_scale
            << " m on " << 100.0 * range.valid / left.total()
            << " % of the frame, true scale " << args.true_scale << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  po::options_description desc("Options");
  AddOptions(&desc, &args);
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, desc), vm);
    if (vm.count("help")) {
      PrintHelp(desc);
      return 0;
    }
    po::notify(vm);
    MakeWorkspace(args);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "ERROR: dpsfm_make_realdp_workspace: " << e.what() << "\n";
    return 1;
  }
}
