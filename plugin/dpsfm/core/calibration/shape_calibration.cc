#include "dpsfm/core/calibration/shape_calibration.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

cv::Rect CellRect(const DPPsfLayout& layout, int cell, const cv::Size& size) {
  const int row = cell / layout.cols, col = cell % layout.cols;
  const double w = (layout.x1 - layout.x0) / layout.cols;
  const double h = (layout.y1 - layout.y0) / layout.rows;
  const int x0 =
      static_cast<int>(std::round((layout.x0 + col * w) * size.width));
  const int x1 =
      static_cast<int>(std::round((layout.x0 + (col + 1) * w) * size.width));
  const int y0 =
      static_cast<int>(std::round((layout.y0 + row * h) * size.height));
  const int y1 =
      static_cast<int>(std::round((layout.y0 + (row + 1) * h) * size.height));
  return cv::Rect(x0, y0, x1 - x0, y1 - y0) & cv::Rect(cv::Point(), size);
}

// Zero-pads an odd square kernel to half-size `half`.
cv::Mat PadTo(const cv::Mat& kernel, int half) {
  const int p = half - kernel.rows / 2;
  DPSFM_CHECK_GE(p, 0);
  cv::Mat out;
  cv::copyMakeBorder(kernel, out, p, p, p, p, cv::BORDER_CONSTANT, 0);
  return out;
}

// Deconvolution leaves faint specks away from the kernel, and magnified
// samples are padded: keep the views' light connected to the centre (the
// pixels above 1 % of the pair's peak, 8-connected, and their 1-px rim),
// crop to the smallest centred square holding it, renormalised to 0.5 per
// view.
DPKernels TrimToSupport(const DPKernels& k) {
  const cv::Mat sum = k.left + k.right;
  double peak = 0;
  cv::minMaxLoc(sum, nullptr, &peak);
  const cv::Mat mask = sum > 0.01 * peak;
  cv::Mat labels;
  cv::connectedComponents(mask, labels, 8, CV_32S);
  const int half = k.left.rows / 2;
  // The component through the centre, else the one nearest to it.
  int label = labels.at<int>(half, half);
  double best = 1e300;
  for (int y = 0; label == 0 && y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      const double d = std::hypot(x - half, y - half);
      if (labels.at<int>(y, x) > 0 && d < best) {
        best = d;
        label = labels.at<int>(y, x);
      }
    }
  }
  cv::Mat keep = labels == label;
  cv::dilate(keep, keep, cv::Mat::ones(3, 3, CV_8U));
  int reach = 0;
  for (int y = 0; y < keep.rows; ++y) {
    for (int x = 0; x < keep.cols; ++x) {
      if (keep.at<uchar>(y, x)) {
        reach = std::max({reach, std::abs(x - half), std::abs(y - half)});
      }
    }
  }
  const cv::Rect r(half - reach, half - reach, 2 * reach + 1, 2 * reach + 1);
  DPKernels out;
  out.left = cv::Mat::zeros(k.left.size(), CV_32FC1);
  out.right = out.left.clone();
  k.left.copyTo(out.left, keep);
  k.right.copyTo(out.right, keep);
  out.left = out.left(r).clone();
  out.right = out.right(r).clone();
  out.left *= 0.5 / cv::sum(out.left)[0];
  out.right *= 0.5 / cv::sum(out.right)[0];
  return out;
}

// The stopped-down capture moved onto the blurred one by whole pixels (a
// tripod nudged while the aperture was changed): the peak of the
// normalised cross-correlation of the views' sum with it, within 24 px
// (phase correlation is no use here: the defocus disk's spectrum changes
// sign, which whitening turns into wrong peaks). What is left (under a
// pixel, plus the kernel's own centroid) the re-centring removes.
cv::Mat RegisterSharp(const ShapeCapture& c, cv::Point2d* shift) {
  cv::Mat sharp, blurred;
  c.sharp.convertTo(sharp, CV_32FC1);
  cv::Mat(c.left + c.right).convertTo(blurred, CV_32FC1);
  const int reach = std::min(24, std::min(sharp.cols, sharp.rows) / 8);
  const cv::Rect inner(
      reach, reach, sharp.cols - 2 * reach, sharp.rows - 2 * reach);
  cv::Mat score;
  cv::matchTemplate(sharp, blurred(inner), score, cv::TM_CCOEFF_NORMED);
  cv::Point best;
  cv::minMaxLoc(score, nullptr, nullptr, nullptr, &best);
  // blurred(inner) matches sharp at `best`: blurred(x) = sharp(x - d) with
  // d = (reach, reach) - best.
  *shift = cv::Point2d(reach - best.x, reach - best.y);
  if (shift->x == 0 && shift->y == 0) return c.sharp;
  const cv::Mat move =
      (cv::Mat_<double>(2, 3) << 1, 0, shift->x, 0, 1, shift->y);
  cv::Mat moved;
  cv::warpAffine(c.sharp,
                 moved,
                 move,
                 c.sharp.size(),
                 cv::INTER_NEAREST,
                 cv::BORDER_REFLECT);
  return moved;
}

