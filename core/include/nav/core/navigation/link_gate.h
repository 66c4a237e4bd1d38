#pragma once
// Camera links between delayed states (Eustice et al., RSS 2005 sec. IV): the gate and
// linearisation of a registered pair (which pairs to propose: link_proposer.h).
//
// Gate: d² = νᵀ S⁻¹ ν, S = H J Hᵀ + R, with ν = z − h(μ_i, μ_j) (angles wrapped), H = [H_j H_i]
// and J the certified joint of the proposal (bounds.h: J >= the filter's true joint, PSD
// difference, in the blocks' own units). S is factored by LLT: a non-positive pivot (S not
// positive definite) rejects the link, so an indefinite S can never pass with a negative d².
// Accepted when d² <= the 5-dof gate (chi_square.h).
//
// Linearisation: an accepted link is linearised at the iterated-EKF point of the robot (state i
// held at its mean; link_linearisation.h), not at the possibly stale mean: after a camera-off
// transit with a DVL dropout the mean can be metres off on a baseline of a few metres, and a
// bearing link linearised there moves the map to the wrong place.

#include <Eigen/Core>
#include <functional>
#include <string>

#include "nav/core/filter/esdf.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/navigation/link_linearisation.h"
#include "nav/core/navigation/nav_filter_records.h"
#include "nav/core/navigation/registration_table.h"
#include "nav/core/recovery/bounds.h"

namespace nav::core {

using WarningSink = std::function<void(const std::string&)>;

class LinkGate {
 public:
  LinkGate(double gate_chi2, WarningSink warn) : gate_chi2_(gate_chi2), warn_(std::move(warn)) {}

  /// The joint the gate uses: the proposal's certified joint (bounds.h).
  static Eigen::MatrixXd gate_joint(const LinkProposal& proposal);
  /// d² = νᵀ S⁻¹ ν by LLT of sym(S); false (d² untouched) when S is not positive definite or
  /// not finite.
  static bool mahalanobis_sq(const Eigen::Matrix<double, 5, 5>& S, const MeasVec& nu, double* d2);
  /// The gate at the means x0 = [x_j; x_i] with the joint covariance: fills the link's
  /// innovation and Mahalanobis distance; true when it passes.
  bool pass(const CameraRelativePoseModel& camera, const LinkPair& x0,
            const Eigen::MatrixXd& joint_cov, const RegistrationResult& reg,
            LinkRecord& link) const;
  /// The accepted link's linearisation at the robot's iterated point, or at the means where
  /// the iteration fails.
  LinkLinearisation linearise(const CameraRelativePoseModel& camera, const LinkPair& x0,
                              const Eigen::MatrixXd& joint_cov, const RegistrationResult& reg,
                              const LinkRecord& link) const;

 private:
  double gate_chi2_;
  WarningSink warn_;
};

/// a - b with the attitude components of both blocks wrapped to (-π, π].
LinkPair wrapped_difference(const LinkPair& a, const LinkPair& b);

}  // namespace nav::core
