// The words of a refusal: the core says why no scale is reported as codes
// and numbers (core/scale/refusal.h); this is the one place that words
// them for users, naming the options (--DPScaleEstimator.*) that may turn a
// refusal into an answer. The run's "no scale: ..." line, its checkpoint
// log, the report's reason and psf.status, and the plots read it from here.
#pragma once

#include <string>

#include "dpsfm/core/scale/refusal.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// The refusal in one sentence ("" for ScaleRefusal::kNone).
std::string RefusalText(const DPScaleRefusal& refusal);

// What happened to the DP PSF (the log's "DP PSF:" line, the report's
// psf.status): the core's psf_status, or, for a translating disk the data
// reject, the refusal's sentence.
std::string PsfStatusText(const DPScaleResult& result);

// How the answer was formed from the cues (the report's cues.how):
// CombinedScale::how, or, when the DP data answered alone, why the recorded
// focus took no part (naming the option that keeps it out).
std::string CombinationText(const DPScaleResult& result);

// The recorded focus as evidence (the log's "Recorded focus:" line, the
// report's focus_check.status): the core's comparison, then ". The answer:
// " and CombinationText when there is one; "" without a recorded focus.
std::string FocusCheckText(const DPScaleResult& result);

// The parts, for tests and for anyone wording one piece alone.
// "too little texture: W of T patches have texture too weak for the sensor
// noise; " when the weak texture leads (PatchAccount::TextureLeads), else "".
std::string LeadingCauseText(const PatchAccount& account);
// " (patches over all views: N tried, M usable; <rejections>)".
std::string PatchSummaryText(const PatchAccount& account);
// "; patches over all views: ... . Typical causes: ..." (the tail of a
// refusal for an undetermined scale).
std::string TypicalCausesText(const PatchAccount& account);
// The options that may turn the refusal into an answer, as "; ..." or "":
// a larger search bound when the patches hit it
// (PatchAccount::SearchBoundLimits).
std::string PatchFixesText(const PatchAccount& account);
// "no view passed selection: ..." and the other failures of the linear
// stage.
std::string LinearFailureText(const LinearFailure& failure);
// Why the DP data alone leave the scale open (without the leading cause).
std::string OpenScaleText(const OpenScale& open);
// An explicitly chosen translating disk that the data reject.
std::string TranslatingDiskRejectionText(const TranslatingDiskRejection& disk);
// The DP data and the recorded focus disagree: both cues, and which to
// trust when.
std::string DisagreementAdviceText(const CueRefusal& cues);

}  // namespace dpsfm
