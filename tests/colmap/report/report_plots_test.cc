// Report pictures: files are written as PNGs of the expected size with
// content, marks land where the axes put their data, patch colours mean what
// the legend says, odd results (NaN, empty, failed) still give pictures
// instead of exceptions, and pictures that cannot be written are reported
// with the reason.
#include "dpsfm/colmap/report/report_plots.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dpsfm/colmap/report/plot_axes.h"
#include "dpsfm/colmap/report/plot_canvas.h"
#include "dpsfm/colmap/report/plot_text.h"
#include "dpsfm/colmap/report/report.h"
#include "dpsfm/core/optics/lens_model.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A plausible successful result: `num_views` views of one scene, patches
// whose measured blur follows the thin-lens model plus noise, a loss curve
// with a minimum near the scale.
DPScaleResult RealisticResult(int num_views, double resize_factor = 1.0) {
  DPScaleResult result;
  result.success = true;
  result.scale = 0.42;
  result.scale_initial = 0.41;
  result.scale_ci_low = 0.40;
  result.scale_ci_high = 0.44;
  result.scale_initial_ci_low = 0.39;
  result.scale_initial_ci_high = 0.43;
  result.intensity.used = true;
  result.intensity.status = "adopted (95 % interval 9.5 % of the scale)";
  result.intensity.scale = 0.42;
  result.intensity.ci_low = 0.40;
  result.intensity.ci_high = 0.44;
  result.intensity.bootstrap_support = 0.87;
  result.intensity.loss = "noise-corrected L2";
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 0.15);
  std::uniform_real_distribution<double> uniform(0, 1);
  for (int v = 0; v < num_views; ++v) {
    DPViewResult view;
    view.name =
        "cam" + std::to_string(v % 3) + "/DP_" + std::to_string(v) + ".jpg";
    view.used = v != 1;
    view.reason = view.used ? "used" : "predicted blur range too small";
    view.lens.focal_length_mm = 50;
    view.lens.f_number = 2.8;
    view.lens.pixel_pitch_um = 30;
    view.focus_distance_model = 2.5 + 0.3 * v;
    view.focus_distance_m = result.scale * view.focus_distance_model;
    result.views.push_back(view);
    const double working_pitch_mm = view.lens.PixelPitchMm() / resize_factor;
    for (int k = 0; k < 60; ++k) {
      PatchSample s;
      s.view = v;
      s.x = 20 + 1160 * uniform(rng);
      s.y = 20 + 760 * uniform(rng);
      s.depth = 1.5 + 4 * uniform(rng);
      s.predicted_radius_px = PredictBlurRadiusPx(view.lens,
                                                  working_pitch_mm,
                                                  result.scale,
                                                  view.focus_distance_model,
                                                  s.depth);
      s.radius_px = s.predicted_radius_px + noise(rng) * resize_factor;
      s.radius_frame_px = s.radius_px / resize_factor;
      s.confidence = uniform(rng);
      s.selected = k < 40;
      s.used = s.selected && view.used;
      result.patches.push_back(s);
    }
  }
  for (int i = 0; i <= 100; ++i) {
    const double s = 0.08 + 0.68 * i / 100.0;
    result.intensity.candidate_scales.push_back(s);
    result.intensity.candidate_losses.push_back(10 +
                                                200 * (s - 0.42) * (s - 0.42));
  }
  return result;
}

bool IsPng(const std::string& path) {
  const std::string bytes = test::ReadTextFile(path);
  return bytes.size() > 8 && bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0;
}

double PixelStdDev(const cv::Mat& image) {
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  return (stddev[0] + stddev[1] + stddev[2]) / 3;
}

// Mean BGR over a small window around `p` (robust to anti-aliased edges).
cv::Vec3d MeanColourAround(const cv::Mat& image, const cv::Point2d& p) {
  const cv::Rect window(static_cast<int>(std::lround(p.x)) - 2,
                        static_cast<int>(std::lround(p.y)) - 2,
                        5,
                        5);
  const cv::Scalar mean =
      cv::mean(image(window & cv::Rect(0, 0, image.cols, image.rows)));
  return cv::Vec3d(mean[0], mean[1], mean[2]);
}

// Example pictures for a person to look at: DPSFM_PLOT_DUMP_DIR=/some/dir.
void MaybeDump(const cv::Mat& image, const std::string& name) {
  const char* dir = std::getenv("DPSFM_PLOT_DUMP_DIR");
  if (dir == nullptr || image.empty()) return;
  cv::imwrite(std::string(dir) + "/" + name, image);
}

TEST(ReportPlots, BlurFitAndLossPlotsAreWrittenAsNonBlankPngs) {
  test::TempDir dir;
  const DPScaleResult result = RealisticResult(4);
  ASSERT_TRUE(WriteBlurFitPlot(result, dir / "blur.png"));
  ASSERT_TRUE(WriteLossCurvePlot(result, dir / "loss.png"));
  for (const std::string name : {"blur.png", "loss.png"}) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(IsPng(dir / name));
    const cv::Mat image = cv::imread(dir / name, cv::IMREAD_COLOR);
    ASSERT_FALSE(image.empty());
    EXPECT_EQ(image.cols, 1000);
    EXPECT_EQ(image.rows, 700);
    EXPECT_GT(PixelStdDev(image), 10);
    MaybeDump(image, "realistic_" + name);
  }
}

