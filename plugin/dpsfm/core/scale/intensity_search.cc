#include "dpsfm/core/scale/intensity_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <tuple>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/curve_math.h"
#include "dpsfm/core/util/statistics.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

cv::Mat ToFloat(const cv::Mat& image) {
  if (image.depth() == CV_32F) return image;
  cv::Mat out;
  const double scale = image.depth() == CV_16U  ? 1.0 / 65535.0
                       : image.depth() == CV_8U ? 1.0 / 255.0
                                                : 1.0;
  image.convertTo(out, CV_MAKETYPE(CV_32F, image.channels()), scale);
  return out;
}

// Largest |r| whose kernels fit inside `border` (and <= max_radius_px).
double MaxSupportedRadius(const DPPsfModel& psf,
                          int border,
                          double max_radius_px) {
  double r = std::min(max_radius_px, border + 0.5);
  while (r > 0 && psf.KernelRadius(r) > border) r -= 0.05;
  return std::max(r, 0.0);
}

// Sums and inner products over the interior of one channel's cross-blurred
// views A = G_l * H_r(r_n), B = G_r * H_l(r_n) at kernel-grid node n, and
// with node n + 1. Kernels interpolated linearly in r make A and B linear in
// t inside the interval, so these give the L2-family losses at any r in it
// exactly (DPKernelGrid).
struct NodeChannelStats {
  double sum_a = 0, sum_b = 0;
  double aa = 0, bb = 0, ab = 0;
  // <A_n, A_n+1>, <B_n, B_n+1>, <A_n, B_n+1>, <B_n, A_n+1>.
  double aa_next = 0, bb_next = 0, ab_next = 0, ba_next = 0;
};

// A patch converted once for the whole search.
struct Prepared {
  const DPPsfModel* psf = nullptr;  // the patch's PSF
  cv::Mat left, right;  // CV_32FC(n); released once `stats` are computed
  int border = 0;
  int channels = 0;
  double num_interior = 0;
  double max_abs_radius = 0;
  std::vector<double> sigma_left, sigma_right;
  // kRelativeL2: per-channel signal power the loss is divided by, fixed per
  // patch (taken at its radius under the initial scale) so that the
  // denominator does not depend on the candidate; empty = the candidate's
  // own power.
  std::vector<double> reference_power;
  // kRelativeL2: channels whose structure at the reference radius does not
  // rise above their noise carry no information and are skipped (empty =
  // all used).
  std::vector<char> channel_used;
  // L2-family losses: statistics of the grid nodes computed so far, per
  // channel (the nodes of the intervals the patch's radii fall in; an entry
  // with has_next also holds the cross terms with the next node). Null grid
  // = the exact path (convolution with the model's kernel at r itself).
  const DPKernelGrid* grid = nullptr;
  struct NodeEntry {
    bool has_next = false;
    std::vector<NodeChannelStats> channel;
  };
  std::map<int, NodeEntry> stats;
};

double SumSquares(const cv::Mat& kernel) { return kernel.dot(kernel); }

// kRelativeL2 per channel: mean squared difference `acc` of the normalised
// cross-blurred patches, its noise gain (noise = sigma^2 gain), the patches'
// power (variances, noise included) and the expected noise in acc.
struct ChannelTerms {
  double acc = 0, gain = 0, power = 0, noise = 0;
};

// What the L2-family losses need of one channel at one radius: the mean
// squared difference of the cross-blurred patches normalised to mean 1,
// their summed variance, and the normalisers al = n / sum(A), ar = n /
// sum(B). ok = false: a dark channel (no alignment information).
struct ChannelMoments {
  bool ok = false;
  double acc = 0, own_power = 0, al = 0, ar = 0;
};

// The L2-family losses from per-channel moments; hr2 = |H_r|^2, hl2 =
// |H_l|^2 of the kernels used.
double CombineChannels(const Prepared& p,
                       IntensityLoss loss,
                       const std::vector<ChannelMoments>& moments,
                       double hr2,
                       double hl2,
                       std::vector<ChannelTerms>* terms) {
  const int channels = static_cast<int>(moments.size());
  double total = 0;
  int relative_channels = 0;
  for (int c = 0; c < channels; ++c) {
    const ChannelMoments& m = moments[c];
    if (!m.ok) continue;
    // E ||n_l * H_r||^2 per pixel = sigma_l^2 ||H_r||^2 (white noise), in
    // the same normalisation: the floor both noise-aware losses remove.
    const double ql =
        c < static_cast<int>(p.sigma_left.size()) ? p.sigma_left[c] * m.al : 0;
    const double qr = c < static_cast<int>(p.sigma_right.size())
                          ? p.sigma_right[c] * m.ar
                          : 0;
    const double noise = ql * ql * hr2 + qr * qr * hl2;
    if (loss == IntensityLoss::kRelativeL2) {
      // The denominator keeps its noise: subtracting it too would divide
      // by ~0 on heavily blurred patches.
      if (terms != nullptr) {
        terms->resize(channels);
        ChannelTerms& t = (*terms)[c];
        t.acc = m.acc;
        t.gain = m.al * m.al * hr2 + m.ar * m.ar * hl2;
        t.power = m.own_power;
        t.noise = noise;
      }
      if (c < static_cast<int>(p.channel_used.size()) && !p.channel_used[c]) {
        continue;
      }
      const double power = c < static_cast<int>(p.reference_power.size())
                               ? p.reference_power[c]
                               : m.own_power;
      if (power > 1e-12) {
        total += (m.acc - noise) / power;
        ++relative_channels;
      }
    } else if (loss == IntensityLoss::kNoiseCorrectedL2) {
      total += m.acc - noise;
    } else {
      total += m.acc;
    }
  }
  // kRelativeL2: the mean over the informative channels, so that every
  // patch weighs alike whatever its colour.
  if (loss == IntensityLoss::kRelativeL2 && relative_channels > 0) {
    total /= relative_channels;
  }
  return total;
}

