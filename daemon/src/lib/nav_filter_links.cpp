// NavFilter link proposal from the Algorithm 1 bounds, registration look-up, 5-dof gating and
// link updates (the test and gate are stated in nav_filter.h).
#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>

#include "nav/core/geometry/rotation.h"
#include "nav/daemon/filter/link_linearisation.h"
#include "nav/daemon/filter/nav_filter.h"

namespace nav::daemon {
namespace {

constexpr int kD = 12;  // block dimension

/// The joint without the truncation inflation: [Σ^_rr Σ^_ri; Σ^_ir Σ~_ii] (nav_filter.h "Gate").
Eigen::MatrixXd gate_joint(const core::LinkProposal& p) {
  Eigen::MatrixXd joint = p.joint;
  joint.topLeftCorner(kD, kD).diagonal().array() -= p.epsilon_robot + p.epsilon_state;
  joint.bottomRightCorner(kD, kD).diagonal().array() -= p.epsilon_state;
  return joint;
}

/// The 5-dof gate at the means x0 = [x_j; x_i] with the joint covariance: fills the link's
/// innovation and Mahalanobis distance; true when it passes (nav_filter.h "Gate").
bool gate_link(const core::CameraRelativePoseModel& camera, const LinkPair& x0,
               const Eigen::MatrixXd& joint_cov, const RegistrationResult& reg, double gate_chi2,
               LinkRecord& link) {
  const auto x_r = x0.head<kD>(), x_i = x0.tail<kD>();
  if (camera.baseline_is_degenerate(x_i, x_r)) return false;
  try {
    core::MeasJac H_i, H_r;
    core::MeasVec nu = reg.z - camera.predict(x_i, x_r, &H_i, &H_r);
    for (int row = 0; row < 5; ++row) nu(row) = core::wrap_angle(nu(row));
    Eigen::Matrix<double, 5, 2 * kD> H;
    H << H_r, H_i;
    const Eigen::Matrix<double, 5, 5> S = H * joint_cov * H.transpose() + reg.covariance;
    const Eigen::LDLT<Eigen::Matrix<double, 5, 5>> ldlt(S);
    link.innovation = nu;
    link.mahalanobis_sq = nu.dot(ldlt.solve(nu));
    return ldlt.info() == Eigen::Success && std::isfinite(link.mahalanobis_sq) &&
           link.mahalanobis_sq <= gate_chi2;
  } catch (const std::exception& e) {
    spdlog::warn("NavFilter: camera model for frames {}-{}: {}", link.frame_i, link.frame_j,
                 e.what());
    return false;
  }
}

/// The accepted link's linearisation at the robot's iterated point (link_linearisation.h;
/// nav_filter.h "Link update"), or at the means where the iteration fails.
LinkLinearisation linearise_at_iterated_point(const core::CameraRelativePoseModel& camera,
                                              const LinkPair& x0, const Eigen::MatrixXd& joint_cov,
                                              const RegistrationResult& reg,
                                              const LinkRecord& link) {
  LinkLinearisation lin;
  try {
    // Only the robot moves: J's robot block is the recovered Σ_rr, while state i's is its
    // conservative bound (loose by orders of magnitude), which would drag x_i to the link.
    Eigen::MatrixXd robot_only = Eigen::MatrixXd::Zero(2 * kD, 2 * kD);
    robot_only.topLeftCorner(kD, kD) = joint_cov.topLeftCorner(kD, kD);
    lin = iterated_link_point(camera, x0, robot_only, reg.z, reg.covariance);
  } catch (const std::exception& e) {  // a degenerate iterate: the mean is the point
    spdlog::warn("NavFilter: camera link {}-{} not iterated: {}", link.frame_i, link.frame_j,
                 e.what());
    lin = LinkLinearisation{};
    lin.x = x0;
    lin.h = camera.predict(x0.tail<kD>(), x0.head<kD>(), &lin.H_i, &lin.H_r);
  }
  return lin;
}

/// a - b with the attitude components wrapped to (-π, π].
LinkPair wrapped_difference(const LinkPair& a, const LinkPair& b) {
  LinkPair d = a - b;
  for (int k = 3; k < 6; ++k) {
    d[k] = core::wrap_angle(d[k]);
    d[kD + k] = core::wrap_angle(d[kD + k]);
  }
  return d;
}

}  // namespace

// iterated_link_point: link_linearisation.h (why: nav_filter.h "Link update").
LinkLinearisation iterated_link_point(const core::CameraRelativePoseModel& camera,
                                      const LinkPair& x0, const Eigen::MatrixXd& joint,
                                      const core::MeasVec& z, const core::MeasCov& R) {
  constexpr int kMaxIterations = 10;
  constexpr double kConverged = 1e-9;  // step norm (m, rad)
  LinkLinearisation l;
  l.x = x0;
  for (;;) {
    l.h = camera.predict(l.x.tail<kD>(), l.x.head<kD>(), &l.H_i, &l.H_r);
    if (l.iterations == kMaxIterations) return l;
    Eigen::Matrix<double, 5, 2 * kD> H;
    H << l.H_r, l.H_i;
    Eigen::Matrix<double, 2 * kD, 1> dx = x0 - l.x;
    for (int k = 3; k < 6; ++k) {  // Euler angles of both blocks along the shorter arc
      dx[k] = core::wrap_angle(dx[k]);
      dx[kD + k] = core::wrap_angle(dx[kD + k]);
    }
    core::MeasVec r = z - l.h;
    core::wrap_angle_rows(camera, r);
    const Eigen::Matrix<double, 5, 1> nu = r - H * dx;
    const Eigen::Matrix<double, 5, 5> S = H * joint * H.transpose() + R;
    const Eigen::Matrix<double, 2 * kD, 1> next =
        x0 + joint * H.transpose() * Eigen::LDLT<Eigen::Matrix<double, 5, 5>>(S).solve(nu);
    if (!next.allFinite()) return l;
    const double step = (next - l.x).norm();
    l.x = next;
    ++l.iterations;
    if (step < kConverged) {
      l.h = camera.predict(l.x.tail<kD>(), l.x.head<kD>(), &l.H_i, &l.H_r);
      return l;
    }
  }
}

double NavFilter::footprint_radius_m(double altitude_m) const {
  return altitude_m * sensors_.footprint_radius_per_altitude();
}

bool NavFilter::is_candidate(const ImageRecord& earlier, const ImageRecord& current, int block,
                             core::LinkProposal* joint) const {
  // The test needs only the 2x2 horizontal parts of the joint: computed first (the same
  // numbers as from the full joint), the 24x24 joint is built for the proposed pairs only.
  const Eigen::Matrix2d sigma_ir_xy = recovery_.solution().block<2, 2>(Eigen::Index{block} * kD, 1);
  Eigen::Matrix2d C;
  if (!bounds_.offset_covariance_2d(block, sigma_ir_xy, &C).ok()) return false;
  const Eigen::Vector2d delta =
      filter_.mean_block(block).head<2>() - filter_.mean_block(core::Esdf::kRobotBlock).head<2>();
  const double lambda_max =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(C, Eigen::EigenvaluesOnly).eigenvalues()(1);
  const core::Vec6& camera = sensors_.camera()->x_body_camera;
  const double reach_m = footprint_radius_m(earlier.altitude_m) +
                         footprint_radius_m(current.altitude_m) + 2.0 * camera.head<2>().norm();
  if (!(delta.norm() - std::sqrt(proposal_chi2_ * std::max(lambda_max, 0.0)) < reach_m)) {
    return false;
  }
  return bounds_.propose(block, recovery_.cross_covariance(block), joint).ok();
}

void NavFilter::propose_and_link(ImageRecord& current) {
  ProposalRecord summary;
  summary.frame_id = current.frame_id;
  scratch_proposals_.clear();
  for (int block = 1; block < filter_.num_blocks(); ++block) {
    const long index = image_of_block_[static_cast<std::size_t>(block)];
    if (index < 0) continue;
    ++summary.candidates;
    Proposal p;
    p.image = static_cast<std::size_t>(index);
    if (is_candidate(images_[p.image], current, block, &p.joint)) {
      scratch_proposals_.push_back(std::move(p));
    }
  }
  summary.proposed = static_cast<int>(scratch_proposals_.size());
  for (const Proposal& p : scratch_proposals_) {
    if (defer_link(p, current)) continue;  // answered later (nav_filter_pending.cpp)
    LinkRecord link = try_link(p, current);
    if (link.outcome == LinkOutcome::kAccepted) ++summary.accepted;
    pending_links_.push_back(links_.size());
    links_.push_back(link);
  }
  counters_.candidates += static_cast<std::uint64_t>(summary.candidates);
  counters_.links_proposed += static_cast<std::uint64_t>(summary.proposed);
  proposals_.push_back(summary);
}

LinkRecord NavFilter::try_link(const Proposal& p, const ImageRecord& current) {
  const ImageRecord& earlier = images_[p.image];
  const int block = p.joint.state;
  LinkRecord link;
  link.t_us = current.t_us;
  link.frame_i = earlier.frame_id;
  link.frame_j = current.frame_id;
  link.state_i = block;
  const std::optional<RegistrationResult> reg =
      registrations_ ? registrations_->find(static_cast<std::int64_t>(earlier.frame_id),
                                            static_cast<std::int64_t>(current.frame_id))
                     : std::nullopt;
  if (!reg) {
    link.outcome = LinkOutcome::kNotRegistered;
    ++counters_.not_registered;
    return link;
  }
  resolve_link(p.joint, core::Esdf::kRobotBlock, *reg, link);
  return link;
}

void NavFilter::resolve_link(const core::LinkProposal& joint, int block_j,
                             const RegistrationResult& reg, LinkRecord& link) {
  const int block = joint.state;
  link.is_outlier = reg.is_outlier;
  if (!reg.success) {
    link.outcome = LinkOutcome::kRegistrationFailed;
    ++counters_.registration_failed;
    return;
  }
  link.z = reg.z;
  link.covariance = reg.covariance;
  // Gate (nav_filter.h): ν = z − h(μ_i, μ_j), S = H J Hᵀ + R with H = [H_j H_i] (j: the robot
  // at the image, or its delayed state for a deferred link).
  const core::CameraRelativePoseModel& camera = *sensors_.camera();
  const LinkPair x0 =
      (LinkPair() << filter_.mean_block(block_j), filter_.mean_block(block)).finished();
  const Eigen::MatrixXd joint_cov = gate_joint(joint);
  link.outcome = gate_link(camera, x0, joint_cov, reg, options_.camera_gate_chi2, link)
                     ? LinkOutcome::kAccepted
                     : LinkOutcome::kGated;
  if (link.outcome == LinkOutcome::kAccepted) {
    const core::MeasCov R = reg.covariance;
    const LinkLinearisation lin = linearise_at_iterated_point(camera, x0, joint_cov, reg, link);
    // The EIF update adds Hᵀ R⁻¹ (z - h(x*) + H x*) to η at the point x*; Esdf::update forms
    // z - h' + H μ, so h' = h(x*) + H (μ - x*).
    const LinkPair dmu = wrapped_difference(x0, lin.x);
    const core::MeasVec h_at_mean = lin.h + lin.H_r * dmu.head<kD>() + lin.H_i * dmu.tail<kD>();
    if (core::Status s = filter_.update(block, block_j, reg.z, h_at_mean, lin.H_i, lin.H_r, R,
                                        core::angle_mask(camera));
        !s.ok()) {
      spdlog::warn("NavFilter: camera link {}-{} rejected by the filter: {}", link.frame_i,
                   link.frame_j, s.to_string());
      link.outcome = LinkOutcome::kGated;
    } else if (block_j == core::Esdf::kRobotBlock &&
               !bounds_.update(joint, lin.H_r, lin.H_i, R).ok()) {
      ++counters_.bound_update_failures;
    }
  }
  if (link.outcome == LinkOutcome::kAccepted) {
    ++counters_.links_accepted;
    if (link.is_outlier) ++counters_.outliers_accepted;
  } else {
    ++counters_.links_gated;
    if (link.is_outlier) ++counters_.outliers_rejected;
  }
}

}  // namespace nav::daemon
