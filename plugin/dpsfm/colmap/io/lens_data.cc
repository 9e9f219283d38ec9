#include "dpsfm/colmap/io/lens_data.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <vector>

#include "colmap/util/logging.h"
#include "dpsfm/colmap/io/text.h"
#include "dpsfm/colmap/io/workspace.h"

namespace fs = std::filesystem;

namespace dpsfm {
namespace {

// Metres per unit of length, by the names people write.
double MetresPer(const std::string& unit) {
  if (unit == "m") return 1;
  if (unit == "cm") return 1e-2;
  if (unit == "mm") return 1e-3;
  if (unit == "um") return 1e-6;
  return 0;
}

// The cells given in another unit than their column's, for one log line
// per column.
struct Conversions {
  std::string first;  // "'100 cm' (line 2) as 1 m"
  int count = 0;
};

// An empty cell is 0 ("not given"); anything else a positive number, which
// may carry a unit as people write it ("50mm", "5.9 um", "1.2 m", "100 cm",
// "f/4"): another unit of length is converted to the column's (the
// conversion is logged, *conversions), anything else is an error that names
// the column's unit. *unit_written (optional): the cell carried a unit.
double ParseCell(const CsvTable& table,
                 const CsvTable::Row& row,
                 const char* column,
                 std::map<std::string, Conversions>* conversions,
                 bool* unit_written = nullptr) {
  std::string cell = table.Cell(row, column);
  if (cell.empty()) return 0;
  const std::string name = column;
  const std::string unit = name.substr(name.rfind('_') + 1);
  double value = 0;
  bool ok = false;
  std::string written;
  if (name == "f_number") {
    if (cell.rfind("f/", 0) == 0 || cell.rfind("F/", 0) == 0) {
      cell = Trim(cell.substr(2));
    }
    char* end = nullptr;
    value = std::strtod(cell.c_str(), &end);
    ok = end != cell.c_str() && Trim(end).empty();
  } else {
    ok = ParseLength(cell, unit, &value, &written);
  }
  if (!ok || !std::isfinite(value) || value <= 0) {
    throw InputError(table.Where(row) + column + " must be a positive number" +
                     (name == "f_number" ? "" : " in " + unit) +
                     " or empty, got '" + table.Cell(row, column) + "'" +
                     (name == "f_number" ? "" : " (m, cm, mm and um convert)"));
  }
  if (unit_written != nullptr) *unit_written = !written.empty();
  if (!written.empty() && written != unit && conversions != nullptr) {
    Conversions& c = (*conversions)[name];
    if (c.count++ == 0) {
      std::ostringstream s;
      s << "'" << table.Cell(row, column) << "' (line " << row.line
        << ") as " << value << " " << unit;
      c.first = s.str();
    }
  }
  return value;
}

// focus_distance_m: one distance, or a window "lower-upper" as cameras
// record one ("2.65-2.94 m", the unit after the upper end), read as its
// middle and its relative half-width.
void ParseFocusCell(const CsvTable& table,
                    const CsvTable::Row& cells,
                    std::map<std::string, Conversions>* conversions,
                    LensCsvRow* row) {
  const std::string cell = table.Cell(cells, "focus_distance_m");
  const size_t dash = cell.find('-', 1);
  if (dash == std::string::npos) {
    row->focus_distance_m = ParseCell(table,
                                      cells,
                                      "focus_distance_m",
                                      conversions,
                                      &row->focus_unit_written);
    return;
  }
  std::string unit;
  double lower = 0, upper = 0;
  const std::string upper_text = cell.substr(dash + 1);
  const bool ok = ParseLength(upper_text, "m", &upper, &unit) &&
                  ParseLength(Trim(cell.substr(0, dash)) + " " +
                                  (unit.empty() ? "m" : unit),
                              "m",
                              &lower) &&
                  lower > 0 && upper >= lower && std::isfinite(upper);
  if (!ok) {
    throw InputError(table.Where(cells) +
                     "focus_distance_m must be a distance or a window "
                     "lower-upper (e.g. 2.65-2.94 m), got '" +
                     cell + "'");
  }
  row->focus_distance_m = 0.5 * (lower + upper);
  row->focus_bracket = (upper - lower) / (upper + lower);
  row->focus_unit_written = !unit.empty();
}

void LogConversions(const std::string& path,
                    const std::map<std::string, Conversions>& conversions) {
  for (const auto& [column, c] : conversions) {
    LOG(INFO) << path << ": " << column << " read " << c.first
              << (c.count > 1 ? " (and " + std::to_string(c.count - 1) +
                                    " more cells converted alike)"
                              : std::string());
  }
}

// A word on the unit when an unknown column looks like a known one in
// another unit.
std::string LensColumnHint(const std::string& column) {
  if (column.rfind("pixel_pitch", 0) == 0) {
    return " (the pitch is given in micrometres, as pixel_pitch_um)";
  }
  if (column.rfind("focal_length", 0) == 0) {
    return " (the focal length is given in millimetres, as focal_length_mm)";
  }
  if (column.rfind("focus_distance", 0) == 0) {
    return " (the focus distance is given in metres, as focus_distance_m)";
  }
  return "";
}

}  // namespace

bool ParseLength(const std::string& text,
                 const std::string& column_unit,
                 double* value,
                 std::string* unit_written) {
  const std::string cell = Trim(text);
  char* end = nullptr;
  const double number = std::strtod(cell.c_str(), &end);
  if (cell.empty() || end == cell.c_str()) return false;
  std::string unit = Trim(end);
  if (unit == "\xC2\xB5m" || unit == "\xCE\xBCm") unit = "um";  // micro sign
  if (!unit.empty() && MetresPer(unit) == 0) return false;
  if (MetresPer(column_unit) == 0) return false;
  *value = unit.empty() ? number
                        : number * MetresPer(unit) / MetresPer(column_unit);
  if (unit_written != nullptr) *unit_written = unit;
  return true;
}

const std::vector<std::string>& LensCsvColumns() {
  static const std::vector<std::string> kColumns = {"name",
                                                    "focal_length_mm",
                                                    "f_number",
                                                    "pixel_pitch_um",
                                                    "focus_distance_m",
                                                    "camera",
                                                    "lens",
                                                    "source"};
  return kColumns;
}

std::map<std::string, LensCsvRow> ReadLensCsv(const std::string& path) {
  const CsvTable table(path,
                       LensCsvColumns(),
                       {"name"},
                       "IMG_1.JPG,50,4,5.93,1.2,Canon / Canon EOS R6m2,RF50mm "
                       "F1.8 STM",
                       LensColumnHint);
  std::map<std::string, LensCsvRow> rows;
  std::map<std::string, Conversions> conversions;
  for (const CsvTable::Row& cells : table.rows()) {
    const std::string name = table.Cell(cells, "name");
    if (name.empty()) {
      throw InputError(table.Where(cells) +
                       "the name cell is empty (the image's name as the "
                       "model stores it, e.g. IMG_1.JPG)");
    }
    LensCsvRow row;
    row.focal_length_mm =
        ParseCell(table, cells, "focal_length_mm", &conversions);
    row.f_number = ParseCell(table, cells, "f_number", &conversions);
    row.pixel_pitch_um =
        ParseCell(table, cells, "pixel_pitch_um", &conversions);
    ParseFocusCell(table, cells, &conversions, &row);
    row.camera = table.Cell(cells, "camera");
    row.lens = table.Cell(cells, "lens");
    row.line = cells.line;
    if (!rows.emplace(name, row).second) {
      throw InputError(table.Where(cells) + "image " + name +
                       " is listed twice");
    }
  }
  LogConversions(path, conversions);
  return rows;
}

namespace {

std::string Cell(double value) {
  if (!(value > 0)) return "";
  std::ostringstream s;
  s.precision(6);
  s << value;
  return s.str();
}

// A cell as RFC 4180 writes it: in quotes when it holds a comma or quote.
std::string Quoted(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) {
    out += c;
    if (c == '"') out += '"';
  }
  return out + "\"";
}

std::string FocusCell(const DPLensData& lens) {
  if (!std::isfinite(lens.recorded_focus_mm)) return "";
  const double m = lens.recorded_focus_mm / 1000;
  const double b = lens.recorded_focus_bracket;
  if (!(b > 0)) return Cell(m) + " m";
  return Cell(m * (1 - b)) + "-" + Cell(m * (1 + b)) + " m";
}

std::string SourceCell(const ResolvedLens& r) {
  std::vector<std::string> parts;
  auto add = [&](const char* column, const std::string& source) {
    if (!source.empty()) parts.push_back(std::string(column) + ": " + source);
  };
  add("focal_length_mm", r.focal_length_source);
  add("f_number", r.f_number_source);
  add("pixel_pitch_um",
      r.pixel_pitch_source == kDerivedPitch
          ? std::string("derived by the run (f_mm / f_px)")
          : r.pixel_pitch_source);
  add("focus_distance_m", r.focus_source);
  std::string text;
  for (const std::string& part : parts) {
    text += (text.empty() ? "" : "; ") + part;
  }
  return text;
}

}  // namespace

