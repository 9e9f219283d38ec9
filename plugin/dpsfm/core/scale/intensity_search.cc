#include "dpsfm/core/scale/intensity_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <tuple>
#include <utility>

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/scale/intensity_loss.h"
#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/curve_math.h"
#include "dpsfm/core/util/matrices.h"
#include "dpsfm/core/util/statistics.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {

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

bool IntensitySearchOptions::Check(std::string* failure) const {
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

namespace {

// Two grids of the same kernels, step and interior give the same spectra
// and statistics.
bool SameKernels(const DPKernelGrid& a, const DPKernelGrid& b) {
  if (a.NumNodes() != b.NumNodes() || a.Step() != b.Step() ||
      a.NumSpectrumClasses() != b.NumSpectrumClasses()) {
    return false;
  }
  for (int c = 0; c < a.NumSpectrumClasses(); ++c) {
    if (a.SpectrumClassAt(c).dft_size != b.SpectrumClassAt(c).dft_size ||
        a.InteriorOf(c) != b.InteriorOf(c)) {
      return false;
    }
  }
  for (int n = 0; n < a.NumNodes(); ++n) {
    if (!SameBytes(a.LeftKernel(n), b.LeftKernel(n)) ||
        !SameBytes(a.RightKernel(n), b.RightKernel(n))) {
      return false;
    }
  }
  return true;
}

}  // namespace

const DPKernelGrid* IntensityStatsCache::Impl::Share(
    std::unique_ptr<DPKernelGrid>* grid) {
  for (const auto& held : grids) {
    if (SameKernels(*held, **grid)) {
      grid->reset();
      return held.get();
    }
  }
  grids.push_back(std::move(*grid));
  return grids.back().get();
}

intensity::CachedCrop* IntensityStatsCache::Impl::Crop(
    const cv::Mat& left,
    const cv::Mat& right,
    int border,
    const DPKernelGrid* grid) {
  bool added = false;
  intensity::CachedCrop* record = crops.Find(
      left,
      right,
      [&](const intensity::CachedCrop& held) {
        return held.border == border && held.grid == grid;
      },
      &added);
  if (added) {
    record->border = border;
    record->grid = grid;
  }
  return record;
}

void IntensityStatsCache::Impl::KeepOnlyUsed(
    const std::vector<const DPKernelGrid*>& used_grids,
    const std::vector<intensity::CachedCrop*>& used_crops) {
  crops.KeepOnly(used_crops);
  grids.erase(std::remove_if(grids.begin(),
                             grids.end(),
                             [&](const std::unique_ptr<DPKernelGrid>& g) {
                               return std::find(used_grids.begin(),
                                                used_grids.end(),
                                                g.get()) == used_grids.end();
                             }),
              grids.end());
}

IntensityStatsCache::IntensityStatsCache() : impl_(new Impl) {}
IntensityStatsCache::~IntensityStatsCache() = default;

int IntensityStatsCache::NumCrops() const { return impl_->crops.Size(); }

namespace {

using intensity::AddIntervals;
using intensity::ChannelTerms;
using intensity::IntervalsOf;
using intensity::LossOfPrepared;
using intensity::PatchRadii;
using intensity::Prepared;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Everything is validated here: nothing may throw inside the parallel loops.
void CheckSearchInput(const std::vector<IntensityView>& views,
                      const std::vector<IntensityPatch>& patches) {
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
}

const DPPsfModel& PsfOf(const IntensityPatch& patch, const DPPsfModel& psf) {
  return patch.psf != nullptr ? *patch.psf : psf;
}

// Kernel grids, one per crop geometry and PSF (L2-family losses only; the
// paper's L1 needs the pixels at every radius), built before the parallel
// loops (or taken from the cache where its kernels are the same); per
// patch its grid (null: the exact path).
struct PatchGrids {
  std::map<std::tuple<int, int, int, const DPPsfModel*>, const DPKernelGrid*>
      grids;
  std::vector<std::unique_ptr<DPKernelGrid>> owned;  // without a cache
  std::vector<const DPKernelGrid*> of_patch;
};
void BuildKernelGrids(const std::vector<IntensityPatch>& patches,
                      const DPPsfModel& psf,
                      const IntensitySearchOptions& options,
                      IntensityStatsCache* cache,
                      PatchGrids* out) {
  out->of_patch.assign(patches.size(), nullptr);
  const bool use_grid =
      options.grid_step_px > 0 && options.loss != IntensityLoss::kPaperL1;
  if (!use_grid) return;
  for (size_t j = 0; j < patches.size(); ++j) {
    const IntensityPatch& patch = patches[j];
    const DPPsfModel& patch_psf = PsfOf(patch, psf);
    const auto key = std::make_tuple(
        patch.left.cols, patch.left.rows, patch.border, &patch_psf);
    auto it = out->grids.find(key);
    if (it == out->grids.end()) {
      // Nodes only where the crop's border supports the kernels.
      const double supported =
          std::floor(intensity::MaxSupportedRadius(
                         patch_psf, patch.border, options.max_radius_px) /
                     options.grid_step_px) *
          options.grid_step_px;
      std::unique_ptr<DPKernelGrid> grid;
      if (supported >= options.grid_step_px) {
        grid.reset(
            new DPKernelGrid(patch_psf,
                             options.grid_step_px,
                             supported,
                             cv::Size(patch.left.cols - 2 * patch.border,
                                      patch.left.rows - 2 * patch.border),
                             options.num_threads));
      }
      const DPKernelGrid* shared = grid.get();
      if (grid != nullptr && cache != nullptr) {
        shared = cache->impl().Share(&grid);
      } else if (grid != nullptr) {
        out->owned.push_back(std::move(grid));
      }
      it = out->grids.emplace(key, shared).first;
    }
    out->of_patch[j] = it->second;
  }
}

// Each patch's record in the cache (null without one, or without a grid),
// the cache left holding only these.
std::vector<intensity::CachedCrop*> CacheRecords(
    const std::vector<IntensityPatch>& patches,
    const PatchGrids& grids,
    IntensityStatsCache* cache) {
  std::vector<intensity::CachedCrop*> records(patches.size(), nullptr);
  if (cache == nullptr) return records;
  IntensityStatsCache::Impl& impl = cache->impl();
  std::set<const intensity::CachedCrop*> taken;
  for (size_t j = 0; j < patches.size(); ++j) {
    if (grids.of_patch[j] == nullptr) continue;
    intensity::CachedCrop* record = impl.Crop(patches[j].left,
                                              patches[j].right,
                                              patches[j].border,
                                              grids.of_patch[j]);
    // A crop listed twice is cached once (its patches run in parallel).
    if (!taken.insert(record).second) continue;
    record->reused = record->computed = 0;
    records[j] = record;
  }
  std::vector<const DPKernelGrid*> used_grids;
  for (const auto& entry : grids.grids) used_grids.push_back(entry.second);
  impl.KeepOnlyUsed(used_grids, records);
  return records;
}

bool UsesNoise(IntensityLoss loss) {
  return loss == IntensityLoss::kNoiseCorrectedL2 ||
         loss == IntensityLoss::kRelativeL2;
}

// Converts crops, estimates noise, and (grid path) reduces each patch to its
// node statistics over the radii its candidates reach: the first-pass
// scales and the initial scale (the reference radius of kRelativeL2); the
// refine pass adds its own.
std::vector<Prepared> PreparePatches(
    const std::vector<IntensityView>& views,
    const std::vector<IntensityPatch>& patches,
    const DPPsfModel& psf,
    const PatchGrids& grids,
    const std::vector<intensity::CachedCrop*>& records,
    const std::vector<double>& scales,
    double initial_scale,
    const IntensitySearchOptions& options) {
  const int num_patches = static_cast<int>(patches.size());
  std::vector<Prepared> prepared(num_patches);
  ParallelFor(num_patches, options.num_threads, [&](int j) {
    Prepared& p = prepared[j];
    const DPPsfModel& patch_psf = PsfOf(patches[j], psf);
    p = intensity::Prepare(
        patches[j], patch_psf, options.max_radius_px);  // checked
    p.psf = &patch_psf;
    p.cached = records[j];
    if (UsesNoise(options.loss)) {
      if (p.cached != nullptr && !p.cached->noise_sigma.empty()) {
        p.sigma_left = p.cached->noise_sigma;
      } else {
        p.sigma_left = EstimatePairNoiseSigma(p.left, p.right);
        if (p.cached != nullptr) p.cached->noise_sigma = p.sigma_left;
      }
      p.sigma_right = p.sigma_left;
    }
    const DPKernelGrid* grid = grids.of_patch[j];
    if (grid == nullptr) return;
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
  });
  return prepared;
}

// Mid-size blurs leak some texture into the noise estimate, and an
// over-estimated floor biases towards small blur (large s); so a patch uses
// min(own, median of its view): the view's median where texture inflates
// the own estimate, the own one where the patch is genuinely quieter
// (darker, under shot noise).
void CapNoiseAtViewMedian(size_t num_views,
                          const std::vector<IntensityPatch>& patches,
                          std::vector<Prepared>* prepared) {
  const int num_patches = static_cast<int>(patches.size());
  const size_t channels = (*prepared)[0].sigma_left.size();
  for (size_t v = 0; v < num_views; ++v) {
    for (size_t c = 0; c < channels; ++c) {
      std::vector<double> s;
      for (int j = 0; j < num_patches; ++j) {
        if (patches[j].view == static_cast<int>(v) &&
            c < (*prepared)[j].sigma_left.size()) {
          s.push_back((*prepared)[j].sigma_left[c]);
        }
      }
      if (s.empty()) continue;
      const double cap = UpperMedianInPlace(&s);
      for (int j = 0; j < num_patches; ++j) {
        Prepared& p = (*prepared)[j];
        if (patches[j].view == static_cast<int>(v) && c < p.sigma_left.size()) {
          p.sigma_left[c] = std::min(p.sigma_left[c], cap);
          p.sigma_right[c] = p.sigma_left[c];
        }
      }
    }
  }
}

// kRelativeL2: each patch's noise estimate tightened with the fit, as the
// blur estimator does: the raw loss at every radius bounds sigma^2 from
// above (it is signal misfit plus noise), and near the patch's true radius
// the bound is the noise alone. The pair estimate can read DP disparity as
// noise; the bound cannot exceed what the data show. Radii: the patch's
// grid nodes that start a prepared interval, and the grid's last node (they
// span every radius its candidates reach, where the minimum lies for a
// patch that fits), or every 0.5 px of the supported range on the exact
// path. A node that only ends an interval has no loss of its own on the
// grid (GridLoss reads the interval above it): it is not evaluated, rather
// than counted as a failure. *failed counts loss evaluations that threw.
void TightenNoiseByFit(const IntensitySearchOptions& options,
                       std::vector<Prepared>* prepared,
                       int* failed) {
  const int num_patches = static_cast<int>(prepared->size());
  ParallelFor(num_patches, options.num_threads, [&](int j) {
    Prepared& p = (*prepared)[j];
    std::vector<double> radii;
    if (p.grid != nullptr) {
      for (const auto& entry : p.stats) {
        const int node = entry.first;
        if (entry.second.has_next || node + 1 == p.grid->NumNodes()) {
          radii.push_back(p.grid->Radius(node));
        }
      }
    } else {
      const int half = static_cast<int>(std::floor(p.max_abs_radius / 0.5));
      for (int k = -half; k <= half; ++k) radii.push_back(0.5 * k);
    }
    for (const double radius : radii) {
      std::vector<ChannelTerms> terms;
      try {
        LossOfPrepared(p, radius, *p.psf, options.loss, &terms);
      } catch (const CheckFailure&) {
#pragma omp atomic
        ++*failed;
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
  });
}

// kRelativeL2: fixed denominators at the initial scale (a denominator that
// shrinks with the candidate's blur would favour small blur, large s), and
// the channels whose signal power is at least the noise power (SNR >= 1).
void FixReferencePower(const std::vector<IntensityView>& views,
                       const std::vector<IntensityPatch>& patches,
                       double initial_scale,
                       const IntensitySearchOptions& options,
                       std::vector<Prepared>* prepared,
                       int* failed) {
  const int num_patches = static_cast<int>(patches.size());
  ParallelFor(num_patches, options.num_threads, [&](int j) {
    Prepared& p = (*prepared)[j];
    const double r = PatchRadii(views[patches[j].view],
                                patches[j].depth,
                                {initial_scale},
                                p.max_abs_radius)[0];
    std::vector<ChannelTerms> terms;
    try {
      LossOfPrepared(p, r, *p.psf, options.loss, &terms);
    } catch (const CheckFailure&) {
#pragma omp atomic
      ++*failed;
      terms.clear();
    }
    p.reference_power.clear();
    p.channel_used.clear();
    for (const ChannelTerms& t : terms) {
      p.reference_power.push_back(t.power);
      p.channel_used.push_back(t.power > 2 * t.noise ? 1 : 0);
    }
  });
}

// Per-patch loss curves over a list of scales: r_ij(s) from eq.
// (solution01) with s g_i' and s z'_ij. A patch whose loss cannot be
// evaluated at a radius (a failed DPSFM_CHECK) contributes nothing there,
// counted in *failed; anything else thrown ends the search (ParallelFor).
std::vector<std::vector<double>> LossCurves(
    const std::vector<IntensityView>& views,
    const std::vector<IntensityPatch>& patches,
    const std::vector<double>& scales,
    const IntensitySearchOptions& options,
    std::vector<Prepared>* prepared,
    int* failed) {
  const int num_patches = static_cast<int>(patches.size());
  std::vector<std::vector<double>> curves(num_patches,
                                          std::vector<double>(scales.size()));
  ParallelFor(num_patches, options.num_threads, [&](int j) {
    Prepared& p = (*prepared)[j];
    const std::vector<double> radii = PatchRadii(
        views[patches[j].view], patches[j].depth, scales, p.max_abs_radius);
    if (p.grid != nullptr) {
      try {
        AddIntervals(patches[j], IntervalsOf(*p.grid, radii), &p);
      } catch (const CheckFailure&) {
        // Evaluated as unprepared below (contributes nothing).
#pragma omp atomic
        ++*failed;
      }
    }
    double last_radius = kInf, last_loss = 0;
    for (size_t k = 0; k < scales.size(); ++k) {
      const double r =
          std::max(-p.max_abs_radius, std::min(p.max_abs_radius, radii[k]));
      if (r != last_radius) {
        try {
          last_loss = LossOfPrepared(p, r, *p.psf, options.loss);
        } catch (const CheckFailure&) {
#pragma omp atomic
          ++*failed;
          last_loss = 0;
        }
        last_radius = r;
      }
      curves[j][k] = last_loss;
    }
  });
  return curves;
}

// kRelativeL2: each patch's curve relative to its own minimum, through a
// saturating function d / (d + c). A patch the model fits has a minimum
// near 0 and a bowl around it; one it cannot fit (blur beyond the crops'
// support, depth varying inside) has a high, sloping curve that would
// otherwise pull the sum towards the range's edge. Saturation bounds what
// any patch can contribute (a redescending M-estimator).
void SaturateCurves(const std::vector<double>& patch_minimum,
                    double scale_c,
                    std::vector<std::vector<double>>* curves) {
  for (size_t j = 0; j < curves->size(); ++j) {
    for (double& value : (*curves)[j]) {
      const double d = std::max(0.0, value - patch_minimum[j]);
      value = d / (d + scale_c);
    }
  }
}

// The second pass's scales: num_refine_candidates between the neighbours
// of the first-pass minimum (without the minimum itself).
std::vector<double> RefineScales(const std::vector<double>& scales,
                                 size_t coarse_best,
                                 double initial_scale,
                                 int num_refine) {
  const double a = scales[coarse_best - 1];
  const double b = scales[coarse_best + 1];
  std::vector<double> fine;
  for (int k = 1; k <= num_refine; ++k) {
    const double s = a + (b - a) * k / (num_refine + 1);
    if (std::abs(s - scales[coarse_best]) > 1e-12 * initial_scale) {
      fine.push_back(s);
    }
  }
  return fine;
}

// The two passes merged into one grid sorted by scale.
void MergeCurves(const std::vector<double>& fine,
                 const std::vector<std::vector<double>>& fine_curves,
                 std::vector<double>* scales,
                 std::vector<std::vector<double>>* curves) {
  const int num = static_cast<int>(scales->size());
  std::vector<std::pair<double, int>> order;  // (scale, column)
  for (int k = 0; k < num; ++k) order.emplace_back((*scales)[k], k);
  for (size_t k = 0; k < fine.size(); ++k) {
    order.emplace_back(fine[k], num + static_cast<int>(k));
  }
  std::sort(order.begin(), order.end());
  std::vector<double> merged_scales;
  std::vector<std::vector<double>> merged(curves->size());
  for (const auto& item : order) merged_scales.push_back(item.first);
  for (size_t j = 0; j < curves->size(); ++j) {
    for (const auto& item : order) {
      merged[j].push_back(item.second < num
                              ? (*curves)[j][item.second]
                              : fine_curves[j][item.second - num]);
    }
  }
  scales->swap(merged_scales);
  curves->swap(merged);
}

// Bootstrap: views with replacement, then patches within each drawn view,
// so patches that share a view (and its g_i' error) are not counted as
// independent evidence. Sets the interval and the share of resamples whose
// minimum lies within `step` of the scale.
void BootstrapInterval(size_t num_views,
                       const std::vector<IntensityPatch>& patches,
                       const std::vector<double>& scales,
                       const std::vector<std::vector<double>>& curves,
                       double step,
                       const IntensitySearchOptions& options,
                       IntensitySearchResult* result) {
  const size_t grid = scales.size();
  std::vector<std::vector<int>> by_view(num_views);
  for (size_t j = 0; j < patches.size(); ++j) {
    by_view[patches[j].view].push_back(static_cast<int>(j));
  }
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
    if (std::abs(s - result->scale) <= step) ++support;
  }
  const double alpha = 0.5 * (1 - options.confidence_level);
  result->scale_ci_low = std::min(result->scale, Percentile(minima, alpha));
  result->scale_ci_high =
      std::max(result->scale, Percentile(minima, 1 - alpha));
  result->bootstrap_support =
      static_cast<double>(support) / options.num_bootstrap;
}

std::vector<double> SumOverPatches(
    const std::vector<std::vector<double>>& curves, size_t grid) {
  std::vector<double> sum(grid, 0.0);
  for (const auto& curve : curves) {
    for (size_t k = 0; k < grid; ++k) sum[k] += curve[k];
  }
  return sum;
}

}  // namespace

IntensitySearchResult SearchScaleByIntensity(
    const std::vector<IntensityView>& views,
    const std::vector<IntensityPatch>& patches,
    double initial_scale,
    const DPPsfModel& psf,
    const IntensitySearchOptions& options,
    IntensityStatsCache* cache) {
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
  CheckSearchInput(views, patches);
  const int num_patches = static_cast<int>(patches.size());
  result.num_patches = num_patches;
  int* failed = &result.num_failed_evaluations;

  // First-pass candidates: the paper's set, s* (1 +- T_s).
  const int num = options.num_candidates;
  const double lo = initial_scale * (1 - options.relative_range);
  const double hi = initial_scale * (1 + options.relative_range);
  const double step = (hi - lo) / (num - 1);
  std::vector<double> scales(num);
  for (int k = 0; k < num; ++k) scales[k] = lo + step * k;

  PatchGrids grids;
  BuildKernelGrids(patches, psf, options, cache, &grids);
  const std::vector<intensity::CachedCrop*> records =
      CacheRecords(patches, grids, cache);
  std::vector<Prepared> prepared = PreparePatches(
      views, patches, psf, grids, records, scales, initial_scale, options);
  if (UsesNoise(options.loss)) {
    CapNoiseAtViewMedian(views.size(), patches, &prepared);
  }
  if (options.loss == IntensityLoss::kRelativeL2) {
    TightenNoiseByFit(options, &prepared, failed);
    FixReferencePower(
        views, patches, initial_scale, options, &prepared, failed);
  }

  // First pass: the paper's candidate set.
  std::vector<std::vector<double>> curves =
      LossCurves(views, patches, scales, options, &prepared, failed);
  result.num_evaluations += num_patches * num;
  const bool robust = options.loss == IntensityLoss::kRelativeL2;
  std::vector<double> patch_minimum(num_patches, 0.0);
  if (robust) {
    for (int j = 0; j < num_patches; ++j) {
      patch_minimum[j] = *std::min_element(curves[j].begin(), curves[j].end());
    }
    SaturateCurves(patch_minimum, options.robust_loss_scale, &curves);
  }
  const std::vector<double> total = SumOverPatches(curves, num);
  const size_t coarse_best =
      std::min_element(total.begin(), total.end()) - total.begin();
  result.at_boundary =
      coarse_best == 0 || coarse_best + 1 == static_cast<size_t>(num);

  // Second pass between the neighbours of the first-pass minimum.
  if (options.num_refine_candidates > 0 && !result.at_boundary) {
    const std::vector<double> fine = RefineScales(
        scales, coarse_best, initial_scale, options.num_refine_candidates);
    std::vector<std::vector<double>> fine_curves =
        LossCurves(views, patches, fine, options, &prepared, failed);
    result.num_evaluations += num_patches * static_cast<int>(fine.size());
    if (robust) {
      SaturateCurves(patch_minimum, options.robust_loss_scale, &fine_curves);
    }
    MergeCurves(fine, fine_curves, &scales, &curves);
  }

  const std::vector<double> sum = SumOverPatches(curves, scales.size());
  result.candidate_scales = scales;
  result.candidate_losses = sum;
  result.scale = CurveMinimum(scales, sum, nullptr);
  result.scale_ci_low = result.scale_ci_high = result.scale;
  if (options.num_bootstrap > 0) {
    BootstrapInterval(
        views.size(), patches, scales, curves, step, options, &result);
  }
  for (const intensity::CachedCrop* record : records) {
    if (record == nullptr) continue;
    result.num_nodes_reused += record->reused;
    result.num_nodes_computed += record->computed;
  }
  result.success = true;
  return result;
}

}  // namespace dpsfm
