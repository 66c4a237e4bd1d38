// Simulated lawnmower camera survey (sim/survey.h).
#include "nav/core/sim/survey.h"

#include "nav/core/geometry/rotation.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

namespace nav::core::sim {
namespace {

using Rng = std::mt19937_64;

double normal(Rng& rng) { return std::normal_distribution<double>(0.0, 1.0)(rng); }

/// Sample of N(0, S) for a symmetric positive semi-definite S (eigen-decomposition).
template <int N>
Eigen::Matrix<double, N, 1> sample(const Eigen::Matrix<double, N, N>& S, Rng& rng) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(S);
  Eigen::Matrix<double, N, 1> n;
  for (int k = 0; k < N; ++k) n[k] = normal(rng) * std::sqrt(std::max(0.0, es.eigenvalues()[k]));
  return es.eigenvectors() * n;
}

MeasCov diag_cov(std::initializer_list<double> sigmas) {
  MeasCov R = MeasCov::Zero(static_cast<Eigen::Index>(sigmas.size()),
                            static_cast<Eigen::Index>(sigmas.size()));
  Eigen::Index k = 0;
  for (double s : sigmas) {
    R(k, k) = s * s;
    ++k;
  }
  return R;
}

template <class Model>
MeasVec measure(const Model& model, const Vec12& x, const MeasCov& R, Rng& rng) {
  MeasVec z = model.predict(x);
  for (Eigen::Index r = 0; r < z.size(); ++r) {
    z[r] += std::sqrt(R(r, r)) * normal(rng);
    if (model.is_angle(static_cast<int>(r))) z[r] = wrap_angle(z[r]);
  }
  return z;
}

MeasVec measure_binary(const Survey& sv, const Vec12& xa, const Vec12& xb, Rng& rng) {
  MeasVec z = sv.camera.predict(xa, xb);
  for (Eigen::Index r = 0; r < z.size(); ++r) {
    z[r] = wrap_angle(z[r] + std::sqrt(sv.R_camera(r, r)) * normal(rng));
  }
  return z;
}

Status field_error(const char* field, const std::string& why) {
  return Status::Error(StatusCode::kInvalidArgument,
                       std::string("SurveyOptions.") + field + ": " + why);
}

/// Where the vehicle is in the lawnmower pattern at step s.
struct Phase {
  int line = 0;        // track line index
  bool turning = false;
};

Phase phase_of(const SurveyOptions& o, int step) {
  const int line_steps = o.images_per_line * o.steps_per_image;
  const int cycle = line_steps + o.turn_steps;
  Phase p;
  p.line = step / cycle;
  p.turning = (step % cycle) >= line_steps;
  return p;
}

/// Known control u_k: steers body velocities and rates towards the lawnmower command.
Vec12 control_for(const SurveyOptions& o, const Vec12& x, int step) {
  const Phase p = phase_of(o, step);
  const bool eastbound = p.line % 2 == 0;
  const double line_heading = eastbound ? std::numbers::pi / 2 : -std::numbers::pi / 2;
  // Turn north: east -> north -> west decreases heading, west -> north -> east increases it.
  const double turn_rate = (eastbound ? -1.0 : 1.0) * std::numbers::pi / (o.turn_steps * o.dt_s);
  Vec6 cmd;
  cmd << o.speed_mps, 0.0, 0.5 * (o.depth_m - x[kZ]), -0.5 * x[kRoll], -0.5 * x[kPitch],
      p.turning ? turn_rate : 0.5 * wrap_angle(line_heading - x[kHeading]);
  Vec12 u = Vec12::Zero();
  u.tail<6>() = 0.5 * (cmd - x.tail<6>());
  return u;
}

}  // namespace

Status SurveyOptions::validate() const {
  if (num_images < 1) return field_error("num_images", "must be >= 1");
  if (steps_per_image < 1) return field_error("steps_per_image", "must be >= 1");
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return field_error("dt_s", "must be finite > 0");
  if (images_per_line < 1) return field_error("images_per_line", "must be >= 1");
  if (turn_steps < 1) return field_error("turn_steps", "must be >= 1");
  if (max_cross_links_per_image < 0) return field_error("max_cross_links_per_image", ">= 0");
  if (min_cross_link_gap < 2) return field_error("min_cross_link_gap", "must be >= 2");
  for (double s : {attitude_sigma_rad, heading_sigma_rad, velocity_sigma_mps, depth_sigma_m,
                   camera_direction_sigma_rad, camera_rotation_sigma_rad}) {
    if (!(s > 0.0) || !std::isfinite(s)) return field_error("*_sigma_*", "must be finite > 0");
  }
  return process.validate();
}

