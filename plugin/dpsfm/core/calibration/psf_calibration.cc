#include "dpsfm/core/calibration/psf_calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <utility>

#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/crop_records.h"
#include "dpsfm/core/util/curve_math.h"
#include "dpsfm/core/util/fields.h"
#include "dpsfm/core/util/statistics.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {

struct ProfileSearchCache::Impl {
  // A crop's searches: per profile key (ProfileSearches), the radius (NaN:
  // no estimate) and relative residual.
  struct Crop {
    std::map<double, std::pair<double, double>> by_key;
    int reused = 0, run = 0;  // in the current calibration
  };
  bool has_options = false;
  BlurEstimationOptions blur;  // the options every held search used
  CropRecords<Crop> crops;     // known by the patch's pixels

  // Starts a calibration with `blur`: searches under other options (any
  // field: SameFields) are dropped.
  void Begin(const BlurEstimationOptions& options) {
    if (!has_options || !SameFields(blur, options)) crops.Clear();
    blur = options;
    has_options = true;
  }
  // The record of the patch's crop (created empty).
  Crop* Find(const ProfilePatch& patch) {
    bool added = false;
    return crops.Find(
        patch.left, patch.right, [](const Crop&) { return true; }, &added);
  }
};

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Per-patch outcome of the blur search under one profile.
struct Evaluation {
  std::vector<double> radius;    // NaN where the search gave no estimate
  std::vector<double> residual;  // relative residual; 1 where none
};

// The blur searches of one calibration's patches (CalibrateSplitProfile:
// the whole frame's fit, then each band's on its share of the same
// patches), kept per patch and profile: a search of the same crop under
// the same profile and options gives the same estimate, so a band's fit
// reads the frame's searches of its patches instead of repeating them. The
// patches are prepared once (PreparedBlurPatch).
class ProfileSearches {
 public:
  // The key of the paper's translating disk: no log centroid offset is
  // infinite.
  static constexpr double kTranslatingDisk =
      std::numeric_limits<double>::infinity();

  // `cache` (optional): searches kept from an earlier calibration, and
  // where this one's go.
  ProfileSearches(const std::vector<ProfilePatch>& patches,
                  const SplitProfileFitOptions& options,
                  ProfileSearchCache* cache)
      : patches_(patches),
        options_(options),
        prepared_(patches.size()),
        is_prepared_(patches.size(), false),
        records_(patches.size(), nullptr) {
    if (cache == nullptr) return;
    ProfileSearchCache::Impl& impl = cache->impl();
    impl.Begin(options.blur);
    for (size_t i = 0; i < patches.size(); ++i) {
      records_[i] = impl.Find(patches[i]);
      records_[i]->reused = records_[i]->run = 0;
    }
    impl.crops.KeepOnly(records_);
  }

  const std::vector<ProfilePatch>& Patches() const { return patches_; }

  // The searches read from the cache and run, per patch and profile (0
  // without a cache).
  void CountSearches(SplitProfileCalibration* calibration) const {
    std::set<const ProfileSearchCache::Impl::Crop*> counted;
    for (const ProfileSearchCache::Impl::Crop* record : records_) {
      if (record == nullptr || !counted.insert(record).second) continue;
      calibration->searches_reused += record->reused;
      calibration->searches_run += record->run;
    }
  }

  // The outcome for `members` (indices into the patches) under the profile
  // of log centroid offset `key` (or kTranslatingDisk): those not searched
  // under it yet are searched (in parallel), the others read.
  Evaluation Search(double key, const std::vector<int>& members) {
    std::vector<Outcome>& known = outcomes_[key];
    if (known.empty()) known.resize(patches_.size());
    std::vector<int> todo;
    for (int i : members) {
      if (!known[i].searched && !FromCache(key, &known[i], records_[i])) {
        todo.push_back(i);
      }
    }
    if (!todo.empty()) SearchPatches(key, todo, &known);
    Evaluation e;
    for (int i : members) {
      e.radius.push_back(known[i].radius);
      e.residual.push_back(known[i].residual);
    }
    return e;
  }

 private:
  struct Outcome {
    bool searched = false;
    double radius = kNaN;   // NaN where the search gave no estimate
    double residual = 1.0;  // no estimate: counts as unexplained
  };

