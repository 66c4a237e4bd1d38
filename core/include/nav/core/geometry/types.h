#pragma once
// Fixed-size Eigen types and the layout of the robot state (core/README.md "State").
//
// Robot state x_r in R^12, all in SI units and radians:
//   [x y z]              position of the vehicle origin in the local-level world frame (NED), m
//   [roll pitch heading] Z-Y-X Euler angles, R_world_body = Rz(heading) Ry(pitch) Rx(roll)
//   [u v w]              body-frame (FRD) linear velocity, m/s
//   [p q r]              body-frame angular rates, rad/s
// A pose-only block (pose graphs) is the first six elements.

#include <Eigen/Core>

namespace nav::core {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Mat6x12 = Eigen::Matrix<double, 6, 12>;

/// Index of each element in the robot state (and, for the first six, in a pose).
enum StateIndex : int {
  kX = 0, kY = 1, kZ = 2,
  kRoll = 3, kPitch = 4, kHeading = 5,
  kU = 6, kV = 7, kW = 8,
  kP = 9, kQ = 10, kR = 11,
};

inline constexpr int kPoseDim = 6;
inline constexpr int kRobotDim = 12;

}  // namespace nav::core
