// Throughput of the whole I/O-free core on a synthetic capture sized like a
// real one (default 30 views of 3000x2000 DP frames): seconds per view for
// each stage, patches per second, peak memory, and the scale error; and, in
// the same run, the time to decode the view's two frames from 16-bit PNG
// (what the command reads), so the core's cost reads as a multiple of
// decoding. Last, the per-patch blur estimator on its own: its setup time
// and the time per 111x111 patch at |r| <= 20 (default
// BlurEstimationOptions), on patches of its own seeds. Prints figures; never
// asserts timing.
//
//   dp_scale_core_bench [--views N] [--width W] [--height H] [--threads T]
//                       [--noise SIGMA] [--budget 1] [--resize F]
// --width alone keeps the 3:2 aspect ratio. --budget 1 visits the views
// under the command's default view budget (core/scale/view_budget.h:
// checkpoints from 14 views every 7, stop when the scale settles, at most 60),
// so a large --views shows the peak memory of a large project: views are
// rendered only when visited. --resize F sets
// PatchGeometryOptions::resize_factor (0 = the automatic working resolution).
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../tests/core/synthetic_dp.h"
#include "bench_timing.h"
#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/scale/scale_estimator.h"
#include "dpsfm/core/scale/view_budget.h"
#include "dpsfm/core/util/threads.h"

namespace {

double PeakMemoryMb() {
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
}

using namespace dpsfm;
using dpsfm::bench::Now;

// PatchBlurEstimator on its own: setup time for 111x111 patches at |r| <= 20
// (default BlurEstimationOptions), and the mean Estimate time over 8 patches
// x 4 repeats. The patches have their own seeds (cv::RNG instances local to
// the texture and the renderer): nothing the capture above draws changes.
void BenchPatchBlurEstimator() {
  const int patch = 111;
  const TranslatingDiskPsf psf;
  const BlurEstimationOptions options;  // |r| <= 20
  double t0 = Now();
  const PatchBlurEstimator estimator(psf, options, cv::Size(patch, patch));
  const double setup_ms = 1e3 * (Now() - t0);
  // Textured patches at blurs across the bound, rendered on a larger canvas
  // so the border holds real blurred content, then cropped.
  test::TextureOptions tex;
  tex.coarsest_cell_px = 48;
  tex.octaves = 6;
  tex.shapes_per_10k_px = 6;
  const int margin = 32;
  std::vector<test::DPPair> pairs;
  for (int i = 0; i < 8; ++i) {
    const cv::Mat sharp = test::MakeTexture(
        cv::Size(patch + 2 * margin, patch + 2 * margin), 200 + i, tex);
    test::RenderOptions render;
    render.noise_sigma = 0.01;
    render.noise_seed = 1200 + i;
    const test::DPPair full = test::RenderDP(sharp, psf, -12 + 3.3 * i, render);
    const cv::Rect crop(margin, margin, patch, patch);
    pairs.push_back({full.left(crop).clone(), full.right(crop).clone()});
  }
  const int repeats = 4;
  int valid = 0;
  t0 = Now();
  for (int k = 0; k < repeats; ++k) {
    for (const test::DPPair& pair : pairs) {
      valid += estimator.Estimate(pair.left, pair.right).valid;
    }
  }
  const double per_patch_ms =
      1e3 * (Now() - t0) / (repeats * static_cast<double>(pairs.size()));
  std::printf(
      "blur estimator:  setup %.1f ms, %.3f ms per %dx%d patch (|r| <= %.0f; "
      "%d patches x %d repeats, 1 thread, %d valid)\n",
      setup_ms,
      per_patch_ms,
      patch,
      patch,
      options.max_radius_px,
      static_cast<int>(pairs.size()),
      repeats,
      valid);
}

// The command line.
struct BenchArguments {
  int num_views = 30, width = 3000, height = 0, threads = -1;
  bool use_budget = false;
  double noise = 0.005, resize = 0;
};

// What the view loop adds up, and where it stopped.
struct ViewLoop {
  double render_seconds = 0, decode_seconds = 0;
  int patches_tried = 0, patches_valid = 0;
  double blur_seconds = 0, checkpoint_seconds = 0;
  int visited = 0;
  DPScaleResult last_checkpoint;
  std::string stop_reason;
};

constexpr double kScale = 0.0421;  // metres per model unit
constexpr double kDepthsM[] = {1.5, 1.8, 2.2, 2.7, 3.3, 4.0};

// Reads the flags (--height defaults to 2/3 of --width); false, with a
// message, on an unknown flag or too small a run.
bool ParseArguments(int argc, char** argv, BenchArguments* args) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--views")
      args->num_views = std::atoi(argv[i + 1]);
    else if (flag == "--width")
      args->width = std::atoi(argv[i + 1]);
    else if (flag == "--height")
      args->height = std::atoi(argv[i + 1]);
    else if (flag == "--threads")
      args->threads = std::atoi(argv[i + 1]);
    else if (flag == "--noise")
      args->noise = std::atof(argv[i + 1]);
    else if (flag == "--budget")
      args->use_budget = std::atoi(argv[i + 1]) != 0;
    else if (flag == "--resize")
      args->resize = std::atof(argv[i + 1]);
    else {
      std::fprintf(stderr, "unknown flag %s\n", argv[i]);
      return false;
    }
  }
  if (args->height <= 0) args->height = args->width * 2 / 3;
  if (args->num_views < 1 || args->width < 64 || args->height < 64) {
    std::fprintf(stderr, "need --views >= 1 and a frame of >= 64 px\n");
    return false;
  }
  return true;
}

