#include "dpsfm/colmap/io/psf_profile.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "dpsfm/colmap/io/npy.h"
#include "dpsfm/colmap/io/text.h"
#include "dpsfm/colmap/io/workspace.h"

namespace fs = std::filesystem;

namespace dpsfm {
namespace {

// The kernels of a measured profile: (rows*cols, K, K), (rows, cols, K, K)
// as grid calibrations are often saved, or (K, K) for one cell.
std::vector<cv::Mat> ReadKernelStack(const std::string& path,
                                     const DPPsfLayout& layout,
                                     const std::string& where) {
  const int cells = layout.NumCells();
  const NpyArray array = ReadNpy(path);
  const std::vector<int>& shape = array.shape;
  const bool single = shape.size() == 2 && cells == 1;
  const bool stacked = shape.size() == 3 && shape[0] == cells;
  const bool grid =
      shape.size() == 4 && shape[0] == layout.rows && shape[1] == layout.cols;
  if (!(single || stacked || grid)) {
    std::ostringstream s;
    s << where << ": " << path << " has shape (";
    for (size_t i = 0; i < shape.size(); ++i) s << (i ? ", " : "") << shape[i];
    s << "); the grid needs (" << cells << ", K, K) or (" << layout.rows << ", "
      << layout.cols << ", K, K)";
    throw InputError(s.str());
  }
  const int rows = shape[shape.size() - 2], cols = shape.back();
  if (rows != cols || rows % 2 == 0 || rows < 1) {
    throw InputError(where + ": " + path + " holds kernels of " +
                     std::to_string(cols) + "x" + std::to_string(rows) +
                     "; they must be square with an odd side (centre pixel = "
                     "origin)");
  }
  std::vector<cv::Mat> kernels;
  const size_t per = static_cast<size_t>(rows) * cols;
  for (int c = 0; c < cells; ++c) {
    cv::Mat k(rows, cols, CV_32FC1);
    for (size_t i = 0; i < per; ++i) {
      k.at<float>(static_cast<int>(i / cols), static_cast<int>(i % cols)) =
          static_cast<float>(array.values[c * per + i]);
    }
    kernels.push_back(k);
  }
  return kernels;
}

std::vector<double> ParseNumbers(const std::string& text,
                                 const std::string& where) {
  std::istringstream stream(text);
  std::string item;
  std::vector<double> numbers;
  while (stream >> item) numbers.push_back(ParseNumber(item, where));
  return numbers;
}

// A profile file's key/value lines (fit_* lines aside), with where each
// was given for messages.
struct ProfileEntries {
  std::string path;
  std::map<std::string, std::string> values;
  std::map<std::string, int> lines;

