#include "nav/vision/matching.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <limits>
#include <vector>

namespace nav::vision {

PutativeMatches match_unconstrained(const ImageFeatures& features_i,
                                    const ImageFeatures& features_j,
                                    const MatchingOptions& options) {
  PutativeMatches out;
  const int n_i = features_i.descriptors.rows;
  const int n_j = features_j.descriptors.rows;
  if (n_i == 0 || n_j == 0 || features_i.descriptors.cols != features_j.descriptors.cols) {
    return out;
  }
  cv::Mat a, b;
  features_i.descriptors.convertTo(a, CV_32F);
  features_j.descriptors.convertTo(b, CV_32F);
  // Squared distances |a|^2 + |b|^2 - 2 a.b for all pairs by one matrix product.
  cv::Mat cross;
  cv::gemm(a, b, -2.0, cv::noArray(), 0.0, cross, cv::GEMM_2_T);
  cv::Mat a2, b2;
  cv::reduce(a.mul(a), a2, 1, cv::REDUCE_SUM);
  cv::reduce(b.mul(b), b2, 1, cv::REDUCE_SUM);
  out.descriptor_comparisons = static_cast<std::size_t>(n_i) * static_cast<std::size_t>(n_j);

  std::vector<int> best_i_of_j(static_cast<std::size_t>(n_j), -1);
  std::vector<float> best_d2_of_j(static_cast<std::size_t>(n_j),
                                  std::numeric_limits<float>::max());
  std::vector<int> best_j(static_cast<std::size_t>(n_i), -1);
  std::vector<float> best_d2(static_cast<std::size_t>(n_i)), second_d2(static_cast<std::size_t>(n_i));
  for (int i = 0; i < n_i; ++i) {
    const float* row = cross.ptr<float>(i);
    const float ai = a2.at<float>(i);
    float d1 = std::numeric_limits<float>::max(), d2 = d1;
    int j1 = -1;
    for (int j = 0; j < n_j; ++j) {
      const float d = std::max(0.0f, ai + b2.at<float>(j) + row[j]);
      if (d < d1) {
        d2 = d1;
        d1 = d;
        j1 = j;
      } else if (d < d2) {
        d2 = d;
      }
      if (d < best_d2_of_j[static_cast<std::size_t>(j)]) {
        best_d2_of_j[static_cast<std::size_t>(j)] = d;
        best_i_of_j[static_cast<std::size_t>(j)] = i;
      }
    }
    best_j[static_cast<std::size_t>(i)] = j1;
    best_d2[static_cast<std::size_t>(i)] = d1;
    second_d2[static_cast<std::size_t>(i)] = d2;
  }
  const double ratio2 = options.ratio * options.ratio;
  const float max_d2 = options.max_distance * options.max_distance;
  for (int i = 0; i < n_i; ++i) {
    const auto si = static_cast<std::size_t>(i);
    const int j = best_j[si];
    if (j < 0) continue;
    if (n_j > 1 && !(best_d2[si] < ratio2 * second_d2[si])) continue;
    if (best_d2[si] > max_d2) continue;
    if (options.mutual && best_i_of_j[static_cast<std::size_t>(j)] != i) continue;
    out.matches.push_back({i, j, std::sqrt(best_d2[si])});
  }
  return out;
}

}  // namespace nav::vision