// Lens: 50 mm f/2.8, pitch chosen so that the blur spans about the
// automatic radius bound at this frame size (a 6720 px wide sensor's
// 5.36 um pitch scaled to the synthetic width).
DPLensData BenchLens(int width) {
  DPLensData lens;
  lens.focal_length_mm = 50;
  lens.f_number = 2.8;
  lens.pixel_pitch_um = 5.36 * 6720.0 / width;
  return lens;
}

// View v: a texture over bands of depth, focused near 2 m, rendered as a DP
// pair (*pair) with the run's noise; the view holds the model depth.
DPView RenderBenchView(const BenchArguments& args,
                       int v,
                       const DPLensData& lens,
                       const DPPsfModel& psf,
                       test::DPPair* pair) {
  const int width = args.width, height = args.height;
  test::TextureOptions tex;
  tex.channels = 3;
  tex.coarsest_cell_px = 32.0 * width / 1500.0;
  const cv::Mat sharp = test::MakeTexture(cv::Size(width, height), 7 + v, tex);
  const double focus_m = 2.0 + 0.05 * (v % 7);
  cv::Mat depth_m(height, width, CV_32FC1);
  const int bands = 6;
  for (int x = 0; x < width; ++x) {
    depth_m.col(x).setTo(kDepthsM[(x * bands / width + v) % bands]);
  }
  cv::Mat radius(height, width, CV_32FC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      radius.at<float>(y, x) = static_cast<float>(PredictBlurRadiusPx(
          lens, lens.PixelPitchMm(), 1.0, focus_m, depth_m.at<float>(y, x)));
    }
  }
  test::RenderOptions render;
  render.noise_sigma = args.noise;
  render.noise_seed = 100 + v;
  *pair = test::RenderDP(sharp, psf, radius, render);
  DPView view;
  view.name = "view" + std::to_string(v);
  view.left = pair->left;
  view.right = pair->right;
  view.lens = lens;
  view.depth = depth_m / kScale;
  return view;
}

