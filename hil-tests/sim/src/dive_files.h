#pragma once
// The files of a simulated dive directory (hil-tests/README.md "A dive directory"): streams
// truth.csv and images.csv while simulating, collects the log events and writes dive.lcmlog
// in host-time order at the end, then sim.json. Internal to nav_survey_sim.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <navlcm/image_metadata_t.hpp>
#include <navlcm/registration_t.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/sim/oracle.h"
#include "nav/sim/sensor_streams.h"

namespace nav::sim {

class DiveFiles {
 public:
  /// Creates config.yaml (the text given), truth.csv and images.csv with their headers in
  /// `dir`. Throws std::runtime_error naming a file that cannot be written.
  DiveFiles(const std::filesystem::path& dir, const std::string& config_yaml);

  void truth(std::int64_t t_us, const core::Vec12& x);
  std::vector<RawEvent>& raw_events() { return raw_; }
  /// A rendered frame's PNG path (relative to the dive directory), 8-bit thumbnail and gain.
  struct Pixels {
    std::string file_path;
    cv::Mat thumbnail;
    double gain_db = 0.0;
  };
  void image(std::int64_t frame_id, std::int64_t t_us, std::int64_t host_us, const core::Vec12& x,
             double altitude_m, const CameraGeometry& camera, const Pixels* pixels = nullptr);
  /// A registration available at host time host_us (after its image's NAV_IMAGE).
  void registration(std::int64_t host_us, navlcm::registration_t registration);
  /// Writes dive.lcmlog (all events ordered by host time, ties in creation order); returns the
  /// number of events. Closes the CSV files.
  std::int64_t write_log();
  void write_json(const nlohmann::json& summary);

 private:
  struct FileCloser {
    void operator()(std::FILE* f) const {
      if (f) std::fclose(f);
    }
  };
  using File = std::unique_ptr<std::FILE, FileCloser>;
  File open(const std::string& name);
  void close(File& f, const std::string& name);

  std::filesystem::path dir_;
  File truth_, images_;
  std::vector<RawEvent> raw_;
  std::vector<std::pair<std::int64_t, navlcm::image_metadata_t>> image_events_;
  std::vector<std::pair<std::int64_t, navlcm::registration_t>> registration_events_;
};

}  // namespace nav::sim