TEST(ReportPlots, BlurFitShowsEveryUsedViewInItsColour) {
  // Used views get the palette's colours, so their points must be on the
  // picture: tab10 blue (view with the most points) appears in many pixels.
  const cv::Mat image = RenderBlurFitPlot(RealisticResult(3));
  const cv::Vec3b tab_blue(180, 119, 31);
  int count = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      if (image.at<cv::Vec3b>(y, x) == tab_blue) ++count;
    }
  }
  EXPECT_GT(count, 200);
}

// Pixel at `p` (rounded), as doubles.
cv::Vec3d PixelAt(const cv::Mat& image, const cv::Point2d& p) {
  const cv::Vec3b v = image.at<cv::Vec3b>(static_cast<int>(std::lround(p.y)),
                                          static_cast<int>(std::lround(p.x)));
  return cv::Vec3d(v[0], v[1], v[2]);
}

// Largest per-channel difference.
double ColourDistance(const cv::Vec3d& a, const cv::Vec3d& b) {
  return std::max(
      {std::abs(a[0] - b[0]), std::abs(a[1] - b[1]), std::abs(a[2] - b[2])});
}

bool Inside(const cv::Rect& area, const cv::Point2d& p, int margin) {
  return p.x >= area.x + margin && p.x <= area.x + area.width - margin &&
         p.y >= area.y + margin && p.y <= area.y + area.height - margin;
}

// Of the used patches whose point falls inside `axes`' area (4 px from its
// edges), how many are drawn in `colour` at the pixel the axes map them to,
// and the first that is not.
struct Landing {
  int inside = 0, landed = 0;
  std::string first_miss;
};
template <typename ToData>
Landing PointsLanding(const cv::Mat& image,
                      const plot::Axes& axes,
                      const DPScaleResult& result,
                      const cv::Vec3d& colour,
                      ToData to_data) {
  Landing landing;
  for (const PatchSample& s : result.patches) {
    if (!s.used) continue;
    const cv::Point2d data = to_data(s);
    const cv::Point2d p = axes.ToPixel(data.x, data.y);
    if (!Inside(axes.area, p, 4)) continue;
    ++landing.inside;
    const cv::Vec3d pixel = PixelAt(image, p);
    if (ColourDistance(pixel, colour) < 10) {
      ++landing.landed;
    } else if (landing.first_miss.empty()) {
      std::ostringstream miss;
      miss << "data " << data << " at pixel " << p << " is " << pixel;
      landing.first_miss = miss.str();
    }
  }
  return landing;
}

TEST(ReportPlots, BlurFitPointsLandWhereThePanelsPutTheirData) {
  const cv::Vec3d tab_blue(180, 119, 31);  // the view with the most points
  // Right panel: measured against predicted radius (the model line is in the
  // left panel only, so a blue pixel there is a point).
  const DPScaleResult result = RealisticResult(1);
  const Landing right = PointsLanding(
      RenderBlurFitPlot(result),
      BlurFitAxes(result).right,
      result,
      tab_blue,
      [](const PatchSample& s) {
        return cv::Point2d(s.predicted_radius_px, s.radius_frame_px);
      });
  EXPECT_GE(right.inside, 30);
  EXPECT_EQ(right.landed, right.inside) << right.first_miss;

  // Left panel: against 1/z'. Without predictions or a lens there is no
  // model line, so again a blue pixel is a point.
  DPScaleResult bare = result;
  bare.views[0].lens = DPLensData();
  for (PatchSample& s : bare.patches) s.predicted_radius_px = kNaN;
  const Landing left =
      PointsLanding(RenderBlurFitPlot(bare),
                    BlurFitAxes(bare).left,
                    bare,
                    tab_blue,
                    [](const PatchSample& s) {
                      return cv::Point2d(1.0 / s.depth, s.radius_frame_px);
                    });
  EXPECT_GE(left.inside, 30);
  EXPECT_EQ(left.landed, left.inside) << left.first_miss;
}

TEST(ReportPlots, ManyViewsAndResizedFramesStillDraw) {
  const DPScaleResult result = RealisticResult(14, 0.5);
  const cv::Mat image = RenderBlurFitPlot(result);
  ASSERT_FALSE(image.empty());
  EXPECT_GT(PixelStdDev(image), 10);
  MaybeDump(image, "many_views_blur.png");
}

DPScaleResult TwoPatchResult() {
  DPScaleResult result;
  result.success = true;
  result.scale = 1;
  DPViewResult view;
  view.name = "DP_0001.jpg";
  view.used = true;
  result.views.push_back(view);
  PatchSample far;
  far.view = 0;
  far.x = 100;
  far.y = 80;
  far.depth = 3;
  far.radius_px = far.radius_frame_px = 3;
  far.selected = far.used = true;
  PatchSample near = far;
  near.x = 300;
  near.y = 220;
  near.radius_px = near.radius_frame_px = -3;
  // A patch of another view at the same place must not be drawn.
  PatchSample other = far;
  other.view = 1;
  other.x = 200;
  other.y = 150;
  result.patches = {far, near, other};
  return result;
}

