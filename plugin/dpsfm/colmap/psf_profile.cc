#include "dpsfm/colmap/psf_profile.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "dpsfm/colmap/text.h"
#include "dpsfm/colmap/workspace.h"

namespace dpsfm {
namespace {

double ParseNumber(const std::string& text, const std::string& where) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end == text.c_str() || *end != '\0' ||
      !std::isfinite(value)) {
    throw InputError(where + ": expected a number, got '" + text + "'");
  }
  return value;
}

}  // namespace

PsfProfileFile ReadPsfProfile(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw InputError("cannot read DP PSF profile " + path);
  PsfProfileFile profile;
  std::map<std::string, std::string> values;
  std::map<std::string, int> lines;
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
      profile.fit_info.emplace_back(key, value);
      continue;
    }
    if (key != "format" && key != "model" && key != "split_exponent" &&
        key != "crosstalk" && key != "rim_softness" &&
        key != "band_split_exponents") {
      throw InputError(where + ": unknown key '" + key + "'");
    }
    if (!values.emplace(key, value).second) {
      throw InputError(where + ": '" + key + "' is given twice");
    }
    lines[key] = number;
  }
  auto where = [&](const std::string& key) {
    return path + ":" + std::to_string(lines[key]);
  };
  if (values.count("format") == 0 || values["format"] != "1") {
    throw InputError(path +
                     " is not a dp-sfm DP PSF profile (needs 'format 1'; "
                     "write one with colmap dp_psf_calibrator)");
  }
  if (values.count("model") == 0 || values["model"] != "split_profile") {
    throw InputError(path + ": needs 'model split_profile'");
  }
  if (values.count("split_exponent") == 0) {
    throw InputError(path + ": needs 'split_exponent'");
  }
  profile.params.split_exponent =
      ParseNumber(values["split_exponent"], where("split_exponent"));
  if (values.count("crosstalk")) {
    profile.params.crosstalk =
        ParseNumber(values["crosstalk"], where("crosstalk"));
  }
  if (values.count("rim_softness")) {
    profile.params.rim_softness =
        ParseNumber(values["rim_softness"], where("rim_softness"));
  }
  if (values.count("band_split_exponents")) {
    std::istringstream stream(values["band_split_exponents"]);
    std::string item;
    while (stream >> item) {
      profile.band_split_exponents.push_back(
          ParseNumber(item, where("band_split_exponents")));
      SplitProfileParams band = profile.params;
      band.split_exponent = profile.band_split_exponents.back();
      if (!band.Check()) {
        throw InputError(where("band_split_exponents") +
                         ": split exponents must lie in [0.05, 8]");
      }
    }
    if (profile.band_split_exponents.size() < 2) {
      throw InputError(where("band_split_exponents") +
                       ": needs two or more bands");
    }
  }
  if (!profile.params.Check()) {
    throw InputError(path + ": profile out of range (" +
                     profile.params.ToString() +
                     "; split_exponent in [0.05, 8], crosstalk in [0, "
                     "0.45], rim_softness in [0, 0.5])");
  }
  return profile;
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
       << "model split_profile\n"
       << std::setprecision(6) << "split_exponent "
       << profile.params.split_exponent << "\n"
       << "crosstalk " << profile.params.crosstalk << "\n"
       << "rim_softness " << profile.params.rim_softness << "\n";
  if (!profile.band_split_exponents.empty()) {
    file << "band_split_exponents";
    for (const double p : profile.band_split_exponents) file << " " << p;
    file << "\n";
  }
  for (const auto& entry : profile.fit_info) {
    file << entry.first << " " << entry.second << "\n";
  }
  if (!file) throw InputError("cannot write DP PSF profile " + path);
}

std::vector<std::shared_ptr<const DPPsfModel>> MakePsfModels(
    const std::string& psf_model,
    const std::string& psf_path,
    DPScaleOptions* core) {
  if (psf_model == "translating_disk" || psf_model == "auto") {
    if (!psf_path.empty()) {
      throw InputError(
          "--DPScaleEstimator.psf_path is only used with "
          "--DPScaleEstimator.psf_model calibrated (got " +
          psf_model + ")");
    }
    core->psf_self_calibration = psf_model == "auto";
    return {std::make_shared<TranslatingDiskPsf>()};
  }
  if (psf_model == "calibrated") {
    if (psf_path.empty()) {
      throw InputError(
          "--DPScaleEstimator.psf_model calibrated needs "
          "--DPScaleEstimator.psf_path (a profile written by colmap "
          "dp_psf_calibrator)");
    }
    core->psf_self_calibration = false;
    const PsfProfileFile profile = ReadPsfProfile(psf_path);
    if (profile.band_split_exponents.empty()) {
      return {std::make_shared<SplitProfilePsf>(profile.params)};
    }
    std::vector<std::shared_ptr<const DPPsfModel>> bands;
    for (const double p : profile.band_split_exponents) {
      SplitProfileParams params = profile.params;
      params.split_exponent = p;
      bands.push_back(std::make_shared<SplitProfilePsf>(params));
    }
    return bands;
  }
  throw InputError("unknown --DPScaleEstimator.psf_model '" + psf_model +
                   "' (translating_disk, calibrated or auto)");
}

std::vector<CalibrationTarget> ReadCalibrationTargets(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw InputError("cannot read calibration targets " + path);
  const std::string header =
      "name,target_distance_m,focus_distance_m,focal_length_mm,f_number,"
      "pixel_pitch_um";
  std::string line;
  if (!std::getline(file, line) || Trim(line) != header) {
    throw InputError("calibration targets " + path +
                     " must start with the header " + header);
  }
  std::vector<CalibrationTarget> targets;
  int number = 1;
  while (std::getline(file, line)) {
    ++number;
    if (Trim(line).empty()) continue;
    const std::string where = path + ":" + std::to_string(number);
    std::vector<std::string> cells;
    std::stringstream stream(line);
    std::string cell;
    while (std::getline(stream, cell, ',')) cells.push_back(Trim(cell));
    if (cells.size() != 6 || cells[0].empty()) {
      throw InputError(where + ": expected " + header);
    }
    CalibrationTarget target;
    target.name = cells[0];
    target.target_distance_m = ParseNumber(cells[1], where);
    target.focus_distance_m = ParseNumber(cells[2], where);
    target.lens.focal_length_mm = ParseNumber(cells[3], where);
    target.lens.f_number = ParseNumber(cells[4], where);
    target.lens.pixel_pitch_um = ParseNumber(cells[5], where);
    if (!target.lens.Check() || !(target.target_distance_m > 0) ||
        !(target.focus_distance_m > 0)) {
      throw InputError(where + ": distances and lens data must be positive");
    }
    if (target.focus_distance_m * 1000 <= target.lens.focal_length_mm) {
      throw InputError(where +
                       ": the focus distance must exceed the focal length");
    }
    targets.push_back(target);
  }
  if (targets.empty()) {
    throw InputError("calibration targets " + path + " list no capture");
  }
  return targets;
}

}  // namespace dpsfm