// Decoding reference: the two frames as 16-bit PNG (encoding untimed);
// adds the decoding time. False, with a message, if the round trip fails.
bool TimeDecoding(const test::DPPair& pair, double* decode_seconds) {
  std::vector<uchar> png_left, png_right;
  cv::Mat u16;
  pair.left.convertTo(u16, CV_16UC3, 65535.0);
  cv::imencode(".png", u16, png_left);
  pair.right.convertTo(u16, CV_16UC3, 65535.0);
  cv::imencode(".png", u16, png_right);
  const double d0 = Now();
  const cv::Mat a = cv::imdecode(png_left, cv::IMREAD_UNCHANGED);
  const cv::Mat b = cv::imdecode(png_right, cv::IMREAD_UNCHANGED);
  *decode_seconds += Now() - d0;
  if (a.empty() || b.empty()) {
    std::fprintf(stderr, "PNG round trip failed\n");
    return false;
  }
  return true;
}

// The first view's working geometry and why its patches were rejected.
void PrintGeometry(const DPViewSummary& s) {
  std::printf(
      "geometry: resize %.3f -> %dx%d, patch %d, stride %d, "
      "|r| <= %.1f px\n",
      s.resize_factor,
      s.working_size.width,
      s.working_size.height,
      s.patch_size,
      s.stride,
      s.max_radius_px);
  for (const auto& rejected : s.rejections) {
    std::printf(
        "  view 0: %d patches %s\n", rejected.second, rejected.first.c_str());
  }
}

// The view's patches, time and the peak memory so far.
void PrintViewLine(int v, const DPViewSummary& s) {
  std::printf(
      "  view %2d: %4d patches (%4d valid, %3d kept) in %.2f s, "
      "peak RSS %.0f MB\n",
      v,
      s.patches_tried,
      s.patches_valid,
      s.patches_kept,
      s.seconds,
      PeakMemoryMb());
  std::fflush(stdout);
}

// Estimates at a checkpoint of the view budget and prints it; true when the
// budget says stop.
bool RunCheckpoint(DPScaleEstimator* estimator,
                   ViewBudget* budget,
                   ViewLoop* loop) {
  const double c0 = Now();
  loop->last_checkpoint = estimator->Estimate();
  loop->checkpoint_seconds += Now() - c0;
  Checkpoint c;
  c.views = loop->visited;
  c.success = loop->last_checkpoint.success;
  c.scale = loop->last_checkpoint.scale;
  c.ci_low = loop->last_checkpoint.scale_ci_low;
  c.ci_high = loop->last_checkpoint.scale_ci_high;
  std::printf("  checkpoint after %d views: %s %.5f (%.1f s)\n",
              loop->visited,
              c.success ? "r_s" : "no scale",
              c.success ? c.scale / kScale : 0.0,
              Now() - c0);
  return budget->Record(c, &loop->stop_reason);
}

// Renders and adds the views the budget plans, with checkpoints; false if
// a PNG round trip failed.
bool VisitViews(const BenchArguments& args,
                const DPLensData& lens,
                const DPPsfModel& psf,
                DPScaleEstimator* estimator,
                ViewBudget* budget,
                ViewLoop* loop) {
  for (int v = 0; v < budget->Planned(); ++v) {
    double t0 = Now();
    test::DPPair pair;
    const DPView view = RenderBenchView(args, v, lens, psf, &pair);
    loop->render_seconds += Now() - t0;
    if (!TimeDecoding(pair, &loop->decode_seconds)) return false;
    const DPViewSummary s = estimator->AddView(view);
    loop->patches_tried += s.patches_tried;
    loop->patches_valid += s.patches_valid;
    loop->blur_seconds += s.seconds;
    if (v == 0) PrintGeometry(s);
    PrintViewLine(v, s);
    loop->visited = v + 1;
    if (budget->IsCheckpoint(loop->visited) &&
        RunCheckpoint(estimator, budget, loop)) {
      break;
    }
  }
  return true;
}