// Exact path: the model's kernels at r itself, convolved in the image domain.
double ExactLoss(const Prepared& p,
                 double radius_px,
                 const DPPsfModel& psf,
                 IntensityLoss loss,
                 std::vector<ChannelTerms>* terms) {
  const double r =
      std::max(-p.max_abs_radius, std::min(p.max_abs_radius, radius_px));
  const DPKernels kernels = psf.Kernels(r);
  const int k = std::max(kernels.left.cols, kernels.left.rows) / 2;
  const int w = p.left.cols - 2 * p.border;
  const int h = p.left.rows - 2 * p.border;
  // Convolve only the interior plus the kernel's reach (cheaper for small
  // kernels; the reflected border of ConvolvePsf never reaches the interior).
  const cv::Rect reach(p.border - k, p.border - k, w + 2 * k, h + 2 * k);
  const cv::Rect interior(k, k, w, h);
  // Eq. (loss_refine): G_l * H_r against G_r * H_l (H_l = flip(H_r)).
  const cv::Mat xl = ConvolvePsf(p.left(reach), kernels.right)(interior);
  const cv::Mat xr = ConvolvePsf(p.right(reach), kernels.left)(interior);
  const int channels = xl.channels();
  const double n = static_cast<double>(w) * h;
  const cv::Scalar sum_l = cv::sum(xl);
  const cv::Scalar sum_r = cv::sum(xr);
  std::vector<ChannelMoments> moments(channels);
  double total_l1 = 0;
  for (int c = 0; c < channels; ++c) {
    // eta(X) = X / ||X||_1; intensities are >= 0 so ||X||_1 = sum X. A dark
    // channel carries no alignment information.
    const double sl = sum_l[c], sr = sum_r[c];
    if (!(sl > 1e-9 * n) || !(sr > 1e-9 * n)) continue;
    if (loss == IntensityLoss::kPaperL1) {
      double acc = 0;
      for (int y = 0; y < h; ++y) {
        const float* a = xl.ptr<float>(y);
        const float* b = xr.ptr<float>(y);
        for (int x = 0; x < w; ++x) {
          acc += std::abs(a[x * channels + c] / sl - b[x * channels + c] / sr);
        }
      }
      total_l1 += acc;
      continue;
    }
    // Normalised to mean 1 so the loss reads as a relative contrast.
    ChannelMoments& m = moments[c];
    m.ok = true;
    m.al = n / sl;
    m.ar = n / sr;
    double acc = 0, power_l = 0, power_r = 0;
    for (int y = 0; y < h; ++y) {
      const float* a = xl.ptr<float>(y);
      const float* b = xr.ptr<float>(y);
      for (int x = 0; x < w; ++x) {
        const double va = a[x * channels + c] * m.al;
        const double vb = b[x * channels + c] * m.ar;
        const double d = va - vb;
        acc += d * d;
        // Both normalised patches have mean 1.
        power_l += (va - 1) * (va - 1);
        power_r += (vb - 1) * (vb - 1);
      }
    }
    m.acc = acc / n;
    m.own_power = (power_l + power_r) / n;
  }
  if (loss == IntensityLoss::kPaperL1) return total_l1;
  return CombineChannels(p,
                         loss,
                         moments,
                         SumSquares(kernels.right),
                         SumSquares(kernels.left),
                         terms);
}