  void SearchPatches(double key,
                     const std::vector<int>& todo,
                     std::vector<Outcome>* known) {
    std::vector<const ProfilePatch*> ptrs;
    std::vector<PreparedBlurPatch> prepared;
    bool all_prepared = true;
    for (int i : todo) {
      ptrs.push_back(&patches_[i]);
      all_prepared = all_prepared && is_prepared_[i];
    }
    // Prepared all at once or not at all (EstimateProfilePatches); a
    // patch prepared again comes out the same.
    if (all_prepared) {
      for (int i : todo) prepared.push_back(prepared_[i]);
    }
    std::unique_ptr<DPPsfModel> psf;
    if (key == kTranslatingDisk) {
      psf.reset(new TranslatingDiskPsf());
    } else {
      psf.reset(new SplitProfilePsf(
          SplitProfileParams::ForCentroidOffset(std::exp(key))));
    }
    const std::vector<PatchBlurEstimate> estimates = EstimateProfilePatches(
        *psf, options_.blur, ptrs, options_.num_threads, &prepared);
    for (size_t k = 0; k < todo.size(); ++k) {
      const int i = todo[k];
      if (!all_prepared) {
        prepared_[i] = prepared[k];
        is_prepared_[i] = true;
      }
      Outcome& o = (*known)[i];
      o.searched = true;
      if (estimates[k].valid && std::isfinite(estimates[k].relative_residual)) {
        o.radius = estimates[k].radius_px;
        o.residual = estimates[k].relative_residual;
      }
      if (records_[i] != nullptr) {
        records_[i]->by_key[key] = {o.radius, o.residual};
        ++records_[i]->run;
      }
    }
  }

  // The outcome an earlier calibration's search of the same crop under
  // the same profile gave, if any.
  static bool FromCache(double key,
                        Outcome* o,
                        ProfileSearchCache::Impl::Crop* record) {
    if (record == nullptr) return false;
    const auto it = record->by_key.find(key);
    if (it == record->by_key.end()) return false;
    o->searched = true;
    o->radius = it->second.first;
    o->residual = it->second.second;
    ++record->reused;
    return true;
  }

  const std::vector<ProfilePatch>& patches_;
  const SplitProfileFitOptions& options_;
  std::vector<PreparedBlurPatch> prepared_;
  std::vector<bool> is_prepared_;
  std::vector<ProfileSearchCache::Impl::Crop*> records_;  // null: no cache
  std::map<double, std::vector<Outcome>> outcomes_;       // by key
};

// 0, 1, ..., n - 1.
std::vector<int> Indices(size_t n) {
  std::vector<int> indices(n);
  std::iota(indices.begin(), indices.end(), 0);
  return indices;
}

// Self-calibration criterion: mean residual of the patches (with
// multiplicities `weight`) after trimming the largest `trim` share.
double TrimmedMean(const std::vector<double>& residual,
                   const std::vector<int>& members,
                   double trim) {
  std::vector<double> v;
  v.reserve(members.size());
  for (int i : members) v.push_back(residual[i]);
  std::sort(v.begin(), v.end());
  const size_t keep = std::max<size_t>(
      1, static_cast<size_t>(std::ceil((1 - trim) * v.size())));
  return std::accumulate(v.begin(), v.begin() + keep, 0.0) / keep;
}

// Calibration criterion: median of r / r_known - 1 (signed; radii shrink as
// the assumed centroid offset grows, so it falls along the path).
double MedianRadiusError(const std::vector<double>& radius,
                         const std::vector<double>& known,
                         const std::vector<int>& members) {
  std::vector<double> v;
  for (int i : members) {
    v.push_back(std::isfinite(radius[i]) ? radius[i] / known[i] - 1 : 1.0);
  }
  return Percentile(v, 0.5);
}

// Where a monotone-ish curve crosses 0, by linear interpolation between
// the bracketing nodes; NaN if it does not.
double ZeroCrossing(const std::vector<double>& xs,
                    const std::vector<double>& ys) {
  for (size_t k = 0; k + 1 < xs.size(); ++k) {
    if ((ys[k] <= 0 && ys[k + 1] >= 0) || (ys[k] >= 0 && ys[k + 1] <= 0)) {
      if (ys[k + 1] == ys[k]) return 0.5 * (xs[k] + xs[k + 1]);
      return xs[k] - ys[k] * (xs[k + 1] - xs[k]) / (ys[k + 1] - ys[k]);
    }
  }
  return kNaN;
}

