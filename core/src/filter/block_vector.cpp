// Block-partitioned vector with a lazily materialised contiguous view (block_vector.h).
#include "nav/core/filter/block_vector.h"

#include <algorithm>
#include <cassert>

namespace nav::core {

BlockVector::BlockVector(int block_dim) : block_dim_(block_dim) { changed_.reserve(kMaxTracked); }

void BlockVector::mark(int i) {
  if (all_changed_) return;
  if (changed_.size() >= kMaxTracked) {
    all_changed_ = true;
    changed_.clear();
    return;
  }
  changed_.push_back(i);
}

int BlockVector::append() {
  blocks_.emplace_back(Segment::Zero(block_dim_));
  const int i = num_blocks() - 1;
  mark(i);
  return i;
}

void BlockVector::clear() {
  blocks_.clear();
  changed_.clear();
  all_changed_ = true;
}

BlockVector::Segment& BlockVector::mutable_segment(int i) {
  mark(i);
  return blocks_[static_cast<size_t>(i)];
}

void BlockVector::swap_blocks(int a, int b) {
  std::swap(blocks_[static_cast<size_t>(a)], blocks_[static_cast<size_t>(b)]);
  mark(a);
  mark(b);
}

void BlockVector::assign(const Eigen::Ref<const Eigen::VectorXd>& v) {
  assert(v.size() == size());
  for (int i = 0; i < num_blocks(); ++i) {
    blocks_[static_cast<size_t>(i)] = v.segment(Eigen::Index{i} * block_dim_, block_dim_);
  }
  changed_.clear();
  all_changed_ = true;
}

const Eigen::VectorXd& BlockVector::dense() const {
  const int d = block_dim_;
  if (dense_.size() != size()) {
    // Appended blocks are in changed_ (or all_changed_); existing values are kept.
    dense_.conservativeResize(size());
  }
  if (all_changed_) {
    for (int i = 0; i < num_blocks(); ++i) {
      dense_.segment(Eigen::Index{i} * d, d) = blocks_[static_cast<size_t>(i)];
    }
  } else {
    for (int i : changed_) {
      if (i < num_blocks()) dense_.segment(Eigen::Index{i} * d, d) = blocks_[static_cast<size_t>(i)];
    }
  }
  changed_.clear();
  all_changed_ = false;
  return dense_;
}

}  // namespace nav::core