  bool Has(const std::string& key) const { return values.count(key) > 0; }
  std::string Value(const std::string& key) const {
    const auto it = values.find(key);
    return it == values.end() ? std::string() : it->second;
  }
  std::string Where(const std::string& key) const {
    const auto it = lines.find(key);
    return path + ":" + std::to_string(it == lines.end() ? 0 : it->second);
  }
  double Number(const std::string& key) const {
    return ParseNumber(Value(key), Where(key));
  }
  // Keys that do not belong to `model` are refused.
  void Refuse(const std::vector<std::string>& keys,
              const std::string& model) const {
    for (const std::string& key : keys) {
      if (Has(key)) {
        throw InputError(Where(key) + ": '" + key +
                         "' does not belong to model " + model);
      }
    }
  }
};

// Reads the lines: "key value", '#' comments, known keys once each; fit_*
// lines go to profile->fit_info as they are.
ProfileEntries ReadProfileEntries(const std::string& path,
                                  PsfProfileFile* profile) {
  std::ifstream file(path);
  if (!file) throw InputError("cannot read DP PSF profile " + path);
  static const std::set<std::string> kKnown = {"format",
                                               "model",
                                               "split_exponent",
                                               "crosstalk",
                                               "rim_softness",
                                               "rim_brightness",
                                               "band_split_exponents",
                                               "reference_radius_px",
                                               "side",
                                               "grid",
                                               "region",
                                               "left",
                                               "right",
                                               "camera",
                                               "lens",
                                               "uncertainty",
                                               "light",
                                               "focal_length_mm",
                                               "f_number",
                                               "pixel_pitch_um",
                                               "frame_size",
                                               "blur_range_px"};
  ProfileEntries entries;
  entries.path = path;
  std::string line;
  int number = 0;
  while (std::getline(file, line)) {
    ++number;
    const std::string where = path + ":" + std::to_string(number);
    const std::string text = Trim(line.substr(0, line.find('#')));
    if (text.empty()) continue;
    const size_t space = text.find_first_of(" \t");
    if (space == std::string::npos) {
      throw InputError(where + ": expected 'key value', got '" + text + "'");
    }
    const std::string key = text.substr(0, space);
    const std::string value = Trim(text.substr(space));
    if (key.compare(0, 4, "fit_") == 0) {
      profile->fit_info.emplace_back(key, value);
      continue;
    }
    if (kKnown.count(key) == 0) {
      throw InputError(where + ": unknown key '" + key + "'");
    }
    if (!entries.values.emplace(key, value).second) {
      throw InputError(where + ": '" + key + "' is given twice");
    }
    entries.lines[key] = number;
  }
  return entries;
}

// What the profile was measured under; each key optional, numbers
// positive.
void ReadConditions(const ProfileEntries& entries, ProfileConditions* c) {
  auto positive = [&](const char* key, double* value) {
    if (!entries.Has(key)) return;
    *value = entries.Number(key);
    if (!(*value > 0)) {
      throw InputError(entries.Where(key) + ": '" + key +
                       "' must be a positive number");
    }
  };
  positive("focal_length_mm", &c->focal_length_mm);
  positive("f_number", &c->f_number);
  positive("pixel_pitch_um", &c->pixel_pitch_um);
  if (entries.Has("frame_size")) {
    const std::vector<double> v =
        ParseNumbers(entries.Value("frame_size"), entries.Where("frame_size"));
    if (v.size() != 2 || !(v[0] >= 1 && v[1] >= 1) ||
        v[0] != std::floor(v[0]) || v[1] != std::floor(v[1])) {
      throw InputError(entries.Where("frame_size") +
                       ": 'frame_size' needs WIDTH HEIGHT in pixels");
    }
    c->frame_width = static_cast<int>(v[0]);
    c->frame_height = static_cast<int>(v[1]);
  }
  if (entries.Has("blur_range_px")) {
    const std::vector<double> v = ParseNumbers(entries.Value("blur_range_px"),
                                               entries.Where("blur_range_px"));
    if (v.size() != 2 || !(v[0] >= 0 && v[1] >= v[0])) {
      throw InputError(entries.Where("blur_range_px") +
                       ": 'blur_range_px' needs MIN MAX with 0 <= MIN <= MAX");
    }
    c->min_blur_px = v[0];
    c->max_blur_px = v[1];
  }
}

// format, camera, lens, light and uncertainty: every model has them.
void ReadCommonKeys(const ProfileEntries& entries, PsfProfileFile* profile) {
  if (entries.Value("format") != "1") {
    throw InputError(entries.path +
                     " is not a dp-sfm DP PSF profile (needs 'format 1'; "
                     "write one with colmap dp_psf_calibrator)");
  }
  profile->camera = entries.Value("camera");
  if (entries.Has("light")) {
    profile->light = entries.Value("light");
    if (profile->light != "linear" && profile->light != "srgb") {
      throw InputError(entries.Where("light") +
                       ": 'light' must be linear or srgb, got '" +
                       profile->light + "'");
    }
  }
  profile->lens = entries.Value("lens");
  ReadConditions(entries, &profile->conditions);
  if (entries.Has("uncertainty")) {
    profile->uncertainty = entries.Number("uncertainty");
    if (!(profile->uncertainty >= 0 && profile->uncertainty < 1)) {
      throw InputError(entries.Where("uncertainty") +
                       ": the relative uncertainty must lie in [0, 1)");
    }
  }
}

// grid ROWS COLS and region x0 y0 x1 y1 of a measured profile.
void ReadLayout(const ProfileEntries& entries, DPPsfLayout* layout) {
  if (entries.Has("grid")) {
    const std::vector<double> g =
        ParseNumbers(entries.Value("grid"), entries.Where("grid"));
    if (g.size() != 2 || g[0] < 1 || g[1] < 1 || g[0] != std::floor(g[0]) ||
        g[1] != std::floor(g[1]) || g[0] * g[1] > 10000) {
      throw InputError(entries.Where("grid") + ": expected 'grid ROWS COLS'");
    }
    layout->rows = static_cast<int>(g[0]);
    layout->cols = static_cast<int>(g[1]);
  }
  if (entries.Has("region")) {
    const std::vector<double> r =
        ParseNumbers(entries.Value("region"), entries.Where("region"));
    if (r.size() != 4) {
      throw InputError(entries.Where("region") +
                       ": expected 'region x0 y0 x1 y1'");
    }
    layout->x0 = r[0];
    layout->y0 = r[1];
    layout->x1 = r[2];
    layout->y1 = r[3];
  }
  if (!layout->Check()) {
    throw InputError(entries.Where("region") +
                     ": the region must satisfy 0 <= x0 < x1 <= 1 and 0 <= "
                     "y0 < y1 <= 1");
  }
}

// model measured_kernels: the reference radius, side, layout and the .npy
// kernel stacks (paths relative to the profile file).
void ReadMeasuredKernels(const ProfileEntries& entries,
                         PsfProfileFile* profile) {
  const std::string& path = entries.path;
  entries.Refuse({"split_exponent",
                  "crosstalk",
                  "rim_softness",
                  "rim_brightness",
                  "band_split_exponents"},
                 profile->model);
  for (const char* key : {"reference_radius_px", "side", "left", "right"}) {
    if (!entries.Has(key)) {
      throw InputError(path + ": model measured_kernels needs '" + key + "'");
    }
  }
  profile->reference_radius_px = entries.Number("reference_radius_px");
  if (!(profile->reference_radius_px > 0.5)) {
    throw InputError(entries.Where("reference_radius_px") +
                     ": the reference radius must exceed 0.5 px");
  }
  const std::string side = entries.Value("side");
  if (side != "far" && side != "near") {
    throw InputError(entries.Where("side") +
                     ": side must be far or near, got '" + side + "'");
  }
  profile->far_side = side == "far";
  ReadLayout(entries, &profile->layout);
  const fs::path dir = fs::path(path).parent_path();
  auto resolve = [&](const std::string& name) {
    const fs::path p(name);
    return (p.is_absolute() ? p : dir / p).string();
  };
  profile->left_kernels = ReadKernelStack(
      resolve(entries.Value("left")), profile->layout, entries.Where("left"));
  profile->right_kernels = ReadKernelStack(
      resolve(entries.Value("right")), profile->layout, entries.Where("right"));
  if (profile->left_kernels[0].size() != profile->right_kernels[0].size()) {
    throw InputError(path + ": the left and right kernels differ in size");
  }
  profile->MakeField(path);  // the conventions, checked once here
}

// model split_profile: the family's parameters, optionally one split
// exponent per column band.
void ReadSplitProfile(const ProfileEntries& entries, PsfProfileFile* profile) {
  const std::string& path = entries.path;
  entries.Refuse(
      {"reference_radius_px", "side", "grid", "region", "left", "right"},
      "split_profile");
  if (!entries.Has("split_exponent")) {
    throw InputError(path + ": needs 'split_exponent'");
  }
  profile->params.split_exponent = entries.Number("split_exponent");
  if (entries.Has("crosstalk")) {
    profile->params.crosstalk = entries.Number("crosstalk");
  }
  if (entries.Has("rim_softness")) {
    profile->params.rim_softness = entries.Number("rim_softness");
  }
  if (entries.Has("rim_brightness")) {
    profile->params.rim_brightness = entries.Number("rim_brightness");
  }
  if (entries.Has("band_split_exponents")) {
    for (const double p : ParseNumbers(entries.Value("band_split_exponents"),
                                       entries.Where("band_split_exponents"))) {
      profile->band_split_exponents.push_back(p);
      SplitProfileParams band = profile->params;
      band.split_exponent = p;
      if (!band.Check()) {
        throw InputError(entries.Where("band_split_exponents") +
                         ": split exponents must lie in [0.05, 8]");
      }
    }
    if (profile->band_split_exponents.size() < 2) {
      throw InputError(entries.Where("band_split_exponents") +
                       ": needs two or more bands");
    }
  }
  if (!profile->params.Check()) {
    throw InputError(path + ": profile out of range (" +
                     profile->params.ToString() +
                     "; split_exponent in [0.05, 8], crosstalk in [0, "
                     "0.45], rim_softness in [0, 0.5], rim_brightness in "
                     "[0, 4])");
  }
}

}  // namespace

PsfProfileFile ReadPsfProfile(const std::string& path) {
  PsfProfileFile profile;
  const ProfileEntries entries = ReadProfileEntries(path, &profile);
  ReadCommonKeys(entries, &profile);
  const std::string model = entries.Value("model");
  if (model == "measured_kernels") {
    profile.model = model;
    ReadMeasuredKernels(entries, &profile);
    return profile;
  }
  if (model == "translating_disk") {
    // The paper's model stated for a camera (e.g. a library entry for the
    // EOS 5D Mark IV the paper measured), with the uncertainty its author
    // vouches for; unlike --DPScaleEstimator.psf_model translating_disk it
    // is trusted, not checked, as any calibrated profile is.
    profile.model = model;
    return profile;
  }
  if (model != "split_profile") {
    throw InputError(path +
                     ": needs 'model split_profile', 'model "
                     "measured_kernels' or 'model translating_disk'");
  }
  ReadSplitProfile(entries, &profile);
  return profile;
}

DPPsfField PsfProfileFile::MakeField(const std::string& path) const {
  if (model == "translating_disk") {
    return DPPsfField::Uniform(std::make_shared<TranslatingDiskPsf>());
  }
  DPPsfField field;
  if (model == "measured_kernels") {
    field.layout = layout;
    for (size_t c = 0; c < left_kernels.size(); ++c) {
      try {
        field.cells.push_back(std::make_shared<MeasuredKernelPsf>(
            left_kernels[c], right_kernels[c], reference_radius_px, far_side));
      } catch (const std::invalid_argument& e) {
        std::string what = e.what();
        const size_t colon = what.find("): ");
        if (colon != std::string::npos) what = what.substr(colon + 3);
        throw InputError(path + ", grid cell " + std::to_string(c) + " (row " +
                         std::to_string(c / layout.cols) + ", column " +
                         std::to_string(c % layout.cols) + "): " + what);
      }
    }
    return field;
  }
  if (band_split_exponents.empty()) {
    return DPPsfField::Uniform(std::make_shared<SplitProfilePsf>(params));
  }
  field.layout =
      DPPsfLayout::ColumnBands(static_cast<int>(band_split_exponents.size()));
  for (const double p : band_split_exponents) {
    SplitProfileParams band = params;
    band.split_exponent = p;
    field.cells.push_back(std::make_shared<SplitProfilePsf>(band));
  }
  return field;
}

void WritePsfProfile(const std::string& path, const PsfProfileFile& profile) {
  std::ofstream file(path);
  if (!file) throw InputError("cannot write DP PSF profile " + path);
  file << "# dp-sfm DP PSF profile (colmap dp_psf_calibrator)\n"
       << "# Use: colmap dp_scale_estimator ... "
          "--DPScaleEstimator.psf_model calibrated "
          "--DPScaleEstimator.psf_path "
       << path << "\n"
       << "format 1\n"
       << "model " << profile.model << "\n";
  if (!profile.camera.empty()) file << "camera " << profile.camera << "\n";
  if (!profile.lens.empty()) file << "lens " << profile.lens << "\n";
  file << std::setprecision(6);
  if (!profile.light.empty()) {
    file << "light " << profile.light
         << "  # the light the kernels were measured in\n";
  }
  if (profile.uncertainty > 0) {
    file << "uncertainty " << profile.uncertainty
         << "  # relative (95 %) uncertainty of the profile's strength\n";
  }
  const ProfileConditions& c = profile.conditions;
  if (c.focal_length_mm > 0) {
    file << "focal_length_mm " << c.focal_length_mm << "\n";
  }
  if (c.f_number > 0) {
    file << "f_number " << c.f_number
         << "  # the aperture the strength holds for\n";
  }
  if (c.pixel_pitch_um > 0) {
    file << "pixel_pitch_um " << c.pixel_pitch_um
         << "  # of the calibration's DP frames\n";
  }
  if (c.frame_width > 0) {
    file << "frame_size " << c.frame_width << " " << c.frame_height << "\n";
  }
  if (c.max_blur_px > 0) {
    file << "blur_range_px " << c.min_blur_px << " " << c.max_blur_px
         << "  # |blur radius| of the captures, DP frame px\n";
  }
  if (profile.model == "measured_kernels") {
    const fs::path p(path);
    const std::string stem = p.stem().string();
    file << "reference_radius_px " << profile.reference_radius_px << "\n"
         << "side " << (profile.far_side ? "far" : "near") << "\n"
         << "grid " << profile.layout.rows << " " << profile.layout.cols << "\n"
         << "region " << profile.layout.x0 << " " << profile.layout.y0 << " "
         << profile.layout.x1 << " " << profile.layout.y1 << "\n"
         << "left " << stem << "_left.npy\n"
         << "right " << stem << "_right.npy\n";
    for (const bool left : {true, false}) {
      const std::vector<cv::Mat>& kernels =
          left ? profile.left_kernels : profile.right_kernels;
      NpyArray array;
      const int k = kernels.empty() ? 0 : kernels[0].rows;
      array.shape = {static_cast<int>(kernels.size()), k, k};
      for (const cv::Mat& m : kernels) {
        for (int i = 0; i < m.rows; ++i) {
          for (int j = 0; j < m.cols; ++j) {
            array.values.push_back(m.at<float>(i, j));
          }
        }
      }
      WriteNpyFloat32(
          (p.parent_path() / (stem + (left ? "_left.npy" : "_right.npy")))
              .string(),
          array);
    }
  } else {
    file << "split_exponent " << profile.params.split_exponent << "\n"
         << "crosstalk " << profile.params.crosstalk << "\n"
         << "rim_softness " << profile.params.rim_softness << "\n";
    if (profile.params.rim_brightness > 0) {
      file << "rim_brightness " << profile.params.rim_brightness << "\n";
    }
    if (!profile.band_split_exponents.empty()) {
      file << "band_split_exponents";
      for (const double p : profile.band_split_exponents) file << " " << p;
      file << "\n";
    }
  }
  for (const auto& entry : profile.fit_info) {
    file << entry.first << " " << entry.second << "\n";
  }
  if (!file) throw InputError("cannot write DP PSF profile " + path);
}

void CheckProfileLight(const PsfProfileFile& profile, const std::string& path) {
  // The estimator reads blur in linear light; a profile measured on
  // sRGB-encoded values reads it differently (the encoding bends blurred
  // edges), so it is never applied silently.
  if (profile.light == "srgb") {
    throw InputError(
        "DP PSF profile " + path +
        " was measured on sRGB-encoded values ('light srgb'), but frames are "
        "brought to linear light before the blur search; re-run colmap "
        "dp_psf_calibrator on the calibration captures to measure it in "
        "linear light");
  }
  if (profile.light.empty() && !profile.fit_info.empty()) {
    throw InputError(
        "DP PSF profile " + path +
        " was written by a dp_psf_calibrator that read the frames as "
        "encoded (it records no 'light'), and the estimator now reads blur "
        "in linear light; re-run colmap dp_psf_calibrator on the "
        "calibration captures");
  }
}

}  // namespace dpsfm
