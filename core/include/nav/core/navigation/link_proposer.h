#pragma once
// Which pairs of images to propose for registration (Eustice et al., RSS 2005 sec. IV), from
// the Algorithm 1 bounds.
//
// Proposal test: with Δ = p_i − p_r (world x, y) and its covariance C from the certified
// proposal joint [Σ_rr Σ_ri; Σ_ir Σ~_ii], the pair is proposed when the confidence ellipse
// Δᵀ C⁻¹ Δ <= chi2(2 dof, confidence) can reach within D of the origin, tested as
//   ‖Δ‖ − sqrt(chi2 · λmax(C)) < D,   D = r_i + r_j + 2 ‖lever_xy‖,
// r = altitude · footprint half-diagonal per metre (the two images' footprints can touch).

#include "nav/core/filter/esdf.h"
#include "nav/core/geometry/types.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {

class LinkProposer {
 public:
  /// confidence in (0, 1); footprint half-diagonal per metre of altitude; the camera's mount.
  LinkProposer(double confidence, double footprint_per_altitude, const Vec6& x_body_camera);

  /// The proposal test (file comment) for delayed state `block` (image altitude altitude_i_m)
  /// against the robot (altitude_j_m); on a proposal fills `joint` from the bounds.
  bool propose(const Esdf& filter, const CovarianceBounds& bounds, const StateRecovery& recovery,
               int block, double altitude_i_m, double altitude_j_m, LinkProposal* joint) const;

 private:
  double chi2_2dof_;
  double footprint_per_altitude_;
  double lever_xy_m_;
};

}  // namespace nav::core
