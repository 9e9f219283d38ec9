#include <algorithm>
#include <cmath>
#include <vector>

#include "dpsfm/core/blur/blur_search_internal.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace internal {

std::vector<float> CoarseBandTerms(const BlurTables& t,
                                   const cv::Mat& gl,
                                   const cv::Mat& gr) {
  const int height = t.patch_size.height;
  const int width = t.patch_size.width;
  const int num_band = static_cast<int>(t.band_rows.size());
  std::vector<float> data(4 * num_band);
  cv::Mat wl = cv::Mat::zeros(t.dft_size, CV_32FC1);
  cv::Mat wr = cv::Mat::zeros(t.dft_size, CV_32FC1);
  for (int y = 0; y < height; ++y) {
    const float* l = gl.ptr<float>(y);
    const float* r = gr.ptr<float>(y);
    float* ol = wl.ptr<float>(y);
    float* orr = wr.ptr<float>(y);
    const float wy = t.window_y[y];
    for (int x = 0; x < width; ++x) {
      const float w = wy * t.window_x[x];
      ol[x] = w * l[x];
      orr[x] = w * r[x];
    }
  }
  // The band lies in the half spectrum (u <= nc / 2).
  cv::Mat fl, fr;
  t.dft->Forward(wl, height, &fl);
  t.dft->Forward(wr, height, &fr);
  for (int k = 0; k < num_band; ++k) {
    const cv::Vec2f a = fl.at<cv::Vec2f>(t.band_rows[k], t.band_cols[k]);
    const cv::Vec2f b = fr.at<cv::Vec2f>(t.band_rows[k], t.band_cols[k]);
    // D = G_l conj(G_r); loss_k = |G_l|^2 |H_r|^2 + |G_r|^2 |H_l|^2
    //                            - 2 Re(D K).
    data[4 * k + 0] = a[0] * a[0] + a[1] * a[1];
    data[4 * k + 1] = b[0] * b[0] + b[1] * b[1];
    data[4 * k + 2] = -2.f * (a[0] * b[0] + a[1] * b[1]);
    data[4 * k + 3] = 2.f * (a[1] * b[0] - a[0] * b[1]);
  }
  return data;
}

CoarseCurve CoarseSearch(const BlurTables& t,
                         const std::vector<float>& band_terms,
                         double sigma2_hp) {
  DPSFM_CHECK_EQ(band_terms.size(), 4 * t.band_rows.size());
  const Eigen::Map<const Eigen::VectorXf> data(
      band_terms.data(), static_cast<Eigen::Index>(band_terms.size()));
  const Eigen::VectorXf coarse_raw_f = t.coarse_table * data;
  const int num_coarse = static_cast<int>(t.coarse_nodes.size());
  std::vector<double> coarse_raw(num_coarse);
  double sigma2_coarse = sigma2_hp;
  for (int i = 0; i < num_coarse; ++i) {
    coarse_raw[i] = std::max(0.0, coarse_raw_f[i] * t.coarse_normaliser);
    sigma2_coarse =
        std::min(sigma2_coarse, coarse_raw[i] / t.coarse_noise_gain[i]);
  }
  if (!t.options.subtract_noise_floor) sigma2_coarse = 0;
  CoarseCurve curve;
  curve.loss.resize(num_coarse);
  std::vector<double>& coarse = curve.loss;
  for (int i = 0; i < num_coarse; ++i) {
    coarse[i] = coarse_raw[i] - sigma2_coarse * t.coarse_noise_gain[i];
  }
  for (int i = 0; i < num_coarse; ++i) {
    const bool left_ok = i == 0 || coarse[i] <= coarse[i - 1];
    const bool right_ok = i == num_coarse - 1 || coarse[i] <= coarse[i + 1];
    if (left_ok && right_ok) curve.minima.push_back(i);
  }
  std::sort(curve.minima.begin(), curve.minima.end(), [&](int a, int b) {
    if (coarse[a] != coarse[b]) return coarse[a] < coarse[b];
    return std::abs(t.Radius(t.coarse_nodes[a])) <
           std::abs(t.Radius(t.coarse_nodes[b]));
  });
  curve.min = coarse[curve.minima.front()];
  curve.max = *std::max_element(coarse.begin(), coarse.end());
  return curve;
}

}  // namespace internal
}  // namespace dpsfm