// Checks the patches' crops; true when every patch has a known radius
// (calibration), false when none has (self-calibration).
bool RadiiKnown(const std::vector<ProfilePatch>& patches) {
  const cv::Size size = patches[0].left.size();
  int num_known = 0;
  for (const ProfilePatch& p : patches) {
    DPSFM_CHECK(p.left.type() == CV_32FC1 && p.right.type() == CV_32FC1 &&
                p.left.size() == size && p.right.size() == size)
        << "profile patches must be CV_32FC1 crops of one size";
    num_known += std::isfinite(p.known_radius_px) ? 1 : 0;
  }
  DPSFM_CHECK(num_known == 0 || num_known == static_cast<int>(patches.size()))
      << "either every patch has a known radius or none";
  return num_known > 0;
}

// The criterion along the path (log centroid offsets xs, sorted) and its
// solution.
struct PathCurve {
  std::vector<double> xs, ys;
  double best = kNaN;  // log centroid offset; NaN when it leaves the range
  bool at_edge = false;
};

// The search along the family's path: the blur search of the patches under
// each evaluated profile (once per profile), the usable patches, and the
// criterion and its solution over any members of them.
class ProfileSearch {
 public:
  // The fit of the patches `members` (indices into searches->Patches()).
  ProfileSearch(ProfileSearches* searches,
                const std::vector<int>& members,
                bool known,
                const SplitProfileFitOptions& options)
      : searches_(*searches),
        members_(members),
        known_(known),
        options_(options),
        n_(static_cast<int>(members.size())) {
    searched_ = Indices(n_);
    SelectUsablePatches();
    // Every criterion reads the usable patches alone (Criterion's members,
    // ValidShare, SetResiduals, the translating disk's residuals): the
    // profiles after the first search them alone.
    searched_ = usable_;
  }

  const std::vector<int>& Usable() const { return usable_; }

  const Evaluation& Evaluate(double log_kappa) {
    auto it = evaluations_.find(log_kappa);
    if (it != evaluations_.end()) return it->second;
    return evaluations_.emplace(log_kappa, Outcomes(log_kappa)).first->second;
  }

  double Criterion(const Evaluation& e, const std::vector<int>& members) const {
    return known_ ? MedianRadiusError(e.radius, known_radius_, members)
                  : TrimmedMean(e.residual, members, options_.trim_fraction);
  }

  // Coarse grid, then a finer one around its solution.
  PathCurve SearchPath() {
    const double lo = std::log(options_.min_centroid_offset);
    const double hi = std::log(options_.max_centroid_offset);
    for (const double kappa : GeometricNodes(options_.min_centroid_offset,
                                             options_.max_centroid_offset,
                                             options_.grid_ratio)) {
      Evaluate(std::log(kappa));
    }
    PathCurve c;
    Curve(usable_, &c.xs, &c.ys);
    c.best = Solve(c.xs, c.ys, &c.at_edge);
    // Refined also next to an end node: the minimum may lie between it and
    // its neighbour (the edge is judged on the refined curve).
    if (std::isfinite(c.best) && options_.num_refine > 0) {
      const double step = std::log(options_.grid_ratio);
      const double a = std::max(lo, c.best - step),
                   b = std::min(hi, c.best + step);
      for (int k = 1; k <= options_.num_refine; ++k) {
        Evaluate(a + (b - a) * k / (options_.num_refine + 1));
      }
      Curve(usable_, &c.xs, &c.ys);
      c.best = Solve(c.xs, c.ys, &c.at_edge);
    }
    return c;
  }

  // Why the solution lies at the edge of the range (or beyond it).
  std::string WhyAtEdge(const PathCurve& c) const {
    const std::vector<double>& xs = c.xs;
    const std::vector<double>& ys = c.ys;
    std::ostringstream s;
    if (known_) {
      s << "no profile with a centroid offset in ["
        << options_.min_centroid_offset << ", " << options_.max_centroid_offset
        << "] R makes the recovered radii agree with the known ones (median "
           "error from "
        << ys.front() << " to " << ys.back() << ")";
    } else {
      s << "the residual is lowest at the edge of the profiles tried "
           "(centroid offset "
        << std::exp(xs[std::min_element(ys.begin(), ys.end()) - ys.begin()])
        << " R in [" << options_.min_centroid_offset << ", "
        << options_.max_centroid_offset
        << "]): the sensor's profile may lie outside the family";
    }
    return s.str();
  }

