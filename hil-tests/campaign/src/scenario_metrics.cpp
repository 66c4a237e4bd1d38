// The fault campaign's measurements; see scenario_metrics.h and fault_campaign.h.
#include "scenario_metrics.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace nav::campaign {
namespace {

/// Horizontal NEES e' P^-1 e (2 DOF) and sqrt(trace P) of a published solution.
struct XyCheck {
  double error_m = 0.0, nees = 0.0, sigma_m = 0.0;
};

XyCheck check_xy(const navlcm::nav_solution_t& s, std::pair<double, double> truth_xy) {
  Eigen::Matrix2d P;
  P << s.pose_covariance[0], s.pose_covariance[1], s.pose_covariance[6], s.pose_covariance[7];
  const Eigen::Vector2d e(s.p_world_m[0] - truth_xy.first, s.p_world_m[1] - truth_xy.second);
  XyCheck c;
  c.error_m = e.norm();
  c.sigma_m = std::sqrt(std::max(0.0, P.trace()));
  const Eigen::LDLT<Eigen::Matrix2d> ldlt(0.5 * (P + P.transpose()));
  c.nees = ldlt.info() == Eigen::Success && ldlt.isPositive() ? e.dot(ldlt.solve(e)) : INFINITY;
  return c;
}

const navlcm::sensor_health_t* find_sensor(const navlcm::health_t& h, const std::string& name) {
  for (const navlcm::sensor_health_t& s : h.sensors) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

/// Which field meets the detector in `now` (against `before`), "" when none.
std::string detector_field(Detector d, const navlcm::sensor_health_t& now,
                           const navlcm::sensor_health_t* before) {
  char text[128] = {};
  switch (d) {
    case Detector::kSilent:
      if (!now.connected) return "connected = false";
      if (now.last_message_age_s > 1.0) {
        std::snprintf(text, sizeof text, "last_message_age_s = %.2f", now.last_message_age_s);
      }
      break;
    case Detector::kDisconnected:
      if (!now.connected) return "connected = false";
      if (before && now.reconnects > before->reconnects) return "reconnects grew";
      break;
    case Detector::kRejected:
      if (before && now.rejected_updates > before->rejected_updates) {
        std::snprintf(text, sizeof text, "rejected_updates +%lld",
                      static_cast<long long>(now.rejected_updates - before->rejected_updates));
      } else if (before && now.decode_errors > before->decode_errors) {
        std::snprintf(text, sizeof text, "decode_errors +%lld",
                      static_cast<long long>(now.decode_errors - before->decode_errors));
      } else if (now.nis_mean > 4.0 * now.nis_expected && now.nis_expected > 0.0) {
        std::snprintf(text, sizeof text, "nis_mean = %.1f (expected %.1f)", now.nis_mean,
                      now.nis_expected);
      }
      break;
    case Detector::kWallClockJump:  // health_t.status, not a sensor's (fill_detection)
    case Detector::kNone:
      break;
  }
  return text;
}

/// The mean, -1 for no samples (a window without solutions).
double mean(const std::vector<double>& v) {
  if (v.empty()) return -1.0;
  double sum = 0.0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

}  // namespace

TruthTrack::TruthTrack(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(csv.string() + ": cannot read the truth");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',') && row.size() < 3;) {
      row.push_back(std::stod(cell));
    }
    if (row.size() == 3) rows_.push_back(std::move(row));
  }
  if (rows_.size() < 2) throw std::runtime_error(csv.string() + ": fewer than 2 truth rows");
}

