// LaggedRenewal (recovery/lagged_renewal.h).
#include "nav/core/recovery/lagged_renewal.h"

#include <string>
#include <utility>

namespace nav::core {

LaggedRenewal& LaggedRenewal::operator=(const LaggedRenewal& other) {
  if (this != &other) {
    drop();
    launcher_ = other.launcher_;
  }
  return *this;
}

void LaggedRenewal::start(Eigen::SparseMatrix<double> lambda, int block_dim) {
  drop();
  auto snapshot = std::make_shared<const Eigen::SparseMatrix<double>>(std::move(lambda));
  MarginalsJob job = [snapshot, block_dim] {
    return std::make_shared<const ExactMarginals>(ExactMarginals::compute(*snapshot, block_dim));
  };
  result_ = launcher_ ? launcher_(std::move(job)) : std::move(job);
}

Status LaggedRenewal::take(std::shared_ptr<const ExactMarginals>* marginals) {
  if (!in_flight()) {
    return Status::Error(StatusCode::kInvalidArgument, "LaggedRenewal::take: none in flight");
  }
  const MarginalsJob result = std::exchange(result_, MarginalsJob{});
  age_ = 0;
  try {
    *marginals = result();
  } catch (const std::exception& e) {
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         std::string("LaggedRenewal::take: ") + e.what());
  }
  if (*marginals == nullptr) {
    return Status::Error(StatusCode::kInvalidArgument, "LaggedRenewal::take: no marginals");
  }
  return Status::Ok();
}

void LaggedRenewal::drop() {
  result_ = MarginalsJob{};
  age_ = 0;
}

}  // namespace nav::core
