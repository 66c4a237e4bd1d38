#pragma once
// A renewal of the exact marginals (exact_marginals.h: a factorisation and a selected inversion
// of the whole map) taken a fixed number of solves after its snapshot of Λ, so that it can be
// computed beside the solves that follow (StateRecoveryOptions::renewal_lag). core has no
// threads: a MarginalsLauncher decides where the job runs. The default (empty) runs it on the
// caller when its result is taken; navd and the replay start it on a thread
// (daemon/filter/marginals_launcher.h). The result is a pure function of the snapshot and is
// taken at a fixed solve, waiting there if it is not done: the filter's outputs are the same
// with either launcher, whatever the threads' timing.

#include <Eigen/SparseCore>
#include <functional>
#include <memory>

#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/status.h"

namespace nav::core {

/// Computes exact marginals (throws ExactMarginalsError as ExactMarginals::compute).
using MarginalsJob = std::function<std::shared_ptr<const ExactMarginals>()>;
/// Starts `job` and returns what waits for its result (called at most once, on the caller).
using MarginalsLauncher = std::function<MarginalsJob(MarginalsJob job)>;

class LaggedRenewal {
 public:
  LaggedRenewal() = default;
  /// A copy carries no renewal in flight (as FactorPreconditioner carries no factor).
  LaggedRenewal(const LaggedRenewal&) {}
  LaggedRenewal& operator=(const LaggedRenewal& other);
  LaggedRenewal(LaggedRenewal&&) noexcept = default;
  LaggedRenewal& operator=(LaggedRenewal&&) noexcept = default;

  /// Where later renewals run (empty: on the caller at take()).
  void set_launcher(MarginalsLauncher launcher) { launcher_ = std::move(launcher); }
  /// Starts the exact marginals of `lambda` (both triangles); drops one in flight first.
  void start(Eigen::SparseMatrix<double> lambda, int block_dim);
  bool in_flight() const { return static_cast<bool>(result_); }
  /// Solves counted (count_solve) since start(); 0 when none is in flight.
  int age() const { return age_; }
  void count_solve() {
    if (in_flight()) ++age_;
  }
  /// Waits for the renewal in flight and hands it over: kNotPositiveDefinite with the reason if
  /// its snapshot could not be factored, kInvalidArgument if none is in flight.
  Status take(std::shared_ptr<const ExactMarginals>* marginals);
  void drop();  ///< forgets the renewal in flight (a started job finishes and is discarded)

 private:
  MarginalsLauncher launcher_;
  MarginalsJob result_;  // empty: none in flight
  int age_ = 0;
};

}  // namespace nav::core
