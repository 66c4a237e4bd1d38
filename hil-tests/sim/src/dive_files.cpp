#include "dive_files.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <tuple>

#include "nav/daemon/log/dive_log.h"

namespace nav::sim {

DiveFiles::DiveFiles(const std::filesystem::path& dir, const std::string& config_yaml) : dir_(dir) {
  {
    std::ofstream cfg(dir / "config.yaml", std::ios::binary | std::ios::trunc);
    cfg << config_yaml;
    if (!cfg) throw std::runtime_error((dir / "config.yaml").string() + ": cannot write");
  }
  truth_ = open("truth.csv");
  std::fputs(
      "t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,u_mps,v_mps,w_mps,p_radps,q_radps,"
      "r_radps\n",
      truth_.get());
  images_ = open("images.csv");
  std::fputs("frame_id,t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,altitude_m,camera_on\n",
             images_.get());
}

DiveFiles::File DiveFiles::open(const std::string& name) {
  File f(std::fopen((dir_ / name).c_str(), "wb"));
  if (!f)
    throw std::runtime_error((dir_ / name).string() + ": cannot create: " + std::strerror(errno));
  return f;
}

void DiveFiles::close(File& f, const std::string& name) {
  if (!f) return;
  const bool ok = std::ferror(f.get()) == 0;
  if (std::fclose(f.release()) != 0 || !ok)
    throw std::runtime_error((dir_ / name).string() + ": write error");
}

void DiveFiles::truth(std::int64_t t_us, const core::Vec12& x) {
  std::fprintf(truth_.get(), "%lld,%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n",
               static_cast<long long>(t_us), x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8],
               x[9], x[10], x[11]);
}

void DiveFiles::image(std::int64_t frame_id, std::int64_t t_us, std::int64_t host_us,
                      const core::Vec12& x, double altitude_m, const CameraGeometry& camera,
                      const Pixels* pixels) {
  std::fprintf(images_.get(), "%lld,%lld,%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,%.4f,1\n",
               static_cast<long long>(frame_id), static_cast<long long>(t_us), x[0], x[1], x[2],
               x[3], x[4], x[5], altitude_m);
  navlcm::image_metadata_t m{};
  m.utime = realtime_of(host_us);
  m.time_of_validity_us = t_us;
  m.frame_id = frame_id;
  m.state_id = -1;
  m.file_path = "";
  m.width = camera.width_px();
  m.height = camera.height_px();
  m.bits_per_pixel = 12;
  m.exposure_us = 4000.0;
  m.gain_db = 0.0;
  m.thumbnail_width = 0;
  m.thumbnail_height = 0;
  m.thumbnail_num_bytes = 0;
  if (pixels) {
    m.file_path = pixels->file_path;
    m.gain_db = pixels->gain_db;
    const cv::Mat& t = pixels->thumbnail;
    m.thumbnail_width = t.cols;
    m.thumbnail_height = t.rows;
    m.thumbnail.assign(t.datastart, t.dataend);
    m.thumbnail_num_bytes = static_cast<std::int32_t>(m.thumbnail.size());
  }
  image_events_.push_back({host_us, std::move(m)});
}

void DiveFiles::registration(std::int64_t host_us, navlcm::registration_t r) {
  r.utime = realtime_of(host_us);
  registration_events_.push_back({host_us, std::move(r)});
}

std::int64_t DiveFiles::write_log() {
  close(truth_, "truth.csv");
  close(images_, "images.csv");
  // (host time, kind, index): raw bytes before an image at the same µs, an image before its
  // registrations, each kind in creation order.
  std::vector<std::tuple<std::int64_t, int, std::size_t>> order;
  order.reserve(raw_.size() + image_events_.size() + registration_events_.size());
  for (std::size_t i = 0; i < raw_.size(); ++i) order.emplace_back(raw_[i].host_monotonic_us, 0, i);
  for (std::size_t i = 0; i < image_events_.size(); ++i)
    order.emplace_back(image_events_[i].first, 1, i);
  for (std::size_t i = 0; i < registration_events_.size(); ++i)
    order.emplace_back(registration_events_[i].first, 2, i);
  std::sort(order.begin(), order.end());
  daemon::DiveLogWriter log((dir_ / "dive.lcmlog").string());
  for (const auto& [host_us, kind, i] : order) {
    if (kind == 0) {
      const RawEvent& e = raw_[i];
      log.write_raw(e.sensor, realtime_of(e.host_monotonic_us), e.host_monotonic_us, e.bytes);
    } else if (kind == 1) {
      log.write(image_events_[i].second);
    } else {
      log.write(registration_events_[i].second);
    }
  }
  return log.events_written();
}

void DiveFiles::write_json(const nlohmann::json& summary) {
  std::ofstream out(dir_ / "sim.json", std::ios::binary | std::ios::trunc);
  out << summary.dump(2) << "\n";
  if (!out) throw std::runtime_error((dir_ / "sim.json").string() + ": cannot write");
}

}  // namespace nav::sim
