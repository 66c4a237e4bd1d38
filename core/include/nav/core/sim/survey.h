#pragma once
// Simulated boustrophedon (lawnmower) camera survey for tests, benchmarks and `navtool demo`,
// after the Titanic survey of Eustice et al. (RSS 2005): a vehicle at constant depth runs
// east-west track lines joined by 180 degree turns, with DVL, heading, attitude and depth at
// the paper's Table II precision, and an image every `steps_per_image` steps. Camera links
// (5-DOF relative pose, CameraRelativePoseModel) join temporally adjacent images and images
// on different track lines whose true positions are closer than `link_radius_m` (loop
// closures). Deterministic for a given seed. No I/O, no clocks (nav_core rules).
//
// Truth follows the filter's process model exactly: x_{k+1} = f(x_k) + u_k + w_k with f the
// constant-velocity model, w_k ~ N(0, Q(x_k)) and u_k a known control (a velocity/rate
// correction that steers the lawnmower), so a consistent filter must pass a NEES test.

#include "nav/core/filter/esdf.h"
#include "nav/core/geometry/types.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/models/measurement.h"
#include "nav/core/models/unary_models.h"
#include "nav/core/status.h"

#include <cstdint>
#include <vector>

namespace nav::core::sim {

struct SurveyOptions {
  int num_images = 200;            ///< images in the survey (>= 1)
  int steps_per_image = 4;         ///< process/sensor steps between images (>= 1)
  double dt_s = 0.5;               ///< step length, s (> 0)
  double speed_mps = 0.5;          ///< forward speed on track lines, m/s
  int images_per_line = 20;        ///< images per straight track line (>= 1)
  int turn_steps = 12;             ///< steps of each 180 degree turn (>= 1)
  double depth_m = 10.0;           ///< survey depth, m (positive down)
  double link_radius_m = 2.0;      ///< cross-track link if true horizontal distance < this, m
  int max_cross_links_per_image = 2;  ///< nearest cross-track partners linked per image
  int min_cross_link_gap = 5;      ///< cross-track partners are >= this many images older
  // Sensor standard deviations (RSS 2005 Table II).
  double attitude_sigma_rad = 0.1 * 3.14159265358979323846 / 180.0;  ///< roll, pitch
  double heading_sigma_rad = 0.1 * 3.14159265358979323846 / 180.0;
  double velocity_sigma_mps = 0.01;  ///< DVL, per axis
  double depth_sigma_m = 0.01;
  double camera_direction_sigma_rad = 0.5 * 3.14159265358979323846 / 180.0;  ///< az, el
  double camera_rotation_sigma_rad = 0.2 * 3.14159265358979323846 / 180.0;   ///< rpy_ab
  /// Process noise of truth and filter (constant-velocity model).
  ConstantVelocityOptions process{Vec3::Constant(1e-4), Vec3::Constant(1e-6), {}};
  std::uint64_t seed = 1;

  /// kInvalidArgument naming the field when a value is out of range.
  Status validate() const;
};

/// A camera link between two images (a older than b): z = camera.predict(x_a, x_b) + noise.
struct CameraLink {
  int image_a = -1;
  int image_b = -1;
  MeasVec z;
};

/// One filter step: if `image >= 0` the state at the START of the step (before predicting)
/// is image `image` (the filter keeps it as a delayed state); then predict by dt_s with the
/// known control, then the navigation sensors measure x_true; then the links are applied.
struct SurveyStep {
  int image = -1;
  double dt_s = 0.0;
  Vec12 control = Vec12::Zero();  ///< known input: x_{k+1} = f(x_k) + control + w_k
  Vec12 x_true = Vec12::Zero();   ///< true robot state after the step
  MeasVec dvl, heading, attitude, depth;
  std::vector<CameraLink> links;
};

struct Survey {
  SurveyOptions options;
  Vec12 x0_true = Vec12::Zero();
  Vec12 x0_mean = Vec12::Zero();  ///< initial estimate, x0_true + N(0, P0) sample
  Mat12 P0 = Mat12::Identity();
  std::vector<SurveyStep> steps;
  std::vector<Vec12> image_truth;  ///< true state of each image
  size_t num_links = 0;
  size_t num_cross_track_links = 0;

  ConstantVelocityModel process;
  DvlVelocityModel dvl;
  HeadingModel heading;
  AttitudeModel attitude;
  DepthModel depth;
  CameraRelativePoseModel camera;
  MeasCov R_dvl, R_heading, R_attitude, R_depth, R_camera;
};

/// Generates the survey; throws std::invalid_argument with validate()'s message.
Survey simulate_survey(const SurveyOptions& options);

/// Feeds one step to a 12-block filter: predict with the known control (keeping the current
/// state when the step starts with an image; its block index is stored in image_blocks),
/// DVL/heading/attitude/depth updates of the robot, then the camera links. Does not recover
/// the mean (the caller decides when).
Status apply_step(const Survey& survey, const SurveyStep& step, Esdf& filter,
                  std::vector<int>& image_blocks);

/// f(μ) + control and F for the step at the filter's current robot mean (what apply_step feeds
/// to Esdf::predict), for reference implementations. Throws like the model.
Vec12 predicted_mean(const Survey& survey, const SurveyStep& step, const Vec12& mean, Mat12* F,
                     Mat12* Q);

}  // namespace nav::core::sim