// Appends a note to a capture's notes ("; " between notes).
void AddNote(std::string* notes, const std::string& note) {
  *notes += (notes->empty() ? "" : "; ") + note;
}

// Which captures show a shape (|r| >= min_radius_px; a note says why not),
// with the per-capture results set up empty. Returns the largest |r| of
// the captures used (0 when none is).
double ListCaptures(const std::vector<ShapeCapture>& captures,
                    const ShapeCalibrationOptions& options,
                    ShapeCalibration* out) {
  const int num_cells = options.layout.NumCells();
  double largest = 0;
  for (const ShapeCapture& c : captures) {
    DPSFM_CHECK(!c.left.empty() && c.left.size() == c.right.size() &&
                c.left.size() == c.sharp.size())
        << "capture " << c.name
        << ": the DP views and the sharp reference differ in size";
    DPSFM_CHECK(std::isfinite(c.signed_radius_px))
        << "capture " << c.name << ": no blur radius";
    out->capture_names.push_back(c.name);
    const bool used = std::abs(c.signed_radius_px) >= options.min_radius_px;
    out->capture_used.push_back(used);
    std::ostringstream note;
    if (!used) {
      note << std::setprecision(3) << "blur radius "
           << std::abs(c.signed_radius_px) << " px < " << options.min_radius_px
           << " px shows no shape";
    }
    out->capture_notes.push_back(note.str());
    if (used) largest = std::max(largest, std::abs(c.signed_radius_px));
    out->capture_cell_offsets.emplace_back(num_cells, kNaN);
    out->capture_shifts.emplace_back(0, 0);
    out->capture_cell_residuals.emplace_back(num_cells, kNaN);
    out->capture_cell_light.emplace_back(num_cells, kNaN);
  }
  return largest;
}

// The sharp reference of each used capture, registered onto its views
// (empty for the others).
std::vector<cv::Mat> RegisterUsedCaptures(
    const std::vector<ShapeCapture>& captures, ShapeCalibration* out) {
  std::vector<cv::Mat> registered(captures.size());
  for (size_t i = 0; i < captures.size(); ++i) {
    if (out->capture_used[i]) {
      registered[i] = RegisterSharp(captures[i], &out->capture_shifts[i]);
    }
  }
  return registered;
}

// Per cell: every usable capture's pair, magnified to the reference radius
// (far side), weighted by |r|^2 (the number of kernel pixels it resolves).
class CellMeasurement {
 public:
  CellMeasurement(const std::vector<ShapeCapture>& captures,
                  const std::vector<cv::Mat>& registered,
                  const ShapeCalibrationOptions& options,
                  ShapeCalibration* out)
      : captures_(captures),
        registered_(registered),
        options_(options),
        ref_(out->reference_radius_px),
        out_(out) {}

  // The cell's averaged kernels and centroid offset; false (with the
  // reason) when it has no usable measurement or breaks the DP convention.
  bool MeasureCell(int cell) {
    Samples samples;
    for (size_t i = 0; i < captures_.size(); ++i) {
      if (!out_->capture_used[i]) continue;
      SampleCapture(static_cast<int>(i), cell, &samples);
    }
    if (samples.kernels.empty()) {
      out_->reason = "cell " + std::to_string(cell) +
                     " of the frame has no usable kernel measurement";
      return false;
    }
    const DPKernels mean = WeightedMean(samples);
    out_->cell_centroid_offsets[cell] = CentroidOffsetPerRadius(mean, ref_);
    if (!(out_->cell_centroid_offsets[cell] > 0)) {
      out_->reason = "cell " + std::to_string(cell) +
                     "'s measured kernels break the DP convention (the left "
                     "view does not lean away from the right one): are the "
                     "views swapped?";
      return false;
    }
    out_->cell_kernels[cell] = TrimToSupport(mean);
    return true;
  }

