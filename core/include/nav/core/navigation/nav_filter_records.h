#pragma once
// What NavFilter records per image, per proposed pair and in total (the replay outputs'
// trajectory.csv, links.csv, proposals.csv and summary counters; camera_link_t in navd).

#include <Eigen/Core>
#include <cstdint>

#include "nav/core/geometry/types.h"

namespace nav::core {

enum class LinkOutcome { kAccepted, kGated, kRegistrationFailed, kNotRegistered };
const char* to_string(LinkOutcome outcome);

struct LinkRecord {  ///< one proposed pair (links.csv)
  std::int64_t t_us = 0;
  std::uint64_t frame_i = 0, frame_j = 0;  ///< earlier, later (the current image)
  int state_i = -1, state_j = -1;          ///< filter blocks (state_j once kept, else -1)
  LinkOutcome outcome = LinkOutcome::kNotRegistered;
  double mahalanobis_sq = -1.0;  ///< gate statistic (-1 when not registered / failed)
  bool is_outlier = false;       ///< registration's simulator truth
  /// The registration's measurement and covariance and the innovation z − h (when registered
  /// successfully; zero otherwise), for camera_link_t.
  Eigen::Matrix<double, 5, 1> z = Eigen::Matrix<double, 5, 1>::Zero();
  Eigen::Matrix<double, 5, 5> covariance = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 1> innovation = Eigen::Matrix<double, 5, 1>::Zero();
};

struct ProposalRecord {  ///< one image (proposals.csv)
  std::uint64_t frame_id = 0;
  int candidates = 0, proposed = 0, accepted = 0;
};

struct ImageRecord {  ///< the estimate at one image (trajectory.csv)
  std::int64_t t_us = 0;
  std::uint64_t frame_id = 0;
  int state = -1;                ///< its delayed-state block once kept
  double altitude_m = 0.0;       ///< used for its footprint
  Vec12 robot_mean = Vec12::Zero();            ///< after this image's links
  Mat12 robot_covariance = Mat12::Zero();      ///< recovered Σ_rr (before links)
  double relative_residual = 0.0;  ///< recovery's max relative residual
  /// Pose part of its bound when inserted (Σ~_ii = Σ_rr, Algorithm 1), once kept.
  Eigen::Matrix<double, 6, 6> initial_bound = Eigen::Matrix<double, 6, 6>::Zero();
};

struct NavFilterCounters {
  std::uint64_t measurements = 0, before_initialisation = 0, out_of_order = 0;
  std::uint64_t updates = 0, update_failures = 0, unused = 0;
  std::uint64_t predictions = 0, images = 0, duplicate_images = 0;
  std::uint64_t recoveries = 0, recovery_failures = 0;
  std::uint64_t candidates = 0, links_proposed = 0, links_accepted = 0, links_gated = 0;
  std::uint64_t registration_failed = 0, not_registered = 0;
  std::uint64_t outliers_rejected = 0, outliers_accepted = 0, bound_update_failures = 0;
  /// Prediction steps held at a pitch off the model's branch (robot_prediction.h).
  std::uint64_t predictions_held = 0;
  double max_cg_relative_residual = 0.0;
};

}  // namespace nav::core
