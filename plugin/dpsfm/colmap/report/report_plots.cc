#include "dpsfm/colmap/report/report_plots.h"

#include <functional>
#include <map>
#include <optional>
#include <set>

#include "colmap/util/threading.h"
#include "dpsfm/colmap/report/plot_canvas.h"
#include "dpsfm/colmap/report/plot_result.h"

namespace dpsfm {
namespace {

// `name` without its extension: the part from the last '.' on, if that is
// in the last component (after the last of `separators`).
std::string DropExtension(std::string name, const char* separators) {
  const size_t slash = name.find_last_of(separators);
  const size_t dot = name.find_last_of('.');
  const size_t base = slash == std::string::npos ? 0 : slash + 1;
  if (dot != std::string::npos && dot > base) name.erase(dot);
  return name;
}

// One picture to render and write.
struct PlotJob {
  std::string name;  // as in PlotFailure::plot
  std::string path;
  std::function<cv::Mat()> render;
};

// Renders and writes the pictures, `num_threads` at a time (each picture's
// drawing and PNG encoding is independent of the others'); records their
// paths in the jobs' order, or why one was not written.
ReportPlotFiles RunPlotJobs(const std::vector<PlotJob>& jobs, int num_threads) {
  const int num_jobs = static_cast<int>(jobs.size());
  std::vector<std::string> errors(num_jobs);
  std::vector<char> written(num_jobs, 0);
#ifdef _OPENMP
  const int threads = colmap::GetEffectiveNumThreads(num_threads);
#pragma omp parallel for schedule(dynamic) num_threads(threads)
#endif
  for (int k = 0; k < num_jobs; ++k) {
    written[k] = plot::RenderPng(jobs[k].render, jobs[k].path, &errors[k]);
  }
  ReportPlotFiles files;
  for (int k = 0; k < num_jobs; ++k) {
    if (written[k]) {
      files.written.push_back(jobs[k].path);
    } else {
      files.failures.push_back({jobs[k].name, jobs[k].path, errors[k]});
    }
  }
  return files;
}

// The overlay's patch side in DP-frame pixels: the working-frame side times
// the view's DP-frame pixels per working-frame pixel (from its patches, else
// from the image's default geometry); 0 (the overlay's default) without a
// working-frame side.
double OverlayPatchSide(int working_patch_size,
                        int view,
                        const cv::Size& frame_size,
                        const std::map<int, double>& frame_per_working) {
  if (working_patch_size <= 0) return 0;
  double ratio = plot::kNaN;
  const auto it = frame_per_working.find(view);
  if (it != frame_per_working.end()) ratio = it->second;
  if (!plot::Finite(ratio)) {
    const std::optional<PatchGeometry> geometry =
        plot::DefaultFrameGeometry(frame_size);
    ratio = geometry ? 1.0 / geometry->resize_factor : 1;
  }
  return working_patch_size * (plot::Finite(ratio) ? ratio : 1.0);
}

}  // namespace

std::string PlotFileComponent(const std::string& view_name) {
  std::string name = DropExtension(view_name, "/\\");
  for (char& c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                    (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
    if (!ok) c = '_';
  }
  if (name.empty()) name = "view";
  return name;
}

ReportPlotFiles WriteReportPlots(
    const DPScaleResult& result,
    const std::vector<OverlayImage>& overlay_images,
    const std::string& report_path,
    int working_patch_size,
    int num_threads) {
  const std::string stem = DropExtension(report_path, "/");
  std::vector<PlotJob> jobs;
  jobs.push_back({"blur_fit", stem + "_blur_fit.png", [&result] {
                    return RenderBlurFitPlot(result);
                  }});
  jobs.push_back({"loss", stem + "_loss.png", [&result] {
                    return RenderLossCurvePlot(result);
                  }});

  const std::map<int, double> frame_per_working =
      plot::FramePerWorkingPixel(result);
  std::set<std::string> used_names;
  for (const OverlayImage& overlay : overlay_images) {
    const int view = overlay.view;
    const cv::Mat& image = overlay.image;
    if (image.empty()) continue;
    const cv::Size frame =
        overlay.frame_size.empty() ? image.size() : overlay.frame_size;
    const std::string view_name = plot::ViewName(result, view);
    std::string component = PlotFileComponent(view_name);
    if (used_names.count(component)) component += "_" + std::to_string(view);
    used_names.insert(component);
    const double patch_size =
        OverlayPatchSide(working_patch_size, view, frame, frame_per_working);
    // The loop's values by copy: the jobs run after the loop.
    jobs.push_back({"patches_" + component,
                    stem + "_patches_" + component + ".png",
                    [&result, &image, view_name, view, patch_size, frame] {
                      return RenderPatchOverlay(
                          image, view_name, view, result, patch_size, frame);
                    }});
  }
  return RunPlotJobs(jobs, num_threads);
}

}  // namespace dpsfm