// Grid path: the same L2-family losses with kernels interpolated between
// grid nodes, from the node statistics (no convolution per radius).
double GridLoss(const Prepared& p,
                double radius_px,
                IntensityLoss loss,
                std::vector<ChannelTerms>* terms) {
  const DPKernelGrid& grid = *p.grid;
  int node = 0;
  double t = 0;
  grid.Locate(radius_px, &node, &t);
  const auto e0 = p.stats.find(node);
  const auto e1 = p.stats.find(node + 1);
  DPSFM_CHECK(e0 != p.stats.end() && e0->second.has_next && e1 != p.stats.end())
      << "kernel-grid interval " << node << " was not prepared";
  const std::vector<NodeChannelStats>& s0 = e0->second.channel;
  const std::vector<NodeChannelStats>& s1 = e1->second.channel;
  const double n = p.num_interior;
  const double u = 1 - t;
  std::vector<ChannelMoments> moments(p.channels);
  for (int c = 0; c < p.channels; ++c) {
    const NodeChannelStats& a = s0[c];
    const NodeChannelStats& b = s1[c];
    const double sl = u * a.sum_a + t * b.sum_a;
    const double sr = u * a.sum_b + t * b.sum_b;
    if (!(sl > 1e-9 * n) || !(sr > 1e-9 * n)) continue;
    const double aa = InterpolatedEnergy(a.aa, a.aa_next, b.aa, t);
    const double bb = InterpolatedEnergy(a.bb, a.bb_next, b.bb, t);
    const double ab =
        u * u * a.ab + t * u * (a.ab_next + a.ba_next) + t * t * b.ab;
    ChannelMoments& m = moments[c];
    m.ok = true;
    m.al = n / sl;
    m.ar = n / sr;
    const double la = m.al * m.al * aa, lb = m.ar * m.ar * bb;
    m.acc = std::max(0.0, (la - 2 * m.al * m.ar * ab + lb) / n);
    // sum (va - 1)^2 = al^2 |A|^2 - n, as va has mean 1.
    m.own_power = std::max(0.0, (la + lb) / n - 2);
  }
  const double hr2 = InterpolatedEnergy(grid.RightEnergy(node),
                                        grid.RightCross(node),
                                        grid.RightEnergy(node + 1),
                                        t);
  const double hl2 = InterpolatedEnergy(grid.LeftEnergy(node),
                                        grid.LeftCross(node),
                                        grid.LeftEnergy(node + 1),
                                        t);
  return CombineChannels(p, loss, moments, hr2, hl2, terms);
}

double LossOfPrepared(const Prepared& p,
                      double radius_px,
                      const DPPsfModel& psf,
                      IntensityLoss loss,
                      std::vector<ChannelTerms>* terms = nullptr) {
  return p.grid != nullptr ? GridLoss(p, radius_px, loss, terms)
                           : ExactLoss(p, radius_px, psf, loss, terms);
}

// Grid intervals (node n <-> [r_n, r_n+1]) that the radii fall in.
std::vector<int> IntervalsOf(const DPKernelGrid& grid,
                             const std::vector<double>& radii) {
  std::vector<int> intervals;
  for (const double r : radii) {
    int node = 0;
    double t = 0;
    grid.Locate(r, &node, &t);
    intervals.push_back(node);
  }
  std::sort(intervals.begin(), intervals.end());
  intervals.erase(std::unique(intervals.begin(), intervals.end()),
                  intervals.end());
  return intervals;
}

// Adds to p->stats the nodes of the given intervals that are not ready yet,
// from the patch's crops: per channel one forward DFT of each view, then per
// node one product and inverse DFT per view (only the interior is kept; the
// grid's kernels fit the crop's border, so circular wrap-around never
// reaches it).
void AddIntervals(const IntensityPatch& patch,
                  const std::vector<int>& intervals,
                  Prepared* p) {
  std::vector<int> nodes;
  for (const int n : intervals) {
    const auto it = p->stats.find(n);
    if (it == p->stats.end() || !it->second.has_next) {
      nodes.push_back(n);
      nodes.push_back(n + 1);
    }
  }
  if (nodes.empty()) return;
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());

  const DPKernelGrid& grid = *p->grid;
  const cv::Size dft = grid.DftSize();
  const cv::Mat left = ToFloat(patch.left), right = ToFloat(patch.right);
  const int channels = left.channels();
  const cv::Rect interior(p->border,
                          p->border,
                          left.cols - 2 * p->border,
                          left.rows - 2 * p->border);
  std::vector<cv::Mat> left_channels, right_channels;
  cv::split(left, left_channels);
  cv::split(right, right_channels);
  std::vector<cv::Mat> spec_left(channels), spec_right(channels);
  cv::Mat padded = cv::Mat::zeros(dft, CV_32FC1);
  const cv::Rect area(0, 0, left.cols, left.rows);
  for (int c = 0; c < channels; ++c) {
    left_channels[c].copyTo(padded(area));
    cv::dft(padded, spec_left[c], 0, left.rows);
    right_channels[c].copyTo(padded(area));
    cv::dft(padded, spec_right[c], 0, left.rows);
  }
  // Rows of the inverse transforms that are needed (up to the interior's
  // last one).
  const int output_rows = interior.y + interior.height;
  std::vector<cv::Mat> previous_a(channels), previous_b(channels);
  int previous_node = -2;
  cv::Mat product, image;
  // The interior of a view's spectrum times a kernel's, back in space.
  auto blurred = [&](const cv::Mat& view_spectrum,
                     const cv::Mat& kernel_spectrum) {
    cv::mulSpectrums(view_spectrum, kernel_spectrum, product, 0);
    cv::dft(product,
            image,
            cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT,
            output_rows);
    return cv::Mat(image(interior).clone());
  };
  for (const int n : nodes) {
    Prepared::NodeEntry& entry = p->stats[n];
    entry.channel.assign(channels, NodeChannelStats());
    Prepared::NodeEntry* before =
        previous_node == n - 1 ? &p->stats[n - 1] : nullptr;
    for (int c = 0; c < channels; ++c) {
      const cv::Mat a = blurred(spec_left[c], grid.RightSpectrum(n));
      const cv::Mat b = blurred(spec_right[c], grid.LeftSpectrum(n));
      NodeChannelStats& s = entry.channel[c];
      s.sum_a = cv::sum(a)[0];
      s.sum_b = cv::sum(b)[0];
      s.aa = a.dot(a);
      s.bb = b.dot(b);
      s.ab = a.dot(b);
      if (before != nullptr) {
        NodeChannelStats& prev = before->channel[c];
        prev.aa_next = previous_a[c].dot(a);
        prev.bb_next = previous_b[c].dot(b);
        prev.ab_next = previous_a[c].dot(b);
        prev.ba_next = previous_b[c].dot(a);
      }
      previous_a[c] = a;
      previous_b[c] = b;
    }
    if (before != nullptr) before->has_next = true;
    previous_node = n;
  }
}

