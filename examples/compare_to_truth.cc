// Prints an estimate next to the ground truth of a generated scene: the scale
// ratio r_s = s_est / s_true (the paper's measure), the error |1 - r_s|, and
// each view's focus distance error. With --tsv, one tab-separated line for
// scripts: r_s of the linear and of the final estimate ("-" where the run
// gave none), views used, and whether the intensity stage was adopted.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include <algorithm>
#include <vector>

#include <nlohmann/json.hpp>

#include "colmap/scene/reconstruction.h"

namespace {

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error("cannot read " + path);
  return nlohmann::json::parse(file);
}

// The command line.
struct Arguments {
  std::string truth_path, report_path, model_path;
  bool tsv = false;
};

// Reads the flags; false without both files.
bool ParseArguments(int argc, char** argv, Arguments* args) {
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--tsv") {
      args->tsv = true;
    } else if (i + 1 < argc) {
      if (flag == "--ground_truth") args->truth_path = argv[i + 1];
      if (flag == "--report") args->report_path = argv[i + 1];
      if (flag == "--model_path") args->model_path = argv[i + 1];
      ++i;
    }
  }
  return !args->truth_path.empty() && !args->report_path.empty();
}

// The projection centres of the model's registered images that the truth
// knows, by name.
std::vector<std::pair<std::string, Eigen::Vector3d>> KnownCenters(
    const colmap::Reconstruction& model, const nlohmann::json& truth) {
  std::vector<std::pair<std::string, Eigen::Vector3d>> centers;
  for (const colmap::image_t id : model.RegImageIds()) {
    const colmap::Image& image = model.Image(id);
    if (truth.at("views").contains(image.Name())) {
      centers.emplace_back(image.Name(), image.ProjectionCenter());
    }
  }
  return centers;
}

// The model's camera distances over the true ones (metres), per pair of
// cameras apart in the truth, sorted.
std::vector<double> DistanceRatios(
    const std::vector<std::pair<std::string, Eigen::Vector3d>>& centers,
    const nlohmann::json& truth) {
  std::vector<double> ratios;
  for (size_t i = 0; i < centers.size(); ++i) {
    for (size_t j = i + 1; j < centers.size(); ++j) {
      const auto& a = truth["views"][centers[i].first]["center_m"];
      const auto& b = truth["views"][centers[j].first]["center_m"];
      const Eigen::Vector3d ta(a[0], a[1], a[2]), tb(b[0], b[1], b[2]);
      const double d_true = (ta - tb).norm();
      if (d_true > 1e-6) {
        ratios.push_back((centers[i].second - centers[j].second).norm() /
                         d_true);
      }
    }
  }
  if (ratios.empty()) throw std::runtime_error("no camera pairs to compare");
  std::sort(ratios.begin(), ratios.end());
  return ratios;
}

// A model of the real pipeline has a frame and scale of its own: judges it
// by its camera distances, which after rescaling must be metres.
void CompareModel(const nlohmann::json& truth, const std::string& model_path) {
  colmap::Reconstruction model;
  model.Read(model_path);
  const std::vector<std::pair<std::string, Eigen::Vector3d>> centers =
      KnownCenters(model, truth);
  const std::vector<double> ratios = DistanceRatios(centers, truth);
  const double median = ratios[ratios.size() / 2];
  std::printf("\nrescaled model %s: %zu registered images\n",
              model_path.c_str(),
              centers.size());
  std::printf(
      "camera distances, metres in the model / true metres: median "
      "%.4f (min %.4f, max %.4f over %zu pairs): error %.2f%%\n",
      median,
      ratios.front(),
      ratios.back(),
      ratios.size(),
      100 * std::abs(1 - median));
}

