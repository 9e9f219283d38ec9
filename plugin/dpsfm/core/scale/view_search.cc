#include "dpsfm/core/scale/view_search.h"

#include <utility>

namespace dpsfm {

ViewSearch::ViewSearch(const DPView& view,
                       const WorkingView& working,
                       const PatchGeometry& geometry,
                       const DPPsfField& field,
                       const DPScaleOptions& options,
                       BlurSearchEstimators* estimators,
                       int view_index)
    : view_(view),
      working_(working),
      field_(field),
      options_(options),
      estimators_(estimators),
      view_index_(view_index),
      geometry_(geometry),
      blur_(options.blur) {}

void ViewSearch::Run() {
  for (;;) {
    Prepare();
    double grown = EarlyGrowth();
    if (!(grown > 0)) grown = Conclude();
    if (!(grown > 0)) return;
    // The patches stay as they were (an explicit max_radius_px keeps them
    // too): larger ones straddle more depth edges and leave fewer patches
    // (on box/002, 13 px patches gave 57 searched and a DP cue 26 % low).
    geometry_.max_radius_px = grown;
    ++growths_;
  }
}

void ViewSearch::Prepare() {
  blur_.max_radius_px = geometry_.max_radius_px;
  border_ = BlurSearchBorder(field_, blur_, geometry_.max_radius_px);
  candidates_ = PatchesWithDepth(view_, working_, geometry_, border_, options_);
  with_depth_ = 0;
  for (const PatchCandidate& c : candidates_) with_depth_ += c.reject.empty();
  search_ = ChooseViewSearch(
      working_, candidates_, border_, with_depth_ > 0, options_);
}

void ViewSearch::SearchPatches(const std::vector<char>* which) {
  SearchChosenPatches(working_,
                      candidates_,
                      field_,
                      blur_,
                      border_,
                      geometry_.patch_size,
                      options_,
                      estimators_,
                      which,
                      &search_);
}

double ViewSearch::EarlyGrowth() {
  if (!SearchBoundMayGrow(growths_, options_)) return 0;
  const std::vector<char> share = GrowthSample(search_);
  SearchPatches(&share);
  if (search_.num_searched == 0) return 0;
  return EarlyGrownSearchBound(search_.num_searched,
                               PatchesAtSearchBound(search_),
                               growths_,
                               geometry_,
                               working_.left.size(),
                               field_,
                               blur_,
                               options_);
}

double ViewSearch::Conclude() {
  SearchPatches(nullptr);
  rejections_.clear();
  sample_candidate_.clear();
  samples_ = ViewSamples(candidates_,
                         search_,
                         working_,
                         field_,
                         geometry_,
                         view_index_,
                         options_,
                         &rejections_,
                         &sample_candidate_);
  if (!SearchBoundReached(search_.num_searched,
                          PatchesAtSearchBound(search_),
                          growths_,
                          options_)) {
    return 0;
  }
  return GrownSearchBound(geometry_, working_.left.size(), field_, blur_);
}

void ViewSearch::Summarize(DPViewSummary* summary) const {
  summary->search_bound_growths = growths_;
  summary->patch_size = geometry_.patch_size;
  summary->stride = geometry_.stride;
  summary->max_radius_px = geometry_.max_radius_px;
  summary->patches_tried = static_cast<int>(candidates_.size());
  summary->patches_with_depth = with_depth_;
  summary->patches_searched = search_.num_searched;
  summary->patches_beyond_bound = PatchesAtSearchBound(search_);
  summary->patches_valid = static_cast<int>(samples_.size());
  // Counted among the rejections by their reason (ViewSamples).
  const auto undetermined = rejections_.find(kBlurUndetermined);
  summary->patches_undetermined =
      undetermined == rejections_.end() ? 0 : undetermined->second;
  summary->rejections.assign(rejections_.begin(), rejections_.end());
}

}  // namespace dpsfm
