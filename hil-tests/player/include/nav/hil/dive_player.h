#pragma once
// Hardware-in-the-loop playback of a recorded or simulated dive (hil-tests/README.md "Playing
// a dive back"): every RAW_<NAME> message of the dive log is written, at its recorded host
// time (CLOCK_MONOTONIC, scaled by `speed`), to the device the sensor's config transport
// names in the navd config the player generates:
//   * serial sensors (dvl_pd0, dvl_pd6, heading_nmea, fog_kvh, pressure_paro, altimeter):
//     one pseudo-terminal each (pty_link.h), a stable symlink `<serial_dir>/<name>`;
//   * CAN sensors (dvl_can): the log's candump lines as frames on a SocketCAN interface
//     (vcan0 by default) when the kernel has it, else skipped with the reason;
//   * the first camera_gige sensor: Aravis' fake GigE Vision camera on lo (fake_gige_camera.h,
//     camera_id 127.0.0.1, Mono12Packed, hardware trigger on Line1 with the player as the
//     trigger line): each NAV_IMAGE of the log becomes one frame, the dive's rendered PNG
//     (`navtool simulate --render-images`) or else a test pattern, sent when the vehicle's
//     frame reached the host (camera_playback.h); counted in the report; a kCameraVanish
//     fault on it destroys and restarts the fake (player_faults.h);
//   * oracle registrations (NAV_REGISTRATION): with `registration_lcm_url`, published on LCM
//     (`registration_channel`) at their log times (the log's realtime utime mapped to the host
//     monotonic schedule through the raw messages' realtime - monotonic offset), each with
//     utime = the host's CLOCK_REALTIME when published (when the answer became available in
//     this run); otherwise not played. Counted in the report. navd's live mode applies them
//     only to its images with the same frame ids (navd numbers frames by the camera's frame
//     counter, not the dive's frame ids).
// The generated navd config is the dive's config.yaml with those transports (sensors not
// played keep `type: sim`, which navd's live mode does not open), without the `sim` section,
// and with the LCM URL given.
//
// Time: navd stamps what it reads with the host clocks, so the dive's timing is preserved
// only at speed 1. At speed > 1 the bytes arrive `speed` times faster: navd sees a dive
// `speed` times shorter (velocities integrate over shorter intervals), useful to check
// decoding and health, not the pose. The report gives the dive-to-host time mapping.
//
// Threads: construct, then call play() on one thread; `stop` may be set from any thread.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "nav/hil/player_faults.h"

namespace nav::hil {

struct PlayerOptions {
  double speed = 1.0;  ///< x real time, (0, 1000]; see the file comment for speed != 1
  /// Directory of the pty links (created if missing); empty: `<dive dir>/hil`.
  std::filesystem::path serial_dir;
  std::string can_interface = "vcan0";  ///< SocketCAN interface for CAN sensors
  /// Serve the first camera_gige sensor with Aravis' fake GigE camera on lo (one per network
  /// namespace: GVCP port 3956); false: cameras are not played.
  bool fake_gige_camera = true;
  /// Where navd writes the camera frames it receives (the played camera's `image_dir` in the
  /// generated config); empty: `<serial_dir>/images`; "none": navd does not write them.
  std::filesystem::path camera_image_dir;
  /// Start the dive's clock only once every pty has a reader (navd opened its devices), so
  /// navd sees the dive from its first byte; false: start at once.
  bool wait_for_readers = true;
  /// Give up waiting for readers after this long (0: wait until stopped).
  std::chrono::milliseconds reader_timeout{0};
  /// Called once when the dive's clock starts, with the dive's first host monotonic time and
  /// the host monotonic time it is played at (µs): dive time t plays at
  /// host_start + (t - dive_start) / speed.
  std::function<void(std::int64_t dive_start_us, std::int64_t host_start_us)> on_start;
  /// Publish the log's NAV_REGISTRATION messages on this LCM URL ("" = not played).
  std::string registration_lcm_url;
  /// Channel they are published on (navd's lcm.channels.registration by default).
  std::string registration_channel = "NAV_REGISTRATION";
  /// The log is played this many times back to back (a soak), pass k shifted in dive time by
  /// k x (the first pass's span + 1 s); registrations play in the first pass only; > 1 needs
  /// fake_gige_camera = false.
  int repeat = 1;
  /// Sensor faults injected into the played bytes (player_faults.h); empty: none.
  std::vector<PlayerFault> faults;

