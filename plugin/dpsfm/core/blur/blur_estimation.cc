#include "dpsfm/core/blur/blur_estimation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Core>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {

const char* const kBlurAtSearchBound = "blur at the search bound";

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// 1-D Tukey window: 1 inside, a raised-cosine taper over `taper` samples at
// both ends. Tapering the border band (where the exact loss is not evaluated
// anyway) suppresses the patch-edge discontinuity of the circular model.
std::vector<float> TukeyWindow(int length, int taper) {
  std::vector<float> window(length, 1.0f);
  taper = std::min(taper, length / 2);
  for (int i = 0; i < taper; ++i) {
    const float w =
        static_cast<float>(0.5 * (1.0 - std::cos(M_PI * (i + 0.5) / taper)));
    window[i] = w;
    window[length - 1 - i] = w;
  }
  return window;
}

bool AllFinite(const cv::Mat& image) {
  for (int y = 0; y < image.rows; ++y) {
    const float* row = image.ptr<float>(y);
    for (int x = 0; x < image.cols; ++x) {
      if (!std::isfinite(row[x])) {
        return false;
      }
    }
  }
  return true;
}

// Sum over `rect` of (image * kernel) (true convolution), from the integral
// image of `image`: sum_d kernel(d) * (sum of image over rect - d). Every
// shifted rect must lie inside the image.
double BlurredSum(const cv::Mat& integral,
                  const cv::Mat& kernel,
                  const cv::Rect& rect) {
  const int cy = kernel.rows / 2;
  const int cx = kernel.cols / 2;
  double total = 0;
  for (int i = 0; i < kernel.rows; ++i) {
    const float* k = kernel.ptr<float>(i);
    const int y0 = rect.y - (i - cy);
    const int y1 = y0 + rect.height;
    const double* top = integral.ptr<double>(y0);
    const double* bottom = integral.ptr<double>(y1);
    for (int j = 0; j < kernel.cols; ++j) {
      if (k[j] == 0) continue;
      const int x0 = rect.x - (j - cx);
      const int x1 = x0 + rect.width;
      total += k[j] * (bottom[x1] - bottom[x0] - top[x1] + top[x0]);
    }
  }
  return total;
}

double Dot(const std::vector<float>& a, const std::vector<float>& b) {
  double sum = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sum += static_cast<double>(a[i]) * b[i];
  }
  return sum;
}

}  // namespace

bool BlurEstimationOptions::Check() const {
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(max_radius_px) && max_radius_px >= 1,
                           max_radius_px);
  DPSFM_CHECK_OPTION_VALUE(
      std::isfinite(grid_step_px) && grid_step_px > 0 && grid_step_px <= 1,
      grid_step_px);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(coarse_step_px) &&
                               coarse_step_px >= grid_step_px &&
                               coarse_step_px <= max_radius_px,
                           coarse_step_px);
  // The coarse nodes are nodes of the kernel grid.
  const double ratio = coarse_step_px / grid_step_px;
  DPSFM_CHECK_OPTION_VALUE(std::abs(ratio - std::round(ratio)) <= 1e-9 * ratio,
                           coarse_step_px);
  DPSFM_CHECK_OPTION_VALUE(coarse_band > 0 && coarse_band <= 1, coarse_band);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(min_texture) && min_texture >= 0,
                           min_texture);
  DPSFM_CHECK_OPTION_VALUE(min_fit_quality >= 0 && min_fit_quality <= 1,
                           min_fit_quality);
  DPSFM_CHECK_OPTION_VALUE(
      fit_quality_offset_px > 0 && fit_quality_offset_px < max_radius_px,
      fit_quality_offset_px);
  DPSFM_CHECK_OPTION_GE(max_refinement_evaluations, 3);
  return true;
}

// Everything that depends only on (psf, options, patch size).
struct PatchBlurEstimator::Tables {
  BlurEstimationOptions options;
  cv::Size patch_size;
  cv::Size dft_size;
  int border = 0;
  cv::Rect interior;
  int num_interior = 0;

  // Kernels and spectra on the radius grid (node n <-> r = Radius(n)).
  std::unique_ptr<DPKernelGrid> grid;
  double step = 0;
  int half_nodes = 0;
  int num_nodes = 0;
  double bound = 0;  // half_nodes * step
  // Noise gain |h_l|^2 + |h_r|^2 per node, and <h_l(n), h_l(n+1)> +
  // <h_r(n), h_r(n+1)> per interval, for the noise floor of interpolated
  // kernels.
  std::vector<double> noise_gain;
  std::vector<double> noise_cross;

  // Coarse search.
  std::vector<int> coarse_nodes;
  std::vector<int> band_rows;  // row index in the full complex spectrum
  std::vector<int> band_cols;  // column index, 0..dft_size.width / 2
  // Row per coarse node, 4 entries per band frequency:
  // (w |H_r|^2, w |H_l|^2, w Re K, w Im K), K = H_r conj(H_l), w = Hermitian
  // multiplicity of the frequency.
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>
      coarse_table;
  // Noise gain of the coarse loss per coarse node: the band's share of
  // |H_l|^2 + |H_r|^2 (the coarse loss sees only the band's noise).
  std::vector<double> coarse_noise_gain;
  std::vector<float> window_x;
  std::vector<float> window_y;
  double coarse_normaliser = 1;  // 1 / (N_total * sum w^2)

  double Radius(int node) const { return (node - half_nodes) * step; }
};

