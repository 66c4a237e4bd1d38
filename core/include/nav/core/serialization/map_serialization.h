#pragma once
// The map's serialize functions (archive.h), one per type serving both directions: the
// information matrix and vectors of the ESDF, the ESDF and the Algorithm 1 bounds (the state
// recovery's warm start: map_codec.cpp). Layouts: map_codec.h. Reading checks every size against the bytes
// present before allocating, every index range, that the two stored halves of Λ are exact
// transposes and the diagonal blocks exactly symmetric, and that bounds belong to states of the
// filter; errors name the field and its offset.

#include <cstdint>
#include <string>

#include "nav/core/filter/esdf.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/serialization/archive.h"

namespace nav::core {

template <class Archive>
void InformationMatrix::serialize(Archive& ar, std::uint32_t num_rows) {
  serialize_size(ar, blocks_written_, "blocks-written counter");
  const int d = block_dim_;
  const std::size_t block_bytes = 8 * static_cast<std::size_t>(d) * static_cast<std::size_t>(d);
  if constexpr (Archive::kReading) rows_.assign(num_rows, Row{});
  for (std::uint32_t i = 0; i < num_rows && ar.ok(); ++i) {
    Row& row = rows_[i];
    if constexpr (Archive::kReading) row.diagonal.resize(d, d);
    ar.values(row.diagonal, "diagonal block");
    auto k = static_cast<std::uint32_t>(row.off.size());
    ar(k, "neighbour count");
    if (!ar.check_count(k, 4 + block_bytes, "neighbour count")) return;
    if (!ar.check(k < num_rows, "row " + std::to_string(i) + " has " + std::to_string(k) +
                                    " neighbours but the filter has " +
                                    std::to_string(num_rows) + " blocks")) {
      return;
    }
    if constexpr (Archive::kReading) row.off.resize(k);
    for (Entry& e : row.off) {
      auto col = static_cast<std::uint32_t>(e.col);
      ar(col, "neighbour column");
      if (!ar.check(col < num_rows && col != i, "row " + std::to_string(i) +
                                                    " neighbour column " + std::to_string(col) +
                                                    " is not another block of " +
                                                    std::to_string(num_rows))) {
        return;
      }
      if constexpr (Archive::kReading) {
        for (const Entry& prev : row.off) {
          if (&prev == &e) break;
          if (!ar.check(prev.col != static_cast<int>(col),
                        "row " + std::to_string(i) + " lists neighbour " + std::to_string(col) +
                            " twice")) {
            return;
          }
        }
        e.col = static_cast<int>(col);
        e.block.resize(d, d);
      }
      ar.values(e.block, "off-diagonal block");
    }
  }
  if constexpr (Archive::kReading) {
    if (!ar.ok()) return;
    std::size_t halves = 0;
    for (std::uint32_t i = 0; i < num_rows; ++i) {
      const Row& row = rows_[i];
      if (!ar.check(row.diagonal == row.diagonal.transpose(),
                    "diagonal block " + std::to_string(i) + " is not symmetric")) {
        return;
      }
      for (const Entry& e : row.off) {
        const Block* mirror = find_block(e.col, static_cast<int>(i));
        if (!ar.check(mirror != nullptr && *mirror == e.block.transpose(),
                      "block (" + std::to_string(i) + ", " + std::to_string(e.col) +
                          ") has no exact transpose at (" + std::to_string(e.col) + ", " +
                          std::to_string(i) + ")")) {
          return;
        }
        ++halves;
      }
    }
    num_pairs_ = halves / 2;  // every half has its mirror and no row lists a column twice
  }
}

template <class Archive>
void BlockVector::serialize(Archive& ar, std::uint32_t num_blocks, const char* field) {
  if (!ar.check_count(std::uint64_t{num_blocks} * static_cast<std::uint64_t>(block_dim_), 8,
                      field)) {
    return;
  }
  if constexpr (Archive::kReading) {
    blocks_.assign(num_blocks, Segment(block_dim_));
    changed_.clear();
    all_changed_ = true;
  }
  for (Segment& s : blocks_) ar.values(s, field);
}

template <class Archive>
void Esdf::serialize(Archive& ar) {
  auto d = static_cast<std::uint32_t>(block_dim());
  auto n = static_cast<std::uint32_t>(num_blocks());
  ar(d, "block_dim");
  if (!ar.check(d >= 1 && d <= static_cast<std::uint32_t>(InformationMatrix::kMaxBlockDim),
                "block_dim " + std::to_string(d) + " outside [1, 12]")) {
    return;
  }
  ar(n, "block count");
  // A row is at least its diagonal block and its neighbour count; η and μ add 2 d doubles.
  if (!ar.check_count(n, 8 * d * d + 4 + 16 * d, "block count")) return;
  if constexpr (Archive::kReading) *this = Esdf(static_cast<int>(d));
  info_.serialize(ar, n);
  eta_.serialize(ar, n, "information vector η");
  mean_.serialize(ar, n, "mean μ");
}

template <class Archive>
void CovarianceBounds::serialize(Archive& ar, int num_filter_blocks) {
  auto d = static_cast<std::uint32_t>(block_dim_);
  ar(d, "bounds block_dim");
  if (!ar.check(d >= 1 && d <= static_cast<std::uint32_t>(InformationMatrix::kMaxBlockDim),
                "bounds block_dim " + std::to_string(d) + " outside [1, 12]")) {
    return;
  }
  bool certify = options_.certify_truncation;
  ar(certify, "certify_truncation");
  if constexpr (Archive::kReading) {
    if (!ar.ok()) return;
    *this = CovarianceBounds(static_cast<int>(d), BoundsOptions{certify});
  }
  const auto di = static_cast<Eigen::Index>(d);
  ar.matrix(robot_bound_, di, di, true, "robot bound");
  double robot_lambda = Archive::kReading ? 0.0 : robot_lambda_max();  // written computed
  ar(robot_lambda, "robot bound λmax");
  ar.check(robot_lambda >= 0, "negative robot bound λmax");
  if constexpr (Archive::kReading) robot_lambda_max_ = robot_lambda;
  ar.matrix(sigma_rr_hat_, di, di, true, "recovered Σ_rr");
  ar(residual_frobenius_, "residual");
  ar.check(residual_frobenius_ >= 0, "negative recovery residual");
  ar(kappa_, "κ");
  ar.check(kappa_ >= 0, "negative certificate κ");
  ar.matrix(certificate_robot_bound_, di, di, true, "certificate robot bound W");
  ar(certificate_lambda_, "certificate L");
  ar(lambda_sum_, "Σ λmax");
  ar(epoch_, "epoch");
  ar.check(epoch_ >= 0, "negative epoch " + std::to_string(epoch_));
  ar(pending_growth_, "rounding growth since set_recovery");
  ar.check(pending_growth_ >= 0, "negative rounding growth");
  auto m = static_cast<std::uint32_t>(num_bounds_);
  ar(m, "bound count");
  // state, bound (shape + d*d), λmax, snapshot bound (at least its 0x0 shape), λmax, epoch
  if (!ar.check_count(m, 4 + (8 + 8 * d * d) + 8 + 8 + 8 + 8, "bound count")) return;
  std::uint32_t state = 0;
  for (std::uint32_t k = 0; k < m && ar.ok(); ++k) {
    const std::uint32_t previous = state;
    if constexpr (!Archive::kReading) {
      while (!entries_[++state].present) {
      }
    }
    ar(state, "bound state");
    // Ascending delayed states of the filter (1..n-1): a corrupt index cannot size the table.
    if (!ar.check(state >= 1 && state > previous &&
                      static_cast<std::int64_t>(state) < num_filter_blocks,
                  "bound state " + std::to_string(state) + " is not a delayed state of the " +
                      std::to_string(num_filter_blocks) + "-block filter after state " +
                      std::to_string(previous))) {
      return;
    }
    if constexpr (Archive::kReading) entries_.resize(state + 1);
    Entry& e = entries_[state];
    e.present = true;
    ar.matrix(e.bound, di, di, false, "state bound");
    ar(e.lambda_max, "state bound λmax");
    ar.matrix(e.snapshot_bound, di, di, true, "snapshot bound");
    ar(e.snapshot_lambda_max, "snapshot λmax");
    ar(e.snapshot_epoch, "snapshot epoch");
    ar.check(e.snapshot_epoch >= -1 && e.snapshot_epoch <= epoch_ &&
                 (e.snapshot_epoch == -1) == (e.snapshot_bound.size() == 0),
             "snapshot epoch " + std::to_string(e.snapshot_epoch) + " of state " +
                 std::to_string(state) + " does not match its snapshot bound (" +
                 std::to_string(e.snapshot_bound.rows()) + " rows) and the epoch " +
                 std::to_string(epoch_));
  }
  if constexpr (Archive::kReading) num_bounds_ = static_cast<int>(m);
}

}  // namespace nav::core