std::string LensCsvText(const std::vector<LensTableRow>& rows) {
  std::string text;
  for (const std::string& column : LensCsvColumns()) {
    text += (text.empty() ? "" : ",") + column;
  }
  text += "\n";
  for (const LensTableRow& row : rows) {
    const ResolvedLens& r = row.lens;
    const bool derived = r.pixel_pitch_source == kDerivedPitch;
    text += Quoted(row.name) + "," + Cell(r.lens.focal_length_mm) + "," +
            Cell(r.lens.f_number) + "," +
            (derived ? "" : Cell(r.lens.pixel_pitch_um)) + "," +
            FocusCell(r.lens) + "," + Quoted(r.camera) + "," +
            Quoted(r.lens_model) + "," + Quoted(SourceCell(r)) + "\n";
  }
  return text;
}

const LensCsvRow* FindLensRow(const std::map<std::string, LensCsvRow>& csv,
                              const std::string& image_name,
                              std::string* matched_name) {
  auto found = csv.find(image_name);
  if (found == csv.end()) {
    // As DP views are matched: the same name with another extension, when
    // exactly one row has it.
    const std::string stem = StripExtension(image_name);
    int matches = 0;
    for (auto it = csv.begin(); it != csv.end(); ++it) {
      if (StripExtension(it->first) == stem) {
        found = it;
        ++matches;
      }
    }
    if (matches != 1) return nullptr;
  }
  if (matched_name != nullptr) *matched_name = found->first;
  return &found->second;
}