  // Bootstrap over the usable patches: each resample's solution (log
  // centroid offset); `best` alone without resamples.
  std::vector<double> BootstrapSolutions(double best) const {
    const double lo = std::log(options_.min_centroid_offset);
    const double hi = std::log(options_.max_centroid_offset);
    std::vector<double> samples;
    if (options_.num_bootstrap > 0) {
      std::mt19937_64 rng(options_.seed);
      std::uniform_int_distribution<size_t> pick(0, usable_.size() - 1);
      std::vector<int> members(usable_.size());
      std::vector<double> bx, by;
      for (int b = 0; b < options_.num_bootstrap; ++b) {
        for (int& m : members) m = usable_[pick(rng)];
        Curve(members, &bx, &by);
        bool edge = false;
        const double x = Solve(bx, by, &edge);
        // No crossing: radii read too small (< 0) everywhere call for the
        // weakest profile, too large for the strongest.
        samples.push_back(std::isfinite(x) ? x : (by.front() < 0 ? lo : hi));
      }
    } else {
      samples.push_back(best);
    }
    return samples;
  }

  // The share of the usable patches the blur search fits under the
  // evaluated profile at log centroid offset x.
  double ValidShare(double x) const {
    const Evaluation& e = evaluations_.at(x);
    int valid = 0;
    for (int i : usable_) valid += std::isfinite(e.radius[i]) ? 1 : 0;
    return static_cast<double>(valid) / usable_.size();
  }

  // Mean relative residual of the usable patches, and (calibration) their
  // median |r / r_known - 1|.
  void SetResiduals(const Evaluation& at_fit, SplitProfileFit* fit) const {
    std::vector<double> residuals;
    for (int i : usable_) residuals.push_back(at_fit.residual[i]);
    fit->mean_relative_residual =
        std::accumulate(residuals.begin(), residuals.end(), 0.0) /
        residuals.size();
    if (known_) {
      std::vector<double> errors;
      for (int i : usable_) {
        errors.push_back(std::isfinite(at_fit.radius[i])
                             ? std::abs(at_fit.radius[i] / known_radius_[i] - 1)
                             : 1.0);
      }
      fit->median_radius_error = Percentile(errors, 0.5);
    }
  }

  // The relative residual of each usable patch under the paper's
  // translating disk (1 where its search gives no estimate; all patches).
  std::vector<double> TranslatingDiskResiduals() {
    return Outcomes(ProfileSearches::kTranslatingDisk).residual;
  }

 private:
  // Patches with enough blur for the shape to matter.
  void SelectUsablePatches() {
    known_radius_.assign(n_, kNaN);
    // The linear split, next to the translating disk.
    const Evaluation& disk =
        Evaluate(std::log(SplitProfileParams().CentroidOffset()));
    for (int i = 0; i < n_; ++i) {
      known_radius_[i] = searches_.Patches()[members_[i]].known_radius_px;
      const double r = known_ ? known_radius_[i] : disk.radius[i];
      if (std::isfinite(r) && std::abs(r) >= options_.min_abs_radius_px &&
          std::isfinite(disk.radius[i])) {
        usable_.push_back(i);
      }
    }
  }

  // The outcome of the searched patches under the profile `key`
  // (ProfileSearches), per member (the others: no estimate).
  Evaluation Outcomes(double key) {
    std::vector<int> ids;
    for (int i : searched_) ids.push_back(members_[i]);
    const Evaluation searched = searches_.Search(key, ids);
    Evaluation e;
    e.radius.assign(n_, kNaN);
    e.residual.assign(n_, 1.0);
    for (size_t k = 0; k < searched_.size(); ++k) {
      e.radius[searched_[k]] = searched.radius[k];
      e.residual[searched_[k]] = searched.residual[k];
    }
    return e;
  }

  void Curve(const std::vector<int>& members,
             std::vector<double>* xs,
             std::vector<double>* ys) const {
    xs->clear();
    ys->clear();
    for (const auto& entry : evaluations_) {
      xs->push_back(entry.first);
      ys->push_back(Criterion(entry.second, members));
    }
  }

  // The fitted log centroid offset of a curve; NaN when it leaves the
  // range.
  double Solve(const std::vector<double>& xs,
               const std::vector<double>& ys,
               bool* at_edge) const {
    if (known_) {
      const double x = ZeroCrossing(xs, ys);
      *at_edge = !std::isfinite(x);
      return x;
    }
    size_t k = 0;
    const double x = CurveMinimum(xs, ys, &k);
    *at_edge = k == 0 || k + 1 == xs.size();
    return x;
  }

  ProfileSearches& searches_;
  const std::vector<int> members_;
  const bool known_;
  const SplitProfileFitOptions& options_;
  const int n_;
  // The members each profile's search runs on (indices into members_): all
  // for the first profile, then the usable ones.
  std::vector<int> searched_;
  std::map<double, Evaluation> evaluations_;  // by log centroid offset
  std::vector<int> usable_;
  std::vector<double> known_radius_;
};