PatchBlurEstimator::PatchBlurEstimator(const DPPsfModel& psf,
                                       const BlurEstimationOptions& options,
                                       const cv::Size& patch_size) {
  DPSFM_CHECK_OPTIONS(options, "BlurEstimationOptions");
  std::unique_ptr<Tables> t(new Tables);
  t->options = options;
  t->patch_size = patch_size;
  // The grid's bound is max_radius_px rounded up to a multiple of the step.
  // Spectra need a DFT size >= the patch only: every interior output reads
  // inputs within `border` of itself, inside the patch, so circular
  // wrap-around never reaches it.
  t->dft_size = cv::Size(cv::getOptimalDFTSize(patch_size.width),
                         cv::getOptimalDFTSize(patch_size.height));
  t->grid.reset(new DPKernelGrid(
      psf, options.grid_step_px, options.max_radius_px, t->dft_size));
  const DPKernelGrid& grid = *t->grid;
  t->step = grid.Step();
  t->half_nodes = grid.HalfNodes();
  t->num_nodes = grid.NumNodes();
  t->bound = grid.Bound();
  t->border = grid.Border();
  DPSFM_CHECK(patch_size.width >= 2 * t->border + 8 &&
              patch_size.height >= 2 * t->border + 8)
      << "patch " << patch_size.width << "x" << patch_size.height
      << " too small for |r| <= " << t->bound << " (border " << t->border
      << " px each side, interior >= 8 px needed)";
  t->interior = cv::Rect(t->border,
                         t->border,
                         patch_size.width - 2 * t->border,
                         patch_size.height - 2 * t->border);
  t->num_interior = t->interior.area();
  const int nr = t->dft_size.height;
  const int nc = t->dft_size.width;

  // Frequencies of the coarse band, on the half spectrum u = 0..nc/2.
  const double band = options.coarse_band;
  std::vector<float> multiplicity;
  for (int v = 0; v < nr; ++v) {
    const int fv = v <= nr / 2 ? v : v - nr;
    if (std::abs(fv) > band * nr / 2.0 + 1e-9) continue;
    for (int u = 0; u <= nc / 2; ++u) {
      if (u > band * nc / 2.0 + 1e-9) continue;
      t->band_rows.push_back(v);
      t->band_cols.push_back(u);
      multiplicity.push_back(u == 0 || (nc % 2 == 0 && u == nc / 2) ? 1.f
                                                                    : 2.f);
    }
  }
  const int num_band = static_cast<int>(t->band_rows.size());

  const int coarse_stride = static_cast<int>(
      std::round(options.coarse_step_px / options.grid_step_px));
  for (int n = t->half_nodes % coarse_stride; n < t->num_nodes;
       n += coarse_stride) {
    t->coarse_nodes.push_back(n);
  }
  if (t->coarse_nodes.front() != 0) {
    t->coarse_nodes.insert(t->coarse_nodes.begin(), 0);
  }
  if (t->coarse_nodes.back() != t->num_nodes - 1) {
    t->coarse_nodes.push_back(t->num_nodes - 1);
  }
  std::vector<int> coarse_row(t->num_nodes, -1);
  for (size_t i = 0; i < t->coarse_nodes.size(); ++i) {
    coarse_row[t->coarse_nodes[i]] = static_cast<int>(i);
  }
  t->coarse_table.resize(t->coarse_nodes.size(), 4 * num_band);

  t->noise_gain.resize(t->num_nodes);
  t->noise_cross.resize(t->num_nodes - 1);
  for (int n = 0; n < t->num_nodes; ++n) {
    t->noise_gain[n] = grid.LeftEnergy(n) + grid.RightEnergy(n);
    if (n + 1 < t->num_nodes) {
      t->noise_cross[n] = grid.LeftCross(n) + grid.RightCross(n);
    }
    if (coarse_row[n] >= 0) {
      const cv::Mat wrapped_left = WrapKernel(grid.LeftKernel(n), t->dft_size);
      const cv::Mat wrapped_right =
          WrapKernel(grid.RightKernel(n), t->dft_size);
      cv::Mat hl, hr;
      cv::dft(wrapped_left, hl, cv::DFT_COMPLEX_OUTPUT);
      cv::dft(wrapped_right, hr, cv::DFT_COMPLEX_OUTPUT);
      float* row = t->coarse_table.row(coarse_row[n]).data();
      for (int k = 0; k < num_band; ++k) {
        const cv::Vec2f l = hl.at<cv::Vec2f>(t->band_rows[k], t->band_cols[k]);
        const cv::Vec2f r = hr.at<cv::Vec2f>(t->band_rows[k], t->band_cols[k]);
        const float w = multiplicity[k];
        row[4 * k + 0] = w * (r[0] * r[0] + r[1] * r[1]);
        row[4 * k + 1] = w * (l[0] * l[0] + l[1] * l[1]);
        // K = H_r conj(H_l).
        row[4 * k + 2] = w * (r[0] * l[0] + r[1] * l[1]);
        row[4 * k + 3] = w * (r[1] * l[0] - r[0] * l[1]);
      }
    }
  }

  t->coarse_noise_gain.resize(t->coarse_nodes.size());
  for (size_t i = 0; i < t->coarse_nodes.size(); ++i) {
    double gain = 0;
    for (int k = 0; k < num_band; ++k) {
      gain += t->coarse_table(i, 4 * k) + t->coarse_table(i, 4 * k + 1);
    }
    t->coarse_noise_gain[i] = gain / (static_cast<double>(nr) * nc);
  }
  t->window_x = TukeyWindow(patch_size.width, t->border);
  t->window_y = TukeyWindow(patch_size.height, t->border);
  double sum_x = 0, sum_y = 0;
  for (const float w : t->window_x) sum_x += w * w;
  for (const float w : t->window_y) sum_y += w * w;
  t->coarse_normaliser = 1.0 / (static_cast<double>(nr) * nc * sum_x * sum_y);
  tables_ = std::move(t);
}

