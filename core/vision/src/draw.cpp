#include "nav/vision/draw.h"

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "nav/vision/camera_model.h"

namespace nav::vision {

namespace {

cv::Point to_cv(const Eigen::Vector2d& p, int x_offset = 0) {
  return {static_cast<int>(std::lround(p.x())) + x_offset, static_cast<int>(std::lround(p.y()))};
}

cv::Scalar colour(int k) {
  static const cv::Scalar palette[] = {{0, 0, 255},   {0, 200, 0},   {255, 0, 0},  {0, 200, 255},
                                       {255, 0, 255}, {255, 255, 0}, {0, 128, 255}, {128, 0, 255}};
  return palette[k % 8];
}

/// Epipolar line of x_i in image j (ideal pixels), clipped to the image: l_j = E^T x_i in
/// normalised coordinates, mapped to pixels by K^-T.
bool epipolar_segment(const Eigen::Matrix3d& E, const CameraIntrinsics& camera,
                      const Eigen::Vector2d& u_i_px, int width, int height, cv::Point* a,
                      cv::Point* b) {
  const Eigen::Vector2d x_i = normalised_from_pixel(camera, u_i_px);
  const Eigen::Vector3d l_norm = E.transpose() * Eigen::Vector3d(x_i.x(), x_i.y(), 1.0);
  Eigen::Matrix3d K_inv = Eigen::Matrix3d::Identity();
  K_inv << 1.0 / camera.fx_px, 0.0, -camera.cx_px / camera.fx_px, 0.0, 1.0 / camera.fy_px,
      -camera.cy_px / camera.fy_px, 0.0, 0.0, 1.0;
  const Eigen::Vector3d l = K_inv.transpose() * l_norm;  // l . [u v 1] = 0 in pixels
  std::vector<cv::Point2d> hits;
  if (std::abs(l.y()) > 1e-12) {
    for (double u : {0.0, static_cast<double>(width - 1)}) {
      const double v = -(l.x() * u + l.z()) / l.y();
      if (v >= 0.0 && v <= height - 1) hits.emplace_back(u, v);
    }
  }
  if (std::abs(l.x()) > 1e-12) {
    for (double v : {0.0, static_cast<double>(height - 1)}) {
      const double u = -(l.y() * v + l.z()) / l.x();
      if (u >= 0.0 && u <= width - 1) hits.emplace_back(u, v);
    }
  }
  if (hits.size() < 2) return false;
  *a = hits[0];
  *b = hits[1];
  return true;
}

}  // namespace

std::vector<SearchBand> search_bands(const ImageFeatures& features_i,
                                     const RegistrationDiagnostics& diagnostics,
                                     const CameraIntrinsics& camera,
                                     const RelativePosePrior* prior, const PccsOptions& options,
                                     int count) {
  std::vector<SearchBand> bands;
  if (prior == nullptr || count <= 0 || features_i.size() == 0) return bands;
  std::vector<int> candidates;
  for (int k : diagnostics.essential.inliers) {
    candidates.push_back(diagnostics.matches.matches[static_cast<std::size_t>(k)].index_i);
  }
  if (candidates.empty()) {
    for (std::size_t k = 0; k < features_i.size(); ++k) candidates.push_back(static_cast<int>(k));
  }
  const int n = std::min<int>(count, static_cast<int>(candidates.size()));
  for (int s = 0; s < n; ++s) {
    const int f = candidates[static_cast<std::size_t>(s) * candidates.size() / static_cast<std::size_t>(n)];
    SearchRegion region;
    try {
      region = search_region(features_i.points_px[static_cast<std::size_t>(f)], camera, *prior, options);
    } catch (const std::invalid_argument&) {
      return bands;  // An unusable prior has no bands to draw.
    }
    SearchBand band;  // Empty when the region is empty: keeps the colour order of the sample.
    band.feature_i = f;
    band.centres_px = region.centres_px;
    for (const Eigen::Matrix2d& S : region.covariances_px2) {
      const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(S).eigenvalues()[1];
      band.half_widths_px.push_back(std::sqrt(region.gate_chi2 * std::max(0.0, largest)));
    }
    bands.push_back(std::move(band));
  }
  return bands;
}

cv::Mat draw_registration(const cv::Mat& image_i_8u, const cv::Mat& image_j_8u,
                          const ImageFeatures& features_i, const ImageFeatures& features_j,
                          const RegistrationDiagnostics& diagnostics,
                          const CameraIntrinsics& camera, const std::vector<SearchBand>& bands,
                          const DrawOptions& options) {
  auto to_bgr = [](const cv::Mat& image) {
    cv::Mat bgr;
    if (image.channels() == 1) {
      cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
    } else {
      bgr = image.clone();
    }
    return bgr;
  };
  const cv::Mat left = to_bgr(image_i_8u), right = to_bgr(image_j_8u);
  const int height = std::max(left.rows, right.rows);
  cv::Mat canvas(height, left.cols + right.cols, CV_8UC3, cv::Scalar(0, 0, 0));
  left.copyTo(canvas(cv::Rect(0, 0, left.cols, left.rows)));
  right.copyTo(canvas(cv::Rect(left.cols, 0, right.cols, right.rows)));
  const int dx = left.cols;
  const int thickness = std::max(1, left.cols / 600);

  // Inlier links (thin, grey-green).
  const auto& inliers = diagnostics.essential.inliers;
  const int n_links = std::min<int>(options.max_inlier_links, static_cast<int>(inliers.size()));
  for (int s = 0; s < n_links; ++s) {
    const std::size_t k = inliers[static_cast<std::size_t>(s) * inliers.size() / static_cast<std::size_t>(n_links)];
    const Match& m = diagnostics.matches.matches[k];
    const cv::Point a = to_cv(features_i.points_px[static_cast<std::size_t>(m.index_i)]);
    const cv::Point b = to_cv(features_j.points_px[static_cast<std::size_t>(m.index_j)], dx);
    cv::line(canvas, a, b, cv::Scalar(120, 200, 120), 1, cv::LINE_AA);
    cv::circle(canvas, a, 2 * thickness, cv::Scalar(0, 255, 0), thickness, cv::LINE_AA);
    cv::circle(canvas, b, 2 * thickness, cv::Scalar(0, 255, 0), thickness, cv::LINE_AA);
  }

  // Search bands (the caller's PCCS regions).
  for (std::size_t b = 0; b < bands.size(); ++b) {
    const SearchBand& band = bands[b];
    const cv::Scalar c = colour(static_cast<int>(b));
    for (std::size_t s = 0; s + 1 < band.centres_px.size(); ++s) {
      cv::line(canvas, to_cv(band.centres_px[s], dx), to_cv(band.centres_px[s + 1], dx), c,
               thickness, cv::LINE_AA);
    }
    for (std::size_t s = 0; s < band.centres_px.size() && s < band.half_widths_px.size(); ++s) {
      cv::circle(canvas, to_cv(band.centres_px[s], dx),
                 std::max(1, static_cast<int>(std::lround(band.half_widths_px[s]))), c, 1,
                 cv::LINE_AA);
    }
    if (band.feature_i >= 0 && static_cast<std::size_t>(band.feature_i) < features_i.size()) {
      cv::drawMarker(canvas, to_cv(features_i.points_px[static_cast<std::size_t>(band.feature_i)]),
                     c, cv::MARKER_CROSS, 10 * thickness, thickness);
    }
  }

  // Epipolar lines of a spread sample of inliers' features of image i.
  if (diagnostics.essential.ok) {
    const int n_lines = std::min<int>(options.max_epipolar_lines, static_cast<int>(inliers.size()));
    for (int s = 0; s < n_lines; ++s) {
      const std::size_t k = inliers[static_cast<std::size_t>(s) * inliers.size() / static_cast<std::size_t>(n_lines)];
      const Match& m = diagnostics.matches.matches[k];
      const Eigen::Vector2d& u_i = features_i.points_px[static_cast<std::size_t>(m.index_i)];
      cv::Point a, b;
      if (!epipolar_segment(diagnostics.essential.E, camera, u_i, right.cols, right.rows, &a, &b)) continue;
      const cv::Scalar c = colour(s);
      cv::line(canvas, a + cv::Point(dx, 0), b + cv::Point(dx, 0), c, thickness, cv::LINE_AA);
      cv::drawMarker(canvas, to_cv(u_i), c, cv::MARKER_TILTED_CROSS, 12 * thickness, thickness);
      cv::circle(canvas, to_cv(features_j.points_px[static_cast<std::size_t>(m.index_j)], dx),
                 5 * thickness, c, thickness, cv::LINE_AA);
    }
  }
  return canvas;
}

}  // namespace nav::vision
