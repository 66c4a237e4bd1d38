#pragma once
// A vector partitioned into equal blocks (one per filter state), used by the ESDF for the
// information vector η and the mean μ. Blocks live in a std::deque, so appending a delayed
// state is O(1) and never copies the vector (the "no allocation proportional to map size"
// rule of the predict step). A contiguous Eigen::VectorXd view is materialised lazily by
// dense(): only blocks changed since the last call are copied (all of them after more than
// kMaxTracked distinct changes, or when blocks were appended and the view must grow).

#include <Eigen/Core>

#include <cstdint>
#include <deque>
#include <vector>

namespace nav::core {

class BlockVector {
 public:
  using Segment = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 12, 1>;

  explicit BlockVector(int block_dim);

  int block_dim() const { return block_dim_; }
  int num_blocks() const { return static_cast<int>(blocks_.size()); }
  Eigen::Index size() const { return Eigen::Index{num_blocks()} * block_dim_; }

  /// Appends a zero block; returns its index.
  int append();
  void clear();

  const Segment& segment(int i) const { return blocks_[static_cast<size_t>(i)]; }
  /// Writable block i (marks it changed for dense()).
  Segment& mutable_segment(int i);
  void swap_blocks(int a, int b);

  /// Replaces all values; v.size() must equal size().
  void assign(const Eigen::Ref<const Eigen::VectorXd>& v);

  /// Contiguous copy, brought up to date on demand (see file comment). The reference stays
  /// valid until the next call of a non-const member.
  const Eigen::VectorXd& dense() const;

  /// `num_blocks` segments both ways; reading replaces the vector
  /// (core/serialization/map_serialization.h).
  template <class Archive>
  void serialize(Archive& ar, std::uint32_t num_blocks, const char* field);

 private:
  static constexpr size_t kMaxTracked = 64;
  void mark(int i);

  int block_dim_;
  std::deque<Segment> blocks_;
  mutable Eigen::VectorXd dense_;
  mutable std::vector<int> changed_;
  mutable bool all_changed_ = false;
};

}  // namespace nav::core