// Radii of a patch under the given scales (eq. (solution01) with s g_i' and
// s z'_ij); non-finite ones (a depth at the focal plane's pole) at the bound.
std::vector<double> PatchRadii(const IntensityView& view,
                               double depth,
                               const std::vector<double>& scales,
                               double bound) {
  std::vector<double> radii;
  for (const double s : scales) {
    double r = PredictBlurRadiusPx(
        view.lens, view.pixel_pitch_mm, s, view.focus_distance_model, depth);
    if (!std::isfinite(r)) r = r > 0 ? bound : -bound;
    radii.push_back(r);
  }
  return radii;
}

Prepared Prepare(const IntensityPatch& patch,
                 const DPPsfModel& psf,
                 double max_radius_px) {
  DPSFM_CHECK(!patch.left.empty() && patch.left.size() == patch.right.size() &&
              patch.left.type() == patch.right.type())
      << "patch crops must be non-empty and of equal size and type";
  DPSFM_CHECK(patch.border >= 0 && patch.left.cols > 2 * patch.border &&
              patch.left.rows > 2 * patch.border)
      << "patch border " << patch.border << " leaves no interior";
  Prepared p;
  p.left = ToFloat(patch.left);
  p.right = ToFloat(patch.right);
  p.border = patch.border;
  p.max_abs_radius = MaxSupportedRadius(psf, patch.border, max_radius_px);
  p.channels = p.left.channels();
  p.num_interior = static_cast<double>(p.left.cols - 2 * p.border) *
                   (p.left.rows - 2 * p.border);
  return p;
}

}  // namespace

const char* IntensityLossName(IntensityLoss loss) {
  switch (loss) {
    case IntensityLoss::kPaperL1:
      return "paper_l1";
    case IntensityLoss::kL2:
      return "l2";
    case IntensityLoss::kNoiseCorrectedL2:
      return "noise_corrected_l2";
    case IntensityLoss::kRelativeL2:
      return "relative_l2";
  }
  return "?";
}

bool IntensitySearchOptions::Check() const {
  DPSFM_CHECK_OPTION_GE(num_candidates, 3);
  // T_s < 1 keeps every candidate scale positive.
  DPSFM_CHECK_OPTION_VALUE(relative_range > 0 && relative_range < 1,
                           relative_range);
  DPSFM_CHECK_OPTION_GE(num_refine_candidates, 0);
  DPSFM_CHECK_OPTION_GT(robust_loss_scale, 0);
  DPSFM_CHECK_OPTION_GT(max_radius_px, 0);
  DPSFM_CHECK_OPTION_VALUE(grid_step_px >= 0 && grid_step_px <= 1,
                           grid_step_px);
  DPSFM_CHECK_OPTION_GE(num_bootstrap, 0);
  DPSFM_CHECK_OPTION_VALUE(confidence_level > 0 && confidence_level < 1,
                           confidence_level);
  DPSFM_CHECK_OPTION_VALUE(num_threads == -1 || num_threads > 0, num_threads);
  return true;
}

