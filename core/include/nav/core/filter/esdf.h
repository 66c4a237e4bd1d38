#pragma once
// Exactly sparse delayed-state filter (ESDF): Eustice, Singh & Leonard, "Exactly Sparse
// Delayed-State Filters", ICRA 2005; Eustice et al., "Visually Navigating the RMS Titanic with
// SLAM Information Filters", RSS 2005, eqs. (1)-(3).
//
// The state is the robot x_r (block 0, always) plus delayed states x_1..x_n (copies of the
// robot at image times), each a block of block_dim elements (12 for the vehicle, 6 for pose
// graphs). The filter keeps the information form  p(x) ∝ exp(-1/2 xᵀΛx + ηᵀx)  and a mean μ
// used only as the linearisation point (set by set_mean / recover_mean_direct, or propagated by
// predict). Delayed-state indices are stable for the filter's life.
//
// Exact sparsity: predict couples only the robot and the newest delayed state; each update
// touches only the blocks in its measurement. Every operation costs O(1) in the map size
// (no allocation proportional to the map), except recover_mean_direct (a sparse Cholesky).
//
// Errors: every fallible call returns a Status and leaves the filter bit-identical on error
// (NaN/Inf, wrong sizes, non-SPD noise, unknown blocks, model singularities).
// Not thread-safe: owned by the filter thread (docs/architecture.md).

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <exception>
#include <stdexcept>
#include <vector>

#include "nav/core/filter/block_vector.h"
#include "nav/core/filter/information_matrix.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/models/measurement.h"
#include "nav/core/status.h"

namespace nav::core {

/// What the last successful operation touched (the constant-time property).
struct UpdateStats {
  int blocks_written = 0;    ///< Λ blocks written/created/removed (both halves of a pair count)
  int segments_written = 0;  ///< η / μ block segments written
  int neighbours = 0;        ///< neighbours of the marginalised robot (predict only)
};

class Esdf {
 public:
  using Block = InformationMatrix::Block;
  static constexpr int kRobotBlock = 0;

  /// block_dim in [1, 12] (12 vehicle, 6 pose graph); throws std::invalid_argument otherwise.
  explicit Esdf(int block_dim);

  int block_dim() const { return info_.block_dim(); }
  int num_blocks() const { return info_.num_blocks(); }
  bool initialized() const { return num_blocks() > 0; }

  /// Starts (or restarts) the filter with the robot only: Λ = P0⁻¹, η = Λ x0, μ = x0.
  Status initialize(const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0);

  /// Time update with the linearised process x_{t+1} = f(x_t) + w, w ~ N(0, Q),
  /// f(x) ≈ f(μ_t) + F (x − μ_t). f_of_mean = f(μ_t) (any known control already added).
  /// Augments x_{t+1}, then marginalises x_t unless keep_current, in which case x_t is kept as
  /// a new delayed block (its index written to *kept_block) and x_{t+1} becomes block 0.
  /// Equations: see esdf.cpp.
  /// Arguments are Eigen::Ref so fixed-size Vec12/Mat12 bind without a heap copy.
  Status predict(const Eigen::Ref<const Eigen::VectorXd>& f_of_mean,
                 const Eigen::Ref<const Eigen::MatrixXd>& F,
                 const Eigen::Ref<const Eigen::MatrixXd>& Q, bool keep_current,
                 int* kept_block = nullptr);

  /// Same with the constant-velocity model evaluated at the current robot mean (block_dim 12).
  Status predict(const ConstantVelocityModel& model, double dt_s, bool keep_current,
                 int* kept_block = nullptr);

  /// EIF measurement update of one block (RSS 2005 eq. 3):
  ///   Λ_bb += Hᵀ R⁻¹ H,  η_b += Hᵀ R⁻¹ (ν + H μ_b),  ν = z − h(μ) with angle rows wrapped.
  /// h_at_mean = h(μ_b), H = ∂h/∂x_b at μ_b (dim x block_dim), R the measurement covariance.
  Status update(int block, const MeasVec& z, const MeasVec& h_at_mean, const MeasJac& H,
                const MeasCov& R, const AngleMask& angle_rows);

