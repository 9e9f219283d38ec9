#pragma once

namespace dpsfm {

// `colmap dp_psf_calibrator`: fits the DP split profile of one camera body
// + lens from DP captures of a textured planar target at measured
// distances (docs/user-guide.md, "Calibrating the DP PSF"), and writes the
// profile file dp_scale_estimator reads with --DPScaleEstimator.psf_model
// calibrated. Returns EXIT_SUCCESS, or EXIT_FAILURE after one error line.
int RunDPPsfCalibrator(int argc, char** argv);

}  // namespace dpsfm
