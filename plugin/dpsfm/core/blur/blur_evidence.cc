// The evidence of a patch's loss curve: whether its minimum is one the data
// determine, how precisely, or whether the blur lies beyond the bound.
//
// The residual at radius r is e(r) = G_l * h_r(r) - G_r * h_l(r) over the
// interior's M pixels, and the corrected loss Lc(r) = |e(r)|^2 / M -
// sigma^2 a(r). With white noise n_l, n_r of variance sigma^2 in the views,
// the noise part of e(r0) is n_l * h_r - n_r * h_l, so for any field D on
// the interior <e(r0), D> carries noise of variance
//
//   sigma^2 (|D (x) h_r|^2 + |D (x) h_l|^2)           (x: correlation)
//
// (its energy through the kernels' transposes). The rise of the loss from
// the minimum r0 to a node r1, with D = e(r1) - e(r0), is |D|^2 / M +
// 2 <e(r0), D> / M, so its noise standard deviation is
//
//   sd = 2 / M sqrt(sigma^2 (|D (x) h_r|^2 + |D (x) h_l|^2))
//
// and z = rise / sd says how far the rise stands above what noise gives.
// Linearising e around r0 (d = D / delta, delta = |r1 - r0|), the minimum's
// standard error is sqrt(var <e, d>) / |d|^2 with |D|^2 = M rise, which is
// delta / (2 z): the same two numbers. Where the residual at the minimum
// exceeds the noise floor (a patch the model fits imperfectly) the excess
// is counted as noise too: sigma^2 is raised to L(r0) / a(r0).
//
// A minimum inside the bound is measured when the rise on each side (the
// best of 1, 2 and 4 px away), to the same blur on the other side of focus
// and towards the other sign's best coarse node reach min_evidence_z; its
// standard error is that of the two sides' local curvatures together
// (1 / se^2 averaged over them), each from its nearest rise (1 px away).
// A minimum at the bound is beyond it when the rise from the bound inwards
// reaches min_evidence_z.
// Everything else is undetermined.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/blur/blur_search_internal.h"