PatchBlurEstimator::~PatchBlurEstimator() = default;

int PatchBlurEstimator::Border() const { return tables_->border; }
const cv::Size& PatchBlurEstimator::PatchSize() const {
  return tables_->patch_size;
}
const BlurEstimationOptions& PatchBlurEstimator::Options() const {
  return tables_->options;
}

// The coarse global search's curve (windowed, frequency domain): the
// corrected loss per coarse node, and its local minima, best first (ties
// prefer small |r|: blurs inside the in-focus threshold are
// indistinguishable).
struct PatchBlurEstimator::CoarseCurve {
  std::vector<double> loss;
  std::vector<int> minima;  // indices into loss
  double min = 0, max = 0;
};

PatchBlurEstimator::CoarseCurve PatchBlurEstimator::CoarseSearch(
    const cv::Mat& gl, const cv::Mat& gr, double sigma2_hp) const {
  const Tables& t = *tables_;
  const int height = t.patch_size.height;
  const int width = t.patch_size.width;
  const int num_band = static_cast<int>(t.band_rows.size());
  Eigen::VectorXf data(4 * num_band);
  {
    cv::Mat wl = cv::Mat::zeros(t.dft_size, CV_32FC1);
    cv::Mat wr = cv::Mat::zeros(t.dft_size, CV_32FC1);
    for (int y = 0; y < height; ++y) {
      const float* l = gl.ptr<float>(y);
      const float* r = gr.ptr<float>(y);
      float* ol = wl.ptr<float>(y);
      float* orr = wr.ptr<float>(y);
      const float wy = t.window_y[y];
      for (int x = 0; x < width; ++x) {
        const float w = wy * t.window_x[x];
        ol[x] = w * l[x];
        orr[x] = w * r[x];
      }
    }
    cv::Mat fl, fr;
    cv::dft(wl, fl, cv::DFT_COMPLEX_OUTPUT, height);
    cv::dft(wr, fr, cv::DFT_COMPLEX_OUTPUT, height);
    for (int k = 0; k < num_band; ++k) {
      const cv::Vec2f a = fl.at<cv::Vec2f>(t.band_rows[k], t.band_cols[k]);
      const cv::Vec2f b = fr.at<cv::Vec2f>(t.band_rows[k], t.band_cols[k]);
      // D = G_l conj(G_r); loss_k = |G_l|^2 |H_r|^2 + |G_r|^2 |H_l|^2
      //                            - 2 Re(D K).
      data[4 * k + 0] = a[0] * a[0] + a[1] * a[1];
      data[4 * k + 1] = b[0] * b[0] + b[1] * b[1];
      data[4 * k + 2] = -2.f * (a[0] * b[0] + a[1] * b[1]);
      data[4 * k + 3] = 2.f * (a[1] * b[0] - a[0] * b[1]);
    }
  }
  const Eigen::VectorXf coarse_raw_f = t.coarse_table * data;
  const int num_coarse = static_cast<int>(t.coarse_nodes.size());
  std::vector<double> coarse_raw(num_coarse);
  double sigma2_coarse = sigma2_hp;
  for (int i = 0; i < num_coarse; ++i) {
    coarse_raw[i] = std::max(0.0, coarse_raw_f[i] * t.coarse_normaliser);
    sigma2_coarse =
        std::min(sigma2_coarse, coarse_raw[i] / t.coarse_noise_gain[i]);
  }
  if (!t.options.subtract_noise_floor) sigma2_coarse = 0;
  CoarseCurve curve;
  curve.loss.resize(num_coarse);
  std::vector<double>& coarse = curve.loss;
  for (int i = 0; i < num_coarse; ++i) {
    coarse[i] = coarse_raw[i] - sigma2_coarse * t.coarse_noise_gain[i];
  }
  for (int i = 0; i < num_coarse; ++i) {
    const bool left_ok = i == 0 || coarse[i] <= coarse[i - 1];
    const bool right_ok = i == num_coarse - 1 || coarse[i] <= coarse[i + 1];
    if (left_ok && right_ok) curve.minima.push_back(i);
  }
  std::sort(curve.minima.begin(), curve.minima.end(), [&](int a, int b) {
    if (coarse[a] != coarse[b]) return coarse[a] < coarse[b];
    return std::abs(t.Radius(t.coarse_nodes[a])) <
           std::abs(t.Radius(t.coarse_nodes[b]));
  });
  curve.min = coarse[curve.minima.front()];
  curve.max = *std::max_element(coarse.begin(), coarse.end());
  return curve;
}

// The exact refinement (spatial valid-region loss via inverse FFT) of one
// patch: the views' spectra, the loss at the grid nodes evaluated so far,
// the noise floor, the closed-form minimum inside grid intervals, the walk
// downhill from a coarse node, and the second-stage gain equalisation.
class PatchBlurEstimator::Refinement {
 public:
  struct Minimum {
    double radius = 0;
    double corrected = kInf;
    double raw = kInf;
    int lo = 0, hi = 0;  // evaluated node range
  };