  // The |r|^2-weighted mean centroid offsets of the measurements nearer
  // and farther than the focus.
  void SetNearAndFar() const {
    if (near_sum_[1] > 0) {
      out_->near_centroid_offset = near_sum_[0] / near_sum_[1];
    }
    if (far_sum_[1] > 0) out_->far_centroid_offset = far_sum_[0] / far_sum_[1];
  }

 private:
  struct Samples {
    std::vector<DPKernels> kernels;  // far side, at the reference radius
    std::vector<double> weights;
    int max_half = 0;
  };

  // Capture i's pair in the cell, added to the samples; or a note on the
  // capture why the cell gives none.
  void SampleCapture(int i, int cell, Samples* samples) {
    const ShapeCapture& c = captures_[i];
    const double r = std::abs(c.signed_radius_px);
    const cv::Rect rect = CellRect(options_.layout, cell, c.left.size());
    KernelEstimationOptions ko;
    ko.half_size =
        std::min(24,
                 static_cast<int>(std::ceil(options_.support_factor * r)) +
                     options_.support_margin_px);
    ko.smoothness = options_.smoothness;
    std::string& notes = out_->capture_notes[i];
    if (rect.width <= 4 * ko.half_size + 8 ||
        rect.height <= 4 * ko.half_size + 8) {
      AddNote(&notes,
              "cell " + std::to_string(cell) + " too small for its kernel");
      return;
    }
    EstimatedDPKernels m;
    try {
      m = EstimateDPKernels(
          registered_[i](rect), c.left(rect), c.right(rect), ko);
    } catch (const std::invalid_argument& e) {
      AddNote(&notes, "cell " + std::to_string(cell) + ": " + e.what());
      return;
    }
    out_->capture_cell_residuals[i][cell] = m.relative_residual;
    out_->capture_cell_light[i][cell] = m.light_ratio;
    if (!(m.light_ratio >= options_.min_light_ratio &&
          m.light_ratio <= options_.max_light_ratio)) {
      std::ostringstream n;
      n << "cell " << cell << ": the kernels carry " << std::setprecision(2)
        << m.light_ratio
        << " of the light (is the sharp capture of the same view?)";
      AddNote(&notes, n.str());
      return;
    }
    DPKernels k = m.kernels;
    if (c.signed_radius_px < 0) {  // near side: rotate to the far side
      cv::flip(k.left, k.left, -1);
      cv::flip(k.right, k.right, -1);
    }
    const double offset = CentroidOffsetPerRadius(k, r);
    out_->capture_cell_offsets[i][cell] = offset;
    std::vector<double>& side = c.signed_radius_px < 0 ? near_sum_ : far_sum_;
    side[0] += r * r * offset;
    side[1] += r * r;
    k.left = MagnifyKernel(k.left, ref_ / r);
    k.right = MagnifyKernel(k.right, ref_ / r);
    samples->max_half = std::max(samples->max_half, k.left.rows / 2);
    samples->kernels.push_back(k);
    samples->weights.push_back(r * r);
  }

  static DPKernels WeightedMean(const Samples& samples) {
    const int max_half = samples.max_half;
    DPKernels mean;
    mean.left = cv::Mat::zeros(2 * max_half + 1, 2 * max_half + 1, CV_32FC1);
    mean.right = mean.left.clone();
    double total = 0;
    for (size_t s = 0; s < samples.kernels.size(); ++s) {
      mean.left +=
          samples.weights[s] * PadTo(samples.kernels[s].left, max_half);
      mean.right +=
          samples.weights[s] * PadTo(samples.kernels[s].right, max_half);
      total += samples.weights[s];
    }
    mean.left /= total;
    mean.right /= total;
    return mean;
  }

  const std::vector<ShapeCapture>& captures_;
  const std::vector<cv::Mat>& registered_;
  const ShapeCalibrationOptions& options_;
  const double ref_;
  ShapeCalibration* out_;
  // Over all measurements nearer and farther than the focus: the sums of
  // |r|^2 offset ([0]) and of |r|^2 ([1]).
  std::vector<double> near_sum_ = std::vector<double>(2, 0);
  std::vector<double> far_sum_ = std::vector<double>(2, 0);
};

