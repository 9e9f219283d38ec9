#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "dpsfm/core/blur/blur_search_internal.h"
#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {
namespace {

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

using internal::BlurTables;

// The patch's interior and the kernel grid with its spectra for it. The
// grid's bound is max_radius_px rounded up to a multiple of the step, the
// border the reach of its kernels there. The coarse search transforms the
// whole windowed patch: its DFT size is >= the patch.
void SetGrid(const DPPsfModel& psf,
             const BlurEstimationOptions& options,
             const cv::Size& patch_size,
             int num_threads,
             BlurTables* t) {
  t->dft_size = cv::Size(cv::getOptimalDFTSize(patch_size.width),
                         cv::getOptimalDFTSize(patch_size.height));
  t->dft.emplace(t->dft_size);
  t->bound = DPKernelGridBound(options.max_radius_px, options.grid_step_px);
  t->border = psf.KernelRadius(t->bound);
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
  t->grid.reset(new DPKernelGrid(psf,
                                 options.grid_step_px,
                                 options.max_radius_px,
                                 t->interior.size(),
                                 num_threads));
  const DPKernelGrid& grid = *t->grid;
  DPSFM_CHECK(grid.Bound() == t->bound && grid.Border() == t->border);
  t->step = grid.Step();
  t->half_nodes = grid.HalfNodes();
  t->num_nodes = grid.NumNodes();
}

// Frequencies of the coarse band, on the half spectrum u = 0..nc/2.
// Returns each one's Hermitian multiplicity.
std::vector<float> SelectBand(BlurTables* t) {
  const int nr = t->dft_size.height;
  const int nc = t->dft_size.width;
  const double band = t->options.coarse_band;
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
  return multiplicity;
}

// The coarse search's nodes (every coarse_step_px through r = 0, and both
// ends).
void SelectCoarseNodes(BlurTables* t) {
  const BlurEstimationOptions& options = t->options;
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
}

// Per node the noise gains; per coarse node its row of the coarse table.
void TabulateKernels(const std::vector<float>& multiplicity,
                     int num_threads,
                     BlurTables* t) {
  const DPKernelGrid& grid = *t->grid;
  const int num_band = static_cast<int>(t->band_rows.size());
  t->coarse_table.resize(t->coarse_nodes.size(), 4 * num_band);

  t->noise_gain.resize(t->num_nodes);
  t->noise_cross.resize(t->num_nodes - 1);
  for (int n = 0; n < t->num_nodes; ++n) {
    t->noise_gain[n] = grid.LeftEnergy(n) + grid.RightEnergy(n);
    if (n + 1 < t->num_nodes) {
      t->noise_cross[n] = grid.LeftCross(n) + grid.RightCross(n);
    }
  }
  const RealDft& dft = *t->dft;
  const int rows = t->dft_size.height;
  ParallelFor(
      static_cast<int>(t->coarse_nodes.size()), num_threads, [&](int i) {
        const int n = t->coarse_nodes[i];
        cv::Mat hl, hr;
        dft.Forward(WrapKernel(grid.LeftKernel(n), t->dft_size), rows, &hl);
        dft.Forward(WrapKernel(grid.RightKernel(n), t->dft_size), rows, &hr);
        float* row = t->coarse_table.row(i).data();
        for (int k = 0; k < num_band; ++k) {
          const cv::Vec2f l =
              hl.at<cv::Vec2f>(t->band_rows[k], t->band_cols[k]);
          const cv::Vec2f r =
              hr.at<cv::Vec2f>(t->band_rows[k], t->band_cols[k]);
          const float w = multiplicity[k];
          row[4 * k + 0] = w * (r[0] * r[0] + r[1] * r[1]);
          row[4 * k + 1] = w * (l[0] * l[0] + l[1] * l[1]);
          // K = H_r conj(H_l).
          row[4 * k + 2] = w * (r[0] * l[0] + r[1] * l[1]);
          row[4 * k + 3] = w * (r[1] * l[0] - r[0] * l[1]);
        }
      });
}

// BlurTables::in_focus_distance: differences of the kernels embedded in one
// frame, in double.
void TabulateInFocusDistances(BlurTables* t) {
  const DPKernelGrid& grid = *t->grid;
  auto embedded = [&](const cv::Mat& kernel) {
    cv::Mat wide;
    EmbedKernel(kernel, t->border).convertTo(wide, CV_64F);
    return wide;
  };
  const int zero = t->half_nodes;
  const cv::Mat zero_left = embedded(grid.LeftKernel(zero));
  const cv::Mat zero_right = embedded(grid.RightKernel(zero));
  cv::Mat left = embedded(grid.LeftKernel(0));
  cv::Mat right = embedded(grid.RightKernel(0));
  t->in_focus_distance.resize(t->num_nodes - 1);
  for (int n = 0; n + 1 < t->num_nodes; ++n) {
    const cv::Mat next_left = embedded(grid.LeftKernel(n + 1));
    const cv::Mat next_right = embedded(grid.RightKernel(n + 1));
    const cv::Mat dl = left - zero_left, dr = right - zero_right;
    const cv::Mat sl = next_left - left, sr = next_right - right;
    t->in_focus_distance[n] = {dl.dot(dl) + dr.dot(dr),
                               dl.dot(sl) + dr.dot(sr),
                               sl.dot(sl) + sr.dot(sr)};
    left = next_left;
    right = next_right;
  }
}

// The coarse loss's noise gains, window and normaliser.
void SetCoarseNormalisation(BlurTables* t) {
  const int nr = t->dft_size.height;
  const int nc = t->dft_size.width;
  const int num_band = static_cast<int>(t->band_rows.size());
  t->coarse_noise_gain.resize(t->coarse_nodes.size());
  for (size_t i = 0; i < t->coarse_nodes.size(); ++i) {
    double gain = 0;
    for (int k = 0; k < num_band; ++k) {
      gain += t->coarse_table(i, 4 * k) + t->coarse_table(i, 4 * k + 1);
    }
    t->coarse_noise_gain[i] = gain / (static_cast<double>(nr) * nc);
  }
  t->window_x = TukeyWindow(t->patch_size.width, t->border);
  t->window_y = TukeyWindow(t->patch_size.height, t->border);
  double sum_x = 0, sum_y = 0;
  for (const float w : t->window_x) sum_x += w * w;
  for (const float w : t->window_y) sum_y += w * w;
  t->coarse_normaliser = 1.0 / (static_cast<double>(nr) * nc * sum_x * sum_y);
}

}  // namespace