  // gl, gr: the gain-equalised views minus `offset`.
  Refinement(const Tables& t,
             const cv::Mat& gl,
             const cv::Mat& gr,
             double offset,
             double sigma2_hp)
      : t_(t),
        options_(t.options),
        gl_(gl),
        gr_(gr),
        offset_(offset),
        sigma2_hp_(sigma2_hp),
        inv_m_(1.0 / t.num_interior),
        evals_(t.num_nodes) {
    left_positive_ = gl_ + offset_;
    right_positive_ = gr_ + offset_;
    TransformViews();
  }

  const cv::Mat& Left() const { return gl_; }
  const cv::Mat& Right() const { return gr_; }

  // Residual G_l * H_r - G_r * H_l at node n (once per node).
  void Evaluate(int n) {
    NodeEval& e = evals_[n];
    if (e.done) return;
    cv::mulSpectrums(spec_left_, t_.grid->RightSpectrum(n), product_left_, 0);
    cv::mulSpectrums(spec_right_, t_.grid->LeftSpectrum(n), product_right_, 0);
    product_left_ -= product_right_;
    cv::dft(product_left_,
            residual_image_,
            cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT,
            t_.interior.y + t_.interior.height);
    e.residual.resize(t_.num_interior);
    float* out = e.residual.data();
    for (int y = 0; y < t_.interior.height; ++y) {
      const float* row =
          residual_image_.ptr<float>(t_.interior.y + y) + t_.interior.x;
      std::copy(row, row + t_.interior.width, out);
      out += t_.interior.width;
    }
    e.energy = Dot(e.residual, e.residual);
    e.done = true;
    if (n > 0 && evals_[n - 1].done) {
      evals_[n - 1].next_dot = Dot(evals_[n - 1].residual, e.residual);
    }
    if (n + 1 < t_.num_nodes && evals_[n + 1].done) {
      e.next_dot = Dot(e.residual, evals_[n + 1].residual);
    }
  }

  double RawLoss(int n) const { return evals_[n].energy * inv_m_; }

  // Noise variance: the patch estimate, tightened by the fit: E[L(r)] =
  // S(r) + sigma^2 a(r) with S >= 0, so every L(r) / a(r) bounds sigma^2
  // from above (up to noise).
  double CurrentSigma2() const {
    if (!options_.subtract_noise_floor) return 0.0;
    double s2 = sigma2_hp_;
    for (int n = 0; n < t_.num_nodes; ++n) {
      if (evals_[n].done) s2 = std::min(s2, RawLoss(n) / t_.noise_gain[n]);
    }
    return s2;
  }

  // Minimum of the corrected loss over the evaluated nodes [lo, hi] with
  // linearly interpolated kernels inside each interval.
  Minimum Minimise(int lo, int hi, double sigma2) const {
    Minimum best;
    best.lo = lo;
    best.hi = hi;
    auto consider = [&](double radius, double corrected, double raw) {
      const double tol = 1e-9 * std::abs(raw) + 1e-300;
      if (corrected < best.corrected - tol ||
          (corrected <= best.corrected + tol &&
           std::abs(radius) < std::abs(best.radius))) {
        best.radius = radius;
        best.corrected = corrected;
        best.raw = raw;
      }
    };
    for (int n = lo; n <= hi; ++n) {
      consider(
          t_.Radius(n), RawLoss(n) - sigma2 * t_.noise_gain[n], RawLoss(n));
    }
    for (int n = lo; n < hi; ++n) {
      // L(t) = alpha (1-t)^2 + 2 beta t (1-t) + gamma t^2 (raw and noise
      // floor are both quadratic forms in the interpolated kernels).
      const double ra = RawLoss(n);
      const double rb = evals_[n].next_dot * inv_m_;
      const double rc = RawLoss(n + 1);
      const double alpha = ra - sigma2 * t_.noise_gain[n];
      const double beta = rb - sigma2 * t_.noise_cross[n];
      const double gamma = rc - sigma2 * t_.noise_gain[n + 1];
      const double curvature = alpha - 2 * beta + gamma;
      if (curvature <= 0) continue;  // minimum at an end node
      const double s = (alpha - beta) / curvature;
      if (s <= 0 || s >= 1) continue;
      const double corrected =
          alpha * (1 - s) * (1 - s) + 2 * beta * s * (1 - s) + gamma * s * s;
      const double raw =
          ra * (1 - s) * (1 - s) + 2 * rb * s * (1 - s) + rc * s * s;
      consider(t_.Radius(n) + s * t_.step, corrected, raw);
    }
    return best;
  }

  // Walks downhill from a coarse node until the minimum is enclosed.
  Minimum Refine(int start) {
    int lo = std::max(0, start - 1);
    int hi = std::min(t_.num_nodes - 1, start + 1);
    for (int n = lo; n <= hi; ++n) Evaluate(n);
    int budget = options_.max_refinement_evaluations - (hi - lo + 1);
    while (true) {
      const double sigma2 = CurrentSigma2();
      const Minimum m = Minimise(lo, hi, sigma2);
      // Extend while an end node is (tied for) the minimum: the loss may
      // still fall beyond it, or a plateau (in-focus deltas) may continue.
      const double tol = 1e-9 * std::abs(m.raw);
      const bool at_lo =
          RawLoss(lo) - sigma2 * t_.noise_gain[lo] <= m.corrected + tol;
      const bool at_hi =
          RawLoss(hi) - sigma2 * t_.noise_gain[hi] <= m.corrected + tol;
      if (at_lo && lo > 0 && budget > 0) {
        Evaluate(--lo);
        --budget;
      } else if (at_hi && hi < t_.num_nodes - 1 && budget > 0) {
        Evaluate(++hi);
        --budget;
      } else {
        return m;
      }
    }
  }