  /// Binary update of blocks a != b with H = [H_a | H_b] (e.g. a camera link between two
  /// delayed states): touches Λ_aa, Λ_ab, Λ_bb, η_a, η_b only.
  Status update(int a, int b, const MeasVec& z, const MeasVec& h_at_mean, const MeasJac& H_a,
                const MeasJac& H_b, const MeasCov& R, const AngleMask& angle_rows);

  /// Convenience: evaluates model.predict(μ_block, &H) at the current mean.
  template <class Model>
  Status update(const Model& model, int block, const MeasVec& z, const MeasCov& R);
  /// Convenience: evaluates model.predict(μ_a, μ_b, &H_a, &H_b) at the current mean.
  template <class Model>
  Status update(const Model& model, int a, int b, const MeasVec& z, const MeasCov& R);

  const InformationMatrix& information() const { return info_; }
  const Eigen::VectorXd& information_vector() const { return eta_.dense(); }
  /// Linearisation point μ (contiguous view; see BlockVector::dense()).
  const Eigen::VectorXd& mean() const { return mean_.dense(); }
  /// Mean of one block (no copy of the whole vector).
  const BlockVector::Segment& mean_block(int i) const { return mean_.segment(i); }

  /// Replaces the linearisation point (e.g. from the CG recovery); size and finiteness checked.
  Status set_mean(const Eigen::VectorXd& mean);
  /// Replaces the linearisation point of one block (O(block_dim), e.g. the robot's O(1)
  /// relinearisation); size and finiteness checked.
  Status set_mean_block(int block, const Eigen::Ref<const Eigen::VectorXd>& mean);
  /// Solves Λ μ = η by sparse Cholesky (CHOLMOD supernodal) and sets the mean.
  Status recover_mean_direct();

  /// Blocks touched by the last successful predict/update.
  const UpdateStats& last_stats() const { return stats_; }

  /// Λ (both halves, in storage order), η and μ both ways; reading replaces the filter
  /// (core/serialization/map_serialization.h, section "ESDF").
  template <class Archive>
  void serialize(Archive& ar);

 private:
  Status check_block(int block, const char* where) const;
  Status check_measurement(const MeasVec& z, const MeasVec& h, const MeasJac* H1, const MeasJac* H2,
                           const MeasCov& R, const char* where, Eigen::LLT<MeasCov>* llt) const;
  void begin_stats();
  void end_stats();

  InformationMatrix info_;
  BlockVector eta_;
  BlockVector mean_;
  UpdateStats stats_;
  size_t blocks_written_at_start_ = 0;
  // Scratch reused by predict (no allocation after the first few calls).
  std::vector<int> scratch_nbrs_;
  std::vector<Block> scratch_lambda_tj_;
  std::vector<Block> scratch_w_;
};

// ---- templates ----------------------------------------------------------------------------

namespace detail {
/// Maps a model's exception to a Status (domain_error -> kOutOfRange, invalid_argument ->
/// kInvalidArgument, anything else -> kNumericalFailure) naming `where`.
Status model_error(const char* where, const std::exception& e);
}  // namespace detail

template <class Model>
Status Esdf::update(const Model& model, int block, const MeasVec& z, const MeasCov& R) {
  if (Status s = check_block(block, "Esdf::update(model)"); !s.ok()) return s;
  MeasJac H;
  MeasVec h;
  try {
    h = model.predict(mean_.segment(block), &H);
  } catch (const std::exception& e) {
    return detail::model_error("Esdf::update(model)", e);
  }
  return update(block, z, h, H, R, angle_mask(model));
}

template <class Model>
Status Esdf::update(const Model& model, int a, int b, const MeasVec& z, const MeasCov& R) {
  if (Status s = check_block(a, "Esdf::update(model, a, b)"); !s.ok()) return s;
  if (Status s = check_block(b, "Esdf::update(model, a, b)"); !s.ok()) return s;
  MeasJac H_a, H_b;
  MeasVec h;
  try {
    h = model.predict(mean_.segment(a), mean_.segment(b), &H_a, &H_b);
  } catch (const std::exception& e) {
    return detail::model_error("Esdf::update(model, a, b)", e);
  }
  return update(a, b, z, h, H_a, H_b, R, angle_mask(model));
}

}  // namespace nav::core
