#pragma once
// Ground truth of the Sparus dataset for the real-frame tests: frame times (frames.csv) and the
// camera attitude interpolated from camera_poses.csv.
//
// camera_poses.csv rows: ts, world, camera, x y z, qx qy qz qw with the quaternion
// R_camera_world. The log repeats each value for ~0.36 s at 10 Hz, so the attitude is known
// only at the instants where the value changes; it is interpolated (slerp) between those
// instants, not row by row, and held constant outside them.

#include <Eigen/Geometry>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace nav::vision::testing {

struct SparusTruth {
  std::vector<std::string> frame_files;
  std::vector<double> frame_times_s;
  std::vector<double> knot_times_s;              ///< Instants where the logged value changes.
  std::vector<Eigen::Quaterniond> q_camera_world;  ///< At the knots.

  /// R_camera_world at time t (slerp between knots).
  Eigen::Matrix3d R_camera_world(double t_s) const {
    if (t_s <= knot_times_s.front()) return q_camera_world.front().toRotationMatrix();
    if (t_s >= knot_times_s.back()) return q_camera_world.back().toRotationMatrix();
    std::size_t k = 1;
    while (knot_times_s[k] < t_s) ++k;
    const double a = (t_s - knot_times_s[k - 1]) / (knot_times_s[k] - knot_times_s[k - 1]);
    return q_camera_world[k - 1].slerp(a, q_camera_world[k]).toRotationMatrix();
  }
  /// R_i_j of frame j in frame i (0-based frame indices): R_ci_w R_cj_w^T.
  Eigen::Matrix3d R_i_j(std::size_t i, std::size_t j) const {
    return R_camera_world(frame_times_s[i]) * R_camera_world(frame_times_s[j]).transpose();
  }
};

inline std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

/// Reads frames.csv and camera_poses.csv from `dir`; empty frame list when unreadable.
inline SparusTruth load_sparus_truth(const std::string& dir) {
  SparusTruth truth;
  std::ifstream frames(dir + "/frames.csv");
  std::string line;
  std::getline(frames, line);  // header
  while (std::getline(frames, line)) {
    const auto f = split_csv(line);
    if (f.size() < 2) continue;
    truth.frame_files.push_back(f[0]);
    truth.frame_times_s.push_back(std::stod(f[1]));
  }
  std::ifstream poses(dir + "/camera_poses.csv");
  std::getline(poses, line);
  std::string previous_value;
  while (std::getline(poses, line)) {
    const auto f = split_csv(line);
    if (f.size() < 10) continue;
    const std::string value = line.substr(line.find(',') + 1);
    if (value == previous_value) continue;
    previous_value = value;
    truth.knot_times_s.push_back(std::stod(f[0]));
    truth.q_camera_world.emplace_back(std::stod(f[9]), std::stod(f[6]), std::stod(f[7]),
                                      std::stod(f[8]));
    truth.q_camera_world.back().normalize();
  }
  return truth;
}

/// Angle of the rotation R_a^T R_b, radians.
inline double rotation_angle_between(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b) {
  return Eigen::AngleAxisd(R_a.transpose() * R_b).angle();
}

}  // namespace nav::vision::testing