TEST(ReportPlots, OverlayColoursPositiveBlurRedAndNegativeBlue) {
  const cv::Mat image(300, 400, CV_32FC1, cv::Scalar(0.05));
  const DPScaleResult result = TwoPatchResult();
  const cv::Mat overlay =
      RenderPatchOverlay(image, "DP_0001.jpg", 0, result, 40);
  ASSERT_FALSE(overlay.empty());
  MaybeDump(overlay, "two_patches.png");

  const cv::Vec3d far =
      MeanColourAround(overlay, PatchOverlayPoint(image.size(), 100, 80));
  const cv::Vec3d near =
      MeanColourAround(overlay, PatchOverlayPoint(image.size(), 300, 220));
  const cv::Vec3d background =
      MeanColourAround(overlay, PatchOverlayPoint(image.size(), 200, 150));
  EXPECT_GT(far[2], far[0] + 40) << far;     // red over blue
  EXPECT_GT(near[0], near[2] + 40) << near;  // blue over red
  // Grey background, untouched by the other view's patch.
  EXPECT_NEAR(background[0], background[2], 3) << background;
}

// The run keeps the overlay's image at the working resolution: with the DP
// frame's size given, a half-size image puts the patches where the frame
// itself does, and the picture is laid out as the frame's.
TEST(ReportPlots, OverlayOfAReducedImageIsLaidOutForItsFrame) {
  const cv::Mat image(300, 400, CV_32FC1, cv::Scalar(0.05));
  cv::Mat half;
  cv::resize(image, half, cv::Size(200, 150), 0, 0, cv::INTER_AREA);
  const DPScaleResult result = TwoPatchResult();
  const cv::Mat full = RenderPatchOverlay(image, "DP_0001.jpg", 0, result, 40);
  const cv::Mat reduced =
      RenderPatchOverlay(half, "DP_0001.jpg", 0, result, 40, image.size());
  ASSERT_FALSE(reduced.empty());
  EXPECT_EQ(reduced.size(), full.size());
  // Taken for the frame, the half-size image puts the patches elsewhere.
  const cv::Mat wrong = RenderPatchOverlay(half, "DP_0001.jpg", 0, result, 40);
  EXPECT_GT(
      cv::norm(
          MeanColourAround(wrong, PatchOverlayPoint(image.size(), 300, 220)) -
          MeanColourAround(full, PatchOverlayPoint(image.size(), 300, 220))),
      20);
  for (const cv::Point2d& at : {cv::Point2d(100, 80), cv::Point2d(300, 220)}) {
    const cv::Vec3d want =
        MeanColourAround(full, PatchOverlayPoint(image.size(), at.x, at.y));
    const cv::Vec3d got =
        MeanColourAround(reduced, PatchOverlayPoint(image.size(), at.x, at.y));
    EXPECT_LT(cv::norm(got - want), 3) << at << ": " << got << " vs " << want;
  }
}

TEST(ReportPlots, OverlayFillsEachUsedPatchSquareWithItsColour) {
  const cv::Mat image(300, 400, CV_32FC1, cv::Scalar(0.05));
  const DPScaleResult result = TwoPatchResult();
  const double patch_size = 40;
  const cv::Mat overlay =
      RenderPatchOverlay(image, "DP_0001.jpg", 0, result, patch_size);
  ASSERT_FALSE(overlay.empty());
  // Picture pixels per frame pixel, and the squares' half side.
  const double d = PatchOverlayPoint(image.size(), 1, 0).x -
                   PatchOverlayPoint(image.size(), 0, 0).x;
  const double half = 0.5 * patch_size * d;
  ASSERT_GT(half, 10);
  const cv::Vec3d background =
      PixelAt(overlay, PatchOverlayPoint(image.size(), 200, 150));
  // Both patches are at the colour map's ends (|r| = 3 is the limit); a
  // used square is the colour blended 70 % over the image.
  for (int k = 0; k < 2; ++k) {
    const PatchSample& s = result.patches[k];
    SCOPED_TRACE("patch at " + std::to_string(s.x) + "," + std::to_string(s.y));
    const cv::Scalar colour = plot::DivergingColour(s.radius_frame_px / 3);
    const cv::Vec3d fill =
        0.3 * background + 0.7 * cv::Vec3d(colour[0], colour[1], colour[2]);
    const cv::Point2d c = PatchOverlayPoint(image.size(), s.x, s.y);
    // At the centre and 4 px inside each edge: the fill; 4 px outside each
    // edge: the image.
    const double in = half - 4, out = half + 4;
    const std::vector<std::pair<cv::Point2d, cv::Vec3d>> expected = {
        {{0, 0}, fill},
        {{-in, 0}, fill},
        {{in, 0}, fill},
        {{0, -in}, fill},
        {{0, in}, fill},
        {{-out, 0}, background},
        {{out, 0}, background},
        {{0, -out}, background},
        {{0, out}, background}};
    for (const auto& [offset, want] : expected) {
      const cv::Vec3d pixel = PixelAt(overlay, c + offset);
      EXPECT_LT(ColourDistance(pixel, want), 3)
          << "at offset " << offset << ": " << pixel << ", expected " << want;
    }
  }
}

