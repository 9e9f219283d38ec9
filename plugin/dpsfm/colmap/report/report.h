// The JSON report of a run (docs/user-guide.md, "Reading the report": the
// outputs the command promises, plus what helps a user judge the result:
// intervals, per-view reasons, lens sources, plots, timings).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// Version of the plugin, written into reports and the scale record.
std::string DPSFMVersion();

struct RunTimings {
  // Loading DP views and depths, and reducing the frames to the working
  // resolution (DPScaleEstimator::ReduceFrame): the reads' own time.
  double read = 0;
  double read_wait = 0;  // of it, not hidden behind the blur search
  double blur = 0;       // per-patch blur estimation (inside AddView)
  double linear = 0;
  double intensity = 0;
  double rescale = 0;
  double total = 0;
};

nlohmann::json MakeReport(const DPScaleResult& result,
                          const std::vector<ViewSource>& sources,
                          const std::vector<DPViewSummary>& summaries,
                          const RunTimings& timings);

// Writes JSON to `path` atomically (colmap/util/durable_file.h: temporary
// file, fsync, rename), so a reader never sees half a report. Throws
// InputError on failure.
void WriteJsonFile(const std::string& path, const nlohmann::json& json);

}  // namespace dpsfm