namespace dpsfm {
namespace internal {
namespace {

using Minimum = BlurRefinement::Minimum;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::array<double, 3> kEvidenceOffsetsPx = {1, 2, 4};

// |D (x) h|^2 for a field D on the interior (zero outside it): the energy of
// D through the kernel's transpose, whole (the padding holds every output
// pixel the kernel reaches).
double EnergyThroughKernel(const cv::Mat& field, const cv::Mat& kernel) {
  const int py = kernel.rows / 2, px = kernel.cols / 2;
  cv::Mat padded;
  cv::copyMakeBorder(
      field, padded, py, py, px, px, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::Mat out;
  cv::filter2D(
      padded, out, CV_32F, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
  return cv::norm(out, cv::NORM_L2SQR);
}

// The loss curve around one minimum: the residual there and its noise.
class EvidenceCurve {
 public:
  EvidenceCurve(const BlurTables& t,
                double sigma2,
                const Minimum& best,
                BlurRefinement* refinement)
      : t_(t), sigma2_(sigma2), best_(best), refinement_(refinement) {
    const double pos = best.radius / t.step + t.half_nodes;
    int n0 = std::max(0, std::min(t.num_nodes - 2, static_cast<int>(pos)));
    double s = std::max(0.0, std::min(1.0, pos - n0));
    refinement->Evaluate(n0);
    refinement->Evaluate(n0 + 1);
    const std::vector<float>& e0 = refinement->Residual(n0);
    const std::vector<float>& e1 = refinement->Residual(n0 + 1);
    residual_.resize(e0.size());
    for (size_t i = 0; i < e0.size(); ++i) {
      residual_[i] = static_cast<float>((1 - s) * e0[i] + s * e1[i]);
    }
    const double gain = (1 - s) * (1 - s) * t.noise_gain[n0] +
                        2 * s * (1 - s) * t.noise_cross[n0] +
                        s * s * t.noise_gain[n0 + 1];
    noise2_ = gain > 0 ? std::max(sigma2, best.raw / gain) : sigma2;
    kernel_node_ = refinement->NearestNode(best.radius);
  }

  // The rise to node n and its significance: z and the standard error it
  // implies (delta / 2 z).
  struct Rise {
    double z = 0;
    double se = kInf;
  };
  Rise RiseTo(int n) {
    refinement_->Evaluate(n);
    const double delta = std::abs(t_.Radius(n) - best_.radius);
    const double rise =
        refinement_->RawLoss(n) - sigma2_ * t_.noise_gain[n] - best_.corrected;
    const std::vector<float>& e = refinement_->Residual(n);
    cv::Mat field(t_.interior.height, t_.interior.width, CV_32FC1);
    float* out = field.ptr<float>(0);
    for (size_t i = 0; i < e.size(); ++i) out[i] = e[i] - residual_[i];
    const double energy =
        EnergyThroughKernel(field, t_.grid->LeftKernel(kernel_node_)) +
        EnergyThroughKernel(field, t_.grid->RightKernel(kernel_node_));
    const double sd = 2.0 / t_.num_interior * std::sqrt(noise2_ * energy);
    Rise r;
    if (!(rise > 0)) return r;
    r.z = sd > 0 ? rise / sd : kInf;
    r.se = delta / (2 * r.z);
    return r;
  }

  // One side (-1, +1) of the minimum, 1, 2 and 4 px away among the nodes
  // inside the grid: the most significant rise, and the standard error from
  // the nearest (the curve's local curvature; farther nodes leave the
  // quadratic, as a blur near focus does when the offset crosses it).
  struct SideRise {
    double z = 0;
    double se = kInf;
  };
  SideRise Side(int side) {
    SideRise out;
    int last = -1;
    for (const double offset : kEvidenceOffsetsPx) {
      const int n = std::max(
          0,
          std::min(t_.num_nodes - 1,
                   static_cast<int>(
                       std::lround((best_.radius + side * offset) / t_.step)) +
                       t_.half_nodes));
      if (n == last || side * (t_.Radius(n) - best_.radius) < 0.999 * t_.step) {
        continue;
      }
      const Rise r = RiseTo(n);
      if (last < 0) out.se = r.se;
      last = n;
      out.z = std::max(out.z, r.z);
    }
    return out;
  }

 private:
  const BlurTables& t_;
  const double sigma2_;
  const Minimum& best_;
  BlurRefinement* refinement_;
  std::vector<float> residual_;  // e at the minimum
  double noise2_ = 0;            // sigma^2, raised to the residual's level
  int kernel_node_ = 0;
};

}  // namespace

void WeighBlurEvidence(const BlurTables& t,
                       double sigma2,
                       const Minimum& best,
                       int opposite_node,
                       BlurRefinement* refinement,
                       PatchBlurEstimate* result) {
  const double z_min = t.options.min_evidence_z;
  EvidenceCurve curve(t, sigma2, best, refinement);
  result->radius_se_px = kInf;
  if (result->at_bound) {
    const int inward = best.radius > 0 ? -1 : 1;
    result->evidence_z = curve.Side(inward).z;
    result->evidence = result->evidence_z >= z_min
                           ? BlurEvidence::kBeyondBound
                           : BlurEvidence::kUndetermined;
    return;
  }
  const EvidenceCurve::SideRise lower = curve.Side(-1);
  const EvidenceCurve::SideRise upper = curve.Side(1);
  double z = std::min(lower.z, upper.z);
  // The sign: the same blur on the other side of focus (the kernels' mirror
  // image), and the other sign's best coarse node where that lies farther.
  const int mirror = refinement->NearestNode(-best.radius);
  if (std::abs(t.Radius(mirror) - best.radius) >= 0.999 * t.step) {
    z = std::min(z, curve.RiseTo(mirror).z);
  }
  if (opposite_node >= 0 && std::abs(t.Radius(opposite_node) - best.radius) >
                                kEvidenceOffsetsPx.back()) {
    z = std::min(z, curve.RiseTo(opposite_node).z);
  }
  result->evidence_z = z;
  if (z >= z_min) {
    result->evidence = BlurEvidence::kMeasured;
    // The curvature of both sides: 1 / se^2 is proportional to it.
    result->radius_se_px =
        std::sqrt(2 / (1 / (lower.se * lower.se) + 1 / (upper.se * upper.se)));
  } else {
    result->evidence = BlurEvidence::kUndetermined;
  }
}

}  // namespace internal
}  // namespace dpsfm
