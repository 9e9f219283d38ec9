// The blur search's internals (PatchBlurEstimator, blur_estimation.h),
// shared by its source files: the tables that depend only on (psf,
// options, patch size) (blur_tables.cc), the coarse global search in the
// frequency domain (blur_coarse_search.cc) and the exact refinement
// (blur_refinement.cc), which PatchBlurEstimator::Estimate
// (blur_estimation.cc) runs in turn. Not part of the API.
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/optics/real_dft.h"

namespace dpsfm {
namespace internal {

// Everything that depends only on (psf, options, patch size).
struct BlurTables {
  BlurEstimationOptions options;
  cv::Size patch_size;
  cv::Size dft_size;
  std::optional<RealDft> dft;  // the coarse search's transforms, of dft_size
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
  // Per interval n (nodes n, n + 1), how far its interpolated kernels lie
  // from those at r = 0, summed over both views: |(1 - s) h(n) + s h(n+1) -
  // h(0)|^2 = c0 + 2 s c1 + s^2 c2 with (c0, c1, c2) = in_focus_distance[n]
  // (the blur search's preference for focus).
  std::vector<std::array<double, 3>> in_focus_distance;

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

// The tables of (psf, options, patch size), on num_threads threads.
std::unique_ptr<BlurTables> MakeBlurTables(const DPPsfModel& psf,
                                           const BlurEstimationOptions& options,
                                           const cv::Size& patch_size,
                                           int num_threads);

// The coarse global search's curve (windowed, frequency domain): the
// corrected loss per coarse node, and its local minima, best first (ties
// prefer small |r|: blurs inside the in-focus threshold are
// indistinguishable).
struct CoarseCurve {
  std::vector<double> loss;
  std::vector<int> minima;  // indices into loss
  double min = 0, max = 0;
};

// What the coarse search needs of the gain-equalised views, whatever the
// PSF: per band frequency of their windowed spectra G_l, G_r, the four
// terms (|G_l|^2, |G_r|^2, -2 Re D, 2 Im D), D = G_l conj(G_r), that the
// coarse table's rows weigh.
std::vector<float> CoarseBandTerms(const BlurTables& t,
                                   const cv::Mat& gl,
                                   const cv::Mat& gr);

// The coarse global search on the views' band terms.
CoarseCurve CoarseSearch(const BlurTables& t,
                         const std::vector<float>& band_terms,
                         double sigma2_hp);

// The exact refinement (spatial valid-region loss via inverse FFT) of one
// patch: the views' spectra, the loss at the grid nodes evaluated so far,
// the noise floor, the closed-form minimum inside grid intervals, the walk
// downhill from a coarse node, and the second-stage gain equalisation.
class BlurRefinement {
 public:
  struct Minimum {
    double radius = 0;
    double corrected = std::numeric_limits<double>::infinity();
    double raw = std::numeric_limits<double>::infinity();
    int lo = 0, hi = 0;  // evaluated node range
  };

  // gl, gr: the gain-equalised views minus `offset`; integral_left,
  // integral_right: their PositiveIntegral, when the caller has them (a
  // prepared patch searched under many profiles), else empty.
  BlurRefinement(const BlurTables& t,
                 const cv::Mat& gl,
                 const cv::Mat& gr,
                 double offset,
                 double sigma2_hp,
                 const cv::Mat& integral_left = cv::Mat(),
                 const cv::Mat& integral_right = cv::Mat());

  // The integral image (CV_64F) of view + offset, which EqualiseGain
  // integrates until it first moves the gains.
  static cv::Mat PositiveIntegral(const cv::Mat& view, double offset);

  const cv::Mat& Left() const { return gl_; }
  const cv::Mat& Right() const { return gr_; }

  // Residual G_l * H_r - G_r * H_l at node n (once per node).
  void Evaluate(int n);

  double RawLoss(int n) const { return evals_[n].energy * inv_m_; }
  // The residual at an evaluated node n, row by row over the interior.
  const std::vector<float>& Residual(int n) const { return evals_[n].residual; }

  // Noise variance: the patch estimate, tightened by the fit: E[L(r)] =
  // S(r) + sigma^2 a(r) with S >= 0, so every L(r) / a(r) bounds sigma^2
  // from above (up to noise).
  double CurrentSigma2() const;

  // Minimum of the corrected loss over the evaluated nodes [lo, hi] with
  // linearly interpolated kernels inside each interval.
  Minimum Minimise(int lo, int hi, double sigma2) const;

  // Walks downhill from a coarse node until the minimum is enclosed.
  Minimum Refine(int start);

  int NearestNode(double radius) const;

  // Gain, second stage. The whole-patch means of the two views differ not
  // only by gain but also because the views are shifted against each other
  // (by ~0.6 r), which the first estimate mistook for gain; at r = 15 that
  // alone moves the estimate by ~0.2 px. The right comparison is the
  // interior means of the two blurred cross views at the blur, which agree
  // exactly for equal gains. The views are transformed again at the next
  // evaluation; evaluations made before stay (the caller resets them when
  // the gain moved the estimate).
  void EqualiseGain(double radius);

  void ResetEvaluations() { evals_.assign(t_.num_nodes, NodeEval()); }

 private:
  struct NodeEval {
    bool done = false;
    std::vector<float> residual;
    double energy = 0;  // |e|^2
    // <e(n), e(n+1)>, once both are known.
    double next_dot = std::numeric_limits<double>::infinity();
  };

  // The views' spectra for one class of the kernel grid's nodes, when an
  // evaluation needs them: the search equalises the gain before its first
  // evaluation, so transforming in the constructor would be wasted, and a
  // search evaluates nodes of one or two classes.
  struct ViewSpectra {
    bool fresh = false;  // of gl_, gr_ as they are
    cv::Mat left, right;
  };
  const ViewSpectra& TransformedViews(int c);
  void MakePositiveViews();

  const BlurTables& t_;
  const BlurEstimationOptions& options_;
  cv::Mat gl_, gr_;
  // The views + offset, which the gains scale: made when first needed (a
  // search whose integrals are given and whose gains never move does not
  // need them).
  cv::Mat left_positive_, right_positive_;
  // PositiveIntegral of the views as given (empty: not given), valid until
  // the gains move.
  cv::Mat given_integral_left_, given_integral_right_;
  bool gains_moved_ = false;
  const double offset_;
  const double sigma2_hp_;
  const double inv_m_;
  std::vector<ViewSpectra> spectra_;  // per spectrum class of the grid
  std::vector<NodeEval> evals_;
  cv::Mat product_, residual_image_;
};

// The evidence of a patch's loss curve (blur_evidence.cc): sets
// result->evidence, radius_se_px and evidence_z from the exact loss around
// `best` (evaluating the nodes it needs), with `opposite_node` the coarse
// search's best node on the other sign of best.radius (-1: none).
void WeighBlurEvidence(const BlurTables& t,
                       double sigma2,
                       const BlurRefinement::Minimum& best,
                       int opposite_node,
                       BlurRefinement* refinement,
                       PatchBlurEstimate* result);

}  // namespace internal
}  // namespace dpsfm
