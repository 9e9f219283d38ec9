// The patch grid of a view and the depth statistics of each patch (the
// first step of DPScaleEstimator::AddView): interiors on the working frame,
// and per patch the median depth, its relative spread (to reject patches
// across depth edges) and its relative variance (in the confidence).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace dpsfm {

// A scale-ambiguous depth sample: DP-frame pixel coordinates (pixel centres
// at integer coordinates) and z' in model units (sparse mode).
struct DepthPoint {
  double x = 0;
  double y = 0;
  double depth = 0;
};

struct DepthStats {
  bool ok = false;
  double median = 0;
  double relative_spread = 0;    // (p90 - p10) / median
  double relative_variance = 0;  // var(z) / median^2
};

// Median, 10-90 % spread and variance of positive finite depths (reorders
// *values).
DepthStats DepthStatsOf(std::vector<float>* values);

struct PatchCandidate {
  cv::Rect interior;  // working-frame pixels
  DepthStats depth;
  std::string reject;  // why it was dropped before screening; "" = kept
};

// The interior with `border` px on every side: the crop the screening, the
// blur search and the crop store read around a patch.
inline cv::Rect PatchCrop(const cv::Rect& interior, int border) {
  return cv::Rect(interior.x - border,
                  interior.y - border,
                  interior.width + 2 * border,
                  interior.height + 2 * border);
}

// Interiors of `patch` px every `stride` px, each with `border` px of frame
// around it, over a working frame of `size`, on a lattice centred in the
// frame whatever the border (a larger search bound drops edge positions and
// moves none).
std::vector<PatchCandidate> MakePatchGrid(const cv::Size& size,
                                          int patch,
                                          int stride,
                                          int border);

struct PatchDepthOptions {
  // Dense maps: fraction of a patch's depth pixels that must be valid.
  double min_coverage = 0.5;
  // Sparse points: how many must fall inside a patch.
  int min_points = 3;
  // Patches whose relative depth spread exceeds this are across an edge.
  double max_relative_spread = 0.1;
  // Candidates measured in parallel (-1: all OpenMP offers); each
  // candidate's statistics are the same on any number.
  int num_threads = 1;
};

// Fills each candidate's depth from a dense map (CV_32FC1 of any size over
// the DP frame) or, if it is empty, from depth points in DP-frame pixels,
// and rejects ("without depth", "across a depth edge") what does not
// qualify. sx, sy: working / frame scale per axis.
void MeasurePatchDepths(const cv::Mat& depth,
                        const std::vector<DepthPoint>& points,
                        const cv::Size& frame_size,
                        double sx,
                        double sy,
                        const PatchDepthOptions& options,
                        std::vector<PatchCandidate>* candidates);

}  // namespace dpsfm
