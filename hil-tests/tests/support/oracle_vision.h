#pragma once
// A stand-in for the vision process in HIL tests: answers navd's link proposals
// (link_proposal_t on NAV_LINK_PROPOSAL) with registration_t on NAV_REGISTRATION computed from
// the dive's truth.csv, as the simulator's oracle does for the dive's own images
// (hil-tests/README.md "Oracle registrations"): the 5-DOF CameraRelativePoseModel of the true
// poses at the two images' times (navd's times of validity mapped back to dive time with the
// player's dive_start_us / host_start_us; truth interpolated linearly between its 20 Hz rows),
// plus the oracle's noise (baseline direction 0.5 deg, rotation 0.2 deg); success when the
// camera centres are closer than 1.8 footprint radii at `altitude_m`, else a failed
// registration. It echoes the proposal's run_id and sequence (navd applies only answers to its
// own proposals). utime = the host's CLOCK_REALTIME when answered. Called on the thread that
// runs lcm.handle*(); the answer is published from the handler.

#include <atomic>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/link_proposal_t.hpp>
#include <navlcm/registration_t.hpp>
#include <random>
#include <string>
#include <vector>

#include "nav/core/geometry/pose.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/core/navigation/sensor_models.h"
#include "sim_dive.h"

namespace nav::hil::test {

class OracleVision {
 public:
  OracleVision(const daemon::NavdConfig& config, const std::filesystem::path& truth_csv,
               double altitude_m, lcm::LCM& lcm)
      : models_(daemon::filter_options_from_config(config).sensors),
        rows_(nav::sim::test::read_csv(truth_csv)),
        lcm_(lcm) {
    r_fp_m_ = altitude_m * models_.footprint_radius_per_altitude();
  }
  /// The player's time mapping (PlayerOptions::on_start; any thread).
  void set_mapping(std::int64_t dive_start_us, std::int64_t host_start_us) {
    dive_start_us_.store(dive_start_us);
    host_start_us_.store(host_start_us);
    mapped_.store(true);
  }
  void on_proposal(const lcm::ReceiveBuffer*, const std::string&,
                   const navlcm::link_proposal_t* p) {
    ++proposals;
    if (!mapped_.load()) return;
    const core::Vec12 x_i = truth_at(dive_time(p->time_of_validity_i_us));
    const core::Vec12 x_j = truth_at(dive_time(p->time_of_validity_j_us));
    const core::CameraRelativePoseModel& camera = *models_.camera();
    const core::Vec6 c_i = core::head_to_tail(x_i.head<6>(), camera.x_body_camera);
    const core::Vec6 c_j = core::head_to_tail(x_j.head<6>(), camera.x_body_camera);
    navlcm::registration_t r{};
    r.frame_id_i = p->frame_id_i;
    r.frame_id_j = p->frame_id_j;
    r.run_id = p->run_id;
    r.sequence = p->sequence;
    r.success = (c_i.head<2>() - c_j.head<2>()).norm() < 1.8 * r_fp_m_;
    r.overlap_fraction = -1.0;
    const double sd_dir = 0.5 * M_PI / 180.0, sd_rot = 0.2 * M_PI / 180.0;
    const double sd[5] = {sd_dir, sd_dir, sd_rot, sd_rot, sd_rot};
    const core::MeasVec z = camera.predict(x_i, x_j);
    for (int k = 0; k < 5; ++k) {
      r.measurement[k] = std::remainder(z(k) + sd[k] * n01_(rng_), 2.0 * M_PI);
      for (int l = 0; l < 5; ++l) r.covariance[k * 5 + l] = k == l ? sd[k] * sd[k] : 0.0;
    }
    r.utime = daemon::realtime_us();
    if (lcm_.publish("NAV_REGISTRATION", &r) == 0) {
      ++answered;
      if (r.success) ++succeeded;
    }
  }

  int proposals = 0, answered = 0, succeeded = 0;

 private:
  double dive_time(std::int64_t host_validity_us) const {
    return static_cast<double>(dive_start_us_.load() + (host_validity_us - host_start_us_.load()));
  }
  /// truth.csv (t_us, 12 state values) interpolated linearly (angles unwrapped) at `t_us`.
  core::Vec12 truth_at(double t_us) const {
    std::size_t k = 1;
    while (k + 1 < rows_.size() && rows_[k][0] < t_us) ++k;
    const std::vector<double>& a = rows_[k - 1];
    const std::vector<double>& b = rows_[k];
    const double w = std::clamp((t_us - a[0]) / (b[0] - a[0]), 0.0, 1.0);
    core::Vec12 x;
    for (int i = 0; i < 12; ++i) {
      double d = b[i + 1] - a[i + 1];
      if (i >= 3 && i <= 5) d = std::remainder(d, 2.0 * M_PI);
      x(i) = a[i + 1] + w * d;
    }
    return x;
  }

  core::SensorModels models_;
  std::vector<std::vector<double>> rows_;
  lcm::LCM& lcm_;
  double r_fp_m_ = 1.0;
  std::atomic<std::int64_t> dive_start_us_{0}, host_start_us_{0};
  std::atomic<bool> mapped_{false};
  std::mt19937_64 rng_{11};
  std::normal_distribution<double> n01_{0.0, 1.0};
};

}  // namespace nav::hil::test
