// `colmap dp_lens_data`: what dp_scale_estimator will take as each image's
// lens data, and from where, listed as a lens.csv.
#pragma once

namespace dpsfm {

// Returns EXIT_SUCCESS, or EXIT_FAILURE after one error line.
int RunDPLensData(int argc, char** argv);

}  // namespace dpsfm