std::vector<MetadataFile> ReadImageMetadata(const FileIndex& originals,
                                            const std::string& image_name,
                                            const std::string& dp_frame) {
  std::vector<MetadataFile> files;
  const std::string original = originals.Find(image_name);
  if (!original.empty()) {
    files.push_back({fs::path(original).filename().string(),
                     ReadCameraMetadata(original)});
  }
  const bool complete = !files.empty() &&
                        files[0].metadata.focal_length_mm.recorded() &&
                        files[0].metadata.f_number.recorded() &&
                        files[0].metadata.focus.distance_mm > 0;
  if (!dp_frame.empty() && !complete) {
    MetadataFile frame{"DP frame " + fs::path(dp_frame).filename().string(),
                       ReadCameraMetadata(dp_frame)};
    // A frame of no format Exiv2 knows simply carries no metadata.
    if (frame.metadata.error.rfind("not an image format", 0) == 0) {
      frame.metadata.error.clear();
    }
    files.push_back(frame);
  }
  return files;
}

void LensNotes::Add(const std::string& image_name,
                    const ResolvedLens& resolved) {
  auto add = [&](Kind* kind, const std::string& note) {
    if (note.empty()) return;
    if (kind->count++ == 0) kind->first = "image " + image_name + ": " + note;
  };
  add(&focus_, resolved.focus_note);
  add(&pitch_, resolved.pitch_note);
  for (const std::string& file : resolved.unreadable) add(&unreadable_, file);
}

void LensNotes::Log() const {
  auto log = [](const Kind& kind, const char* what) {
    if (kind.count == 0) return;
    LOG(INFO) << what << ": " << kind.first
              << (kind.count > 1 ? " (and " + std::to_string(kind.count - 1) +
                                       " more like it)"
                                 : std::string());
  };
  log(focus_, "No recorded focus");
  log(pitch_, "Metadata pixel pitch not used");
  log(unreadable_, "Image metadata not read");
}

const char kDerivedPitch[] = "derived f_mm/f_px";

bool IsMetadataSource(const std::string& source) {
  return source.find(" Exif.") != std::string::npos;
}

