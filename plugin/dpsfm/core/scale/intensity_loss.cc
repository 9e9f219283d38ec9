#include "dpsfm/core/scale/intensity_loss.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/lanes.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace intensity {
namespace {

cv::Mat ToFloat(const cv::Mat& image) {
  if (image.depth() == CV_32F) return image;
  cv::Mat out;
  const double scale = image.depth() == CV_16U  ? 1.0 / 65535.0
                       : image.depth() == CV_8U ? 1.0 / 255.0
                                                : 1.0;
  image.convertTo(out, CV_MAKETYPE(CV_32F, image.channels()), scale);
  return out;
}

double SumSquares(const cv::Mat& kernel) { return kernel.dot(kernel); }

// Sum of a continuous CV_32FC1 image accumulated in double.
double SumD(const cv::Mat& a) {
  const float* p = a.ptr<float>();
  // cv::Mat::total is not inline: called in the loop's condition, it kept
  // the sum in memory across the call (a third of AddIntervals' own time).
  const size_t count = a.total();
  double sum = 0;
  for (size_t i = 0; i < count; ++i) sum += p[i];
  return sum;
}

// Sums and inner products of a node's blurred mean-removed views a, b and,
// when given (non-empty), with the previous node's pa, pb: one pass over
// continuous CV_32FC1 images, accumulated in double. cv::Mat::dot adds
// floats in blocks, whose 1e-6 relative error the cancellation in the loss
// amplified to percents of it; nine separate passes cost three times one.
struct NodeMoments {
  double sum_a = 0, sum_b = 0, aa = 0, bb = 0, ab = 0;
  double pa_a = 0, pb_b = 0, pa_b = 0, pb_a = 0;  // with the previous node
};

// MomentsOf on count values of x, y, px, py (px, py taken against x, y
// and dropped when !previous), in lanes (core/util/lanes.h): 5.5 us a
// 33 x 33 interior in one chain per sum, 1.2 us in lanes with AVX2 and 2.4
// us on the baseline.
DPSFM_VECTOR_CLONES NodeMoments MomentsOfValues(const float* x,
                                                const float* y,
                                                const float* px,
                                                const float* py,
                                                size_t count,
                                                bool previous) {
  Lanes sum_a{}, sum_b{}, aa{}, bb{}, ab{}, pa_a{}, pb_b{}, pa_b{}, pb_a{};
  size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    Lanes u, v, pu, pv;
    LoadLanes(x + i, &u);
    LoadLanes(y + i, &v);
    LoadLanes(px + i, &pu);
    LoadLanes(py + i, &pv);
    sum_a += u;
    sum_b += v;
    aa += u * u;
    bb += v * v;
    ab += u * v;
    pa_a += pu * u;
    pb_b += pv * v;
    pa_b += pu * v;
    pb_a += pv * u;
  }
  for (; i < count; ++i) {
    const double u = x[i], v = y[i], pu = px[i], pv = py[i];
    sum_a[0] += u;
    sum_b[0] += v;
    aa[0] += u * u;
    bb[0] += v * v;
    ab[0] += u * v;
    pa_a[0] += pu * u;
    pb_b[0] += pv * v;
    pa_b[0] += pu * v;
    pb_a[0] += pv * u;
  }
  NodeMoments m;
  m.sum_a = LanesTotal(sum_a);
  m.sum_b = LanesTotal(sum_b);
  m.aa = LanesTotal(aa);
  m.bb = LanesTotal(bb);
  m.ab = LanesTotal(ab);
  if (previous) {
    m.pa_a = LanesTotal(pa_a);
    m.pb_b = LanesTotal(pb_b);
    m.pa_b = LanesTotal(pa_b);
    m.pb_a = LanesTotal(pb_a);
  }
  return m;
}