namespace internal {

std::unique_ptr<BlurTables> MakeBlurTables(const DPPsfModel& psf,
                                           const BlurEstimationOptions& options,
                                           const cv::Size& patch_size,
                                           int num_threads) {
  std::unique_ptr<BlurTables> t(new BlurTables);
  t->options = options;
  t->patch_size = patch_size;
  SetGrid(psf, options, patch_size, num_threads, t.get());
  const std::vector<float> multiplicity = SelectBand(t.get());
  SelectCoarseNodes(t.get());
  TabulateKernels(multiplicity, num_threads, t.get());
  SetCoarseNormalisation(t.get());
  TabulateInFocusDistances(t.get());
  return t;
}

}  // namespace internal

PatchBlurEstimator::PatchBlurEstimator(const DPPsfModel& psf,
                                       const BlurEstimationOptions& options,
                                       const cv::Size& patch_size,
                                       int num_threads) {
  DPSFM_CHECK_OPTIONS(options, "BlurEstimationOptions");
  tables_ = internal::MakeBlurTables(psf, options, patch_size, num_threads);
}

PatchBlurEstimator::~PatchBlurEstimator() = default;

int PatchBlurEstimator::Border() const { return tables_->border; }
const cv::Size& PatchBlurEstimator::PatchSize() const {
  return tables_->patch_size;
}
const BlurEstimationOptions& PatchBlurEstimator::Options() const {
  return tables_->options;
}

}  // namespace dpsfm