// How many views the budget visited and why it stopped.
void PrintBudget(const ViewLoop& loop, int requested_views) {
  std::printf(
      "\nview budget: %d of %d views visited (%s); checkpoints %.1f s\n",
      loop.visited,
      requested_views,
      !loop.stop_reason.empty()         ? loop.stop_reason.c_str()
      : loop.visited == requested_views ? "every view"
                                        : "the cap reached",
      loop.checkpoint_seconds);
}

// Seconds per view of each stage, patches per second, peak memory and the
// core's cost against decoding, over the visited views.
void PrintStageFigures(const ViewLoop& loop, const DPScaleResult& r) {
  const int num_views = loop.visited;
  std::printf("\nrendering (not part of the core): %.2f s per view\n",
              loop.render_seconds / num_views);
  std::printf(
      "blur stage:      %.3f s per view, %.0f patches/s (%d patches, "
      "%d valid)\n",
      loop.blur_seconds / num_views,
      loop.patches_tried / loop.blur_seconds,
      loop.patches_tried,
      loop.patches_valid);
  std::printf("linear stage:    %.4f s per view (%.3f s total)\n",
              r.seconds.linear / num_views,
              r.seconds.linear);
  std::printf(
      "intensity stage: %.3f s per view (%.2f s total, %d patches x "
      "%zu candidates)\n",
      r.seconds.intensity / num_views,
      r.seconds.intensity,
      r.num_patches,
      r.intensity.candidate_scales.size());
  std::printf("peak memory:     %.0f MB (ru_maxrss)\n", PeakMemoryMb());
  const double core_per_view =
      (loop.blur_seconds + r.seconds.linear + r.seconds.intensity) / num_views;
  std::printf(
      "decoding:        %.3f s per view (two 16-bit PNG frames, 1 thread); "
      "core %.3f s per view = %.1f x decoding\n",
      loop.decode_seconds / num_views,
      core_per_view,
      core_per_view / (loop.decode_seconds / num_views));
}

// The scale's errors and interval, or why the estimate failed.
void PrintScaleError(const DPScaleResult& r) {
  if (r.success) {
    std::printf(
        "scale error:     linear %+.4f, final %+.4f (intensity: %s), "
        "95%% interval [%+.4f, %+.4f], %d views used\n",
        r.scale_initial / kScale - 1,
        r.scale / kScale - 1,
        r.intensity.status.c_str(),
        r.scale_ci_low / kScale - 1,
        r.scale_ci_high / kScale - 1,
        r.num_views_used);
  } else {
    std::printf("estimate failed: %s\n", ScaleRefusalName(r.refusal.code));
  }
}

}  // namespace

int main(int argc, char** argv) {
  BenchArguments args;
  if (!ParseArguments(argc, argv, &args)) return 1;
  const int used_threads = EffectiveNumThreads(args.threads);
  std::printf(
      "dp_scale_core_bench: %d views of %dx%d RGB DP frames, noise "
      "%.4f, %d threads\n",
      args.num_views,
      args.width,
      args.height,
      args.noise,
      used_threads);
  auto psf = std::make_shared<TranslatingDiskPsf>();
  DPScaleOptions options;  // automatic geometry for the frame size
  options.num_threads = args.threads;
  options.geometry.resize_factor = args.resize;
  DPScaleEstimator estimator(options, psf);
  const DPLensData lens = BenchLens(args.width);
  ViewBudgetOptions budget_options;
  budget_options.all_views = !args.use_budget;
  ViewBudget budget(budget_options, args.num_views);
  ViewLoop loop;
  if (!VisitViews(args, lens, *psf, &estimator, &budget, &loop)) return 1;
  const DPScaleResult r =
      loop.stop_reason.empty() ? estimator.Estimate() : loop.last_checkpoint;
  if (args.use_budget) PrintBudget(loop, args.num_views);
  PrintStageFigures(loop, r);
  PrintScaleError(r);
  BenchPatchBlurEstimator();
  return 0;
}