namespace {

// The first of the files whose metadata records `number`, and the source
// it is named by.
const MetadataNumber* FirstRecorded(
    const std::vector<MetadataFile>& files,
    MetadataNumber CameraMetadata::*number,
    std::string* source) {
  for (const MetadataFile& file : files) {
    const MetadataNumber& n = file.metadata.*number;
    if (n.recorded()) {
      *source = file.name + " " + n.tag;
      return &n;
    }
  }
  return nullptr;
}

// v / f of a lens of focal length f focused at `focus_mm` from the sensor.
double Breathing(double focus_mm, double f_mm) {
  const double u = FocusObjectDistanceMm(focus_mm, f_mm);
  return (focus_mm - u) / f_mm;
}

// The calibrated f_px over f_mm / pitch: the image distance over f, which
// focus breathing puts at v / f >= 1. Its accepted band (the check's).
struct PitchRatioBand {
  double low = 0, high = 0;
};
PitchRatioBand AcceptedPitchRatio(const DPLensData& lens,
                                  const LensCheckOptions& options) {
  const double breathing =
      std::isfinite(lens.recorded_focus_mm)
          ? Breathing(lens.recorded_focus_mm, lens.focal_length_mm)
          : options.breathing_without_focus;
  return {1 / (1 + options.tolerance), (1 + options.tolerance) * breathing};
}

// The ratio itself: the calibrated f_px x pitch / f_mm.
double PitchRatio(double focal_px, double pitch_um, double focal_length_mm) {
  return focal_px * pitch_um / (1000 * focal_length_mm);
}

std::string Number(double value) {
  std::ostringstream s;
  s.precision(4);
  s << value;
  return s.str();
}

// The recorded focus: lens.csv's, else the first file's that records one
// (unless switched off).
void ResolveFocus(const LensCsvRow* csv_row,
                  const std::string& csv_source,
                  const LensFlags& flags,
                  const std::vector<MetadataFile>& metadata,
                  ResolvedLens* resolved) {
  if (csv_row && csv_row->focus_distance_m > 0) {
    resolved->lens.recorded_focus_mm = 1000 * csv_row->focus_distance_m;
    resolved->lens.recorded_focus_bracket = csv_row->focus_bracket;
    resolved->focus_source = csv_source;
    resolved->focus_unit_written = csv_row->focus_unit_written;
    return;
  }
  for (const MetadataFile& file : metadata) {
    const RecordedFocus& focus = file.metadata.focus;
    if (!(focus.distance_mm > 0)) {
      if (resolved->focus_note.empty() && !file.metadata.focus_note.empty()) {
        resolved->focus_note =
            file.metadata.focus_note +
            (file.name.rfind("DP frame", 0) == 0 ? " (" + file.name + ")" : "");
      }
      continue;
    }
    if (!flags.use_recorded_focus) {
      resolved->focus_note = file.name + " records a focus at " +
                             Number(focus.distance_mm / 1000) + " m (" +
                             focus.tag +
                             "), not used (use_recorded_focus is off)";
      return;
    }
    resolved->lens.recorded_focus_mm = focus.distance_mm;
    resolved->lens.recorded_focus_bracket = focus.bracket;
    resolved->focus_source = file.name + " " + focus.tag;
    resolved->focus_note.clear();
    return;
  }
}

// A metadata pitch is the camera's full-resolution pixels': used when it
// fits the model camera (within the lens check's band), else noted and
// left for the derived one.
void ResolveMetadataPitch(const std::vector<MetadataFile>& metadata,
                          double camera_focal_px,
                          const LensCheckOptions& check,
                          ResolvedLens* resolved) {
  std::string source;
  const MetadataNumber* pitch =
      FirstRecorded(metadata, &CameraMetadata::pixel_pitch_um, &source);
  if (pitch == nullptr) return;
  if (!(camera_focal_px > 0)) {
    // No camera to check it against here (a folder listed without a
    // model): the run checks it.
    resolved->lens.pixel_pitch_um = pitch->value;
    resolved->pixel_pitch_source = source;
    return;
  }
  const DPLensData& lens = resolved->lens;
  const double ratio =
      PitchRatio(camera_focal_px, pitch->value, lens.focal_length_mm);
  const PitchRatioBand band = AcceptedPitchRatio(lens, check);
  if (ratio >= band.low && ratio <= band.high) {
    resolved->lens.pixel_pitch_um = pitch->value;
    resolved->pixel_pitch_source = source;
    return;
  }
  resolved->pitch_note =
      "pixel pitch " + Number(pitch->value) + " um (" + source + ") with " +
      Number(lens.focal_length_mm) + " mm gives f = " +
      Number(1000 * lens.focal_length_mm / pitch->value) +
      " px against the model camera's " + Number(camera_focal_px) +
      " px: the model's pixels are not the full-resolution image's (resized "
      "images?), so the pitch is derived from f_mm / f_px";
}

}  // namespace