TEST(ReportPlots, OverlayOfLargeColourFrameIsDownscaledTo1600) {
  test::TempDir dir;
  cv::Mat image(2000, 3000, CV_32FC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(0.1));  // dark linear
  DPScaleResult result = TwoPatchResult();
  result.patches[0].x = 2500;
  result.patches[0].y = 1500;
  result.patches[1].x = 500;
  result.patches[1].y = 400;
  ASSERT_TRUE(WritePatchOverlay(image, "big", 0, result, 150, dir / "o.png"));
  const cv::Mat overlay = cv::imread(dir / "o.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(overlay.empty());
  EXPECT_TRUE(IsPng(dir / "o.png"));
  const cv::Point2d corner = PatchOverlayPoint(image.size(), 2999.5, 1999.5);
  EXPECT_NEAR(
      corner.x - PatchOverlayPoint(image.size(), -0.5, -0.5).x, 1600, 1);
  EXPECT_LE(overlay.cols, 1600 + 250);
  EXPECT_GT(overlay.cols, 1600);
  EXPECT_GT(overlay.rows, 1067);
  const cv::Vec3d far =
      MeanColourAround(overlay, PatchOverlayPoint(image.size(), 2500, 1500));
  const cv::Vec3d near =
      MeanColourAround(overlay, PatchOverlayPoint(image.size(), 500, 400));
  EXPECT_GT(far[2], far[0] + 40) << far;
  EXPECT_GT(near[0], near[2] + 40) << near;
  // The display gamma makes a dark frame visible: the image area is not
  // near-black.
  const cv::Point2d middle = PatchOverlayPoint(image.size(), 1500, 1000);
  const cv::Scalar mean =
      cv::mean(overlay(cv::Rect(static_cast<int>(middle.x) - 50,
                                static_cast<int>(middle.y) - 50,
                                100,
                                100)));
  EXPECT_GT(mean[0], 80);
}

TEST(ReportPlots, OverlayAcceptsOtherImageTypes) {
  const DPScaleResult result = TwoPatchResult();
  for (const int type : {CV_8UC1, CV_8UC3, CV_16UC1, CV_16UC3, CV_64FC1}) {
    cv::Mat image(300, 400, type, cv::Scalar::all(10));
    const cv::Mat overlay = RenderPatchOverlay(image, "", 0, result, 0);
    EXPECT_FALSE(overlay.empty()) << type;
  }
  EXPECT_TRUE(RenderPatchOverlay(cv::Mat(), "x", 0, result, 40).empty());
  test::TempDir dir;
  EXPECT_FALSE(
      WritePatchOverlay(cv::Mat(), "x", 0, result, 40, dir / "none.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "none.png"));
}

TEST(ReportPlots, EmptyAndNaNResultsDoNotThrow) {
  test::TempDir dir;
  const DPScaleResult empty;
  EXPECT_NO_THROW(EXPECT_TRUE(WriteBlurFitPlot(empty, dir / "e_blur.png")));
  EXPECT_NO_THROW(EXPECT_TRUE(WriteLossCurvePlot(empty, dir / "e_loss.png")));
  const cv::Mat image(50, 60, CV_32FC1, cv::Scalar(kNaN));
  EXPECT_NO_THROW(EXPECT_TRUE(
      WritePatchOverlay(image, "v", 0, empty, 10, dir / "e_patches.png")));
  MaybeDump(cv::imread(dir / "e_loss.png"), "empty_loss.png");

  DPScaleResult odd = RealisticResult(3);
  odd.success = false;
  // A long refusal: no view passed selection, and where the patches went.
  odd.refusal.code = ScaleRefusal::kLinearStageFailed;
  odd.refusal.linear_failure.cause = LinearFailureCause::kNoViewSelected;
  odd.refusal.linear_failure.min_blur_range_px = 2;
  odd.refusal.linear_failure.view_rejections = {
      {2, ViewRejection::kSmallBlurRange}, {1, ViewRejection::kPoorFit}};
  odd.refusal.patches.tried = 300;
  odd.refusal.patches.usable = 12;
  odd.scale = kNaN;
  odd.scale_ci_low = kNaN;
  odd.scale_ci_high = kNaN;
  odd.intensity.scale = kNaN;
  odd.intensity.ci_low = -kNaN;
  odd.intensity.bootstrap_support = kNaN;
  odd.intensity.candidate_scales.push_back(kNaN);  // longer than the losses
  odd.intensity.candidate_losses[3] = kNaN;
  odd.intensity.candidate_losses[4] = std::numeric_limits<double>::infinity();
  for (PatchSample& s : odd.patches) s.used = false;
  odd.patches[0].x = kNaN;
  odd.patches[1].depth = 0;
  odd.patches[2].radius_frame_px = kNaN;
  odd.patches[3].predicted_radius_px = kNaN;
  odd.patches[4].view = 99;
  odd.patches[5].view = -1;
  odd.patches[6].x = 1e300;
  odd.patches[7].radius_frame_px = 1e300;
  odd.views[0].focus_distance_model = kNaN;
  odd.views[0].focus_distance_m = kNaN;
  const cv::Mat frame(800, 1200, CV_32FC3, cv::Scalar::all(0.3));
  ReportPlotFiles files;
  EXPECT_NO_THROW(
      files = WriteReportPlots(odd,
                               {{0, frame}, {99, frame}, {-1, cv::Mat()}},
                               dir / "failed.json",
                               33));
  EXPECT_EQ(files.written.size(), 4u);
  EXPECT_TRUE(files.failures.empty());
  for (const std::string& path : files.written) {
    EXPECT_TRUE(IsPng(path)) << path;
    const cv::Mat picture = cv::imread(path);
    EXPECT_GT(PixelStdDev(picture), 5) << path;
    MaybeDump(picture,
              "failed_" + std::filesystem::path(path).filename().string());
  }

  // No curve at all (intensity stage skipped).
  DPScaleResult skipped = RealisticResult(2);
  skipped.intensity.candidate_scales.clear();
  skipped.intensity.candidate_losses.clear();
  skipped.intensity.used = false;
  skipped.intensity.status = "skipped (--intensity_refinement 0)";
  cv::Mat loss;
  EXPECT_NO_THROW(loss = RenderLossCurvePlot(skipped));
  EXPECT_GT(PixelStdDev(loss), 5);
  MaybeDump(loss, "skipped_loss.png");
}

// The column of the pixel in row `y` of `area` closest to `colour`.
int ClosestColumn(const cv::Mat& image,
                  const cv::Rect& area,
                  int y,
                  const cv::Vec3d& colour) {
  int best = -1;
  double best_distance = 1e9;
  for (int x = area.x + 2; x < area.x + area.width - 2; ++x) {
    const double distance =
        ColourDistance(PixelAt(image, {double(x), double(y)}), colour);
    if (distance < best_distance) {
      best_distance = distance;
      best = x;
    }
  }
  return best;
}

TEST(ReportPlots, LossCurveMarksLandAtTheirScales) {
  // Final scale, linear estimate and minimiser apart from each other.
  DPScaleResult result = RealisticResult(2);
  result.scale = 0.55;
  result.scale_ci_low = 0.53;
  result.scale_ci_high = 0.57;
  result.scale_initial = 0.3;
  const cv::Mat image = RenderLossCurvePlot(result);
  const plot::Axes axes = LossCurveAxes(result);
  EXPECT_EQ(axes.area.br().y, 530);
  MaybeDump(image, "marks_loss.png");

  // The final scale's line: in rows below the legend and above the curve,
  // the pixel closest to its colour is where the axes put s.
  const cv::Vec3d final_colour(170, 90, 20);
  const double final_x = axes.ToPixel(result.scale, 0).x;
  for (const double fraction : {0.45, 0.55, 0.65}) {
    const int y = axes.area.y + static_cast<int>(fraction * axes.area.height);
    const int x = ClosestColumn(image, axes.area, y, final_colour);
    EXPECT_NEAR(x, final_x, 1) << "row " << y;
    EXPECT_LT(
        ColourDistance(PixelAt(image, {double(x), double(y)}), final_colour),
        40)
        << "row " << y;
  }

  // The minimiser's diamond on the curve at s = 0.42, where the loss is 10.
  const cv::Vec3d minimum_colour(50, 40, 215);
  const cv::Point2d minimum = axes.ToPixel(result.intensity.scale, 10);
  for (const cv::Point2d& offset :
       {cv::Point2d(0, 0), cv::Point2d(0, -4), cv::Point2d(0, 4)}) {
    EXPECT_LT(ColourDistance(PixelAt(image, minimum + offset), minimum_colour),
              10)
        << "minimiser at " << minimum << " + " << offset << ": "
        << PixelAt(image, minimum + offset);
  }
}

// The walkthrough's answer (docs/user-guide.md, "A first hour"): the
// intensity stage skipped, no loss curve, and the answer formed from two
// cues that agree, neither of which it equals.
DPScaleResult AnswerFromTwoCues() {
  DPScaleResult result = RealisticResult(2);
  result.intensity.candidate_scales.clear();
  result.intensity.candidate_losses.clear();
  result.intensity.used = false;
  result.intensity.status = "skipped (the DP profile is calibrated)";
  result.intensity.scale = 0;
  result.intensity.ci_low = result.intensity.ci_high = 0;
  result.scale_initial = 0.318;
  result.scale_initial_ci_low = 0.287;
  result.scale_initial_ci_high = 0.351;
  result.cues.dp.valid = true;
  result.cues.dp.scale = 0.318;
  result.cues.dp.ci_low = 0.287;
  result.cues.dp.ci_high = 0.351;
  result.cues.focus.valid = true;
  result.cues.focus.scale = 0.357;
  result.cues.focus.ci_low = 0.331;
  result.cues.focus.ci_high = 0.385;
  result.cues.focus.num_views = 2;
  result.cues.agreement = CueAgreement::kAgree;
  result.cues.combined = true;
  result.cues.source = "DP data and recorded focus";
  result.cues.combination = "the inverse-variance mean of the two cues";
  result.scale = 0.348;
  result.scale_ci_low = 0.329;
  result.scale_ci_high = 0.368;
  return result;
}

TEST(ReportPlots, LossPlotWithoutCurveNamesTheCuesAndTheAnswerAsTheReport) {
  const DPScaleResult result = AnswerFromTwoCues();
  const nlohmann::json report = MakeReport(result, {}, {}, RunTimings());
  const std::string title = LossCurveTitle(result);
  const std::string subtitle = LossCurveSubtitle(result);
  SCOPED_TRACE(title + " / " + subtitle);
  // Every number the report gives for the cues and the answer, as the
  // picture formats it.
  const nlohmann::json& dp = report.at("cues").at("dual_pixel");
  const nlohmann::json& focus = report.at("cues").at("recorded_focus");
  for (const double value : {dp.at("scale").get<double>(),
                             dp.at("ci")[0].get<double>(),
                             dp.at("ci")[1].get<double>(),
                             focus.at("scale").get<double>(),
                             focus.at("ci")[0].get<double>(),
                             focus.at("ci")[1].get<double>(),
                             report.at("scale").get<double>(),
                             report.at("scale_ci_low").get<double>(),
                             report.at("scale_ci_high").get<double>()}) {
    EXPECT_NE(subtitle.find(plot::FormatValue(value)), std::string::npos)
        << value;
  }
  EXPECT_NE(subtitle.find("DP data s = 0.318"), std::string::npos);
  EXPECT_NE(subtitle.find("recorded focus s = 0.357"), std::string::npos);
  EXPECT_NE(subtitle.find("final s = 0.348"), std::string::npos);
  EXPECT_NE(title.find("DP data"), std::string::npos);
  EXPECT_NE(title.find("recorded focus"), std::string::npos);
  for (const std::string& text : {title, subtitle}) {
    EXPECT_EQ(text.find("linear estimate kept"), std::string::npos);
  }
  EXPECT_TRUE(LossCurveShowsCues(result));

  // With a curve too, an answer from the cues is not "the linear estimate
  // kept"; a linear estimate that is the answer still says so.
  DPScaleResult with_curve = RealisticResult(2);
  with_curve.intensity.used = false;
  with_curve.cues.combined = true;
  with_curve.cues.agreement = CueAgreement::kAgree;
  with_curve.cues.dp = result.cues.dp;
  with_curve.cues.focus = result.cues.focus;
  EXPECT_EQ(LossCurveSubtitle(with_curve).find("linear estimate kept"),
            std::string::npos);
  DPScaleResult linear = RealisticResult(2);
  linear.intensity.used = false;
  linear.scale = linear.scale_initial;
  EXPECT_NE(LossCurveSubtitle(linear).find("linear estimate kept"),
            std::string::npos);
}

TEST(ReportPlots, LossPlotWithoutCurveDrawsTheCuesAsBars) {
  const DPScaleResult result = AnswerFromTwoCues();
  DPScaleResult no_cues = result;  // the empty frame of before
  no_cues.cues.dp.valid = false;
  no_cues.cues.focus.valid = false;
  const cv::Mat image = RenderLossCurvePlot(result);
  const cv::Mat empty = RenderLossCurvePlot(no_cues);
  MaybeDump(image, "cues_loss.png");
  MaybeDump(empty, "no_cues_loss.png");
  const plot::Axes axes = LossCurveAxes(result);
  ASSERT_GT(axes.area.area(), 0);

  // The plotting area differs from the empty frame's.
  cv::Mat difference;
  cv::absdiff(image(axes.area), empty(axes.area), difference);
  cv::Mat grey;
  cv::cvtColor(difference, grey, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::countNonZero(grey > 40), 2000);

  // Each cue's bar: its colour in the area, spanning its interval. The bar
  // of the recorded focus (green) runs from ci_low to ci_high on the axis.
  const cv::Vec3d focus_colour(44, 160, 44), dp_colour(189, 103, 148);
  for (const auto& [colour, cue] :
       {std::make_pair(focus_colour, &result.cues.focus),
        std::make_pair(dp_colour, &result.cues.dp)}) {
    int count = 0, x_min = 1 << 30, x_max = -1;
    for (int y = axes.area.y; y < axes.area.br().y; ++y) {
      for (int x = axes.area.x; x < axes.area.br().x; ++x) {
        if (ColourDistance(PixelAt(image, {double(x), double(y)}), colour) <
            20) {
          ++count;
          x_min = std::min(x_min, x);
          x_max = std::max(x_max, x);
        }
      }
    }
    EXPECT_GT(count, 100) << colour;
    EXPECT_NEAR(x_min, axes.ToPixel(cue->ci_low, 0).x, 3) << colour;
    EXPECT_NEAR(x_max, axes.ToPixel(cue->ci_high, 0).x, 3) << colour;
  }
}

// Pixels with a colour (not white, grey or black): the views' points.
int ColouredPixels(const cv::Mat& bgr) {
  int count = 0;
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      const int hi = std::max({p[0], p[1], p[2]});
      const int lo = std::min({p[0], p[1], p[2]});
      count += hi - lo > 60;
    }
  }
  return count;
}

// The median |measured - predicted| over the used patches of used views,
// in DP-frame px, with predictions under `scale` (NaN: the result's own).
double MedianResidual(const DPScaleResult& result, double scale) {
  std::vector<double> residuals;
  for (const PatchSample& s : result.patches) {
    if (!s.used || !result.views[s.view].used) continue;
    const DPViewResult& view = result.views[s.view];
    // RealisticResult: DP-frame px are the lens's pixels.
    const double predicted =
        std::isnan(scale)
            ? s.predicted_radius_px * s.radius_frame_px / s.radius_px
            : PredictBlurRadiusPx(view.lens,
                                  view.lens.PixelPitchMm(),
                                  scale,
                                  view.focus_distance_model,
                                  s.depth);
    residuals.push_back(std::abs(s.radius_frame_px - predicted));
  }
  std::sort(residuals.begin(), residuals.end());
  return residuals[residuals.size() / 2];
}

// The number after "median |residual| " in a title.
double TitleResidual(const std::string& title) {
  const std::string key = "median |residual| ";
  const size_t at = title.find(key);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(title.c_str() + at + key.size(), nullptr);
}

// The blur-fit title names the scale its lines and predictions are drawn
// under, and the median residual of the points it draws under that scale:
// the answer's, or for a refused run the DP data's own reading s*.
TEST(ReportPlots, BlurFitTitleNamesItsScaleAndTheDrawnResidual) {
  DPScaleResult result = RealisticResult(3, 2.0);
  const std::string title = BlurFitTitle(result);
  SCOPED_TRACE(title);
  MaybeDump(RenderBlurFitPlot(result), "residual_blur_fit.png");
  EXPECT_NE(title.find("final s = 0.42"), std::string::npos);
  const double expected = MedianResidual(result, std::nan(""));
  EXPECT_NEAR(TitleResidual(title), expected, 5e-3 * expected);

  // Refused with the DP data's reading: drawn under s*, said so.
  DPScaleResult refused = result;
  refused.success = false;
  refused.scale = std::nan("");
  refused.scale_initial = 0.35;
  for (PatchSample& s : refused.patches) s.predicted_radius_px = std::nan("");
  const std::string refused_title = BlurFitTitle(refused);
  SCOPED_TRACE(refused_title);
  MaybeDump(RenderBlurFitPlot(refused), "residual_refused_blur_fit.png");
  EXPECT_NE(refused_title.find("s* = 0.35"), std::string::npos);
  EXPECT_NE(refused_title.find("not adopted"), std::string::npos);
  const double under_s_star = MedianResidual(refused, 0.35);
  EXPECT_NEAR(TitleResidual(refused_title), under_s_star, 5e-3 * under_s_star);
  EXPECT_GT(std::abs(under_s_star - expected), 0.05 * expected);
  // Its right panel has the points (measured against predicted under s*).
  const BlurFitPanels panels = BlurFitAxes(refused);
  const cv::Mat picture = RenderBlurFitPlot(refused);
  EXPECT_GT(ColouredPixels(picture(panels.right.area)), 200);

  // No reading at all (a refusal before the linear stage): no number.
  refused.scale_initial = std::nan("");
  EXPECT_EQ(BlurFitTitle(refused).find("="), std::string::npos);
}

// A reason of any length is drawn whole: the picture grows to hold it, and
// no line is shortened.
TEST(ReportPlots, LongReasonsAreWrappedNotCut) {
  DPScaleResult result = RealisticResult(3, 2.0);
  result.success = false;
  std::string reason;
  for (int k = 0; k < 40; ++k) reason += "word" + std::to_string(k) + " ";
  const std::vector<std::string> lines =
      plot::WrapText(reason, 0.62, 2, 960, 60);
  std::string joined;
  for (const std::string& line : lines) {
    EXPECT_EQ(line.find("..."), std::string::npos) << line;
    joined += (joined.empty() ? "" : " ") + line;
  }
  EXPECT_EQ(joined + " ", reason);
  const cv::Mat header = plot::HeaderStrip(
      cv::Mat(1, 1000, CV_8UC3), 80, reason, "title", "subtitle");
  EXPECT_GT(header.rows, 80 + 26 * 2);
  // Long names lose their middle, keeping start and end.
  const std::string name = "casual_iphone_capture_of_the_box_number_002.png";
  const std::string shortened = plot::Ellipsize(name, 0.45, 1, 180);
  EXPECT_EQ(shortened.substr(0, 4), "casu");
  EXPECT_EQ(shortened.substr(shortened.size() - 4), ".png");
  EXPECT_NE(shortened.find("..."), std::string::npos);
}

TEST(ReportPlots, ReportPlotsAreNamedAfterTheReportAndSanitisedViews) {
  test::TempDir dir;
  const DPScaleResult result = RealisticResult(4);
  const cv::Mat frame(800, 1200, CV_32FC1, cv::Scalar(0.2));
  const ReportPlotFiles files = WriteReportPlots(
      result, {{0, frame}, {2, frame}}, dir / "report.json", 33);
  const std::vector<std::string> expected = {
      dir / "report_blur_fit.png",
      dir / "report_loss.png",
      dir / "report_patches_cam0_DP_0.png",
      dir / "report_patches_cam2_DP_2.png"};
  EXPECT_EQ(files.written, expected);
  EXPECT_TRUE(files.failures.empty());
  for (const std::string& path : expected) {
    EXPECT_TRUE(IsPng(path)) << path;
  }
  MaybeDump(cv::imread(dir / "report_patches_cam0_DP_0.png"),
            "realistic_patches.png");

  // Two views whose names sanitise alike get distinct files.
  DPScaleResult twins = result;
  twins.views[1].name = "cam0_DP_0.jpg";
  const std::vector<std::string> twin_paths =
      WriteReportPlots(twins, {{0, frame}, {1, frame}}, dir / "twins", 33)
          .written;
  ASSERT_EQ(twin_paths.size(), 4u);
  EXPECT_NE(twin_paths[2], twin_paths[3]);
}

TEST(ReportPlots, PicturesDrawnOnManyThreadsAreTheSameFilesInTheSameOrder) {
  test::TempDir dir;
  const DPScaleResult result = RealisticResult(4);
  // Each overlay its own frame, so that a picture drawn from another
  // overlay's values (a job reading the loop's variables after the loop)
  // shows in the bytes.
  std::vector<OverlayImage> overlays;
  for (int view = 0; view < 4; ++view) {
    overlays.push_back(
        {view, cv::Mat(800, 1200, CV_32FC1, cv::Scalar(0.1 + 0.2 * view))});
  }
  std::filesystem::create_directories(dir / "one");
  std::filesystem::create_directories(dir / "three");
  const ReportPlotFiles one =
      WriteReportPlots(result, overlays, dir / "one/report.json", 33, 1);
  const ReportPlotFiles three =
      WriteReportPlots(result, overlays, dir / "three/report.json", 33, 3);
  ASSERT_EQ(one.written.size(), 6u);
  ASSERT_EQ(three.written.size(), one.written.size());
  EXPECT_TRUE(three.failures.empty());
  std::set<std::string> distinct;
  for (size_t k = 0; k < one.written.size(); ++k) {
    const std::filesystem::path a = one.written[k], b = three.written[k];
    EXPECT_EQ(a.filename(), b.filename());
    EXPECT_EQ(b.parent_path(), dir / "three");
    const std::string bytes = test::ReadTextFile(a);
    EXPECT_EQ(bytes, test::ReadTextFile(b)) << b;
    distinct.insert(bytes);
  }
  // Every picture its own: the overlays differ from each other.
  EXPECT_EQ(distinct.size(), one.written.size());

  // Failures in the pictures' order too.
  const ReportPlotFiles failed = WriteReportPlots(
      result, overlays, dir / "missing/dir/report.json", 33, 3);
  EXPECT_TRUE(failed.written.empty());
  ASSERT_EQ(failed.failures.size(), 6u);
  EXPECT_EQ(failed.failures[0].plot, "blur_fit");
  EXPECT_EQ(failed.failures[1].plot, "loss");
  for (int view = 0; view < 4; ++view) {
    EXPECT_EQ(failed.failures[2 + view].plot,
              "patches_" + PlotFileComponent(result.views[view].name));
  }
}

TEST(ReportPlots, PicturesThatCannotBeWrittenAreReportedWithTheReason) {
  test::TempDir dir;
  const DPScaleResult result = RealisticResult(2);
  const cv::Mat frame(800, 1200, CV_32FC1, cv::Scalar(0.2));
  // An unwritable location: no paths, no exception, one failure a picture.
  ReportPlotFiles files;
  EXPECT_NO_THROW(
      files = WriteReportPlots(
          result, {{0, frame}}, dir / "missing/dir/report.json", 33));
  EXPECT_TRUE(files.written.empty());
  ASSERT_EQ(files.failures.size(), 3u);
  const std::vector<std::string> plots = {
      "blur_fit", "loss", "patches_cam0_DP_0"};
  for (size_t i = 0; i < plots.size(); ++i) {
    EXPECT_EQ(files.failures[i].plot, plots[i]);
    EXPECT_EQ(files.failures[i].path,
              dir / ("missing/dir/report_" + plots[i] + ".png"));
    EXPECT_FALSE(files.failures[i].error.empty()) << plots[i];
  }

  // The writers say why: OpenCV's exception for a format it does not know,
  // an empty picture for an empty image.
  std::string error;
  EXPECT_FALSE(WriteBlurFitPlot(result, dir / "blur.unknown", &error));
  EXPECT_NE(error.find("could not find a writer"), std::string::npos) << error;
  error.clear();
  EXPECT_FALSE(
      WritePatchOverlay(cv::Mat(), "x", 0, result, 40, dir / "o.png", &error));
  EXPECT_EQ(error, "empty picture");
}

TEST(ReportPlots, FileComponentsAreSafe) {
  EXPECT_EQ(PlotFileComponent("DP_0001.jpg"), "DP_0001");
  EXPECT_EQ(PlotFileComponent("cam 1/sub\\DP 2.JPG"), "cam_1_sub_DP_2");
  EXPECT_EQ(PlotFileComponent("a.b/c"), "a.b_c");
  EXPECT_EQ(PlotFileComponent(""), "view");
  EXPECT_EQ(PlotFileComponent("../../etc/x.png"), ".._.._etc_x");
}

}  // namespace
}  // namespace dpsfm
