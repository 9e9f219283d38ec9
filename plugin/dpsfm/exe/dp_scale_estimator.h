#pragma once

namespace dpsfm {

// `colmap dp_scale_estimator`: estimates the metric scale of a COLMAP
// reconstruction from dual-pixel views and rescales the workspace to metres.
// Options: docs/user-guide.md ("Options"); --help lists them all.
// Returns EXIT_SUCCESS, or EXIT_FAILURE after one error line on stderr.
int RunDPScaleEstimator(int argc, char** argv);

}  // namespace dpsfm