ResolvedLens GatherLens(const std::string& image_name,
                        const std::map<std::string, LensCsvRow>& csv,
                        const LensFlags& flags,
                        const std::vector<MetadataFile>& metadata,
                        double camera_focal_px,
                        const LensCheckOptions& check) {
  ResolvedLens resolved;
  const LensCsvRow* csv_row = FindLensRow(csv, image_name, nullptr);
  const std::string csv_source =
      csv_row == nullptr  ? ""
      : csv_row->line > 0 ? "lens.csv line " + std::to_string(csv_row->line)
                          : "lens.csv";
  for (const MetadataFile& file : metadata) {
    if (!file.metadata.error.empty()) {
      resolved.unreadable.push_back(file.name + ": " + file.metadata.error);
    }
  }

  auto pick = [&](double csv_value,
                  double flag_value,
                  MetadataNumber CameraMetadata::*number,
                  double* out,
                  std::string* source) {
    std::string metadata_source;
    const MetadataNumber* recorded =
        number ? FirstRecorded(metadata, number, &metadata_source) : nullptr;
    if (csv_value > 0) {
      *out = csv_value;
      *source = csv_source;
    } else if (flag_value > 0) {
      *out = flag_value;
      *source = "flag";
    } else if (recorded != nullptr) {
      *out = recorded->value;
      *source = metadata_source;
    }
  };
  pick(csv_row ? csv_row->focal_length_mm : 0,
       flags.focal_length_mm,
       &CameraMetadata::focal_length_mm,
       &resolved.lens.focal_length_mm,
       &resolved.focal_length_source);
  pick(csv_row ? csv_row->f_number : 0,
       flags.f_number,
       &CameraMetadata::f_number,
       &resolved.lens.f_number,
       &resolved.f_number_source);
  pick(csv_row ? csv_row->pixel_pitch_um : 0,
       flags.pixel_pitch_um,
       nullptr,
       &resolved.lens.pixel_pitch_um,
       &resolved.pixel_pitch_source);
  ResolveFocus(csv_row, csv_source, flags, metadata, &resolved);

  auto first_text = [&](std::string (*of)(const CameraMetadata&)) {
    for (const MetadataFile& file : metadata) {
      const std::string text = of(file.metadata);
      if (!text.empty()) return text;
    }
    return std::string();
  };
  resolved.camera =
      csv_row && !csv_row->camera.empty()
          ? csv_row->camera
          : first_text([](const CameraMetadata& m) { return m.Camera(); });
  resolved.lens_model =
      csv_row && !csv_row->lens.empty()
          ? csv_row->lens
          : first_text([](const CameraMetadata& m) { return m.lens_model; });

  if (resolved.lens.pixel_pitch_um <= 0 && resolved.lens.focal_length_mm > 0) {
    ResolveMetadataPitch(metadata, camera_focal_px, check, &resolved);
  }
  if (resolved.lens.pixel_pitch_um <= 0 && resolved.lens.focal_length_mm > 0 &&
      camera_focal_px > 0) {
    // f_mm / f_px is the physical size of one model camera pixel.
    resolved.lens.pixel_pitch_um =
        1000.0 * resolved.lens.focal_length_mm / camera_focal_px;
    resolved.pixel_pitch_source = kDerivedPitch;
  }
  return resolved;
}

void RequireLensData(const std::string& image_name,
                     const ResolvedLens& resolved) {
  const char* kHowTo =
      " (give it in --lens_path lens.csv, with --DPScaleEstimator.%s, or in "
      "the metadata of the original image under --image_path)";
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
    throw InputError("no pixel pitch for image " + image_name +
                     " and its camera has no focal length to derive it from");
  }
}

ResolvedLens ResolveLens(const std::string& image_name,
                         const std::map<std::string, LensCsvRow>& csv,
                         const LensFlags& flags,
                         const std::vector<MetadataFile>& metadata,
                         double camera_focal_px,
                         const LensCheckOptions& check) {
  ResolvedLens resolved =
      GatherLens(image_name, csv, flags, metadata, camera_focal_px, check);
  RequireLensData(image_name, resolved);
  return resolved;
}