Survey simulate_survey(const SurveyOptions& o) {
  if (Status s = o.validate(); !s.ok()) throw std::invalid_argument(s.to_string());
  Survey sv;
  sv.options = o;
  sv.process = ConstantVelocityModel(o.process);
  sv.camera.x_body_camera << 0, 0, 0, 0, 0, std::numbers::pi / 2;  // looking down, x right
  sv.R_dvl = diag_cov({o.velocity_sigma_mps, o.velocity_sigma_mps, o.velocity_sigma_mps});
  sv.R_heading = diag_cov({o.heading_sigma_rad});
  sv.R_attitude = diag_cov({o.attitude_sigma_rad, o.attitude_sigma_rad});
  sv.R_depth = diag_cov({o.depth_sigma_m});
  const double sd = o.camera_direction_sigma_rad, sr = o.camera_rotation_sigma_rad;
  sv.R_camera = diag_cov({sd, sd, sr, sr, sr});

  Rng rng(o.seed);
  sv.x0_true << 0, 0, o.depth_m, 0, 0, std::numbers::pi / 2, o.speed_mps, 0, 0, 0, 0, 0;
  Vec12 sig0;
  sig0 << 0.1, 0.1, 0.05, 0.005, 0.005, 0.01, 0.02, 0.02, 0.02, 0.002, 0.002, 0.002;
  sv.P0 = sig0.cwiseAbs2().asDiagonal();
  sv.x0_mean = sv.x0_true + sample<12>(sv.P0, rng);

  const int num_steps = o.num_images * o.steps_per_image;
  sv.steps.reserve(static_cast<size_t>(num_steps));
  Vec12 x = sv.x0_true;
  std::vector<Phase> image_phase;
  for (int s = 0; s < num_steps; ++s) {
    SurveyStep st;
    st.dt_s = o.dt_s;
    if (s % o.steps_per_image == 0) {
      st.image = static_cast<int>(sv.image_truth.size());
      sv.image_truth.push_back(x);
      image_phase.push_back(phase_of(o, s));
    }
    st.control = control_for(o, x, s);
    const Mat12 Q = sv.process.process_noise(x, o.dt_s);
    x = sv.process.predict(x, o.dt_s) + st.control + sample<12>(Q, rng);
    for (int k : {kRoll, kPitch, kHeading}) x[k] = wrap_angle(x[k]);
    st.x_true = x;
    st.dvl = measure(sv.dvl, x, sv.R_dvl, rng);
    st.heading = measure(sv.heading, x, sv.R_heading, rng);
    st.attitude = measure(sv.attitude, x, sv.R_attitude, rng);
    st.depth = measure(sv.depth, x, sv.R_depth, rng);

    if (st.image >= 0) {
      const int b = st.image;
      const Vec12& xb = sv.image_truth[static_cast<size_t>(b)];
      std::vector<int> partners;
      if (b > 0) partners.push_back(b - 1);
      // Cross-track (loop-closure) partners: nearest older images within the radius.
      std::vector<std::pair<double, int>> near;
      for (int a = 0; a + o.min_cross_link_gap <= b; ++a) {
        const Vec12& xa = sv.image_truth[static_cast<size_t>(a)];
        const double dist = (xa.head<2>() - xb.head<2>()).norm();
        if (dist < o.link_radius_m) near.emplace_back(dist, a);
      }
      std::sort(near.begin(), near.end());
      for (size_t k = 0; k < near.size() && static_cast<int>(k) < o.max_cross_links_per_image;
           ++k) {
        partners.push_back(near[k].second);
      }
      for (int a : partners) {
        const Vec12& xa = sv.image_truth[static_cast<size_t>(a)];
        if (sv.camera.baseline_is_degenerate(xa, xb)) continue;
        st.links.push_back(CameraLink{a, b, measure_binary(sv, xa, xb, rng)});
        ++sv.num_links;
        if (a != b - 1) ++sv.num_cross_track_links;
      }
    }
    sv.steps.push_back(std::move(st));
  }
  return sv;
}

Vec12 predicted_mean(const Survey& survey, const SurveyStep& step, const Vec12& mean, Mat12* F,
                     Mat12* Q) {
  Vec12 f = survey.process.predict(mean, step.dt_s, F) + step.control;
  for (int k : {kRoll, kPitch, kHeading}) f[k] = wrap_angle(f[k]);
  if (Q != nullptr) *Q = survey.process.process_noise(mean, step.dt_s);
  return f;
}

Status apply_step(const Survey& survey, const SurveyStep& step, Esdf& filter,
                  std::vector<int>& image_blocks) {
  Mat12 F, Q;
  Vec12 f;
  try {
    f = predicted_mean(survey, step, filter.mean_block(Esdf::kRobotBlock), &F, &Q);
  } catch (const std::exception& e) {
    return Status::Error(StatusCode::kOutOfRange, std::string("sim::apply_step: ") + e.what());
  }
  int kept = -1;
  if (Status s = filter.predict(f, F, Q, step.image >= 0, &kept); !s.ok()) return s;
  if (step.image >= 0) {
    if (static_cast<int>(image_blocks.size()) != step.image) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "sim::apply_step: image " + std::to_string(step.image) +
                               " out of order (have " + std::to_string(image_blocks.size()) +
                               " images)");
    }
    image_blocks.push_back(kept);
  }
  const int r = Esdf::kRobotBlock;
  if (Status s = filter.update(survey.dvl, r, step.dvl, survey.R_dvl); !s.ok()) return s;
  if (Status s = filter.update(survey.heading, r, step.heading, survey.R_heading); !s.ok()) {
    return s;
  }
  if (Status s = filter.update(survey.attitude, r, step.attitude, survey.R_attitude); !s.ok()) {
    return s;
  }
  if (Status s = filter.update(survey.depth, r, step.depth, survey.R_depth); !s.ok()) return s;
  for (const CameraLink& link : step.links) {
    const int a = image_blocks[static_cast<size_t>(link.image_a)];
    const int b = image_blocks[static_cast<size_t>(link.image_b)];
    if (Status s = filter.update(survey.camera, a, b, link.z, survey.R_camera); !s.ok()) return s;
  }
  return Status::Ok();
}

}  // namespace nav::core::sim
