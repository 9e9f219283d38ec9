// One view's search for usable patches (DPScaleEstimator::AddView's steps 1
// to 4, view_patches.h) as an object: at a search bound, the patch grid with
// each patch's depth, the screening, the blur-search share, the blur search,
// and the usable patches as samples (the others counted by reason). An
// automatic bound whose patches' blur lies beyond it is grown and the view
// searched again (SearchBoundReached, GrownSearchBound), as soon as a share
// of its patches settles it (EarlyGrownSearchBound).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_grid.h"
#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/scale/scale_estimator.h"
#include "dpsfm/core/scale/view_patches.h"

namespace dpsfm {

class ViewSearch {
 public:
  // Everything given must outlive this. `geometry`: the first bound's
  // (ViewPatchGeometry); `view_index`: the samples' view.
  ViewSearch(const DPView& view,
             const WorkingView& working,
             const PatchGeometry& geometry,
             const DPPsfField& field,
             const DPScaleOptions& options,
             BlurSearchEstimators* estimators,
             int view_index);

  // Searches at the first bound and at each grown one; what the last
  // bound's search found stays.
  void Run();

  // The last bound's geometry and counts, and the growths, in *summary.
  void Summarize(DPViewSummary* summary) const;

  const PatchGeometry& Geometry() const { return geometry_; }
  int Border() const { return border_; }
  const std::vector<PatchCandidate>& Candidates() const { return candidates_; }
  const ViewBlurSearch& Search() const { return search_; }
  // The usable patches, and each one's index among the candidates.
  std::vector<PatchSample> TakeSamples() { return std::move(samples_); }
  const std::vector<int>& SampleCandidates() const { return sample_candidate_; }

 private:
  // Steps 1 and 2 at the current bound; nothing searched yet.
  void Prepare();
  // Step 3 on the chosen patches that `which` marks (all: null).
  void SearchPatches(const std::vector<char>* which);
  // The bound that the search of the growth share settles on (0: none).
  double EarlyGrowth();
  // Step 3 on the rest, then step 4; the bound the whole search asks for
  // (0: this one stands).
  double Conclude();

  const DPView& view_;
  const WorkingView& working_;
  const DPPsfField& field_;
  const DPScaleOptions& options_;
  BlurSearchEstimators* const estimators_;
  const int view_index_;
  PatchGeometry geometry_;
  BlurEstimationOptions blur_;
  int border_ = 0;
  int growths_ = 0;
  std::vector<PatchCandidate> candidates_;
  int with_depth_ = 0;
  ViewBlurSearch search_;
  std::map<std::string, int> rejections_;
  std::vector<PatchSample> samples_;
  std::vector<int> sample_candidate_;
};

}  // namespace dpsfm
