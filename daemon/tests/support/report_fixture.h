#pragma once
// Test helper: writes a small simulated dive directory and the replay output directory of it
// (formats of hil-tests/README.md) with known values, for the `navtool report` tests.
//   truth: a lawnmower of 4 legs of 40 m north/south, 10 m apart east, 1 m/s, sampled every
//          1 s (piecewise linear, so interpolation at the samples is exact);
//   images every 4 s; SLAM = truth + (1 m north), dead reckoning = truth + (2 m east);
//   states: pose = truth + noise drawn from the exact marginal E (fixed seed), bound = 1.5 E
//           except every 10th state (bound = 0.5 E: not conservative), initial = 3 E;
//   links: a fixed list with known counts (kLinks); logdet: known values.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace nav::report::test {

namespace fs = std::filesystem;

inline constexpr long long kStartUs = 1'000'000'000;  // monotonic dive start (hil-tests)
inline constexpr int kTruthSeconds = 160;             // 4 legs of 40 s
inline constexpr int kImageEverySeconds = 4;
inline constexpr int kImages = kTruthSeconds / kImageEverySeconds;  // 40 (t = 0, 4, ..., 156 s)

/// True (x north, y east, heading) at t seconds after the start.
inline Eigen::Vector3d truth_xyh(double t_s) {
  const int leg = std::min(static_cast<int>(t_s / 40.0), 3);
  const double s = t_s - 40.0 * leg;
  const bool north = leg % 2 == 0;
  return {north ? s : 40.0 - s, 10.0 * leg, north ? 0.0 : M_PI};
}

/// The exact marginal of state k: a fixed SPD matrix growing slowly with k.
inline Eigen::Matrix<double, 6, 6> exact_marginal(int k) {
  Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Identity();
  a.diagonal() << 0.04, 0.09, 0.01, 1e-4, 1e-4, 4e-4;
  a *= 1.0 + 0.05 * k;
  a(0, 1) = a(1, 0) = 0.02;
  return a;
}

inline void write_file(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

// Built with streams: GCC 12 -O3 reports a false -Wrestrict on "," + std::string.
inline std::string matrix_cells(const Eigen::Matrix<double, 6, 6>& m) {
  std::ostringstream s;
  s.precision(17);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) s << ',' << m(r, c);
  return s.str();
}

inline std::string matrix_header(char prefix) {
  std::ostringstream s;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) s << ',' << prefix << r << c;
  return s.str();
}

inline std::string pose_row(long long t_us, const Eigen::Vector3d& xyh, double dx, double dy) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%lld,%.17g,%.17g,5,0,0,%.17g", t_us, xyh.x() + dx, xyh.y() + dy,
                xyh.z());
  return buf;
}

/// Writes the dive directory: truth.csv, images.csv, sim.json, config.yaml.
inline void write_dive(const fs::path& dir) {
  fs::create_directories(dir);
  std::string truth =
      "t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,u_mps,v_mps,w_mps,"
      "p_radps,q_radps,r_radps\n";
  for (int t = 0; t <= kTruthSeconds; ++t) {
    truth += pose_row(kStartUs + 1'000'000LL * t, truth_xyh(t), 0, 0) + ",1,0,0,0,0,0\n";
  }
  write_file(dir / "truth.csv", truth);
  std::string images =
      "frame_id,t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,altitude_m,camera_on\n";
  for (int k = 0; k < kImages; ++k) {
    const int t = k * kImageEverySeconds;
    images += std::to_string(k) + "," + pose_row(kStartUs + 1'000'000LL * t, truth_xyh(t), 0, 0) +
              ",3,1\n";
  }
  write_file(dir / "images.csv", images);
  write_file(dir / "sim.json",
             "{\"seed\": 7, \"images\": 40, \"registrations\": 30, "
             "\"registrations_succeeded\": 20, \"outliers_injected\": 4, "
             "\"track_length_m\": 190, \"duration_s\": 160}\n");
  write_file(dir / "config.yaml", "# fixture\n");
}

/// links.csv rows: 6 accepted (pairs (0,9) twice: 5 distinct), 2 gated (one outlier),
/// 1 registration_failed, 1 not_registered; outliers: 1 accepted, 2 rejected.
inline const char* kLinks =
    "t_us,frame_i,frame_j,state_i,state_j,outcome,mahalanobis_sq,is_outlier\n"
    "1036000000,0,9,0,9,accepted,2.5,0\n"
    "1036000000,0,9,0,9,accepted,2.1,0\n"
    "1040000000,1,10,1,10,accepted,1.0,0\n"
    "1080000000,2,20,2,20,accepted,3.0,0\n"
    "1100000000,5,25,5,25,accepted,4.0,1\n"
    "1120000000,3,30,3,30,accepted,0.5,0\n"
    "1120000000,4,30,4,30,gated,80.0,1\n"
    "1124000000,6,31,6,31,gated,50.0,0\n"
    "1128000000,7,32,7,32,registration_failed,,1\n"
    "1132000000,8,33,8,33,not_registered,,0\n";