  int NearestNode(double radius) const {
    return std::max(0,
                    std::min(t_.num_nodes - 1,
                             static_cast<int>(std::round(radius / t_.step)) +
                                 t_.half_nodes));
  }

  // Gain, second stage. The whole-patch means of the two views differ not
  // only by gain but also because the views are shifted against each other
  // (by ~0.6 r), which the first estimate mistook for gain; at r = 15 that
  // alone moves the estimate by ~0.2 px. The right comparison is the
  // interior means of the two blurred cross views at the blur, which agree
  // exactly for equal gains. Re-transforms the views; evaluations made
  // before stay (the caller resets them when the gain moved the estimate).
  void EqualiseGain(double radius) {
    cv::Mat integral_left, integral_right;
    cv::integral(left_positive_, integral_left, CV_64F);
    cv::integral(right_positive_, integral_right, CV_64F);
    // Interior sums are linear in the kernels: interpolate like them.
    const double pos = std::max(
        0.0, std::min(t_.num_nodes - 1.0, radius / t_.step + t_.half_nodes));
    const int n0 = std::min(t_.num_nodes - 2, static_cast<int>(pos));
    const double s = pos - n0;
    double a = 0, b = 0;
    for (const int n : {n0, n0 + 1}) {
      const double w = n == n0 ? 1 - s : s;
      a += w * BlurredSum(integral_left, t_.grid->RightKernel(n), t_.interior);
      b += w * BlurredSum(integral_right, t_.grid->LeftKernel(n), t_.interior);
    }
    if (!(a > 0 && b > 0) || std::abs(a / b - 1) < 1e-7) return;
    const double half_log_ratio = 0.5 * std::log(a / b);
    left_positive_ *= std::exp(-half_log_ratio);
    right_positive_ *= std::exp(half_log_ratio);
    left_positive_.convertTo(gl_, CV_32FC1, 1.0, -offset_);
    right_positive_.convertTo(gr_, CV_32FC1, 1.0, -offset_);
    TransformViews();
  }

  void ResetEvaluations() { evals_.assign(t_.num_nodes, NodeEval()); }

 private:
  struct NodeEval {
    bool done = false;
    std::vector<float> residual;
    double energy = 0;       // |e|^2
    double next_dot = kInf;  // <e(n), e(n+1)>, once both are known
  };

  void TransformViews() {
    const int width = t_.patch_size.width, height = t_.patch_size.height;
    cv::Mat pl = cv::Mat::zeros(t_.dft_size, CV_32FC1);
    cv::Mat pr = cv::Mat::zeros(t_.dft_size, CV_32FC1);
    gl_.copyTo(pl(cv::Rect(0, 0, width, height)));
    gr_.copyTo(pr(cv::Rect(0, 0, width, height)));
    cv::dft(pl, spec_left_, 0, height);
    cv::dft(pr, spec_right_, 0, height);
  }

  const Tables& t_;
  const BlurEstimationOptions& options_;
  cv::Mat gl_, gr_;
  cv::Mat left_positive_, right_positive_;
  const double offset_;
  const double sigma2_hp_;
  const double inv_m_;
  cv::Mat spec_left_, spec_right_;
  std::vector<NodeEval> evals_;
  cv::Mat product_left_, product_right_, residual_image_;
};

