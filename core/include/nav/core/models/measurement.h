#pragma once
// Common types of the measurement models (core/README.md; docs/architecture.md "Conventions" "one
// small type per sensor"). Fixed-capacity Eigen storage (at most 6 rows, 12 columns) so predicting
// a measurement and its Jacobian never allocates in the real-time path.
//
// Every model exposes:
//   int  dim() const;            number of measurement rows (<= kMaxMeasDim)
//   bool is_angle(int row) const; true when that row is an angle: residuals z - h(x) of such
//                                 rows must be wrapped to (-pi, pi] (wrap_angle_rows below).
// Unary models (one state block of size 6 = pose or 12 = robot state):
//   MeasVec predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H = nullptr) const;
//   H is dim x x.size(); columns of state elements the model does not use are zero.
// Binary models (two blocks a and b of equal size 6 or 12):
//   MeasVec predict(x_a, x_b, MeasJac* H_a = nullptr, MeasJac* H_b = nullptr) const;
//   H_a is dim x x_a.size() (columns of block a), H_b is dim x x_b.size() (block b); the
//   filter places them side by side as [H_a | H_b].
// A state of the wrong size is a programming error: std::invalid_argument naming the model.

#include <Eigen/Core>
#include <array>
#include <cstddef>

namespace nav::core {

inline constexpr int kMaxMeasDim = 6;
inline constexpr int kMaxBlockDim = 12;

using MeasVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxMeasDim, 1>;
using MeasCov = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxMeasDim, kMaxMeasDim>;
using MeasJac = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxMeasDim, kMaxBlockDim>;

/// Which rows of a measurement are angles (wrapped residuals).
struct AngleMask {
  std::array<bool, kMaxMeasDim> is_angle{};
  bool operator[](int row) const { return is_angle[static_cast<std::size_t>(row)]; }
};

/// Wraps the angle rows of a residual r (size model.dim()) to (-pi, pi] in place.
template <class Model>
void wrap_angle_rows(const Model& model, MeasVec& r);

/// The model's is_angle() rows as a mask (rows >= dim() are false), e.g. to store with a
/// queued measurement.
template <class Model>
AngleMask angle_mask(const Model& model);

/// Throws std::invalid_argument("<model>: state block has N elements, expected 6 or 12")
/// unless x.size() is 6 or 12 (or exactly 12 when `need_velocity`).
void require_block_size(Eigen::Index size, bool need_velocity, const char* model);

}  // namespace nav::core

#include "nav/core/geometry/rotation.h"

namespace nav::core {

template <class Model>
void wrap_angle_rows(const Model& model, MeasVec& r) {
  for (int row = 0; row < model.dim(); ++row) {
    if (model.is_angle(row)) r[row] = wrap_angle(r[row]);
  }
}

template <class Model>
AngleMask angle_mask(const Model& model) {
  AngleMask mask;
  for (int row = 0; row < model.dim(); ++row) {
    mask.is_angle[static_cast<std::size_t>(row)] = model.is_angle(row);
  }
  return mask;
}

}  // namespace nav::core
