// The DP forward model as a renderer: from an all-in-focus image, its depth
// and a per-pixel signed blur radius, the left and right DP views a sensor
// with a given PSF profile would record. Used by the example generator, the
// tests and the benchmarks; the estimator itself never renders whole frames.
#pragma once

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"

namespace dpsfm {

struct DPRenderOptions {
  // Width of the blur-radius bins in px. Each bin is rendered as one layer
  // with one kernel pair. Rounding to 0.25 px bins errs by at most 0.125 px
  // and without bias, which averages out over the many patches of a scene,
  // at a third of the cost of 0.1 px bins.
  double radius_step_px = 0.25;

  // How the radius bins are combined.
  enum class Compositing {
    // Sum of every bin blurred by its own kernel: each scene point spreads
    // its light with its own PSF. Exact for surfaces without occlusion, so
    // continuous slanted surfaces stay seamless; at depth edges the blurred
    // foreground does not hide the background (a halo), which only patches
    // straddling the edge see, and the estimator discards those.
    kAdditive,
    // Bins composited back to front with "over": the nearer layer hides
    // what lies behind it. Right at depth edges, but a continuous surface
    // split into bins gets a seam at every bin boundary (each bin's soft
    // edge partly hides its neighbour), which biases blur estimates on
    // slanted surfaces.
    kOcclusionLayers,
  };
  Compositing compositing = Compositing::kAdditive;

  bool Check(std::string* failure = nullptr) const;
};

// sharp: CV_32FC1 or CV_32FC3 all-in-focus image in [0, 1].
// depth: CV_32FC1 depth (any unit) used only to order layers far to near;
//        pixels with depth <= 0 are treated as background at infinity.
// radius_px: CV_32FC1 signed blur radius per pixel (> 0 farther than focus).
// Outputs left and right views of the same type as `sharp`. Each view
// receives half of the light (left + right is the ordinary defocused image).
// See DPRenderOptions::compositing for how occlusion is treated.
void RenderDPViews(const cv::Mat& sharp,
                   const cv::Mat& depth,
                   const cv::Mat& radius_px,
                   const DPPsfModel& psf,
                   const DPRenderOptions& options,
                   cv::Mat* left,
                   cv::Mat* right);

}  // namespace dpsfm