PatchBlurEstimate PatchBlurEstimator::Estimate(const cv::Mat& left,
                                               const cv::Mat& right) const {
  const Tables& t = *tables_;
  const BlurEstimationOptions& options = t.options;
  DPSFM_CHECK(left.type() == CV_32FC1 && right.type() == CV_32FC1)
      << "DP patches must be CV_32FC1";
  DPSFM_CHECK(left.size() == t.patch_size && right.size() == t.patch_size)
      << "DP patches must be " << t.patch_size.width << "x"
      << t.patch_size.height << ", got " << left.cols << "x" << left.rows
      << " and " << right.cols << "x" << right.rows;

  PatchBlurEstimate result;
  result.opposite_sign_loss = kInf;
  if (!AllFinite(left) || !AllFinite(right)) {
    result.reject_reason = "non-finite pixels";
    return result;
  }
  {
    cv::Mat sum;
    cv::add(left, right, sum);
    result.texture = HorizontalTexture(sum);
  }
  if (!(result.texture > options.min_texture) || result.texture <= 0) {
    result.reject_reason = "no horizontal texture";
    return result;
  }

  // Gain equalisation: scale both views to their common mean, then remove
  // it. The residual is unchanged by the mean removal (both kernels of a pair
  // pass the same DC), and float precision improves.
  const double mean_left = cv::mean(left)[0];
  const double mean_right = cv::mean(right)[0];
  double gain_left = 1, gain_right = 1;
  if (options.normalize_gain) {
    if (!(mean_left > 1e-6 && mean_right > 1e-6)) {
      result.reject_reason = "view too dark for gain equalisation";
      return result;
    }
    const double common = 0.5 * (mean_left + mean_right);
    gain_left = common / mean_left;
    gain_right = common / mean_right;
  }
  const double offset = 0.5 * (mean_left * gain_left + mean_right * gain_right);
  cv::Mat gl, gr;
  left.convertTo(gl, CV_32FC1, gain_left, -offset);
  right.convertTo(gr, CV_32FC1, gain_right, -offset);

  // Noise: the Laplacian-mask estimate of each view is inflated by texture,
  // that of the difference of the views by DP disparity; take the smaller.
  // The refinement tightens it further with the fit itself.
  double sigma2_hp = kInf;
  if (options.subtract_noise_floor) {
    const double sl = EstimateNoiseSigma(gl);
    const double sr = EstimateNoiseSigma(gr);
    cv::Mat diff = gl - gr;
    const double sd = EstimateNoiseSigma(diff) / std::sqrt(2.0);
    sigma2_hp = std::min(0.5 * (sl * sl + sr * sr), sd * sd);
  }

  const CoarseCurve coarse = CoarseSearch(gl, gr, sigma2_hp);
  const std::vector<int>& minima = coarse.minima;

  // ---- Exact refinement. ----
  Refinement refinement(t, gl, gr, offset, sigma2_hp);
  using Minimum = Refinement::Minimum;
  double gain_radius = t.Radius(t.coarse_nodes[minima.front()]);
  if (options.normalize_gain) refinement.EqualiseGain(gain_radius);

  Minimum best = refinement.Refine(t.coarse_nodes[minima.front()]);
  // A second basin of similar coarse loss (e.g. the other sign) is refined
  // too: the windowed coarse loss is only an approximation.
  for (size_t i = 1; i < minima.size() && i < 3; ++i) {
    const double r = t.Radius(t.coarse_nodes[minima[i]]);
    if (r >= t.Radius(best.lo) - 1 && r <= t.Radius(best.hi) + 1) continue;
    if (coarse.loss[minima[i]] - coarse.min > 0.1 * (coarse.max - coarse.min)) {
      break;
    }
    const Minimum other =
        refinement.Refine(t.coarse_nodes[minima[i]]);  // same gain
    if (other.corrected < best.corrected) best = other;
    break;
  }
  // Gain at the refined estimate if it moved much from where the gain was
  // computed.
  for (int round = 0; round < 3 && options.normalize_gain &&
                      std::abs(best.radius - gain_radius) > 0.1;
       ++round) {
    gain_radius = best.radius;
    refinement.EqualiseGain(gain_radius);
    refinement.ResetEvaluations();
    best = refinement.Refine(refinement.NearestNode(gain_radius));
  }
  // Final values with the final noise estimate.
  const double sigma2 = refinement.CurrentSigma2();
  best = refinement.Minimise(best.lo, best.hi, sigma2);
  const double inv_m = 1.0 / t.num_interior;

  // In focus unless the data say otherwise. Blurs near focus change the
  // kernels little, so the loss is flat there (exactly flat inside the
  // disk's in-focus threshold) and noise alone picks a minimum somewhere on
  // or just beyond the plateau. Keep r = 0 unless the improvement over it
  // exceeds 3 standard deviations of what noise alone gives: the loss
  // difference between kernels h and h0 = h(0) has a noise term
  // 2 <e(0), n * (h - h0)> / M with std ~ 2 sigma^2 sqrt(a(0) D / M),
  // D = |h_l - h0_l|^2 + |h_r - h0_r|^2.
  if (best.radius != 0 && std::isfinite(sigma2) && sigma2 > 0) {
    const int zero = t.half_nodes;
    refinement.Evaluate(zero);
    const double zero_corrected =
        refinement.RawLoss(zero) - sigma2 * t.noise_gain[zero];
    const double pos = best.radius / t.step + t.half_nodes;
    const int n0 = std::min(t.num_nodes - 2, static_cast<int>(pos));
    const double s = pos - n0;
    const int half = t.border;
    cv::Mat dl = (1 - s) * EmbedKernel(t.grid->LeftKernel(n0), half) +
                 s * EmbedKernel(t.grid->LeftKernel(n0 + 1), half) -
                 EmbedKernel(t.grid->LeftKernel(zero), half);
    cv::Mat dr = (1 - s) * EmbedKernel(t.grid->RightKernel(n0), half) +
                 s * EmbedKernel(t.grid->RightKernel(n0 + 1), half) -
                 EmbedKernel(t.grid->RightKernel(zero), half);
    const double d = dl.dot(dl) + dr.dot(dr);
    const double threshold =
        3 * 2 * sigma2 * std::sqrt(t.noise_gain[zero] * d * inv_m);
    if (zero_corrected - best.corrected <= threshold) {
      best.radius = 0;
      best.corrected = zero_corrected;
      best.raw = refinement.RawLoss(zero);
    }
  }

  {
    // Signal power of the interior: gain-equalised variances minus noise.
    const cv::Mat il = refinement.Left()(t.interior),
                  ir = refinement.Right()(t.interior);
    cv::Scalar ml, sl, mr, sr;
    cv::meanStdDev(il, ml, sl);
    cv::meanStdDev(ir, mr, sr);
    const double noise2 = std::isfinite(sigma2) ? sigma2 : 0.0;
    const double power =
        std::max(sl[0] * sl[0] + sr[0] * sr[0] - 2 * noise2, 1e-300);
    result.relative_residual = std::max(best.corrected, 0.0) / power;
  }
  result.radius_px = best.radius;
  result.loss = best.raw;
  result.corrected_loss = best.corrected;
  result.noise_sigma =
      std::isfinite(sigma2_hp) ? std::sqrt(sigma2_hp) : std::sqrt(sigma2);

  // Fit quality: rise of the exact corrected loss fit_quality_offset_px away
  // (weaker side), against the residual at the minimum.
  const int offset_nodes = std::max(
      1, static_cast<int>(std::round(options.fit_quality_offset_px / t.step)));
  const double node_pos = best.radius / t.step + t.half_nodes;
  double rise = kInf;
  for (const int side : {-1, 1}) {
    const int n = static_cast<int>(std::round(node_pos)) + side * offset_nodes;
    if (n < 0 || n >= t.num_nodes) continue;
    refinement.Evaluate(n);
    rise = std::min(
        rise,
        refinement.RawLoss(n) - sigma2 * t.noise_gain[n] - best.corrected);
  }
  // Sign ambiguity: the best coarse loss on the other sign, against the
  // coarse loss at the estimate.
  if (best.radius != 0) {
    double opposite = kInf;
    double here = kInf;
    for (size_t i = 0; i < coarse.loss.size(); ++i) {
      const double r = t.Radius(t.coarse_nodes[i]);
      if (r * best.radius < 0) opposite = std::min(opposite, coarse.loss[i]);
      if (std::abs(r - best.radius) <= 0.5 * options.coarse_step_px + 1e-9) {
        here = std::min(here, coarse.loss[i]);
      }
    }
    result.opposite_sign_loss = opposite;
    if (std::isfinite(opposite) && std::isfinite(here)) {
      rise = std::min(rise, opposite - here);
    }
  }
  const double residual = std::max(best.raw, 1e-300);
  result.fit_quality =
      std::isfinite(rise) && rise > 0 ? rise / (rise + residual) : 0.0;
  result.fit_quality = std::min(1.0, std::max(1e-6, result.fit_quality));

  result.at_bound = std::abs(best.radius) > t.bound - 0.5 * t.step;
  if (result.at_bound) {
    result.reject_reason = kBlurAtSearchBound;
    return result;
  }
  if (result.fit_quality < options.min_fit_quality) {
    result.reject_reason = "fit quality below threshold";
    return result;
  }
  result.valid = true;
  return result;
}