  /// "" if valid, else what is wrong.
  std::string validate() const;
};

enum class SensorOutput { kPty, kCan, kGige, kNotPlayed };

struct PlayedSensor {
  std::string name;
  std::string type;  ///< config sensor type, e.g. "dvl_pd0"
  SensorOutput output = SensorOutput::kNotPlayed;
  std::filesystem::path device;     ///< pty link, or the CAN interface name
  std::string note;                 ///< why it is not played ("" when played)
  std::int64_t messages = 0;        ///< RAW_<NAME> messages written
  std::int64_t bytes = 0;           ///< bytes (pty) or frames' data bytes (CAN) written
  std::int64_t dropped_bytes = 0;   ///< pty: bytes the reader had no room for / no reader
  std::int64_t dropped_frames = 0;  ///< CAN: lines that did not parse or frames not sent
  std::int64_t faulted = 0;         ///< messages a PlayerFault withheld or changed
  std::int64_t unplugs = 0;         ///< times its pty was closed by a kUnplug fault
};

/// The camera part of the playback (camera_playback.h), when a camera is played.
struct CameraPlayReport {
  std::int64_t images = 0;         ///< NAV_IMAGE events played (triggered, or `vanished`)
  std::int64_t with_frame = 0;     ///< of those, with the dive's PNG loaded
  std::int64_t frame_missing = 0;  ///< file_path set but the PNG could not be read
  std::int64_t sent = 0;           ///< frames the fake sent for them
  std::int64_t not_taken = 0;      ///< triggers the fake had not acted on by the next one
  double max_send_late_s = 0.0;    ///< worst frame send time after its due time
  double mean_send_late_s = 0.0;
  std::int64_t vanished = 0;   ///< images due while a kCameraVanish fault had the camera gone
  std::int64_t vanishes = 0;   ///< times the fake was destroyed (kCameraVanish)
  std::string reappear_error;  ///< why the fake could not be started again ("" = it was)
};

struct PlayReport {
  std::vector<PlayedSensor> sensors;
  std::int64_t images_not_played = 0;                 ///< NAV_IMAGE events not played
  CameraPlayReport camera;                            ///< NAV_IMAGE events played
  std::int64_t registrations_not_played = 0;          ///< NAV_REGISTRATION events
  std::int64_t registrations_played = 0;              ///< published (registration_lcm_url)
  std::int64_t raw_unknown_sensor = 0;                ///< RAW_ messages of no sensor in the config
  std::int64_t dive_start_us = 0, host_start_us = 0;  ///< see PlayerOptions::on_start
  double dive_span_s = 0.0;                           ///< first to last played message, dive time
  double wall_s = 0.0;           ///< from the clock's start to the last message
  double max_late_s = 0.0;       ///< worst lateness of a write against its schedule
  std::int64_t late_writes = 0;  ///< writes more than 10 ms late
  bool started = false;          ///< false: stopped or timed out while waiting for readers
  bool stopped = false;          ///< `stop` ended it before the end of the log
};

class DivePlayer {
 public:
  /// `dive` is a dive directory (dive.lcmlog + config.yaml) or a log file (its directory's
  /// config.yaml is used). Loads and validates the config, opens the ptys and the CAN bus.
  /// Throws std::runtime_error (or daemon::ConfigError) with the file and reason.
  DivePlayer(const std::filesystem::path& dive, PlayerOptions options);
  ~DivePlayer();
  DivePlayer(const DivePlayer&) = delete;
  DivePlayer& operator=(const DivePlayer&) = delete;

  /// Per-sensor plan (counters are zero until play()).
  const std::vector<PlayedSensor>& sensors() const;
  const std::filesystem::path& log_path() const;
  /// Where the pty links are (PlayerOptions::serial_dir or its default).
  const std::filesystem::path& serial_dir() const;

  /// Writes the navd config for this playback to `path` and checks that navd's loader
  /// accepts it. Throws std::runtime_error / daemon::ConfigError naming the file.
  void write_navd_config(const std::filesystem::path& path, const std::string& lcm_url) const;

  /// Plays the log to its end or until `stop`. Blocks.
  PlayReport play(const std::atomic<bool>& stop);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace nav::hil
