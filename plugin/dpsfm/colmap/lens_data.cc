#include "dpsfm/colmap/lens_data.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "dpsfm/colmap/text.h"
#include "dpsfm/colmap/workspace.h"

namespace dpsfm {
namespace {

double ParseCell(const std::string& cell,
                 const std::string& path,
                 int line,
                 const char* column,
                 bool allow_empty) {
  if (cell.empty()) {
    if (allow_empty) return 0;
    throw InputError(path + ":" + std::to_string(line) + ": " + column +
                     " is empty");
  }
  char* end = nullptr;
  const double value = std::strtod(cell.c_str(), &end);
  if (end == cell.c_str() || *end != '\0' || !std::isfinite(value) ||
      value <= 0) {
    throw InputError(path + ":" + std::to_string(line) + ": " + column +
                     " must be a positive number, got '" + cell + "'");
  }
  return value;
}

}  // namespace

std::map<std::string, LensCsvRow> ReadLensCsv(const std::string& path) {
  std::ifstream file(path);
  if (!file) {
    throw InputError("cannot read lens file " + path);
  }
  std::string line;
  if (!std::getline(file, line)) {
    throw InputError("lens file is empty: " + path);
  }
  const std::vector<std::string> header = SplitCsvLine(line);
  const std::vector<std::string> required = {
      "name", "focal_length_mm", "f_number", "pixel_pitch_um"};
  bool valid = header.size() >= required.size() &&
               std::equal(required.begin(), required.end(), header.begin());
  int focus_column = -1, camera_column = -1, lens_column = -1;
  for (size_t c = required.size(); valid && c < header.size(); ++c) {
    int* column = header[c] == "focus_distance_m" ? &focus_column
                  : header[c] == "camera"         ? &camera_column
                  : header[c] == "lens"           ? &lens_column
                                                  : nullptr;
    valid = column != nullptr && *column < 0;
    if (valid) *column = static_cast<int>(c);
  }
  if (!valid) {
    throw InputError("lens file " + path +
                     " must start with the header "
                     "name,focal_length_mm,f_number,pixel_pitch_um (optionally "
                     "followed by focus_distance_m, camera, lens, each once)");
  }
  const size_t max_cells = header.size();
  const bool with_focus = focus_column >= 0;
  std::map<std::string, LensCsvRow> rows;
  int line_number = 1;
  while (std::getline(file, line)) {
    ++line_number;
    if (Trim(line).empty()) continue;
    const std::vector<std::string> cells = SplitCsvLine(line);
    if (cells.size() < 3 || cells.size() > max_cells || cells[0].empty()) {
      throw InputError(
          path + ":" + std::to_string(line_number) +
          ": expected name,focal_length_mm,f_number[,"
          "pixel_pitch_um" +
          (with_focus ? std::string("[,...]]") : std::string("]")));
    }
    LensCsvRow row;
    row.focal_length_mm =
        ParseCell(cells[1], path, line_number, "focal_length_mm", false);
    row.f_number = ParseCell(cells[2], path, line_number, "f_number", false);
    row.pixel_pitch_um =
        cells.size() == 4
            ? ParseCell(cells[3], path, line_number, "pixel_pitch_um", true)
            : 0;
    auto cell = [&](int column) {
      return column >= 0 && column < static_cast<int>(cells.size())
                 ? cells[column]
                 : std::string();
    };
    row.focus_distance_m = ParseCell(
        cell(focus_column), path, line_number, "focus_distance_m", true);
    row.camera = cell(camera_column);
    row.lens = cell(lens_column);
    if (!rows.emplace(cells[0], row).second) {
      throw InputError(path + ":" + std::to_string(line_number) + ": image " +
                       cells[0] + " is listed twice");
    }
  }
  return rows;
}

ResolvedLens ResolveLens(const std::string& image_name,
                         const std::map<std::string, LensCsvRow>& csv,
                         const LensFlags& flags,
                         const ExifLens* exif,
                         double camera_focal_px) {
  ResolvedLens resolved;
  const auto row = csv.find(image_name);
  const LensCsvRow* csv_row = row == csv.end() ? nullptr : &row->second;

  auto pick = [&](double csv_value,
                  double flag_value,
                  double exif_value,
                  double* out,
                  std::string* source) {
    if (csv_value > 0) {
      *out = csv_value;
      *source = "lens.csv";
    } else if (flag_value > 0) {
      *out = flag_value;
      *source = "flag";
    } else if (exif_value > 0) {
      *out = exif_value;
      *source = "EXIF";
    }
  };
  pick(csv_row ? csv_row->focal_length_mm : 0,
       flags.focal_length_mm,
       exif ? exif->focal_length_mm : 0,
       &resolved.lens.focal_length_mm,
       &resolved.focal_length_source);
  pick(csv_row ? csv_row->f_number : 0,
       flags.f_number,
       exif ? exif->f_number : 0,
       &resolved.lens.f_number,
       &resolved.f_number_source);
  pick(csv_row ? csv_row->pixel_pitch_um : 0,
       flags.pixel_pitch_um,
       0,
       &resolved.lens.pixel_pitch_um,
       &resolved.pixel_pitch_source);

  if (csv_row && csv_row->focus_distance_m > 0) {
    resolved.lens.recorded_focus_mm = 1000 * csv_row->focus_distance_m;
    resolved.focus_source = "lens.csv";
  } else if (exif && exif->focus_distance_mm > 0) {
    resolved.lens.recorded_focus_mm = exif->focus_distance_mm;
    resolved.lens.recorded_focus_bracket = exif->focus_bracket;
    resolved.focus_source = "EXIF " + exif->focus_source;
  }
  resolved.camera = csv_row && !csv_row->camera.empty()
                        ? csv_row->camera
                        : (exif ? exif->camera : "");
  resolved.lens_model = csv_row && !csv_row->lens.empty()
                            ? csv_row->lens
                            : (exif ? exif->lens : "");

  const char* kHowTo =
      " (give it in --lens_path lens.csv, with --DPScaleEstimator.%s, or in "
      "the EXIF of the original image under --image_path)";
  char how[256];
  if (resolved.lens.focal_length_mm <= 0) {
    std::snprintf(how, sizeof(how), kHowTo, "focal_length_mm");
    throw InputError("no focal length for image " + image_name + how);
  }
  if (resolved.lens.f_number <= 0) {
    std::snprintf(how, sizeof(how), kHowTo, "f_number");
    throw InputError("no f-number for image " + image_name + how);
  }
  if (resolved.lens.pixel_pitch_um <= 0) {
    if (!(camera_focal_px > 0)) {
      throw InputError("no pixel pitch for image " + image_name +
                       " and its camera has no focal length to derive it from");
    }
    // f_mm / f_px is the physical size of one model camera pixel.
    resolved.lens.pixel_pitch_um =
        1000.0 * resolved.lens.focal_length_mm / camera_focal_px;
    resolved.pixel_pitch_source = "derived f_mm/f_px";
  }
  return resolved;
}

}  // namespace dpsfm
