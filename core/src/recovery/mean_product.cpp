// Λμ kept between steps of the recovery (recovery/mean_product.h).
#include "nav/core/recovery/mean_product.h"

#include <algorithm>

namespace nav::core {

void MeanProduct::moved(int block) {
  if (valid_ && std::find(moved_.begin(), moved_.end(), block) == moved_.end()) {
    moved_.push_back(block);
  }
}

void MeanProduct::set(const Eigen::Ref<const Eigen::VectorXd>& product, long stamp) {
  base_ = product;
  stamp_ = stamp;
  valid_ = true;
  moved_.clear();
}

int MeanProduct::update(const InformationMatrix& lambda, const std::vector<int>* changed_rows,
                        const Eigen::Ref<const Eigen::VectorXd>& mean, long stamp,
                        Eigen::Ref<Eigen::VectorXd> out) {
  const int d = lambda.block_dim(), blocks = lambda.num_blocks();
  const bool usable = valid_ && changed_rows != nullptr && stamp == stamp_ + 1 &&
                      mean.size() == lambda.dim() && out.size() == lambda.dim() &&
                      base_.size() <= lambda.dim() && base_.size() % d == 0;
  valid_ = false;
  if (!usable) {
    moved_.clear();
    return -1;
  }
  due_.assign(static_cast<size_t>(blocks), 0);
  // Rows appended since the base have no old value: they are due.
  for (int b = static_cast<int>(base_.size() / d); b < blocks; ++b)
    due_[static_cast<size_t>(b)] = 1;
  for (int b : *changed_rows) {
    if (b >= 0 && b < blocks) due_[static_cast<size_t>(b)] = 1;
  }
  for (int b : moved_) {
    if (b < 0 || b >= blocks) continue;
    due_[static_cast<size_t>(b)] = 1;
    for (int k = 0; k < lambda.num_neighbours(b); ++k) {
      due_[static_cast<size_t>(lambda.neighbour(b, k))] = 1;
    }
  }
  moved_.clear();
  out.head(base_.size()) = base_;
  int recomputed = 0;
  for (int b = 0; b < blocks; ++b) {
    if (!due_[static_cast<size_t>(b)]) continue;
    auto row = out.segment(Eigen::Index{b} * d, d);
    row.noalias() = lambda.diagonal_block(b) * mean.segment(Eigen::Index{b} * d, d);
    for (int k = 0; k < lambda.num_neighbours(b); ++k) {
      const Eigen::Index j = lambda.neighbour(b, k);
      row.noalias() += lambda.neighbour_block(b, k) * mean.segment(j * d, d);
    }
    ++recomputed;
  }
  return recomputed;
}

}  // namespace nav::core
