#pragma once
// Replays a 3-D pose graph (g2o.h) as the delayed-state filter of Eustice et al. (RSS 2005),
// with state recovery (recovery/state_recovery.h) and the covariance bounds of Algorithm 1
// (recovery/bounds.h) at every step, and checks the bounds against exact marginals at the end.
//
// Mapping (data/README.md): vertices in index order; vertex 0 initialises the filter
// (Esdf, block 6) with the prior covariance `prior_covariance` (the same gauge prior as
// AssemblyOptions, so the final Λ equals assemble_information() when the chain is unbroken).
// Vertex k >= 1 is the new robot state:
//   * process model: the odometry edge (k-1 -> k) (or (k -> k-1), inverted): x_k = x_{k-1} (+) z
//     with F = ∂(x (+) z)/∂x, Q = J_z R J_zᵀ, R = Ω⁻¹; the previous robot is kept as a delayed
//     state (Esdf::predict keep_current).
//   * broken odometry chain (no edge between k-1 and k): the FIRST edge (file order) joining k
//     to any earlier vertex is used instead: the robot is predicted with F = 0 and a diffuse
//     Q = diffuse_process_variance I (x_k independent of x_{k-1}: a weak prior of information
//     1/diffuse at the file's estimate) and that edge is applied as an ordinary link. A vertex
//     with no edge to an earlier vertex is an error naming it (start()).
//   * every other edge (j, k), j < k, is a camera link: it tightens the bound of j (propose +
//     Kalman update, before the filter sees it) and then updates the filter (binary
//     RelativePose6Model update).
// Bounds timing: the recovery of step k runs after the prediction and before k's links (link
// proposal needs the pre-registration joint); the bound stored for vertex k when it becomes a
// delayed state (step k+1) is the robot bound of step k, i.e. before k's own links (certified,
// slightly looser than after them).
// Linearisation: at the file's estimates throughout (the filter's mean is the file estimate;
// f(μ) of each prediction is the file's pose of the new vertex).
//
// Each step runs in four phases so a caller can time them (core has no clocks): predict(),
// recover(), update_bounds(), apply_links(); step() runs all four.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/geometry/types.h"
#include "nav/core/posegraph/g2o.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/recovery/state_recovery.h"
#include "nav/core/status.h"

namespace nav::core {

/// Which representation of Λ the recovery multiplies with.
enum class RecoveryOperator {
  kInformationMatrix,  ///< the filter's block matrix directly (InformationMatrix::multiply)
  kCsrSnapshot,        ///< a CSR copy per step (InformationMatrix::to_sparse, O(nnz) per step)
};

struct ReplayOptions {
  StateRecoveryOptions recovery;
  BoundsOptions bounds;
  RecoveryOperator recovery_operator = RecoveryOperator::kInformationMatrix;
  /// Covariance of vertex 0 (gauge prior), [x y z roll pitch heading]; default σ 1 mm, 1 mrad.
  Mat6 prior_covariance = Mat6::Identity() * 1e-6;
  /// Variance of the diffuse process noise used for a broken odometry chain (> 0).
  double diffuse_process_variance = 1e6;

  Status validate() const;
};

class PoseGraphReplay {
 public:
  /// Keeps a reference to `graph` (must outlive the replay).
  PoseGraphReplay(const PoseGraph& graph, ReplayOptions options);

  /// Validates the graph and options, assigns process models, initialises with vertex 0.
  /// kInvalidArgument names the vertex id without an edge to an earlier vertex, or the edge
  /// line with a non-SPD information matrix / a self-loop.
  Status start();

  int num_vertices() const { return static_cast<int>(graph_.vertices.size()); }
  /// Vertex index handled by the next predict(); num_vertices() when done.
  int next_vertex() const { return next_; }
  bool done() const { return next_ >= num_vertices(); }

  /// Phase 1: new robot state for vertex next_vertex() (filter, warm start, robot bound).
  Status predict();
  /// Phase 2: state recovery on the current Λ (mode from options) and the bounds certificate.
  RecoveryResult recover();
  /// Phase 3: propose + Kalman update of the bound of every link of the current vertex. A
  /// refused update (joint not PSD) is counted (skipped_bound_updates) and not an error.
  Status update_bounds();
  /// Phase 4: the filter's link updates; advances to the next vertex.
  Status apply_links();
  /// All four phases; *result (optional) receives the recovery result.
  Status step(RecoveryResult* result = nullptr);

  /// Links (non-process edges) of the vertex being processed (after predict()).
  int current_links() const;
  /// Vertices whose odometry chain was broken (process from another edge).
  int broken_chain_vertices() const { return broken_chain_; }
  /// Link bound updates refused because the proposal joint was not PSD (only possible
  /// without certification, from a stale truncated recovery); that bound stays as it was.
  int skipped_bound_updates() const { return skipped_bound_updates_; }

  const Esdf& filter() const { return filter_; }
  const StateRecovery& recovery() const { return recovery_; }
  const CovarianceBounds& bounds() const { return bounds_; }
  const ReplayOptions& options() const { return options_; }
  /// Filter block of a vertex index already in the filter (robot = 0), -1 otherwise.
  int block_of_vertex(int vertex_index) const;

 private:
  struct Link {
    const G2oEdge* edge;
    Mat6 covariance;
  };
  struct VertexPlan {
    const G2oEdge* process = nullptr;  // edge used as the process model
    bool chain = false;                // process edge joins k-1 and k
    std::vector<Link> links;           // every other edge (j, k), j < k
  };

  Status process_model(int k, Eigen::MatrixXd* F, Eigen::MatrixXd* Q) const;
  Status link_jacobians(const Link& link, MeasJac* H_a, MeasJac* H_b) const;

  const PoseGraph& graph_;
  ReplayOptions options_;
  Esdf filter_;
  StateRecovery recovery_;
  CovarianceBounds bounds_;
  BoundsSnapshot renewal_snapshot_;  // of the Λ of the lagged renewal in flight
  std::vector<VertexPlan> plan_;
  std::vector<int> block_of_vertex_;
  int next_ = 0;
  int current_ = -1;  // vertex being processed (between predict and apply_links)
  int broken_chain_ = 0;
  int skipped_bound_updates_ = 0;
  bool started_ = false;
};

/// Bounds against exact marginals at the end of a replay (paper Fig. 3).
struct BoundsCheck {
  int checked = 0;                        ///< delayed states + the robot
  int conservative = 0;                   ///< bound - exact PSD within tolerance
  double worst_min_eigenvalue = 0;        ///< smallest eigenvalue of bound - exact over all states
  std::vector<double> logdet_ratio_ours;  ///< per delayed state
  std::vector<double> logdet_ratio_markov_blanket;  ///< per delayed state
  int markov_blanket_overconfident = 0;             ///< MB - exact not PSD
  int not_positive_definite_bounds = 0;  ///< bounds that are not SPD (no log det; uncertified)
};

/// Compares every stored bound (and the robot's) with the exact marginal from `exact`
/// (computed by the caller from the filter's final Λ, so it can be timed), and evaluates the
/// Markov-blanket covariance of each delayed state against the robot for comparison.
/// `tolerance` is is_conservative()'s relative tolerance.
BoundsCheck check_bounds(const PoseGraphReplay& replay, const ExactMarginals& exact,
                         double tolerance = 1e-9, bool with_markov_blanket = true);

}  // namespace nav::core
