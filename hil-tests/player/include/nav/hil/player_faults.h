#pragma once
// Sensor faults the HIL player injects into a played dive (docs/faults.md, hil-tests/README.md
// "Fault injection"): each PlayerFault acts on one serial sensor's RAW_<NAME> messages whose
// dive time (host_monotonic_us of the log, seconds after the first played message) is in
// [from_s, to_s):
//   kDrop          the message is not written (the device goes silent: a DVL dropout);
//   kGarbage       PD0 only: the bottom-track velocities become uniform random values in
//                  +-`value` m/s (seeded, deterministic), re-encoded with a valid checksum, so
//                  the ensemble decodes: only the filter's gating can refuse it;
//   kHeadingStuck  NMEA HDT only: the heading field is replaced by `value` rad (re-encoded
//                  with its checksum); other sentences pass unchanged;
//   kDepthSpike    Paroscientific only: every reply in the window reads `value` metres deeper
//                  and shallower in turn (+value, -value, ...): the pressure moves by
//                  value x 1025 kg/m^3 x 9.80665 m/s^2 (hydrostatic, surface density: at
//                  3,800 m, where seawater is denser, the UNESCO 1983 depth moves by 0.98 x
//                  value);
//   kUnplug        the sensor's pty is closed at from_s (navd sees the device vanish: EIO /
//                  POLLHUP, the symlink removed) and a new pty is opened under the same
//                  symlink at to_s; messages in between are not written;
//   kCameraVanish  the played GigE camera (`sensor` names the camera_gige sensor) is destroyed
//                  at from_s (Aravis' fake stops answering GVCP and streaming: navd's heartbeat
//                  fails, control lost) and a new fake with the same serial is started at
//                  to_s; the images due in between are not sent (camera_playback.h).
// The byte transforms are pure functions (tested against the drivers' decoders).
//
// Threads: none of their own; the player calls them on its playing thread.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace nav::hil {

enum class FaultKind { kDrop, kGarbage, kHeadingStuck, kDepthSpike, kUnplug, kCameraVanish };

/// "drop", "garbage", "heading_stuck", "depth_spike", "unplug", "camera_vanish".
const char* to_string(FaultKind kind);

struct PlayerFault {
  FaultKind kind = FaultKind::kDrop;
  std::string sensor;   ///< config sensor name (a serial sensor)
  double from_s = 0.0;  ///< dive seconds after the first played message
  double to_s = 0.0;    ///< end (exclusive), > from_s
  double value = 0.0;   ///< kind-specific, see the file comment

  bool active(double dive_s) const { return dive_s >= from_s && dive_s < to_s; }
  /// "" if usable, else what is wrong.
  std::string validate() const;
};

/// Bottom-track velocities of a PD0 ensemble replaced by uniform values in +-`max_mps`, drawn
/// from splitmix64(`seed`); the checksum recomputed. nullopt when the bytes are not a complete
/// PD0 ensemble with bottom track (the caller then writes them unchanged).
std::optional<std::vector<std::uint8_t>> pd0_with_garbage_velocity(
    std::span<const std::uint8_t> ensemble, double max_mps, std::uint64_t seed);

/// An NMEA HDT sentence with its heading set to `heading_rad` (checksum recomputed); nullopt
/// for anything else (attitude sentences, bytes that do not decode).
std::optional<std::vector<std::uint8_t>> nmea_with_heading(std::span<const std::uint8_t> bytes,
                                                           double heading_rad);

/// A Paroscientific psia reply reading `depth_offset_m` deeper (negative: shallower);
/// nullopt when the bytes are not one such reply.
std::optional<std::vector<std::uint8_t>> paro_with_depth_offset(std::span<const std::uint8_t> bytes,
                                                                double depth_offset_m);

/// What the player does with one message of a sensor under `fault` (not kUnplug, which the
/// player handles with the pty itself, nor kCameraVanish, which the camera playback does). `count`
/// numbers the fault's messages from 0 (depth spikes alternate on it; garbage seeds on it). Returns
/// the bytes to write: empty = write nothing; `bytes` unchanged when the message is not of the kind
/// the fault acts on.
std::vector<std::uint8_t> apply_fault(const PlayerFault& fault, std::span<const std::uint8_t> bytes,
                                      std::int64_t count);

}  // namespace nav::hil
