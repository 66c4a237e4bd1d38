// Recovery jobs, the inline executor and the hand-off schedule (navigation/recovery_executor.h).
#include "nav/core/navigation/recovery_executor.h"

#include <cmath>
#include <utility>

#include "nav/core/recovery/exact_marginals.h"

namespace nav::core {

void run_recovery_job(StateRecovery& recovery, const InformationMatrix& lambda,
                      const Eigen::VectorXd& eta, RecoveryOutput& output) {
  output.result = RecoveryResult{};
  output.marginals.resize(0, 0);
  if (Status s = recovery.set_solution(output.solution); !s.ok()) {
    output.result.status = s;
    return;
  }
  output.result = recovery.solve(lambda, eta);
  output.solution = recovery.solution();
  const ExactMarginals* exact = recovery.refreshed_marginals();
  if (!output.result.status.ok() || !output.result.refreshed || exact == nullptr) return;
  output.marginals = exact->marginals();
}

InlineRecoveryExecutor::InlineRecoveryExecutor(int block_dim, const StateRecoveryOptions& options)
    : block_dim_(block_dim), options_(options), recovery_(block_dim, options), lambda_(block_dim) {}

void InlineRecoveryExecutor::submit(const InformationMatrix& lambda, const Eigen::VectorXd& eta,
                                    const Eigen::MatrixXd& warm_start) {
  lambda_ = lambda;  // the job runs later, on this snapshot
  eta_ = eta;
  output_.solution = warm_start;
  submitted_ = true;
  done_ = false;
}

const RecoveryOutput& InlineRecoveryExecutor::peek() {
  if (!done_) run_recovery_job(recovery_, lambda_, eta_, output_);
  done_ = true;
  return output_;
}

const RecoveryOutput& InlineRecoveryExecutor::wait() {
  const RecoveryOutput& out = peek();
  submitted_ = false;
  return out;
}

void InlineRecoveryExecutor::set_ready(const RecoveryOutput& output) {
  output_ = output;
  submitted_ = true;
  done_ = true;
}

std::unique_ptr<RecoveryExecutor> InlineRecoveryExecutor::make_idle() const {
  return std::make_unique<InlineRecoveryExecutor>(block_dim_, options_);
}

RecoverySchedule::RecoverySchedule(std::unique_ptr<RecoveryExecutor> executor, double handoff_s)
    : executor_(std::move(executor)),
      handoff_delay_us_(static_cast<std::int64_t>(std::llround(handoff_s * 1e6))) {}

RecoverySchedule::RecoverySchedule(const RecoverySchedule& other)
    : handoff_delay_us_(other.handoff_delay_us_), handoff_us_(other.handoff_us_) {
  if (!other.executor_) return;
  executor_ = other.executor_->make_idle();
  if (other.executor_->busy()) executor_->set_ready(other.executor_->peek());
}

RecoverySchedule& RecoverySchedule::operator=(const RecoverySchedule& other) {
  if (this != &other) {
    RecoverySchedule copy(other);
    *this = std::move(copy);
  }
  return *this;
}

void RecoverySchedule::submit(const InformationMatrix& lambda, const Eigen::VectorXd& eta,
                              const Eigen::MatrixXd& warm_start, std::int64_t time_us) {
  executor_->submit(lambda, eta, warm_start);
  handoff_us_ = time_us + handoff_delay_us_;
}

void RecoverySchedule::restore(const RecoveryOutput& output, std::int64_t handoff_us) {
  executor_->set_ready(output);
  handoff_us_ = handoff_us;
}

}  // namespace nav::core
