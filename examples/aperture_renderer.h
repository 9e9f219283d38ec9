// A second DP renderer that shares no code with the estimator's optics: no
// kernel, no DPPsfModel, no radius formula of the core. It follows the light
// instead: each pixel of the sharp image sends its light through sample
// points of the lens's unit aperture, each point's share landing on the
// sensor at the pixel plus its signed blur radius times the point (a thin
// lens focused elsewhere images the aperture to a disk of that radius,
// inverted in front of the focus), and the pixel that point falls on
// collects it; the DP photodiodes split that light by the half of the
// aperture it came through. The end-to-end tests run the
// estimator on scenes it renders, so that their accuracy is not that of a
// model inverting its own kernels.
#pragma once

#include <opencv2/core.hpp>

namespace dpsfm {
namespace examples {

struct ApertureRenderOptions {
  // Aperture points per pixel of blur radius along each axis: the points
  // (a square lattice over the disk) land this many per pixel, so a pixel
  // collects its area's share of the light to within the lattice's step.
  int subsamples_per_pixel = 2;
  // The share of a half aperture's light that reaches the other half's
  // photodiode (0: a sharp split between the halves; 0.5: no DP signal).
  double crosstalk = 0.1;
  int num_threads = -1;  // -1: all
};

// The signed blur radius in pixels of a point at `depth_mm` from a thin lens
// of focal length `focal_length_mm` and f-number `f_number` focused at
// `focus_mm` (both measured from the lens), on pixels of `pixel_pitch_mm`:
// positive beyond the focus. Written from image distances: the sensor sits
// where the focus images (v_g), the point images at v_z, and the cone from
// the aperture (diameter f / N) to v_z meets the sensor in a disk of
// diameter (f / N) (v_g - v_z) / v_z. depth_mm may be infinite.
double ThinLensBlurRadiusPx(double focal_length_mm,
                            double f_number,
                            double pixel_pitch_mm,
                            double focus_mm,
                            double depth_mm);

// The left and right DP views (each half the light; same type as `sharp`,
// CV_32FC1 or CV_32FC3) of `sharp` whose pixels have the signed blur radii
// `radius_px` (CV_32FC1). The left photodiode takes the light of the
// aperture half at -x, the right that at +x (each less the crosstalk). Light
// is added, not occluded; what lands outside the frame is lost.
void RenderDPByApertureSampling(const cv::Mat& sharp,
                                const cv::Mat& radius_px,
                                const ApertureRenderOptions& options,
                                cv::Mat* left,
                                cv::Mat* right);

}  // namespace examples
}  // namespace dpsfm
