#include "dpsfm/colmap/io/calibration_targets.h"

#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include "colmap/util/logging.h"
#include "dpsfm/colmap/io/lens_data.h"
#include "dpsfm/colmap/io/text.h"
#include "dpsfm/colmap/io/workspace.h"

namespace dpsfm {

namespace {

// Per column, the first cell read in another unit ("'60 cm' (line 2) as
// 0.6 m") and how many were converted, for one log line each.
using UnitConversions = std::map<std::string, std::pair<std::string, int>>;

// The targets file's table: its columns checked, left and right together.
CsvTable ReadTargetsTable(const std::string& path) {
  CsvTable table(path,
                 {"name",
                  "target_distance_m",
                  "focus_distance_m",
                  "focal_length_mm",
                  "f_number",
                  "pixel_pitch_um",
                  "left",
                  "right"},
                 {"name",
                  "target_distance_m",
                  "focal_length_mm",
                  "f_number",
                  "pixel_pitch_um"},
                 "near_f4,0.6,1.0,49.57,4,46.875,0600/f4/l.png,"
                 "0600/f4/r.png");
  if (table.Has("left") != table.Has("right")) {
    throw InputError(path +
                     ":1: give both left and right columns (each capture's "
                     "DP view files, relative to --dp_image_path) or neither");
  }
  return table;
}

// A number cell of `row`, a length converted to its column's unit (the
// unit after the column name's last '_'), noted in *conversions.
double TargetNumber(const CsvTable& table,
                    const CsvTable::Row& row,
                    const char* column,
                    UnitConversions* conversions) {
  const std::string where = table.Where(row);
  const std::string cell = table.Cell(row, column);
  if (cell.empty()) {
    throw InputError(where + column + " is empty");
  }
  const std::string name = column;
  const std::string unit = name.substr(name.rfind('_') + 1);
  double value = 0;
  std::string written;
  if (name == "f_number" || !ParseLength(cell, unit, &value, &written)) {
    return ParseNumber(cell, where + column);
  }
  if (!written.empty() && written != unit) {
    auto& c = (*conversions)[name];
    if (c.second++ == 0) {
      std::ostringstream s;
      s << "'" << cell << "' (line " << row.line << ") as " << value << " "
        << unit;
      c.first = s.str();
    }
  }
  return value;
}

// One row's cells as a target, unchecked but for an empty name.
CalibrationTarget ReadTarget(const CsvTable& table,
                             const CsvTable::Row& row,
                             UnitConversions* conversions) {
  auto number = [&](const char* column) {
    return TargetNumber(table, row, column, conversions);
  };
  CalibrationTarget target;
  target.line = row.line;
  target.name = table.Cell(row, "name");
  if (target.name.empty()) {
    throw InputError(table.Where(row) + "the name cell is empty");
  }
  target.target_distance_m = number("target_distance_m");
  // Empty = unknown: dp_psf_calibrator fits it.
  target.focus_distance_m = table.Cell(row, "focus_distance_m").empty()
                                ? std::numeric_limits<double>::quiet_NaN()
                                : number("focus_distance_m");
  target.lens.focal_length_mm = number("focal_length_mm");
  target.lens.f_number = number("f_number");
  target.lens.pixel_pitch_um = number("pixel_pitch_um");
  target.left = table.Cell(row, "left");
  target.right = table.Cell(row, "right");
  return target;
}

// A target's files, distances and lens data, as a capture can have them
// (`where`: the row's message prefix).
void CheckTarget(const CalibrationTarget& target,
                 const std::string& where,
                 bool has_file_columns) {
  if (has_file_columns && (target.left.empty() || target.right.empty())) {
    throw InputError(where +
                     "left and right name the capture's DP view "
                     "files and may not be empty");
  }
  const bool focus_known = !std::isnan(target.focus_distance_m);
  if (!target.lens.Check() || !(target.target_distance_m > 0) ||
      (focus_known && !(target.focus_distance_m > 0))) {
    throw InputError(where + "distances and lens data must be positive");
  }
  // Distances are from the focal-plane mark: a lens focuses no nearer
  // than 4 f from the sensor.
  for (const double d : {target.target_distance_m, target.focus_distance_m}) {
    if (!std::isnan(d) && d * 1000 < 4 * target.lens.focal_length_mm) {
      throw InputError(where +
                       "distances from the focal-plane mark must "
                       "be at least 4 focal lengths (they are in metres)");
    }
  }
  if (focus_known && target.focus_distance_m >= 1000) {
    throw InputError(where + "focus_distance_m " +
                     std::to_string(target.focus_distance_m) +
                     " looks like millimetres: it is in metres (leave it "
                     "empty to fit it)");
  }
}

// One line per column whose cells were converted to its unit.
void LogConversions(const std::string& path,
                    const UnitConversions& conversions) {
  for (const auto& [column, c] : conversions) {
    LOG(INFO) << path << ": " << column << " read " << c.first
              << (c.second > 1 ? " (and " + std::to_string(c.second - 1) +
                                     " more cells converted alike)"
                               : std::string());
  }
}

}  // namespace

std::vector<CalibrationTarget> ReadCalibrationTargets(const std::string& path) {
  const CsvTable table = ReadTargetsTable(path);
  std::vector<CalibrationTarget> targets;
  UnitConversions conversions;
  for (const CsvTable::Row& row : table.rows()) {
    const CalibrationTarget target = ReadTarget(table, row, &conversions);
    CheckTarget(target, table.Where(row), table.Has("left"));
    targets.push_back(target);
  }
  if (targets.empty()) {
    throw InputError("calibration targets " + path + " list no capture");
  }
  LogConversions(path, conversions);
  return targets;
}

}  // namespace dpsfm