std::string TooFewUsablePatches(int num_usable,
                                int n,
                                const SplitProfileFitOptions& options) {
  std::ostringstream s;
  s << "only " << num_usable << " of " << n
    << " patches have a usable blur of at least " << options.min_abs_radius_px
    << " px (need " << options.min_patches
    << "); the profile's shape cannot be seen in smaller blur";
  return s.str();
}

// The profile at the solution, with the bootstrap's 95 % interval as the
// range of centroid offsets the data allow so far.
void SetFittedProfile(double best,
                      const std::vector<double>& samples,
                      SplitProfileFit* fit) {
  fit->params = SplitProfileParams::ForCentroidOffset(std::exp(best));
  fit->centroid_offset = std::exp(best);
  fit->centroid_offset_ci_low =
      std::exp(std::min(best, Percentile(samples, 0.025)));
  fit->centroid_offset_ci_high =
      std::exp(std::max(best, Percentile(samples, 0.975)));
  fit->consistent_low = fit->centroid_offset_ci_low;
  fit->consistent_high = fit->centroid_offset_ci_high;
}

// Self-calibration: the consistent range also holds every evaluated
// profile within consistency_tolerance of the minimum.
void WidenToConsistentRange(const ProfileSearch& search,
                            const PathCurve& curve,
                            const SplitProfileFitOptions& options,
                            SplitProfileFit* fit) {
  const std::vector<double>& xs = curve.xs;
  const std::vector<double>& ys = curve.ys;
  const double floor = *std::min_element(ys.begin(), ys.end());
  size_t lo_node = xs.size(), hi_node = 0;
  for (size_t k = 0; k < xs.size(); ++k) {
    if (ys[k] <= (1 + options.consistency_tolerance) * floor) {
      lo_node = std::min(lo_node, k);
      hi_node = std::max(hi_node, k);
    }
  }
  // Next to the consistent nodes, a node where the blur search loses
  // many of the patches the best node fits (their blur read under that
  // profile lies beyond the search bound) is not evaluated, not refuted:
  // the consistent range runs on through such nodes. (On a real R6 II
  // scene the minimum sat next to them, at 0.116 R for a sensor of
  // ~0.07 R, and the scale came out 17 % large with +-10 %.)
  const double best_share = search.ValidShare(
      xs[std::min_element(ys.begin(), ys.end()) - ys.begin()]);
  auto unresolved = [&](size_t k) {
    return search.ValidShare(xs[k]) < 0.8 * best_share;
  };
  while (lo_node > 0 && unresolved(lo_node - 1)) --lo_node;
  while (hi_node + 1 < xs.size() && unresolved(hi_node + 1)) ++hi_node;
  fit->consistent_low = std::min(fit->consistent_low, std::exp(xs[lo_node]));
  fit->consistent_high = std::max(fit->consistent_high, std::exp(xs[hi_node]));
  // A consistent node at the end of the range: the data allow profiles
  // beyond it.
  if (fit->consistent_low <= std::exp(xs.front()) * (1 + 1e-9)) {
    fit->consistent_low = 0;
  }
  if (fit->consistent_high >= std::exp(xs.back()) * (1 - 1e-9)) {
    fit->consistent_high = std::numeric_limits<double>::infinity();
  }
}

// Self-calibration: the paper's translating disk against the best split
// profile.
void WeighTranslatingDisk(ProfileSearch* search,
                          const Evaluation& at_fit,
                          const SplitProfileFitOptions& options,
                          SplitProfileFit* fit) {
  const std::vector<int>& usable = search->Usable();
  const std::vector<double> residual = search->TranslatingDiskResiduals();
  fit->translating_disk_criterion =
      TrimmedMean(residual, usable, options.trim_fraction);
  // The paper's model is kept unless the split profile fits significantly
  // better: in at least 95 % of paired bootstrap resamples of the patches.
  // Translating-disk data lie outside the family, and its best member
  // there can fit about as well with a centroid offset some % off (seen:
  // p 1.14 on one generated scene, 7 % off in scale).
  int family_better = 0, resamples = 0;
  if (fit->translating_disk_criterion >
      options.min_improvement_over_translating_disk *
          search->Criterion(at_fit, usable)) {
    std::mt19937_64 rng(options.seed + 1);
    std::uniform_int_distribution<size_t> pick(0, usable.size() - 1);
    std::vector<int> members(usable.size());
    resamples = std::max(options.num_bootstrap, 100);
    for (int b = 0; b < resamples; ++b) {
      for (int& m : members) m = usable[pick(rng)];
      if (TrimmedMean(residual, members, options.trim_fraction) >
          TrimmedMean(at_fit.residual, members, options.trim_fraction)) {
        ++family_better;
      }
    }
  }
  fit->translating_disk = resamples == 0 || family_better < 0.95 * resamples;
  if (fit->translating_disk || fit->translating_disk_criterion <=
                                   (1 + options.consistency_tolerance) *
                                       search->Criterion(at_fit, usable)) {
    fit->consistent_low =
        std::min(fit->consistent_low, fit->translating_disk_centroid_offset);
    fit->consistent_high =
        std::max(fit->consistent_high, fit->translating_disk_centroid_offset);
  }
}