PatchBlurEstimate EstimatePatchBlur(const cv::Mat& left,
                                    const cv::Mat& right,
                                    const DPPsfModel& psf,
                                    const BlurEstimationOptions& options) {
  DPSFM_CHECK_OPTIONS(options, "BlurEstimationOptions");
  DPSFM_CHECK(left.size() == right.size())
      << "left and right patches differ in size";
  // One estimator per call: its tables cost tens of ms, so a caller with
  // many patches holds a PatchBlurEstimator instead (as the scale estimator
  // does); nothing is cached behind the caller's back.
  return PatchBlurEstimator(psf, options, left.size()).Estimate(left, right);
}

cv::Mat ToLuma(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat gray;
  cv::transform(image, gray, cv::Matx13f(0.299f, 0.587f, 0.114f));
  return gray;
}

double HorizontalTexture(const cv::Mat& gray_patch) {
  DPSFM_CHECK(gray_patch.type() == CV_32FC1 && !gray_patch.empty())
      << "HorizontalTexture needs a non-empty CV_32FC1 patch";
  cv::Mat gx;
  cv::Sobel(gray_patch, gx, CV_32F, 1, 0, 3, 1, 0, cv::BORDER_REFLECT_101);
  return cv::mean(cv::abs(gx))[0];
}

double EstimateNoiseSigma(const cv::Mat& gray_patch) {
  DPSFM_CHECK(gray_patch.type() == CV_32FC1 && gray_patch.rows >= 3 &&
              gray_patch.cols >= 3)
      << "EstimateNoiseSigma needs a CV_32FC1 patch of at least 3x3";
  std::vector<float> responses;
  responses.reserve((gray_patch.rows - 2) * (gray_patch.cols - 2));
  for (int y = 1; y + 1 < gray_patch.rows; ++y) {
    const float* a = gray_patch.ptr<float>(y - 1);
    const float* b = gray_patch.ptr<float>(y);
    const float* c = gray_patch.ptr<float>(y + 1);
    for (int x = 1; x + 1 < gray_patch.cols; ++x) {
      const float v = (a[x - 1] - 2 * a[x] + a[x + 1]) -
                      2 * (b[x - 1] - 2 * b[x] + b[x + 1]) +
                      (c[x - 1] - 2 * c[x] + c[x + 1]);
      responses.push_back(std::abs(v));
    }
  }
  // The filter's gain is 6 (the norm of its taps).
  return SigmaFromMedianAbsolute(UpperMedianInPlace(&responses), 6.0);
}

namespace {

// EstimateNoiseSigma over `rect` (without its outer ring) from a map of
// absolute responses, on every other pixel in both directions: the median of
// thousands of responses is as good as that of all of them for screening.
double SubsampledNoiseSigma(const cv::Mat& response, const cv::Rect& rect) {
  std::vector<float> values;
  values.reserve((rect.width / 2 + 1) * (rect.height / 2 + 1));
  for (int y = rect.y + 1; y + 1 < rect.y + rect.height; y += 2) {
    const float* row = response.ptr<float>(y);
    for (int x = rect.x + 1; x + 1 < rect.x + rect.width; x += 2) {
      values.push_back(row[x]);
    }
  }
  if (values.empty()) return 0;
  return SigmaFromMedianAbsolute(UpperMedianInPlace(&values), 6.0);
}

}  // namespace

