// The searches' transforms: RealDft (the build's backend, OpenCV's or
// FFTW's) against cv::dft in CCS packing, its cheapest form, at the
// DFT sizes the kernel grids use (FastDftSize) and a few the coarse search
// gets from cv::getOptimalDFTSize, for the work one blur-refinement node
// does: a forward transform of a patch whose last third of rows is padding,
// a spectrum product, and an inverse transform of which five sixths of the
// rows are kept. Prints microseconds per node (median of 5 rounds), the
// ratio and, with FFTW, how RealDft runs each size's column passes here;
// never asserts.
//
//   real_dft_bench [--rounds N]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>

#include "bench_timing.h"
#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/optics/real_dft.h"

namespace {

using namespace dpsfm;

using bench::Now;

// Microseconds per call of `work`, the median of `rounds` rounds.
template <typename Work>
double MedianMicroseconds(int rounds, int calls, Work work) {
  return bench::MedianOf(rounds, [&] {
    const double start = Now();
    for (int i = 0; i < calls; ++i) work();
    return 1e6 * (Now() - start) / calls;
  });
}

#ifdef DPSFM_WITH_FFTW
const char* PassName(RealDft::ColumnPass pass) {
  switch (pass) {
    case RealDft::ColumnPass::kApart:
      return "apart";
    case RealDft::ColumnPass::kThroughColumns:
      return "through columns";
    case RealDft::ColumnPass::kInPlace:
      return "in place";
  }
  return "?";
}

#endif

}  // namespace

int main(int argc, char** argv) {
  int rounds = 5;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--rounds") == 0) rounds = std::atoi(argv[++i]);
  }
  std::printf(
      "One refinement node: forward (2/3 of the rows nonzero), product, "
      "inverse (5/6 of the rows), us, median of %d rounds\n",
      rounds);
  std::printf(
      "| size | cv::dft (CCS) | RealDft (%s) | cv / RealDft | column pass "
      "(forward, inverse) |\n|---|---|---|---|---|\n",
      RealDftBackend());
  const std::vector<int> sizes = {36, 40, 45, 48, 50, 54, 60, 64,
                                  72, 80, 96, 100, 128, 144};
  for (const int n : sizes) {
    const cv::Size size(n, n);
    const int nonzero = 2 * n / 3, kept = 5 * n / 6;
    cv::Mat image = cv::Mat::zeros(size, CV_32FC1);
    cv::RNG rng(n);
    rng.fill(image.rowRange(0, nonzero), cv::RNG::UNIFORM, -1.0, 1.0);
    cv::Mat kernel = cv::Mat::zeros(size, CV_32FC1);
    rng.fill(kernel, cv::RNG::UNIFORM, 0.0, 1.0);
    const int calls = std::max(50, 2000000 / (n * n));

    cv::Mat cv_kernel, cv_spectrum, cv_product, cv_back;
    cv::dft(kernel, cv_kernel);
    const double cv_us = MedianMicroseconds(rounds, calls, [&] {
      cv::dft(image, cv_spectrum, 0, nonzero);
      cv::mulSpectrums(cv_spectrum, cv_kernel, cv_product, 0);
      cv::dft(cv_product,
              cv_back,
              cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT,
              kept);
    });

    const RealDft dft(size);
    cv::Mat kernel_spectrum, spectrum, product, back;
    dft.Forward(kernel, n, &kernel_spectrum);
    const double dft_us = MedianMicroseconds(rounds, calls, [&] {
      dft.Forward(image, nonzero, &spectrum);
      cv::mulSpectrums(spectrum, kernel_spectrum, product, 0);
      dft.Inverse(&product, cv::Range(0, kept), &back);
    });
    std::printf("| %d%s | %.1f | %.1f | %.2f | %s, %s |\n",
                n,
                FastDftSize(n) == n ? "" : " (coarse)",
                cv_us,
                dft_us,
                cv_us / dft_us,
#ifdef DPSFM_WITH_FFTW
                PassName(dft.ColumnPassOf(true)),
                PassName(dft.ColumnPassOf(false)));
#else
                "-", "-");
#endif
  }
  return 0;
}