// Determined when the 95 % interval is narrow enough; the translating disk
// replaces the split profile when it fits about as well. Sets the summary.
void Conclude(double residual_at_fit,
              const SplitProfileFitOptions& options,
              SplitProfileFit* fit) {
  const double worst_side =
      std::max(fit->centroid_offset - fit->centroid_offset_ci_low,
               fit->centroid_offset_ci_high - fit->centroid_offset) /
      fit->centroid_offset;
  std::ostringstream s;
  s << "centroid offset " << fit->centroid_offset << " R (95 % interval "
    << fit->centroid_offset_ci_low << " - " << fit->centroid_offset_ci_high
    << "; " << fit->params.ToString() << "; translating disk "
    << fit->translating_disk_centroid_offset << " R) from " << fit->num_patches
    << " patches, residual " << residual_at_fit;
  if (worst_side > options.max_relative_uncertainty) {
    s << ": not determined (the centroid offset is uncertain by "
      << std::lround(100 * worst_side) << " %, limit "
      << std::lround(100 * options.max_relative_uncertainty) << " %)";
    fit->reason = s.str();
    return;
  }
  fit->determined = true;
  if (fit->translating_disk) {
    s << "; the translating disk fits about as well (residual "
      << fit->translating_disk_criterion << " vs " << residual_at_fit
      << ") and is kept";
    fit->params = SplitProfileParams();
    fit->centroid_offset = fit->translating_disk_centroid_offset;
  }
  fit->reason = s.str();
}

}  // namespace

bool SplitProfileFitOptions::Check(std::string* failure) const {
  if (!SplitProfileParams::CheckCentroidOffsetRange(
          min_centroid_offset, max_centroid_offset, failure)) {
    return false;
  }
  DPSFM_CHECK_OPTION_GE(consistency_tolerance, 0);
  DPSFM_CHECK_OPTION_VALUE(grid_ratio > 1.01 && grid_ratio < 3, grid_ratio);
  DPSFM_CHECK_OPTION_GE(num_refine, 0);
  DPSFM_CHECK_OPTION_GE(min_abs_radius_px, 0);
  DPSFM_CHECK_OPTION_VALUE(trim_fraction >= 0 && trim_fraction < 1,
                           trim_fraction);
  DPSFM_CHECK_OPTION_GE(min_patches, 3);
  DPSFM_CHECK_OPTION_GE(num_bootstrap, 0);
  DPSFM_CHECK_OPTION_GT(max_relative_uncertainty, 0);
  DPSFM_CHECK_OPTION_GE(min_improvement_over_translating_disk, 1);
  DPSFM_CHECK_NESTED_OPTIONS(blur);
  DPSFM_CHECK_OPTION_VALUE(num_threads == -1 || num_threads > 0, num_threads);
  return true;
}

