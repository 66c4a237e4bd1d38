#pragma once
// The registration picture of Eustice et al., RSS 2005, Fig. 4: image i and image j side by
// side; in image i a sample of features, in image j for each the epipolar line of the estimated
// essential matrix (x_j^T E^T x_i = 0) and, when the pair had a pose prior, the pose-constrained
// search band given by the caller (a polyline of centres per feature). Inlier correspondences
// are joined across the two images. Pure drawing on copies; the caller writes the file.

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

#include "nav/vision/registration.h"
#include "nav/vision/vision_types.h"

namespace nav::vision {

/// A search band of one feature of image i in image j: the centre polyline (pixels of j) and
/// the half-width (pixels) drawn around it.
struct SearchBand {
  int feature_i = -1;
  std::vector<Eigen::Vector2d> centres_px;
  std::vector<double> half_widths_px;
};

struct DrawOptions {
  int max_epipolar_lines = 12;  ///< Features of image i whose epipolar line is drawn.
  int max_inlier_links = 60;    ///< Inlier correspondences joined across the images.
};

/// PCCS search bands (pccs.h search_region) of up to `count` features of image i, spread over
/// the pair's essential-matrix inliers (or over all of image i's features when there are none);
/// half-width = sqrt(gate x largest eigenvalue of S(d)). Empty without a prior. With count =
/// DrawOptions::max_epipolar_lines the sample is the features whose epipolar lines are drawn,
/// and each band takes its line's colour.
std::vector<SearchBand> search_bands(const ImageFeatures& features_i,
                                     const RegistrationDiagnostics& diagnostics,
                                     const CameraIntrinsics& camera,
                                     const RelativePosePrior* prior, const PccsOptions& options,
                                     int count);

/// Side-by-side BGR picture (8-bit grey inputs, as the Preprocessor makes them).
cv::Mat draw_registration(const cv::Mat& image_i_8u, const cv::Mat& image_j_8u,
                          const ImageFeatures& features_i, const ImageFeatures& features_j,
                          const RegistrationDiagnostics& diagnostics,
                          const CameraIntrinsics& camera, const std::vector<SearchBand>& bands,
                          const DrawOptions& options = {});

}  // namespace nav::vision
