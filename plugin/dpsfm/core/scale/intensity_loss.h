// The intensity search's per-patch loss (eq. loss_refine and its L2
// variants): a patch converted once (Prepared), the kernel-grid statistics
// that make the L2-family losses exact at any radius inside a grid interval,
// and the loss at one radius. Internal to intensity_search.cc; the public
// entry points are in intensity_search.h.
#pragma once

#include <map>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/scale/intensity_search.h"
#include "dpsfm/core/util/crop_records.h"

namespace dpsfm {
namespace intensity {

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

struct CachedCrop;

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
  // The crop's record in an IntensityStatsCache (null: none): AddIntervals
  // takes the statistics it holds and adds what it computes.
  CachedCrop* cached = nullptr;
};

// A crop's statistics on one grid, kept across searches.
struct CachedCrop {
  // What it is known by besides the crop's pixels (CropRecords): its border
  // and grid (held by the cache, one per distinct set of kernels).
  int border = 0;
  const DPKernelGrid* grid = nullptr;
  std::vector<double> noise_sigma;  // EstimatePairNoiseSigma (empty: not yet)
  std::map<int, Prepared::NodeEntry> nodes;  // cross terms where has_next
  int reused = 0, computed = 0;              // nodes, in the current search
};

}  // namespace intensity

struct IntensityStatsCache::Impl {
  std::vector<std::unique_ptr<DPKernelGrid>> grids;
  CropRecords<intensity::CachedCrop> crops;

  // The cached grid whose kernels equal *grid's (then *grid is dropped),
  // else *grid, now held here.
  const DPKernelGrid* Share(std::unique_ptr<DPKernelGrid>* grid);
  // The record of a crop (the same pixels, border and grid) on a grid
  // (created empty, holding the crop).
  intensity::CachedCrop* Crop(const cv::Mat& left,
                              const cv::Mat& right,
                              int border,
                              const DPKernelGrid* grid);
  // Drops the grids and crops the current search does not use: call once
  // its records are taken, before the statistics are computed.
  void KeepOnlyUsed(const std::vector<const DPKernelGrid*>& used_grids,
                    const std::vector<intensity::CachedCrop*>& used_crops);
};

namespace intensity {

// kRelativeL2 per channel: mean squared difference `acc` of the normalised
// cross-blurred patches, its noise gain (noise = sigma^2 gain), the patches'
// power (variances, noise included) and the expected noise in acc.
struct ChannelTerms {
  double acc = 0, gain = 0, power = 0, noise = 0;
};

// Largest |r| whose kernels fit inside `border` (and <= max_radius_px).
double MaxSupportedRadius(const DPPsfModel& psf,
                          int border,
                          double max_radius_px);

// The patch's loss at one signed radius: on its kernel grid's statistics
// when it has a grid, else by convolution with the model's kernels at r.
// `terms` (optional) receives kRelativeL2's per-channel terms.
double LossOfPrepared(const Prepared& p,
                      double radius_px,
                      const DPPsfModel& psf,
                      IntensityLoss loss,
                      std::vector<ChannelTerms>* terms = nullptr);

// Grid intervals (node n <-> [r_n, r_n+1]) that the radii fall in.
std::vector<int> IntervalsOf(const DPKernelGrid& grid,
                             const std::vector<double>& radii);

// Adds to p->stats the nodes of the given intervals that are not ready yet:
// from p->cached where it holds them (a node's own statistics, and its
// cross terms with the next node where both are added), else from the
// patch's crops (then added to p->cached).
void AddIntervals(const IntensityPatch& patch,
                  const std::vector<int>& intervals,
                  Prepared* p);

// Radii of a patch under the given scales (eq. (solution01) with s g_i' and
// s z'_ij); non-finite ones (a depth at the focal plane's pole) at the bound.
std::vector<double> PatchRadii(const IntensityView& view,
                               double depth,
                               const std::vector<double>& scales,
                               double bound);

// The patch's crops as float, its border, interior size and the largest
// radius its border supports. Throws for malformed crops.
Prepared Prepare(const IntensityPatch& patch,
                 const DPPsfModel& psf,
                 double max_radius_px);

}  // namespace intensity
}  // namespace dpsfm