std::vector<double> EstimateChannelNoiseSigma(const cv::Mat& image) {
  const cv::Mat f = ToFloat(image);
  const cv::Mat mask = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
  std::vector<cv::Mat> channels;
  cv::split(f, channels);
  std::vector<double> sigmas;
  for (const cv::Mat& ch : channels) {
    if (ch.rows < 3 || ch.cols < 3) {
      sigmas.push_back(0);
      continue;
    }
    cv::Mat response;
    cv::filter2D(ch, response, CV_32F, mask);
    // Drop the filter's own border.
    const cv::Mat inner = response(cv::Rect(1, 1, ch.cols - 2, ch.rows - 2));
    std::vector<float> values;
    values.reserve(inner.total());
    for (int y = 0; y < inner.rows; ++y) {
      const float* row = inner.ptr<float>(y);
      for (int x = 0; x < inner.cols; ++x) values.push_back(std::abs(row[x]));
    }
    sigmas.push_back(SigmaFromMedianAbsolute(UpperMedianInPlace(&values), 6.0));
  }
  return sigmas;
}

std::vector<double> EstimatePairNoiseSigma(const cv::Mat& left,
                                           const cv::Mat& right) {
  const cv::Mat l = ToFloat(left), r = ToFloat(right);
  const cv::Scalar ml = cv::mean(l), mr = cv::mean(r);
  std::vector<cv::Mat> lc, rc;
  cv::split(l, lc);
  cv::split(r, rc);
  std::vector<cv::Mat> diff(lc.size());
  for (size_t c = 0; c < lc.size(); ++c) {
    const double m = 0.5 * (ml[c] + mr[c]);
    const double gl = ml[c] > 0 ? m / ml[c] : 1.0;
    const double gr = mr[c] > 0 ? m / mr[c] : 1.0;
    diff[c] = (lc[c] * gl - rc[c] * gr) * (1.0 / std::sqrt(2.0));
  }
  cv::Mat merged;
  cv::merge(diff, merged);
  return EstimateChannelNoiseSigma(merged);
}

double PatchAlignmentLoss(const IntensityPatch& patch,
                          double radius_px,
                          const DPPsfModel& psf,
                          IntensityLoss loss,
                          double max_radius_px,
                          const std::vector<double>& noise_sigma_left,
                          const std::vector<double>& noise_sigma_right) {
  Prepared p = Prepare(patch, psf, max_radius_px);
  p.sigma_left = noise_sigma_left;
  p.sigma_right = noise_sigma_right;
  return LossOfPrepared(p, radius_px, psf, loss);
}