namespace {

// FitSplitProfile on the patches `members` of `searches`.
SplitProfileFit FitProfile(ProfileSearches* searches,
                           const std::vector<int>& members,
                           const SplitProfileFitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  SplitProfileFit fit;
  fit.translating_disk_centroid_offset =
      TranslatingDiskPsf::CentroidOffsetPerRadius();
  fit.params.split_exponent = 1;
  fit.centroid_offset = fit.translating_disk_centroid_offset;
  // Until determined, the data allow any profile.
  fit.consistent_low = 0;
  fit.consistent_high = std::numeric_limits<double>::infinity();
  auto finish = [&]() {
    fit.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
            .count();
    return fit;
  };
  if (members.empty()) {
    fit.reason = "no patches";
    return finish();
  }
  const bool known = RadiiKnown(searches->Patches());
  fit.self_calibrated = !known;
  ProfileSearch search(searches, members, known, options);
  fit.num_patches = static_cast<int>(search.Usable().size());
  if (fit.num_patches < options.min_patches) {
    fit.reason = TooFewUsablePatches(
        fit.num_patches, static_cast<int>(members.size()), options);
    return finish();
  }

  const PathCurve curve = search.SearchPath();
  fit.centroid_offsets.clear();
  for (const double x : curve.xs) fit.centroid_offsets.push_back(std::exp(x));
  fit.criterion = curve.ys;
  fit.at_edge = curve.at_edge || !std::isfinite(curve.best);
  if (fit.at_edge) {
    fit.reason = search.WhyAtEdge(curve);
    return finish();
  }
  SetFittedProfile(curve.best, search.BootstrapSolutions(curve.best), &fit);
  if (!known) WidenToConsistentRange(search, curve, options, &fit);

  const Evaluation& at_fit = search.Evaluate(curve.best);
  if (!known) WeighTranslatingDisk(&search, at_fit, options, &fit);
  search.SetResiduals(at_fit, &fit);
  Conclude(search.Criterion(at_fit, search.Usable()), options, &fit);
  return finish();
}

}  // namespace

ProfileSearchCache::ProfileSearchCache() : impl_(new Impl) {}
ProfileSearchCache::~ProfileSearchCache() = default;

int ProfileSearchCache::NumCrops() const { return impl_->crops.Size(); }

SplitProfileFit FitSplitProfile(const std::vector<ProfilePatch>& patches,
                                const SplitProfileFitOptions& options) {
  DPSFM_CHECK_OPTIONS(options, "SplitProfileFitOptions");
  ProfileSearches searches(patches, options, nullptr);
  return FitProfile(&searches, Indices(patches.size()), options);
}

std::vector<PatchBlurEstimate> EstimateProfilePatches(
    const DPPsfModel& psf,
    const BlurEstimationOptions& blur,
    const std::vector<const ProfilePatch*>& patches,
    int num_threads,
    std::vector<PreparedBlurPatch>* prepared) {
  std::vector<PatchBlurEstimate> estimates(patches.size());
  if (patches.empty()) return estimates;
  const PatchBlurEstimator estimator(
      psf, blur, patches[0]->left.size(), num_threads);
  const int n = static_cast<int>(patches.size());
  const bool prepare = prepared->empty();
  if (prepare) prepared->resize(n);
  DPSFM_CHECK_EQ(static_cast<int>(prepared->size()), n)
      << "prepared patches of another list";
  // A patch the estimator cannot take (a failed DPSFM_CHECK) is invalid;
  // anything else thrown ends the calibration (ParallelFor).
  ParallelFor(n, num_threads, [&](int i) {
    try {
      if (prepare) {
        (*prepared)[i] = estimator.Prepare(patches[i]->left, patches[i]->right);
      }
      estimates[i] = estimator.Estimate((*prepared)[i]);
      if (estimates[i].at_bound || !std::isfinite(estimates[i].radius_px)) {
        estimates[i].valid = false;
      }
    } catch (const CheckFailure&) {
      estimates[i].valid = false;
    }
  });
  return estimates;
}

std::vector<ProfilePatch> ExtractProfilePatches(const cv::Mat& gray_left,
                                                const cv::Mat& gray_right,
                                                int patch_size,
                                                int stride,
                                                int border,
                                                double known_radius_px,
                                                double min_texture_snr) {
  DPSFM_CHECK(patch_size > 0 && stride > 0 && border >= 0)
      << "invalid patch geometry";
  const PatchScreening screening(gray_left, gray_right);
  const int crop = patch_size + 2 * border;
  std::vector<ProfilePatch> patches;
  for (int y = 0; y + crop <= gray_left.rows; y += stride) {
    for (int x = 0; x + crop <= gray_left.cols; x += stride) {
      const cv::Rect rect(x, y, crop, crop);
      if (screening.TextureSnr(rect) < min_texture_snr) continue;
      ProfilePatch patch;
      patch.left = gray_left(rect).clone();
      patch.right = gray_right(rect).clone();
      patch.known_radius_px = known_radius_px;
      patch.x_fraction = (x + 0.5 * crop) / gray_left.cols;
      patch.y_fraction = (y + 0.5 * crop) / gray_left.rows;
      patches.push_back(patch);
    }
  }
  return patches;
}

