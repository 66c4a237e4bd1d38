#pragma once
// SolutionBoard (filter thread -> publisher thread): what nav_solution_t and health_t carry, a
// mutex-protected slot held only for a copy, so the filter thread never waits for publishing.

#include <Eigen/Core>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/daemon/filter/filter_options.h"

namespace nav::daemon::service {

/// The published view of the estimate.
struct SolutionView {
  std::int64_t time_of_validity_us = 0;
  core::Vec12 robot_mean = core::Vec12::Zero();
  /// The robot's marginal (LinkPublisher::update_board); the identity only as a placeholder
  /// before the first estimate, never published (has_estimate false).
  core::Mat12 robot_covariance = core::Mat12::Identity();
  int num_delayed_states = 0;
  int num_camera_links = 0;
  int filter_status = 2;  ///< 0 ok, 1 degraded, 2 initialising (nav_solution_t)
  double cg_relative_residual = 0.0;
  int cg_iterations = 0;
  std::string status_line = "initialising";
  std::vector<daemon::SensorInnovation> innovations;  ///< NavFilter::innovations(), cumulative
  bool has_estimate = false;
};

class SolutionBoard {
 public:
  template <class F>
  void modify(F&& f) {
    std::lock_guard lock(mutex_);
    f(view_);
  }
  SolutionView read() const {
    std::lock_guard lock(mutex_);
    return view_;
  }

 private:
  mutable std::mutex mutex_;
  SolutionView view_;
};

}  // namespace nav::daemon::service
