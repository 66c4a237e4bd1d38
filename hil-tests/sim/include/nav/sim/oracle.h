#pragma once
// Oracle image registration (hil-tests/README.md "Registrations"): plays the vision stage until
// it exists. For each new image j and every earlier image i whose true seafloor footprints
// overlap, one registration_t: success with a probability that falls with smaller overlap and
// with a longer time gap; on success the 5-DOF measurement of core CameraRelativePoseModel
// (config camera mount) of the TRUE states plus noise drawn from the stated covariance; a
// fraction of the successes are outliers (reversed baseline direction, wrong relative heading).

#include <Eigen/Core>
#include <cstdint>
#include <navlcm/registration_t.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/core/models/binary_models.h"
#include "nav/daemon/config/config.h"
#include "nav/sim/geometry2d.h"

namespace nav::sim {

using Mat5 = Eigen::Matrix<double, 5, 5>;
using Vec5 = Eigen::Matrix<double, 5, 1>;

struct OracleOptions {
  double azimuth_sigma_rad = 0.017453292519943295;    ///< 1 deg, baseline azimuth
  double elevation_sigma_rad = 0.017453292519943295;  ///< 1 deg, baseline elevation
  double rotation_sigma_rad = 0.003490658503988659;   ///< 0.2 deg, relative roll/pitch/heading
  double outlier_rate = 0.05;  ///< fraction of successful registrations that are outliers
  double min_overlap = 0.02;   ///< pairs overlapping less are not tried at all
  double overlap_zero = 0.15;  ///< success probability 0 at or below this overlap
  double overlap_full = 0.60;  ///< ... rising linearly to its maximum at this overlap
  double max_success_probability = 0.95;
  double time_gap_scale_s = 1800.0;  ///< long gaps lose up to 70 % of the success probability
  /// Empty when usable, else "<field>: <reason>".
  std::string validate() const;
};

/// Camera intrinsics and mount from a camera sensor of the config.
struct CameraGeometry {
  double fx_px = 1.0, fy_px = 1.0, cx_px = 0.0, cy_px = 0.0;
  core::Vec6 x_body_camera = core::Vec6::Zero();
  int width_px() const { return static_cast<int>(2.0 * cx_px + 0.5); }
  int height_px() const { return static_cast<int>(2.0 * cy_px + 0.5); }
  static CameraGeometry from_config(const daemon::SensorConfig& camera);
};

/// The image's footprint on the horizontal plane at `seafloor_depth_m` (the seafloor below the
/// camera): the four corner rays of the 2cx x 2cy image; empty if a corner ray does not hit it.
Polygon2 image_footprint(const CameraGeometry& camera, const core::Vec12& x_true,
                         double seafloor_depth_m);

struct OracleImage {
  std::int64_t frame_id = 0;
  std::int64_t t_us = 0;  ///< time of validity (monotonic)
  core::Vec12 x_true = core::Vec12::Zero();
  Polygon2 footprint;
};

struct OracleCounts {
  std::int64_t registrations = 0, succeeded = 0, outliers = 0, degenerate_skipped = 0;
};

class RegistrationOracle {
 public:
  RegistrationOracle(const CameraGeometry& camera, const OracleOptions& options,
                     std::uint64_t seed);
  /// Registers image j against every earlier image (ascending frame id); utime is left 0.
  std::vector<navlcm::registration_t> add_image(const OracleImage& image);
  const Mat5& covariance() const { return covariance_; }
  const OracleCounts& counts() const { return counts_; }
  const core::CameraRelativePoseModel& model() const { return model_; }
  /// Overlap fraction of two footprints: intersection area / smaller footprint area.
  static double overlap_fraction(const Polygon2& a, const Polygon2& b);

 private:
  struct Stored {
    OracleImage image;
    Point2 centre;
    double radius_m = 0.0;
  };
  std::optional<navlcm::registration_t> try_pair(const Stored& i, const OracleImage& j,
                                                 double overlap);

  CameraGeometry camera_;
  OracleOptions options_;
  core::CameraRelativePoseModel model_;
  Mat5 covariance_ = Mat5::Zero();
  Mat5 covariance_sqrt_ = Mat5::Zero();
  std::mt19937_64 rng_;
  std::vector<Stored> images_;
  OracleCounts counts_;
};

}  // namespace nav::sim