NodeMoments MomentsOf(const cv::Mat& a,
                      const cv::Mat& b,
                      const cv::Mat& pa,
                      const cv::Mat& pb) {
  // Without a previous node the terms with it are taken against the node
  // itself and dropped.
  const bool previous = !pa.empty();
  return MomentsOfValues(a.ptr<float>(),
                         b.ptr<float>(),
                         previous ? pa.ptr<float>() : a.ptr<float>(),
                         previous ? pb.ptr<float>() : b.ptr<float>(),
                         a.total(),
                         previous);
}

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

}  // namespace

// Largest |r| whose kernels fit inside `border` (and <= max_radius_px).
double MaxSupportedRadius(const DPPsfModel& psf,
                          int border,
                          double max_radius_px) {
  double r = std::min(max_radius_px, border + 0.5);
  while (r > 0 && psf.KernelRadius(r) > border) r -= 0.05;
  return std::max(r, 0.0);
}

double LossOfPrepared(const Prepared& p,
                      double radius_px,
                      const DPPsfModel& psf,
                      IntensityLoss loss,
                      std::vector<ChannelTerms>* terms) {
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
// from the patch's crops: per spectrum class of the nodes (kernel_grid.h)
// and channel one forward DFT of each view, then per node one product and
// inverse DFT per view (only the interior is kept).
//
// The loss is a small difference of these statistics (a patch's misfit
// against its mean), so they are taken with the views' means removed: a
// constant mu convolved with a kernel of sum s is mu s on the interior, so
// A = mu_l s_r + a with a = (G_l - mu_l) * H_r, and every sum and inner
// product of A and B follows in closed form from those of a and b, which
// the float transforms give to their own precision rather than to that of
// the mean.
namespace {

// The statistics of a node that do not involve the next one.
void CopyOwnStats(const NodeChannelStats& from, NodeChannelStats* to) {
  to->sum_a = from.sum_a;
  to->sum_b = from.sum_b;
  to->aa = from.aa;
  to->bb = from.bb;
  to->ab = from.ab;
}

void CopyNextStats(const NodeChannelStats& from, NodeChannelStats* to) {
  to->aa_next = from.aa_next;
  to->bb_next = from.bb_next;
  to->ab_next = from.ab_next;
  to->ba_next = from.ba_next;
}

// Which of the (sorted) nodes must be computed from the crops: those the
// cache lacks, and both ends of a pair of consecutive nodes whose cross
// terms it lacks. All of them without a cache.
std::vector<char> NodesToCompute(const std::vector<int>& nodes,
                                 const CachedCrop* cached) {
  std::vector<char> compute(nodes.size(), 1);
  if (cached == nullptr) return compute;
  auto pair_cached = [&](int n) {
    const auto it = cached->nodes.find(n);
    return it != cached->nodes.end() && it->second.has_next;
  };
  for (size_t i = 0; i < nodes.size(); ++i) {
    const int n = nodes[i];
    bool known = cached->nodes.count(n) > 0;
    if (i + 1 < nodes.size() && nodes[i + 1] == n + 1) {
      known = known && pair_cached(n);
    }
    if (i > 0 && nodes[i - 1] == n - 1) known = known && pair_cached(n - 1);
    compute[i] = !known;
  }
  return compute;
}

// The nodes an AddIntervals call added, into the crop's cache record (a
// node's own statistics are the same however often computed; cross terms
// are added where the record lacks them).
void CacheNodes(const std::vector<int>& nodes,
                const Prepared& p,
                CachedCrop* cached) {
  for (const int n : nodes) {
    const Prepared::NodeEntry& entry = p.stats.at(n);
    const auto it = cached->nodes.find(n);
    if (it == cached->nodes.end() || (entry.has_next && !it->second.has_next)) {
      cached->nodes[n] = entry;
    }
  }
}

// The nodes of the intervals whose statistics, or cross terms with the
// next node, p lacks (both ends of each such interval), sorted.
std::vector<int> NodesToAdd(const std::vector<int>& intervals,
                            const Prepared& p) {
  std::vector<int> nodes;
  for (const int n : intervals) {
    const auto it = p.stats.find(n);
    if (it == p.stats.end() || !it->second.has_next) {
      nodes.push_back(n);
      nodes.push_back(n + 1);
    }
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

// A view blurred at a node: the mean-removed part on the interior, its
// sum, and the constant the mean contributes.
struct BlurredView {
  cv::Mat image;
  double sum = 0, constant = 0;
};

// The arithmetic of the nodes' statistics from a patch's crops (the
// cross-blurred views A = G_l * H_r(r_n), B = G_r * H_l(r_n) by the grid's
// spectra): the channels mean-removed once (the means come back as
// constants), their spectra per class when a node first needs them, and
// the last node's blurred views for the cross terms with the next.
class NodeStatistics {
 public:
  NodeStatistics(const IntensityPatch& patch, const Prepared& p)
      : grid_(*p.grid),
        border_(p.border),
        count_(p.num_interior),
        spec_left_(grid_.NumSpectrumClasses()),
        spec_right_(grid_.NumSpectrumClasses()) {
    cv::split(ToFloat(patch.left), left_);
    cv::split(ToFloat(patch.right), right_);
    for (size_t c = 0; c < left_.size(); ++c) {
      mean_left_.push_back(SumD(left_[c]) / left_[c].total());
      mean_right_.push_back(SumD(right_[c]) / right_[c].total());
      left_[c] -= mean_left_[c];
      right_[c] -= mean_right_[c];
    }
    previous_a_.resize(left_.size());
    previous_b_.resize(left_.size());
  }

  int Channels() const { return static_cast<int>(left_.size()); }

  // Node n's own statistics into *entry and, when `before` is given (node
  // n - 1, computed by the previous call), the cross terms with it.
  void Compute(int n, Prepared::NodeEntry* entry, Prepared::NodeEntry* before) {
    const int k = grid_.SpectrumClassOf(n);
    Transform(k);
    for (int c = 0; c < Channels(); ++c) {
      BlurredView a, b;
      a.image = Blurred(spec_left_[k][c], grid_.RightSpectrum(n), k);
      b.image = Blurred(spec_right_[k][c], grid_.LeftSpectrum(n), k);
      const NodeMoments m =
          MomentsOf(a.image,
                    b.image,
                    before != nullptr ? previous_a_[c].image : cv::Mat(),
                    before != nullptr ? previous_b_[c].image : cv::Mat());
      a.sum = m.sum_a;
      b.sum = m.sum_b;
      a.constant = mean_left_[c] * grid_.RightSum(n);
      b.constant = mean_right_[c] * grid_.LeftSum(n);
      NodeChannelStats& s = entry->channel[c];
      s.sum_a = a.sum + count_ * a.constant;
      s.sum_b = b.sum + count_ * b.constant;
      s.aa = Inner(m.aa, a, a);
      s.bb = Inner(m.bb, b, b);
      s.ab = Inner(m.ab, a, b);
      if (before != nullptr) {
        NodeChannelStats& prev = before->channel[c];
        prev.aa_next = Inner(m.pa_a, previous_a_[c], a);
        prev.bb_next = Inner(m.pb_b, previous_b_[c], b);
        prev.ab_next = Inner(m.pa_b, previous_a_[c], b);
        prev.ba_next = Inner(m.pb_a, previous_b_[c], a);
      }
      previous_a_[c] = a;
      previous_b_[c] = b;
    }
    if (before != nullptr) before->has_next = true;
  }

 private:
  // The views' spectra of class k, per channel.
  void Transform(int k) {
    if (!spec_left_[k].empty()) return;
    for (int c = 0; c < Channels(); ++c) {
      spec_left_[k].push_back(grid_.TransformInput(left_[c], border_, k));
      spec_right_[k].push_back(grid_.TransformInput(right_[c], border_, k));
    }
  }
  // The interior of a view's spectrum times a kernel's, back in space.
  cv::Mat Blurred(const cv::Mat& view_spectrum,
                  const cv::Mat& kernel_spectrum,
                  int k) {
    SpectraProduct(view_spectrum, kernel_spectrum, &product_);
    return grid_.InteriorOfInverse(k, &product_, &image_).clone();
  }
  // <x + cx, y + cy> from <x, y> = xy, the sums of x and y and the
  // constants.
  double Inner(double xy, const BlurredView& x, const BlurredView& y) const {
    return xy + x.constant * y.sum + y.constant * x.sum +
           count_ * x.constant * y.constant;
  }

  const DPKernelGrid& grid_;
  const int border_;
  const double count_;
  std::vector<cv::Mat> left_, right_;  // mean removed
  std::vector<double> mean_left_, mean_right_;
  std::vector<std::vector<cv::Mat>> spec_left_, spec_right_;  // per class
  std::vector<BlurredView> previous_a_, previous_b_;
  cv::Mat product_, image_;
};

}  // namespace

void AddIntervals(const IntensityPatch& patch,
                  const std::vector<int>& intervals,
                  Prepared* p) {
  const std::vector<int> nodes = NodesToAdd(intervals, *p);
  if (nodes.empty()) return;
  CachedCrop* cached = p->cached;
  const std::vector<char> compute = NodesToCompute(nodes, cached);
  std::unique_ptr<NodeStatistics> statistics;
  if (std::find(compute.begin(), compute.end(), 1) != compute.end()) {
    statistics.reset(new NodeStatistics(patch, *p));
  }
  const int channels = statistics ? statistics->Channels() : p->channels;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const int n = nodes[i];
    Prepared::NodeEntry& entry = p->stats[n];
    // A node computed again (the first node of an interval below one
    // prepared before) keeps its terms with the next node: they are the
    // same, and the next node is not computed again.
    entry.channel.resize(channels);
    const bool after_previous = i > 0 && nodes[i - 1] == n - 1;
    Prepared::NodeEntry* before = after_previous ? &p->stats[n - 1] : nullptr;
    // The cross terms with the previous node from the cache unless both
    // nodes are computed here.
    const bool cached_pair =
        before != nullptr && !(compute[i] && compute[i - 1]);
    if (cached_pair) {
      const Prepared::NodeEntry& from = cached->nodes.at(n - 1);
      for (int c = 0; c < channels; ++c) {
        CopyNextStats(from.channel[c], &before->channel[c]);
      }
      before->has_next = true;
    }
    if (!compute[i]) {
      const Prepared::NodeEntry& from = cached->nodes.at(n);
      for (int c = 0; c < channels; ++c) {
        CopyOwnStats(from.channel[c], &entry.channel[c]);
      }
      ++cached->reused;
      continue;
    }
    if (cached != nullptr) ++cached->computed;
    statistics->Compute(n, &entry, cached_pair ? nullptr : before);
  }
  if (cached != nullptr) CacheNodes(nodes, *p, cached);
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

}  // namespace intensity

std::vector<double> EstimateChannelNoiseSigma(const cv::Mat& image) {
  const cv::Mat f = intensity::ToFloat(image);
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
    std::vector<float> values(inner.total());
    float* out = values.data();
    for (int y = 0; y < inner.rows; ++y, out += inner.cols) {
      const float* row = inner.ptr<float>(y);
      for (int x = 0; x < inner.cols; ++x) out[x] = std::abs(row[x]);
    }
    sigmas.push_back(
        SigmaFromMedianAbsolute(UpperMedianBySelection(&values), 6.0));
  }
  return sigmas;
}

std::vector<double> EstimatePairNoiseSigma(const cv::Mat& left,
                                           const cv::Mat& right) {
  const cv::Mat l = intensity::ToFloat(left), r = intensity::ToFloat(right);
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
  intensity::Prepared p = intensity::Prepare(patch, psf, max_radius_px);
  p.sigma_left = noise_sigma_left;
  p.sigma_right = noise_sigma_right;
  return intensity::LossOfPrepared(p, radius_px, psf, loss);
}

}  // namespace dpsfm