namespace {

// Where a number can be corrected, in the words of its source.
std::string FixFor(const std::string& source, const char* column) {
  if (source.rfind("lens.csv", 0) == 0) {
    return "correct " + std::string(column) + " in " + source;
  }
  if (source == "flag") {
    return "correct --DPScaleEstimator." + std::string(column);
  }
  if (IsMetadataSource(source)) {
    return "the file's metadata (" + source +
           ") is wrong here: override it with --DPScaleEstimator." +
           std::string(column) + " or lens.csv";
  }
  return "give " + std::string(column) + " in lens.csv or as a flag";
}


void CheckRanges(const std::string& image_name,
                 const ResolvedLens& resolved,
                 const LensCheckOptions& options) {
  const DPLensData& lens = resolved.lens;
  const std::string prefix = "image " + image_name + ": ";
  if (lens.focal_length_mm > options.max_focal_length_mm) {
    throw InputError(prefix + "focal length " + Number(lens.focal_length_mm) +
                     " mm (" + resolved.focal_length_source +
                     ") is beyond any lens: is it in pixels? Give it in "
                     "millimetres; " +
                     FixFor(resolved.focal_length_source, "focal_length_mm"));
  }
  if (lens.f_number < options.min_f_number ||
      lens.f_number > options.max_f_number) {
    throw InputError(prefix + "f-number " + Number(lens.f_number) + " (" +
                     resolved.f_number_source + ") is outside [" +
                     Number(options.min_f_number) + ", " +
                     Number(options.max_f_number) + "]; " +
                     FixFor(resolved.f_number_source, "f_number"));
  }
  const double focus_mm = lens.recorded_focus_mm;
  if (std::isfinite(focus_mm)) {
    if (focus_mm < 4 * lens.focal_length_mm) {
      throw InputError(
          prefix + "recorded focus distance " + Number(focus_mm / 1000) +
          " m (" + resolved.focus_source + ") is nearer than a " +
          Number(lens.focal_length_mm) +
          " mm lens can focus (4 f): is it in the wrong unit? lens.csv's "
          "focus_distance_m is in metres from the focal-plane mark");
    }
    if (focus_mm >= 1000 * options.max_recorded_focus_m &&
        resolved.focus_source.rfind("lens.csv", 0) == 0) {
      throw InputError(prefix + "recorded focus distance " +
                       Number(focus_mm / 1000) + " m (" +
                       resolved.focus_source +
                       ") looks like millimetres: focus_distance_m is in "
                       "metres (leave it empty for a focus at infinity)");
    }
    // A bare number beyond the hyperfocal distance (one pixel's blur
    // circle), where focus tells the depths next to nothing: once "100"
    // (cm) ran on to "an interval covering both spans 1251.0 % of the
    // scale". Written with its unit ("100 m"), a far focus is meant.
    const double hyperfocal_mm =
        lens.focal_length_mm * lens.focal_length_mm /
            (lens.f_number * lens.PixelPitchMm()) +
        lens.focal_length_mm;
    if (resolved.focus_source.rfind("lens.csv", 0) == 0 &&
        !resolved.focus_unit_written && lens.pixel_pitch_um > 0 &&
        focus_mm > hyperfocal_mm) {
      const double value = focus_mm / 1000;  // as written, in "metres"
      const bool cm = value * 10 >= 4 * lens.focal_length_mm;
      throw InputError(
          prefix + "recorded focus distance " + Number(value) + " m (" +
          resolved.focus_source + ") lies beyond the hyperfocal distance (" +
          Number(hyperfocal_mm / 1000) + " m at f/" + Number(lens.f_number) +
          ", " + Number(lens.focal_length_mm) + " mm, " +
          Number(lens.pixel_pitch_um) +
          " um pixels), where the focus tells the depths next to nothing: " +
          (cm ? "is it in centimetres (" + Number(value / 100) +
                    " m)? Write the unit (" + Number(value) + " cm)"
              : "is it in another unit? Write the unit") +
          ", or " + Number(value) +
          " m if that is meant; leave it empty for a focus at infinity");
    }
  }
}

}  // namespace