PatchScreening::PatchScreening(const cv::Mat& gray_left,
                               const cv::Mat& gray_right) {
  DPSFM_CHECK(gray_left.type() == CV_32FC1 && gray_right.type() == CV_32FC1 &&
              gray_left.size() == gray_right.size())
      << "PatchScreening needs two CV_32FC1 views of one size";
  cv::Mat sum, diff, gx;
  cv::add(gray_left, gray_right, sum);
  cv::subtract(gray_left, gray_right, diff);
  cv::Sobel(sum, gx, CV_32F, 1, 0, 3, 1, 0, cv::BORDER_REFLECT_101);
  cv::integral(cv::abs(gx), texture_integral_, CV_64F);
  const cv::Mat mask = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::filter2D(gray_left, noise_left_, CV_32F, mask);
  cv::filter2D(gray_right, noise_right_, CV_32F, mask);
  cv::filter2D(diff, noise_diff_, CV_32F, mask);
  noise_left_ = cv::abs(noise_left_);
  noise_right_ = cv::abs(noise_right_);
  noise_diff_ = cv::abs(noise_diff_);
}

double PatchScreening::Texture(const cv::Rect& r) const {
  const cv::Mat& t = texture_integral_;
  return (t.at<double>(r.y + r.height, r.x + r.width) -
          t.at<double>(r.y, r.x + r.width) - t.at<double>(r.y + r.height, r.x) +
          t.at<double>(r.y, r.x)) /
         r.area();
}

double PatchScreening::NoiseSigma(const cv::Rect& rect) const {
  const double sl = SubsampledNoiseSigma(noise_left_, rect);
  const double sr = SubsampledNoiseSigma(noise_right_, rect);
  const double sd = SubsampledNoiseSigma(noise_diff_, rect) / std::sqrt(2.0);
  return std::sqrt(std::min(0.5 * (sl * sl + sr * sr), sd * sd));
}

double TextureSnr(double texture, double noise_sigma) {
  return texture / (3.91 * std::max(noise_sigma, 1e-6));
}

double PatchScreening::TextureSnr(const cv::Rect& rect) const {
  return dpsfm::TextureSnr(Texture(rect), NoiseSigma(rect));
}

namespace {

// The search bound in px of the whole frame: the reference rule (anchors
// below) applied at the reference resize 1/k, smallest integer k with a
// working short side <= 2800 px, then expressed in frame px.
double FrameRadiusBound(const cv::Size& frame_size) {
  DPSFM_CHECK(frame_size.width > 0 && frame_size.height > 0)
      << "empty frame size";
  const int frame_short = std::min(frame_size.width, frame_size.height);
  const int k = std::max(1, static_cast<int>(std::ceil(frame_short / 2800.0)));
  const double short_side = static_cast<double>(frame_short) / k;
  // Anchors: phone (1512 px, |r| <= 10), DSLR at 0.5 (2240 px, |r| <= 20).
  double max_radius;
  if (short_side <= 1512) {
    max_radius = 10.0 * short_side / 1512;
  } else if (short_side <= 2240) {
    max_radius = 10.0 + (short_side - 1512) * 10.0 / (2240 - 1512);
  } else {
    max_radius = 20.0 * short_side / 2240;
  }
  return max_radius * k;
}

}  // namespace

PatchGeometry DefaultPatchGeometry(const cv::Size& frame_size) {
  // Work at the coarsest integer reduction that keeps the search bound near
  // the phone anchor's 10 px: blur of a few pixels or more has no detail
  // finer than the reduced grid, and area averaging keeps the shift
  // information (noise falls as the pixels grow), so the scale does not
  // change while a patch's FFTs shrink by k^2 (docs/benchmark.md: 3000x2000
  // frames at 1/2 give the full-resolution scale and interval at 1/6 of the
  // blur stage's cost). Frames with a short side below ~1880 px keep their
  // resolution.
  const double bound = FrameRadiusBound(frame_size);
  const int k = std::max(1, static_cast<int>(std::lround(bound / 10.0)));
  return DefaultPatchGeometry(frame_size, 1.0 / k);
}

PatchGeometry DefaultPatchGeometry(const cv::Size& frame_size,
                                   double resize_factor) {
  DPSFM_CHECK(resize_factor > 0 && resize_factor <= 1)
      << "resize factor must be in (0, 1], got " << resize_factor;
  const double max_radius = FrameRadiusBound(frame_size) * resize_factor;
  // Half-pixel steps keep the bound on the blur estimator's kernel grid.
  return PatchGeometryForRadius(std::max(3.0, std::round(2 * max_radius) / 2),
                                resize_factor);
}

PatchGeometry PatchGeometryForRadius(double max_radius, double resize_factor) {
  DPSFM_CHECK(max_radius >= 1 && std::isfinite(max_radius))
      << "radius bound must be at least 1 px, got " << max_radius;
  PatchGeometry geometry;
  geometry.max_radius_px = max_radius;
  const double patch = std::max(6 * max_radius - 9, 2 * max_radius + 21);
  geometry.patch_size = 2 * static_cast<int>(std::round((patch - 1) / 2)) + 1;
  geometry.stride = static_cast<int>(std::round(2 * max_radius + 7));
  geometry.resize_factor = resize_factor;
  return geometry;
}

}  // namespace dpsfm
