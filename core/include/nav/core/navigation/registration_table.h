#pragma once
// Image registration results keyed by (earlier frame id, later frame id): the vision stage's
// answers, or the survey simulator's oracle answers read from a dive log. NavFilter proposes a
// pair from its bounds and asks the table; a pair with no entry was never registered (no
// overlap) and counts as not registered. The daemon converts its messages to `Registration`.

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>

namespace nav::core {

/// One answer of the vision stage for the camera pair (frame_id_i, frame_id_j).
struct Registration {
  std::int64_t frame_id_i = 0, frame_id_j = 0;  ///< earlier, later image; i < j
  bool success = false;                         ///< false: the registration failed
  /// 5-dof relative pose of camera j in camera i (CameraRelativePoseModel order) and its
  /// covariance (row-major 5 x 5 in the message, an Eigen matrix here).
  Eigen::Matrix<double, 5, 1> z = Eigen::Matrix<double, 5, 1>::Zero();
  Eigen::Matrix<double, 5, 5> covariance = Eigen::Matrix<double, 5, 5>::Identity();
  double overlap_fraction = -1.0;
  bool is_outlier = false;        ///< simulator truth only
  std::int64_t available_us = 0;  ///< host CLOCK_REALTIME at which the answer existed
};

struct RegistrationResult {
  bool success = false;
  Eigen::Matrix<double, 5, 1> z = Eigen::Matrix<double, 5, 1>::Zero();  ///< camera model order
  Eigen::Matrix<double, 5, 5> covariance = Eigen::Matrix<double, 5, 5>::Identity();
  double overlap_fraction = -1.0;
  bool is_outlier = false;        ///< simulator truth only
  std::int64_t available_us = 0;  ///< Registration::available_us
};

/// Why `registration` must not reach the filter, or nullopt when it may. An answer crosses a trust
/// boundary (LCM multicast, a dive log), so before the gate ever sees it: frame_id_i < frame_id_j;
/// and for a successful registration a finite measurement with azimuth, roll, pitch, heading in
/// [-pi, pi] and elevation in [-pi/2, pi/2], and a finite, symmetric (relative 1e-9) and positive
/// definite covariance (Cholesky). A NaN or indefinite covariance would otherwise give a gate
/// statistic that no threshold test rejects.
std::optional<std::string> registration_problem(const Registration& registration);

class RegistrationTable {
 public:
  /// Adds the result for (frame_id_i, frame_id_j); false (the table unchanged) when the pair
  /// is already registered: the first answer is kept, so a link applied from it is never
  /// contradicted or applied twice. Requires frame_id_i < frame_id_j (the measurement is
  /// always camera i -> camera j, earlier to later) and a valid answer: throws
  /// std::invalid_argument with registration_problem()'s reason otherwise.
  bool insert(const Registration& registration);
  /// The result for the pair given in either order (its measurement is always from the smaller
  /// frame id to the larger), or nullopt if it was never registered.
  std::optional<RegistrationResult> find(std::int64_t frame_a, std::int64_t frame_b) const;
  std::size_t size() const { return results_.size(); }
  std::size_t outliers() const;
  /// Incremented by every insert that adds a result (lets a reader notice new entries).
  std::uint64_t generation() const { return generation_; }

 private:
  std::uint64_t generation_ = 0;
  std::map<std::pair<std::int64_t, std::int64_t>, RegistrationResult> results_;
};

}  // namespace nav::core
