#pragma once
// Plays a dive's NAV_IMAGE events through the fake GigE camera (fake_gige_camera.h): for each
// image, in log order, the frame (the dive's rendered 16-bit PNG `file_path`, relative to the
// dive directory, when present; else the fake's test pattern) leaves the camera when the
// vehicle's frame reached the host: dive time `time_of_validity_us + latency` (the camera's
// config latency_ms, which navd subtracts again), mapped to host time like the serial bytes
// (dive_player.h). navd's image time of validity is then the dive's plus the fake's send and
// GVSP delivery delay (hil-tests/README.md, measured). kCameraVanish faults (player_faults.h):
// the fake is destroyed at the window's start and started again at its end, on this object's
// thread (which then waits through the window's edges as well as the images' due times); an
// image due inside a window is counted (`vanished`) and not sent.
//
// Threads: start() and finish() from the player's thread; the images are played on a thread of
// this object, reading the log with its own reader.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <thread>
#include <vector>

#include "fake_gige_camera.h"
#include "nav/hil/dive_player.h"

namespace nav::hil {

class CameraPlayback {
 public:
  /// `latency_s`: the camera sensor's config latency; `lead_us`: how early the fake is
  /// triggered (its trigger acknowledgement is up to ~100 ms late).
  /// `vanish`: the kCameraVanish faults of this camera (others are ignored).
  CameraPlayback(FakeGigeCamera& camera, std::filesystem::path log_path,
                 std::filesystem::path dive_dir, double latency_s,
                 std::vector<PlayerFault> vanish = {}, std::int64_t lead_us = 250'000);
  ~CameraPlayback();
  CameraPlayback(const CameraPlayback&) = delete;
  CameraPlayback& operator=(const CameraPlayback&) = delete;

  /// Starts playing: dive time t is due at host_start + (t - dive_start) / speed (µs).
  void start(std::int64_t dive_start_us, std::int64_t host_start_us, double speed);
  /// Waits until every image is played and its frame sent (or `stop`), then reports.
  CameraPlayReport finish(const std::atomic<bool>& stop);

 private:
  void run();
  /// Whether host monotonic `t_us` is inside a vanish window.
  bool gone_at(std::int64_t t_us) const;
  /// Destroys / restarts the fake as the windows say at host time now.
  void follow_windows();
  /// Sleeps until `until_us`, acting on the windows' edges on the way; false if stopped.
  bool wait_until(std::int64_t until_us);

  FakeGigeCamera& camera_;
  std::filesystem::path log_path_, dive_dir_;
  std::vector<PlayerFault> vanish_;
  std::int64_t latency_us_, lead_us_;
  std::int64_t dive_start_us_ = 0, host_start_us_ = 0;
  double speed_ = 1.0;
  std::atomic<bool> stop_{false};
  std::atomic<bool> done_{false};
  std::thread thread_;
  CameraPlayReport report_;  ///< written by the thread until it is joined
};

}  // namespace nav::hil