struct ReplayFixtureOptions {
  bool with_initial_bound = true;
  bool with_optional_files = true;  ///< information_blocks.csv, logdet.csv, proposals.csv,
                                    ///< time_of_use.csv
  std::string dive_dir;             ///< written to summary.json "dive_dir" when not empty
};

/// Writes the replay output directory.
inline void write_replay(const fs::path& dir, const ReplayFixtureOptions& o = {}) {
  fs::create_directories(dir);
  std::string head =
      "t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,var_x,var_y,var_z,var_heading\n";
  std::string traj = head, dr = head;
  for (int k = 0; k < kImages; ++k) {
    const int t = k * kImageEverySeconds;
    const long long t_us = kStartUs + 1'000'000LL * t;
    traj += pose_row(t_us, truth_xyh(t), 1.0, 0.0) + ",0.01,0.01,0.01,0.0001\n";
    dr += pose_row(t_us, truth_xyh(t), 0.0, 2.0) + ",1,1,0.01,0.0001\n";
  }
  write_file(dir / "trajectory.csv", traj);
  write_file(dir / "dead_reckoning.csv", dr);

  std::mt19937 rng(42);
  std::normal_distribution<double> n01;
  std::string states = "state_id,frame_id,t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad" +
                       matrix_header('b') + matrix_header('e') +
                       (o.with_initial_bound ? matrix_header('i') : "") + "\n";
  for (int k = 0; k < kImages; ++k) {
    const int t = k * kImageEverySeconds;
    const Eigen::Matrix<double, 6, 6> e = exact_marginal(k);
    Eigen::Matrix<double, 6, 1> z;
    for (int i = 0; i < 6; ++i) z[i] = n01(rng);
    const Eigen::Matrix<double, 6, 1> err =
        Eigen::LLT<Eigen::Matrix<double, 6, 6>>(e).matrixL() * z;
    const Eigen::Vector3d xyh = truth_xyh(t);
    char pose[256];
    std::snprintf(pose, sizeof pose, "%d,%d,%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", k, k,
                  kStartUs + 1'000'000LL * t, xyh.x() + err[0], xyh.y() + err[1], 5 + err[2],
                  err[3], err[4], xyh.z() + err[5]);
    const double bound_scale = (k % 10 == 9) ? 0.5 : 1.5;
    states += pose + matrix_cells(bound_scale * e) + matrix_cells(e) +
              (o.with_initial_bound ? matrix_cells(3.0 * e) : "") + "\n";
  }
  write_file(dir / "states.csv", states);
  write_file(dir / "links.csv", kLinks);
  std::string summary = "{\"wall_s\": 2.0, \"images\": 40";
  if (o.with_optional_files) {
    summary += ", \"time_of_use_checks\": 2, \"time_of_use_conservative_fraction\": 1.0";
  }
  if (!o.dive_dir.empty()) summary += ", \"dive_dir\": \"" + o.dive_dir + "\"";
  write_file(dir / "summary.json", summary + "}\n");
  if (!o.with_optional_files) return;

  std::string proposals = "frame_id,candidates,proposed,accepted\n";
  for (int k = 0; k < kImages; ++k) proposals += std::to_string(k) + ",3,1,0\n";
  write_file(dir / "proposals.csv", proposals);
  // 41 blocks of 6 (40 states + robot): diagonal + chain + 5 distinct accepted links.
  std::string blocks = "# block_dim 6 num_blocks 41\ni,j\n";
  for (int k = 0; k < 41; ++k) blocks += std::to_string(k) + "," + std::to_string(k) + "\n";
  for (int k = 0; k < 40; ++k) blocks += std::to_string(k) + "," + std::to_string(k + 1) + "\n";
  for (const char* pair : {"0,9", "1,10", "2,20", "5,25", "3,30"})
    blocks += std::string(pair) + "\n";
  write_file(dir / "information_blocks.csv", blocks);
  std::string logdet = "state_i,state_j,ours,markov_blanket\n";
  for (int k = 0; k < kImages - 1; ++k) {
    logdet += std::to_string(kImages - 1) + "," + std::to_string(k) + "," +
              std::to_string(0.1 * k) + "," + std::to_string(-2.0 - 0.05 * k) + "\n";
  }
  write_file(dir / "logdet.csv", logdet);
  // Two checks (frames 10 and 20): ours 0.0 .. 0.8 (median 0.4), blanket -1 except one unset.
  std::string tou = "frame_id,state,ours,markov_blanket\n";
  for (int k = 0; k < 9; ++k) {
    tou += std::string(k < 4 ? "10," : "20,") + std::to_string(k % 4 + 1) + "," +
           std::to_string(0.1 * k) + "," + (k == 8 ? "" : "-1") + "\n";
  }
  write_file(dir / "time_of_use.csv", tou);
}

}  // namespace nav::report::test
