// The words of a refusal: the core says why no scale is reported as codes
// and numbers (core/scale/refusal.h); this is the one place that words
// them for users, naming the options (--DPScaleEstimator.*) that may turn a
// refusal into an answer. A refusal has two forms: its line (the reason that
// decided, with its numbers, and at most two fixes that address it: the
// run's "no scale: ..." error line, its checkpoint log, the report's reason
// and the plots) and its account (everything else: the other causes, patch
// counts and rejections, every remedy: the log before the error line and
// the report's reason_detail).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "dpsfm/core/scale/refusal.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// The longest RefusalLine: the command's error line adds "ERROR:
// dp_scale_estimator: no scale: " and "; nothing was changed" (58
// characters) and stays within 300.
constexpr std::size_t kRefusalLineMaxChars = 242;

// The refusal's first line ("" for ScaleRefusal::kNone): the reason that
// decided, with its numbers, then at most two fixes that address that
// reason (fewer when they would not fit); at most kRefusalLineMaxChars.
std::string RefusalLine(const DPScaleRefusal& refusal);

// The refusal in full, one sentence a line, the deciding reason first: the
// other causes, where the patches went, and every remedy.
std::vector<std::string> RefusalAccount(const DPScaleRefusal& refusal);

// What happened to the DP PSF (the log's "DP PSF:" line, the report's
// psf.status): the core's psf.status, or, for a translating disk the data
// reject, TranslatingDiskRejectionText (the account's first line).
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
// trust when; `dp_data_answer` false: the DP data alone leave the scale
// open (ScaleRefusal::kScaleOpen), so trusting them is no remedy.
std::string DisagreementAdviceText(const CueRefusal& cues,
                                   bool dp_data_answer = true);
// "the DP data and the recorded focus disagree: 0.318 against 0.583, an
// interval covering both 103.2 % wide (limit 30 %)".
std::string DisagreementCauseText(const CueRefusal& cues);

}  // namespace dpsfm