// The --tsv line: r_s of the linear and of the final estimate, views used,
// and whether the intensity stage was adopted.
void PrintTsvLine(const nlohmann::json& report, double s_true) {
  const auto ratio = [&](const char* key) {
    return report.contains(key) && report[key].is_number()
               ? std::to_string(report[key].get<double>() / s_true)
               : std::string("-");
  };
  std::printf("%s\t%s\t%d\t%s\n",
              ratio("scale_initial").c_str(),
              ratio("scale").c_str(),
              report.value("num_views_used", 0),
              report.at("intensity").value("used", false) ? "yes" : "no");
}

// The true scale, the linear and the final estimate with their ratios and
// errors, and the confidence interval.
void PrintScales(const nlohmann::json& report, double s_true) {
  const double s_est = report.at("scale").get<double>();
  const double s_lin = report.at("scale_initial").get<double>();
  std::printf("\n%-28s %12s %12s %10s\n", "", "scale", "ratio r_s", "error");
  std::printf("%-28s %12.6f\n", "true (metres / model unit)", s_true);
  std::printf("%-28s %12.6f %12.4f %9.2f%%\n",
              "linear initial estimate",
              s_lin,
              s_lin / s_true,
              100 * std::abs(1 - s_lin / s_true));
  std::printf("%-28s %12.6f %12.4f %9.2f%%\n",
              "final estimate",
              s_est,
              s_est / s_true,
              100 * std::abs(1 - s_est / s_true));
  if (report.contains("scale_ci_low") && report.contains("scale_ci_high")) {
    std::printf("%-28s [%.6f, %.6f]\n",
                "confidence interval",
                report["scale_ci_low"].get<double>(),
                report["scale_ci_high"].get<double>());
  }
}

// Each view's true and estimated focus distance, the error, and whether
// the estimate used the view.
void PrintViews(const nlohmann::json& truth, const nlohmann::json& report) {
  std::printf("\n%-16s %14s %14s %8s  %s\n",
              "view",
              "focus true m",
              "focus est m",
              "error",
              "used");
  for (const auto& item : truth.at("views").items()) {
    const double g_true = item.value().at("focus_distance_m").get<double>();
    if (!report.at("views").contains(item.key())) {
      std::printf("%-16s %14.4f %14s\n", item.key().c_str(), g_true, "-");
      continue;
    }
    const auto& view = report["views"][item.key()];
    const bool used = view.value("used", false);
    if (view.contains("focus_distance_m") &&
        view["focus_distance_m"].is_number()) {
      const double g_est = view["focus_distance_m"].get<double>();
      std::printf("%-16s %14.4f %14.4f %7.2f%%  %s\n",
                  item.key().c_str(),
                  g_true,
                  g_est,
                  100 * std::abs(1 - g_est / g_true),
                  used ? "yes" : ("no: " + view.value("reason", "")).c_str());
    } else {
      std::printf("%-16s %14.4f %14s %8s  %s\n",
                  item.key().c_str(),
                  g_true,
                  "-",
                  "-",
                  ("no: " + view.value("reason", "")).c_str());
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  if (!ParseArguments(argc, argv, &args)) {
    std::cerr << "usage: dpsfm_compare_to_truth --ground_truth FILE --report "
                 "FILE [--model_path RESCALED_MODEL | --tsv]\n";
    return EXIT_FAILURE;
  }
  try {
    const nlohmann::json truth = ReadJson(args.truth_path);
    const nlohmann::json report = ReadJson(args.report_path);
    if (!args.model_path.empty()) {
      CompareModel(truth, args.model_path);
      return EXIT_SUCCESS;
    }
    const double s_true = truth.at("scale").get<double>();
    if (args.tsv) {
      PrintTsvLine(report, s_true);
      return EXIT_SUCCESS;
    }
    PrintScales(report, s_true);
    PrintViews(truth, report);
    return EXIT_SUCCESS;
  } catch (const std::exception& error) {
    std::cerr << "ERROR: dpsfm_compare_to_truth: " << error.what() << std::endl;
    return EXIT_FAILURE;
  }
}
