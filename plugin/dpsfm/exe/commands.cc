#include "dpsfm/exe/commands.h"

#include "dpsfm/exe/dp_lens_data.h"
#include "dpsfm/exe/dp_psf_calibrator.h"
#include "dpsfm/exe/dp_scale_estimator.h"

namespace dpsfm {

std::vector<std::pair<std::string, std::function<int(int, char**)>>>
Commands() {
  // Alphabetical, as COLMAP lists its own.
  return {{"dp_lens_data", &RunDPLensData},
          {"dp_psf_calibrator", &RunDPPsfCalibrator},
          {"dp_scale_estimator", &RunDPScaleEstimator}};
}

}  // namespace dpsfm