void CheckLensAgainstCamera(const std::string& image_name,
                            const ResolvedLens& resolved,
                            const CameraGeometry& camera,
                            const LensCheckOptions& options) {
  CheckRanges(image_name, resolved, options);
  const DPLensData& lens = resolved.lens;
  const std::string prefix = "image " + image_name + ": ";
  const int long_side = std::max(camera.width, camera.height);
  const double sensor_mm = lens.pixel_pitch_um * long_side / 1000;
  const std::string pitch_text = "pixel pitch " + Number(lens.pixel_pitch_um) +
                                 " um (" + resolved.pixel_pitch_source + ")";
  const double implied_pitch_um =
      camera.focal_px > 0 ? 1000 * lens.focal_length_mm / camera.focal_px : 0;
  const std::string implied =
      implied_pitch_um > 0 ? " (f_mm / f_px gives " + Number(implied_pitch_um) +
                                 " um; leave the pitch out to use that)"
                           : "";
  if (sensor_mm < options.min_sensor_mm || sensor_mm > options.max_sensor_mm) {
    const bool derived = resolved.pixel_pitch_source == kDerivedPitch;
    // A pitch in mm makes the sensor 1000 times too small.
    const bool in_mm = 1000 * sensor_mm >= options.min_sensor_mm &&
                       1000 * sensor_mm <= options.max_sensor_mm;
    const std::string cause =
        derived
            ? "the focal length " + Number(lens.focal_length_mm) + " mm (" +
                  resolved.focal_length_source + ") and the camera's " +
                  Number(camera.focal_px) +
                  " px disagree: is the focal length in " +
                  (sensor_mm > options.max_sensor_mm ? "pixels" : "metres") +
                  " (it is in millimetres), or the camera's calibration "
                  "wrong? " +
                  FixFor(resolved.focal_length_source, "focal_length_mm")
            : (in_mm ? "is the pitch in millimetres? Give micrometres; " : "") +
                  FixFor(resolved.pixel_pitch_source, "pixel_pitch_um") +
                  " (the pitch is of the model camera's pixels)" + implied;
    throw InputError(prefix + pitch_text + " x the camera's " +
                     std::to_string(long_side) + " px makes a sensor of " +
                     Number(sensor_mm) + " mm, outside [" +
                     Number(options.min_sensor_mm) + ", " +
                     Number(options.max_sensor_mm) + "] mm: " + cause);
  }
  if (resolved.pixel_pitch_source == kDerivedPitch ||
      !(camera.focal_px > 0)) {
    return;
  }
  // The calibrated f_px is the image distance v over the pitch; v >= f.
  const double ratio =
      PitchRatio(camera.focal_px, lens.pixel_pitch_um, lens.focal_length_mm);
  const bool focus = std::isfinite(lens.recorded_focus_mm);
  const PitchRatioBand band = AcceptedPitchRatio(lens, options);
  const double low = band.low, high = band.high;
  if (ratio >= low && ratio <= high) return;

  std::string hint;
  // ratio = given pitch / the pitch f_mm / f_px implies.
  const double nearest = std::round(ratio);
  if (nearest >= 2 && std::abs(ratio / nearest - 1) < options.tolerance) {
    hint = "; if " + Number(lens.pixel_pitch_um) +
           " um is the pitch of the DP frames' pixels (" + Number(nearest) +
           " model pixels each), give the model camera's";
  } else if (std::abs(ratio * 1000 - 1) < 0.5) {
    hint = "; is the pitch in millimetres? Give micrometres";
  }
  throw InputError(
      prefix + "focal length " + Number(lens.focal_length_mm) + " mm (" +
      resolved.focal_length_source + ") / " + pitch_text + " = " +
      Number(1000 * lens.focal_length_mm / lens.pixel_pitch_um) +
      " px, but the model's camera has f = " + Number(camera.focal_px) +
      " px (ratio " + Number(ratio) + ", accepted " + Number(low) + "-" +
      Number(high) +
      (focus ? " with the recorded focus" : " without a recorded focus") +
      "). The pitch is of the model camera's pixels" + implied + hint + "; " +
      FixFor(resolved.pixel_pitch_source, "pixel_pitch_um") +
      " or the focal length (" +
      FixFor(resolved.focal_length_source, "focal_length_mm") +
      "), or allow more with --DPScaleEstimator.lens_check_tolerance");
}

}  // namespace dpsfm