// One kernel size for every cell (profile files hold one stack).
void PadToCommonSize(std::vector<DPKernels>* cell_kernels) {
  int common_half = 0;
  for (const DPKernels& k : *cell_kernels) {
    common_half = std::max(common_half, k.left.rows / 2);
  }
  for (DPKernels& k : *cell_kernels) {
    k.left = PadTo(k.left, common_half);
    k.right = PadTo(k.right, common_half);
  }
}

// The largest relative deviation of a capture's cell offset from the
// cell's.
double Spread(const ShapeCalibration& out) {
  double spread = 0;
  for (size_t i = 0; i < out.capture_cell_offsets.size(); ++i) {
    for (size_t cell = 0; cell < out.cell_centroid_offsets.size(); ++cell) {
      const double o = out.capture_cell_offsets[i][cell];
      if (std::isfinite(o)) {
        spread =
            std::max(spread, std::abs(o / out.cell_centroid_offsets[cell] - 1));
      }
    }
  }
  return spread;
}

std::string Summary(const ShapeCalibration& out) {
  const int num_cells = static_cast<int>(out.cell_centroid_offsets.size());
  std::ostringstream summary;
  summary << std::setprecision(3) << "kernel shapes measured in " << num_cells
          << " cell(s) at " << out.reference_radius_px
          << " px; centroid offset per radius";
  for (int cell = 0; cell < num_cells; ++cell) {
    summary << (cell ? ", " : " ") << out.cell_centroid_offsets[cell];
  }
  summary << " (captures within " << 100 * out.spread << " % of it";
  if (std::isfinite(out.near_centroid_offset) &&
      std::isfinite(out.far_centroid_offset)) {
    summary << "; nearer than the focus " << out.near_centroid_offset
            << ", farther " << out.far_centroid_offset;
  }
  summary << ")";
  return summary.str();
}

}  // namespace

bool ShapeCalibrationOptions::Check(std::string* failure) const {
  DPSFM_CHECK_NESTED_OPTIONS(layout);
  DPSFM_CHECK_OPTION_VALUE(
      reference_radius_px >= 0 && std::isfinite(reference_radius_px),
      reference_radius_px);
  DPSFM_CHECK_OPTION_GE(min_radius_px, 0.5);
  DPSFM_CHECK_OPTION_GE(support_factor, 1);
  DPSFM_CHECK_OPTION_GE(support_margin_px, 1);
  DPSFM_CHECK_OPTION_GE(smoothness, 0);
  DPSFM_CHECK_OPTION_GT(min_light_ratio, 0);
  DPSFM_CHECK_OPTION_GT(max_light_ratio, min_light_ratio);
  return true;
}

ShapeCalibration CalibrateShapes(const std::vector<ShapeCapture>& captures,
                                 const ShapeCalibrationOptions& options) {
  DPSFM_CHECK_OPTIONS(options, "ShapeCalibrationOptions");
  ShapeCalibration out;
  out.layout = options.layout;
  const int num_cells = options.layout.NumCells();

  // Which captures show a shape, and the reference radius.
  const double largest = ListCaptures(captures, options, &out);
  if (largest == 0) {
    out.reason = "no capture has a blur of " +
                 std::to_string(options.min_radius_px) +
                 " px or more to measure the kernels' shape";
    return out;
  }
  out.reference_radius_px =
      options.reference_radius_px > 0 ? options.reference_radius_px : largest;
  const std::vector<cv::Mat> registered = RegisterUsedCaptures(captures, &out);

  out.cell_kernels.resize(num_cells);
  out.cell_centroid_offsets.assign(num_cells, kNaN);
  CellMeasurement measurement(captures, registered, options, &out);
  for (int cell = 0; cell < num_cells; ++cell) {
    if (!measurement.MeasureCell(cell)) return out;
  }
  PadToCommonSize(&out.cell_kernels);
  measurement.SetNearAndFar();
  out.spread = Spread(out);
  out.reason = Summary(out);
  out.determined = true;
  return out;
}

double MeasuredStrength(const ShapeCalibration& shape,
                        const std::vector<int>& cell_weights) {
  DPSFM_CHECK(shape.determined &&
              cell_weights.size() == shape.cell_centroid_offsets.size())
      << "MeasuredStrength needs a measured shape and one weight per cell";
  double log_sum = 0, weight = 0;
  for (size_t c = 0; c < cell_weights.size(); ++c) {
    const double w = std::max(1, cell_weights[c]);
    log_sum += w * std::log(shape.cell_centroid_offsets[c]);
    weight += w;
  }
  return std::exp(log_sum / weight);
}

}  // namespace dpsfm