std::pair<double, double> TruthTrack::xy_at(double t_us) const {
  auto it = std::lower_bound(rows_.begin(), rows_.end(), t_us,
                             [](const std::vector<double>& r, double t) { return r[0] < t; });
  if (it == rows_.begin()) return {rows_.front()[1], rows_.front()[2]};
  if (it == rows_.end()) return {rows_.back()[1], rows_.back()[2]};
  const std::vector<double>& b = *it;
  const std::vector<double>& a = *(it - 1);
  const double f = (t_us - a[0]) / (b[0] - a[0]);
  return {a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
}

void fill_track_metrics(const Recording& rec, const TruthTrack& truth, const TimeMap& map,
                        const FaultScenario& scenario, ScenarioResult& out) {
  std::vector<double> before, during, after;
  for (const navlcm::nav_solution_t& s : rec.solutions) {
    const double t_s = map.dive_s(s.time_of_validity_us);
    if (t_s < 0.0) continue;
    const XyCheck c = check_xy(s, truth.xy_at(map.dive_start_us + t_s * 1e6));
    ++out.solutions;
    if (t_s < scenario.from_s) {
      if (t_s >= 10.0) before.push_back(c.nees);  // after initialisation settles
      out.sigma_xy_start_m = c.sigma_m;
      continue;
    }
    out.max_xy_error_m = std::max(out.max_xy_error_m, c.error_m);
    if (t_s < scenario.to_s) {
      during.push_back(c.nees);
      out.sigma_xy_end_m = c.sigma_m;
    } else {
      after.push_back(c.nees);
    }
  }
  out.nees_before = mean(before);
  out.nees_during = mean(during);
  out.nees_after = mean(after);
}

void fill_detection(const Recording& rec, std::int64_t fault_realtime_us,
                    const FaultScenario& scenario, ScenarioResult& out) {
  if (scenario.detector == Detector::kNone) return;
  if (scenario.detector == Detector::kWallClockJump) {
    for (std::size_t i = 0; i < rec.health.size() && i < rec.health_received_us.size(); ++i) {
      const std::string& status = rec.health[i].status;
      const auto at = status.find("wall clock jumped");
      if (rec.health_received_us[i] < fault_realtime_us || at == std::string::npos) continue;
      out.detected_after_s = (rec.health_received_us[i] - fault_realtime_us) * 1e-6;
      out.detected_by = "status: " + status.substr(at);
      return;
    }
    return;
  }
  const navlcm::sensor_health_t* before = nullptr;
  for (const navlcm::health_t& h : rec.health) {
    const navlcm::sensor_health_t* now = find_sensor(h, scenario.sensor);
    if (now == nullptr) continue;
    if (h.utime < fault_realtime_us) {
      before = now;
      continue;
    }
    if (std::string field = detector_field(scenario.detector, *now, before); !field.empty()) {
      out.detected_after_s = (h.utime - fault_realtime_us) * 1e-6;
      out.detected_by = scenario.sensor + "." + field;
      return;
    }
  }
}

const navlcm::sensor_health_t* sensor_at(const Recording& rec, const std::string& sensor,
                                         std::int64_t realtime_us) {
  const navlcm::sensor_health_t* found = nullptr;
  for (std::size_t i = 0; i < rec.health.size() && i < rec.health_received_us.size(); ++i) {
    if (rec.health_received_us[i] >= realtime_us) break;
    found = find_sensor(rec.health[i], sensor);
  }
  return found;
}

void write_health_csv(const Recording& rec, const std::filesystem::path& path) {
  std::ofstream out(path, std::ios::trunc);
  out << "utime,queue_depth,cpu_percent,rss_mb";
  const auto widest = std::max_element(rec.health.begin(), rec.health.end(),
                                       [](const navlcm::health_t& a, const navlcm::health_t& b) {
                                         return a.sensors.size() < b.sensors.size();
                                       });
  if (widest != rec.health.end()) {
    for (const navlcm::sensor_health_t& s : widest->sensors) {
      for (const char* f : {"connected", "age_s", "records", "decode_errors", "reconnects",
                            "rejected_updates", "nis_mean"}) {
        out << "," << s.name << "." << f;
      }
    }
  }
  out << "\n";
  for (const navlcm::health_t& h : rec.health) {
    out << h.utime << "," << h.queue_depth << "," << h.cpu_percent << "," << h.rss_mb;
    for (const navlcm::sensor_health_t& s : h.sensors) {
      out << "," << int{s.connected} << "," << s.last_message_age_s << "," << s.records << ","
          << s.decode_errors << "," << s.reconnects << "," << s.rejected_updates << ","
          << s.nis_mean;
    }
    out << "\n";
  }
  if (!out) throw std::runtime_error(path.string() + ": cannot write the health CSV");
}

void write_solutions_csv(const Recording& rec, const TruthTrack& truth, const TimeMap& map,
                         const std::filesystem::path& path) {
  std::ofstream out(path, std::ios::trunc);
  out << "dive_s,x_m,y_m,truth_x_m,truth_y_m,xy_error_m,sigma_xy_m,nees_xy,delayed_states,"
         "filter_status\n";
  for (const navlcm::nav_solution_t& s : rec.solutions) {
    const double t_s = map.dive_s(s.time_of_validity_us);
    const auto xy = truth.xy_at(map.dive_start_us + t_s * 1e6);
    const XyCheck c = check_xy(s, xy);
    out << t_s << "," << s.p_world_m[0] << "," << s.p_world_m[1] << "," << xy.first << ","
        << xy.second << "," << c.error_m << "," << c.sigma_m << "," << c.nees << ","
        << s.num_delayed_states << "," << int{s.filter_status} << "\n";
  }
  if (!out) throw std::runtime_error(path.string() + ": cannot write the solutions CSV");
}

double map_xy_rms_m(const Recording& rec, const TruthTrack& truth, const TimeMap& map) {
  if (!rec.last_snapshot || rec.last_snapshot->states.empty()) return -1.0;
  double sum = 0.0;
  for (const navlcm::delayed_state_bound_t& b : rec.last_snapshot->states) {
    const double t_s = map.dive_s(b.image_time_us);
    const auto [x, y] = truth.xy_at(map.dive_start_us + t_s * 1e6);
    sum += std::pow(b.mean_pose[0] - x, 2) + std::pow(b.mean_pose[1] - y, 2);
  }
  return std::sqrt(sum / static_cast<double>(rec.last_snapshot->states.size()));
}

}  // namespace nav::campaign