IntensitySearchResult SearchScaleByIntensity(
    const std::vector<IntensityView>& views,
    const std::vector<IntensityPatch>& patches,
    double initial_scale,
    const DPPsfModel& psf,
    const IntensitySearchOptions& options) {
  DPSFM_CHECK_OPTIONS(options, "IntensitySearchOptions");
  IntensitySearchResult result;
  if (!(initial_scale > 0) || !std::isfinite(initial_scale)) {
    result.failure_reason = "no positive initial scale";
    return result;
  }
  if (patches.empty()) {
    result.failure_reason = "no patches to evaluate";
    return result;
  }
  // Validate everything here: nothing may throw inside the parallel loops.
  for (const IntensityPatch& patch : patches) {
    DPSFM_CHECK(patch.view >= 0 && patch.view < static_cast<int>(views.size()))
        << "patch refers to view " << patch.view;
    DPSFM_CHECK_GT(patch.depth, 0);
    DPSFM_CHECK(!patch.left.empty() &&
                patch.left.size() == patch.right.size() &&
                patch.left.type() == patch.right.type())
        << "patch crops must be non-empty and of equal size and type";
    DPSFM_CHECK(patch.border >= 0 && patch.left.cols > 2 * patch.border &&
                patch.left.rows > 2 * patch.border)
        << "patch border " << patch.border << " leaves no interior";
  }
  for (const IntensityView& view : views) {
    DPSFM_CHECK(view.lens.Check()) << view.lens.ToString();
    DPSFM_CHECK_GT(view.pixel_pitch_mm, 0);
  }
  const int num_patches = static_cast<int>(patches.size());
  result.num_patches = num_patches;
#ifdef _OPENMP
  const int threads = EffectiveNumThreads(options.num_threads);
#endif

  // First-pass candidates: the paper's set, s* (1 +- T_s).
  const int num = options.num_candidates;
  const double lo = initial_scale * (1 - options.relative_range);
  const double hi = initial_scale * (1 + options.relative_range);
  const double step = (hi - lo) / (num - 1);
  std::vector<double> scales(num);
  for (int k = 0; k < num; ++k) scales[k] = lo + step * k;

  // Kernel grids, one per crop geometry (L2-family losses only; the paper's
  // L1 needs the pixels at every radius). Built before the parallel loop.
  const bool use_grid =
      options.grid_step_px > 0 && options.loss != IntensityLoss::kPaperL1;
  std::map<std::tuple<int, int, int, const DPPsfModel*>,
           std::unique_ptr<DPKernelGrid>>
      grids;
  std::vector<const DPKernelGrid*> patch_grid(num_patches, nullptr);
  if (use_grid) {
    for (int j = 0; j < num_patches; ++j) {
      const IntensityPatch& patch = patches[j];
      const DPPsfModel& patch_psf = patch.psf != nullptr ? *patch.psf : psf;
      const auto key = std::make_tuple(
          patch.left.cols, patch.left.rows, patch.border, &patch_psf);
      auto it = grids.find(key);
      if (it == grids.end()) {
        // Nodes only where the crop's border supports the kernels.
        const double supported =
            std::floor(MaxSupportedRadius(
                           patch_psf, patch.border, options.max_radius_px) /
                       options.grid_step_px) *
            options.grid_step_px;
        std::unique_ptr<DPKernelGrid> grid;
        if (supported >= options.grid_step_px) {
          grid.reset(new DPKernelGrid(
              patch_psf,
              options.grid_step_px,
              supported,
              cv::Size(cv::getOptimalDFTSize(patch.left.cols),
                       cv::getOptimalDFTSize(patch.left.rows))));
        }
        it = grids.emplace(key, std::move(grid)).first;
      }
      patch_grid[j] = it->second.get();
    }
  }

  // Convert crops, estimate noise, and (grid path) reduce each patch to its
  // node statistics over the radii its candidates reach.
  std::vector<Prepared> prepared(num_patches);
#ifdef _OPENMP
#pragma omp parallel for num_threads(threads) schedule(dynamic)
#endif
  for (int j = 0; j < num_patches; ++j) {
    Prepared& p = prepared[j];
    const DPPsfModel& patch_psf =
        patches[j].psf != nullptr ? *patches[j].psf : psf;
    p = Prepare(patches[j], patch_psf, options.max_radius_px);  // checked
    p.psf = &patch_psf;
    if (options.loss == IntensityLoss::kNoiseCorrectedL2 ||
        options.loss == IntensityLoss::kRelativeL2) {
      p.sigma_left = EstimatePairNoiseSigma(p.left, p.right);
      p.sigma_right = p.sigma_left;
    }
    const DPKernelGrid* grid = patch_grid[j];
    if (grid == nullptr) continue;
    // Nodes for the first-pass candidates and the initial scale (the
    // reference radius of kRelativeL2); the refine pass adds its own.
    std::vector<double> needed = scales;
    needed.push_back(initial_scale);
    p.grid = grid;
    p.max_abs_radius = grid->Bound();
    AddIntervals(patches[j],
                 IntervalsOf(*grid,
                             PatchRadii(views[patches[j].view],
                                        patches[j].depth,
                                        needed,
                                        grid->Bound())),
                 &p);
    // The float crops are no longer needed: the statistics are the patch.
    p.left.release();
    p.right.release();
  }
  if (options.loss == IntensityLoss::kNoiseCorrectedL2 ||
      options.loss == IntensityLoss::kRelativeL2) {
    // Mid-size blurs leak some texture into the estimate, and an
    // over-estimated floor biases towards small blur (large s); so a patch
    // uses min(own, median of its view): the view's median where texture
    // inflates the own estimate, the own one where the patch is genuinely
    // quieter (darker, under shot noise). Measured on the whole-core scene:
    // capping at twice the median instead left +1.2 % at noise 0.02, this
    // +0.7 %.
    const size_t channels = prepared[0].sigma_left.size();
    for (size_t v = 0; v < views.size(); ++v) {
      for (size_t c = 0; c < channels; ++c) {
        std::vector<double> s;
        for (int j = 0; j < num_patches; ++j) {
          if (patches[j].view == static_cast<int>(v) &&
              c < prepared[j].sigma_left.size()) {
            s.push_back(prepared[j].sigma_left[c]);
          }
        }
        if (s.empty()) continue;
        const double cap = UpperMedianInPlace(&s);
        for (int j = 0; j < num_patches; ++j) {
          if (patches[j].view == static_cast<int>(v) &&
              c < prepared[j].sigma_left.size()) {
            prepared[j].sigma_left[c] =
                std::min(prepared[j].sigma_left[c], cap);
            prepared[j].sigma_right[c] = prepared[j].sigma_left[c];
          }
        }
      }
    }
  }

  if (options.loss == IntensityLoss::kRelativeL2) {
    // Tighten each patch's noise estimate with the fit, as the blur
    // estimator does: the raw loss at every radius bounds sigma^2 from
    // above (it is signal misfit plus noise), and near the patch's true
    // radius the bound is the noise alone. The minimiser is sensitive to the
    // noise term (on the example scenes no correction moved s by -0.4 to
    // -2.3 %, half of it by -1 to +0.2 %); the pair estimate can read DP
    // disparity as noise, the bound cannot exceed what the data show.
#ifdef _OPENMP
#pragma omp parallel for num_threads(threads) schedule(dynamic)
#endif
    for (int j = 0; j < num_patches; ++j) {
      Prepared& p = prepared[j];
      // Radii: the patch's grid nodes (they span every radius its
      // candidates reach, where the minimum lies for a patch that fits),
      // or every 0.5 px of the supported range on the exact path.
      std::vector<double> radii;
      if (p.grid != nullptr) {
        for (const auto& entry : p.stats) {
          radii.push_back(p.grid->Radius(entry.first));
        }
      } else {
        const int half = static_cast<int>(std::floor(p.max_abs_radius / 0.5));
        for (int k = -half; k <= half; ++k) radii.push_back(0.5 * k);
      }
      for (const double radius : radii) {
        std::vector<ChannelTerms> terms;
        try {
          LossOfPrepared(p, radius, *p.psf, options.loss, &terms);
        } catch (...) {
#pragma omp atomic
          ++result.num_failed_evaluations;
          continue;
        }
        for (size_t c = 0; c < terms.size() && c < p.sigma_left.size(); ++c) {
          // acc = S + sigma^2 gain with S >= 0: an upper bound on sigma^2.
          if (!(terms[c].gain > 0)) continue;
          const double bound = terms[c].acc / terms[c].gain;
          if (bound >= 0 && bound < p.sigma_left[c] * p.sigma_left[c]) {
            p.sigma_left[c] = std::sqrt(bound);
            p.sigma_right[c] = p.sigma_left[c];
          }
        }
      }
    }
  }

  // Per-patch loss curves over a list of scales.
  if (options.loss == IntensityLoss::kRelativeL2) {
    // Fixed denominators at the initial scale: a denominator that shrinks
    // with the candidate's blur would favour small blur (large s).
#ifdef _OPENMP
#pragma omp parallel for num_threads(threads) schedule(dynamic)
#endif
    for (int j = 0; j < num_patches; ++j) {
      Prepared& p = prepared[j];
      const double r = PatchRadii(views[patches[j].view],
                                  patches[j].depth,
                                  {initial_scale},
                                  p.max_abs_radius)[0];
      std::vector<ChannelTerms> terms;
      try {
        LossOfPrepared(p, r, *p.psf, options.loss, &terms);
      } catch (...) {
#pragma omp atomic
        ++result.num_failed_evaluations;
        terms.clear();
      }
      p.reference_power.clear();
      p.channel_used.clear();
      for (const ChannelTerms& t : terms) {
        p.reference_power.push_back(t.power);
        // Signal power at least the noise power (SNR >= 1).
        p.channel_used.push_back(t.power > 2 * t.noise ? 1 : 0);
      }
    }
  }

  auto evaluate = [&](const std::vector<double>& scales) {
    std::vector<std::vector<double>> curves(num_patches,
                                            std::vector<double>(scales.size()));
#ifdef _OPENMP
#pragma omp parallel for num_threads(threads) schedule(dynamic)
#endif
    for (int j = 0; j < num_patches; ++j) {
      Prepared& p = prepared[j];
      // r_ij(s) from eq. (solution01) with s g_i' and s z'_ij.
      const std::vector<double> radii = PatchRadii(
          views[patches[j].view], patches[j].depth, scales, p.max_abs_radius);
      if (p.grid != nullptr) {
        try {
          AddIntervals(patches[j], IntervalsOf(*p.grid, radii), &p);
        } catch (...) {
          // Evaluated as unprepared below (contributes nothing).
#pragma omp atomic
          ++result.num_failed_evaluations;
        }
      }
      double last_radius = kInf, last_loss = 0;
      for (size_t k = 0; k < scales.size(); ++k) {
        const double r =
            std::max(-p.max_abs_radius, std::min(p.max_abs_radius, radii[k]));
        if (r != last_radius) {
          try {
            last_loss = LossOfPrepared(p, r, *p.psf, options.loss);
          } catch (...) {
            // An exception must not leave the parallel region; a patch
            // whose loss cannot be evaluated contributes nothing.
#pragma omp atomic
            ++result.num_failed_evaluations;
            last_loss = 0;
          }
          last_radius = r;
        }
        curves[j][k] = last_loss;
      }
    }
    result.num_evaluations += num_patches * static_cast<int>(scales.size());
    return curves;
  };

  // First pass: the paper's candidate set.
  std::vector<std::vector<double>> curves = evaluate(scales);
  // kRelativeL2: each patch's curve relative to its own minimum, through a
  // saturating function d / (d + c). A patch the model fits has a minimum
  // near 0 and a bowl around it; one it cannot fit (blur beyond the crops'
  // support, depth varying inside) has a high, sloping curve that would
  // otherwise pull the sum towards the range's edge. Saturation bounds what
  // any patch can contribute (a redescending M-estimator).
  std::vector<double> patch_minimum(num_patches, 0.0);
  const bool robust = options.loss == IntensityLoss::kRelativeL2;
  auto robustify = [&](std::vector<std::vector<double>>* c) {
    if (!robust) return;
    const double scale_c = options.robust_loss_scale;
    for (int j = 0; j < num_patches; ++j) {
      for (double& value : (*c)[j]) {
        const double d = std::max(0.0, value - patch_minimum[j]);
        value = d / (d + scale_c);
      }
    }
  };
  if (robust) {
    for (int j = 0; j < num_patches; ++j) {
      patch_minimum[j] = *std::min_element(curves[j].begin(), curves[j].end());
    }
    robustify(&curves);
  }
  std::vector<double> total(num, 0.0);
  for (const auto& curve : curves) {
    for (int k = 0; k < num; ++k) total[k] += curve[k];
  }
  const size_t coarse_best =
      std::min_element(total.begin(), total.end()) - total.begin();
  result.at_boundary =
      coarse_best == 0 || coarse_best + 1 == static_cast<size_t>(num);

  // Second pass between the neighbours of the first-pass minimum.
  if (options.num_refine_candidates > 0 && !result.at_boundary) {
    const double a = scales[coarse_best - 1];
    const double b = scales[coarse_best + 1];
    std::vector<double> fine;
    const int m = options.num_refine_candidates;
    for (int k = 1; k <= m; ++k) {
      const double s = a + (b - a) * k / (m + 1);
      if (std::abs(s - scales[coarse_best]) > 1e-12 * initial_scale) {
        fine.push_back(s);
      }
    }
    std::vector<std::vector<double>> fine_curves = evaluate(fine);
    robustify(&fine_curves);
    // Merge into one sorted grid.
    std::vector<std::pair<double, int>> order;  // (scale, column)
    for (int k = 0; k < num; ++k) order.emplace_back(scales[k], k);
    for (size_t k = 0; k < fine.size(); ++k) {
      order.emplace_back(fine[k], num + static_cast<int>(k));
    }
    std::sort(order.begin(), order.end());
    std::vector<double> merged_scales;
    std::vector<std::vector<double>> merged(num_patches);
    for (const auto& item : order) merged_scales.push_back(item.first);
    for (int j = 0; j < num_patches; ++j) {
      for (const auto& item : order) {
        merged[j].push_back(item.second < num
                                ? curves[j][item.second]
                                : fine_curves[j][item.second - num]);
      }
    }
    scales.swap(merged_scales);
    curves.swap(merged);
  }

  const size_t grid = scales.size();
  std::vector<double> sum(grid, 0.0);
  for (const auto& curve : curves) {
    for (size_t k = 0; k < grid; ++k) sum[k] += curve[k];
  }
  result.candidate_scales = scales;
  result.candidate_losses = sum;
  result.scale = CurveMinimum(scales, sum, nullptr);
  result.scale_ci_low = result.scale_ci_high = result.scale;

  // Bootstrap: views with replacement, then patches within each drawn view,
  // so patches that share a view (and its g_i' error) are not counted as
  // independent evidence.
  if (options.num_bootstrap > 0) {
    std::vector<std::vector<int>> by_view(views.size());
    for (int j = 0; j < num_patches; ++j) by_view[patches[j].view].push_back(j);
    std::vector<int> nonempty;
    for (size_t v = 0; v < by_view.size(); ++v) {
      if (!by_view[v].empty()) nonempty.push_back(static_cast<int>(v));
    }
    std::mt19937_64 rng(options.seed);
    std::uniform_int_distribution<size_t> pick_view(0, nonempty.size() - 1);
    std::vector<double> minima;
    std::vector<double> resampled(grid);
    int support = 0;
    for (int b = 0; b < options.num_bootstrap; ++b) {
      std::fill(resampled.begin(), resampled.end(), 0.0);
      for (size_t t = 0; t < nonempty.size(); ++t) {
        const std::vector<int>& members =
            by_view[nonempty[nonempty.size() == 1 ? 0 : pick_view(rng)]];
        std::uniform_int_distribution<size_t> pick(0, members.size() - 1);
        for (size_t q = 0; q < members.size(); ++q) {
          const std::vector<double>& curve = curves[members[pick(rng)]];
          for (size_t k = 0; k < grid; ++k) resampled[k] += curve[k];
        }
      }
      const double s = CurveMinimum(scales, resampled, nullptr);
      minima.push_back(s);
      if (std::abs(s - result.scale) <= step) ++support;
    }
    const double alpha = 0.5 * (1 - options.confidence_level);
    result.scale_ci_low = std::min(result.scale, Percentile(minima, alpha));
    result.scale_ci_high =
        std::max(result.scale, Percentile(minima, 1 - alpha));
    result.bootstrap_support =
        static_cast<double>(support) / options.num_bootstrap;
  }
  result.success = true;
  return result;
}

}  // namespace dpsfm