SplitProfileCalibration CalibrateSplitProfile(
    const std::vector<ProfilePatch>& patches,
    int num_bands,
    const SplitProfileFitOptions& options,
    double min_band_difference,
    bool bands_when_frame_fits,
    ProfileSearchCache* cache) {
  DPSFM_CHECK_GE(num_bands, 1);
  DPSFM_CHECK_OPTIONS(options, "SplitProfileFitOptions");
  SplitProfileCalibration calibration;
  // The bands' fits read the frame's searches of their patches.
  ProfileSearches searches(patches, options, cache);
  calibration.frame = FitProfile(&searches, Indices(patches.size()), options);
  std::ostringstream summary;
  summary << "whole frame: " << calibration.frame.reason;
  if (num_bands == 1 ||
      (!bands_when_frame_fits && calibration.frame.determined)) {
    calibration.summary = summary.str();
    searches.CountSearches(&calibration);
    return calibration;
  }
  std::vector<std::vector<int>> by_band(num_bands);
  for (size_t i = 0; i < patches.size(); ++i) {
    const int band =
        std::max(0,
                 std::min(num_bands - 1,
                          static_cast<int>(patches[i].x_fraction * num_bands)));
    by_band[band].push_back(static_cast<int>(i));
  }
  bool all_determined = true;
  bool significant = false;  // some band's interval excludes the frame's
  double largest_difference = 0;
  for (int b = 0; b < num_bands; ++b) {
    calibration.bands.push_back(FitProfile(&searches, by_band[b], options));
    const SplitProfileFit& fit = calibration.bands.back();
    summary << "; band " << b + 1 << " of " << num_bands << ": "
            << (fit.determined ? "" : "not determined, ") << fit.reason;
    all_determined = all_determined && fit.determined;
    if (fit.determined && calibration.frame.determined) {
      const double difference =
          std::abs(fit.centroid_offset / calibration.frame.centroid_offset - 1);
      largest_difference = std::max(largest_difference, difference);
      const double c = calibration.frame.centroid_offset;
      if (difference > min_band_difference &&
          (c < fit.centroid_offset_ci_low || c > fit.centroid_offset_ci_high)) {
        significant = true;
      }
    }
  }
  // Bands when they differ, or when only they are determined (a profile
  // that changes across the frame fits no single one well). Without a
  // whole-frame profile, a band the data leave open (a few patches) takes
  // the geometric mean of its determined neighbours' centroid offsets (the
  // profile changes smoothly across the frame), when two or more bands are
  // determined.
  int num_determined = 0;
  for (const SplitProfileFit& fit : calibration.bands) {
    num_determined += fit.determined ? 1 : 0;
  }
  if (!all_determined && !calibration.frame.determined && num_determined >= 2) {
    for (int b = 0; b < num_bands; ++b) {
      SplitProfileFit& fit = calibration.bands[b];
      if (fit.determined) continue;
      double log_sum = 0;
      int count = 0;
      double low = std::numeric_limits<double>::infinity(), high = 0;
      for (int step : {-1, 1}) {
        for (int n = b + step; n >= 0 && n < num_bands; n += step) {
          const SplitProfileFit& neighbour = calibration.bands[n];
          if (neighbour.determined &&
              neighbour.reason.find("interpolated") == std::string::npos) {
            log_sum += std::log(neighbour.centroid_offset);
            low = std::min(low, neighbour.consistent_low);
            high = std::max(high, neighbour.consistent_high);
            ++count;
            break;
          }
        }
      }
      fit = SplitProfileFit();
      fit.determined = true;
      fit.self_calibrated = calibration.frame.self_calibrated;
      fit.centroid_offset = std::exp(log_sum / count);
      fit.params = SplitProfileParams::ForCentroidOffset(fit.centroid_offset);
      // What its neighbours allow (the profile changes smoothly).
      fit.centroid_offset_ci_low = fit.consistent_low = low;
      fit.centroid_offset_ci_high = fit.consistent_high = high;
      std::ostringstream reason;
      reason << "centroid offset " << fit.centroid_offset
             << " R interpolated from the neighbouring bands";
      fit.reason = reason.str();
      summary << "; band " << b + 1 << " " << fit.reason;
    }
    all_determined = true;
  }
  calibration.banded =
      all_determined && (!calibration.frame.determined || significant);
  summary << (calibration.banded ? "; the profile changes across the frame ("
                                 : "; one profile for the whole frame (")
          << "largest band difference in centroid offset "
          << std::lround(1000 * largest_difference) / 10.0 << " %)";
  calibration.summary = summary.str();
  searches.CountSearches(&calibration);
  return calibration;
}

}  // namespace dpsfm
