#pragma once
// Sensor decoders: what a driver thread (device_sources) and the dive-log source
// (dive_log_source.h) run on each read of a configured sensor. Bytes in, typed Measurements
// out (measurement.h), through the drivers' streaming codecs, so the vehicle and a replayed
// dive decode identically. One decoder per configured sensor (SensorConfig::type):
//
// | type          | wire (drivers codec)                 | measurement                       |
// |---------------|--------------------------------------|-----------------------------------|
// | dvl_pd0       | RDI PD0 ensembles (pd0.h)            | DvlVelocity = -(bottom track XYZ) |
// | dvl_pd6       | RDI PD6 lines (pd6.h), :BI only      | DvlVelocity = :BI X, Y, Z         |
// | dvl_can       | CAN frames (can_frame_decoder.h)     | DvlVelocity from v_{x,y,z}_mps    |
// | heading_nmea  | HDT, PHTRO, PIXSE ATITUD/HEADNG      | Attitude, has_heading / _roll_pitch|
// | fog_kvh       | KVH DSP-3000 rate lines (kvh.h)      | AngularRate about sensor z only   |
// | pressure_paro | Paroscientific replies, psia         | Depth (UNESCO 1983, seawater.h)   |
// | altimeter     | Tritech PA500 lines (altimeter.h)    | Altitude                          |
//
// Velocity sign: PD0 bottom-track velocity is the bottom relative to the instrument (RDI
// manual; pd0.h), so the DVL's velocity over ground in its own (instrument) frame is its
// negative. PD6 :BI and the CAN signals are already the vehicle over the bottom. Only the
// instrument frame is usable (the filter rotates it with the sensor mount): PD0 ensembles in
// beam, ship or earth coordinates and PD6 :BS/:BE lines give no measurement (counted).
//
// Time of validity (hil-tests/README.md "Clocks", all on host CLOCK_MONOTONIC):
// * dvl_pd0: the ensemble's RTC time mapped onto the host clock by a ClockMapping
//   (clock_mapping.h: lower envelope of host - RTC, `latency_s` subtracted as the known fixed
//   latency, 10 ms RTC resolution) once the mapping holds `min_clock_samples`; before that, or
//   when the RTC is missing or the sample is an outlier/jump, host_monotonic - latency.
// * dvl_can: the message's time-of-validity counter through CanFrameDecoder's mapping when it
//   is initialised, else host_monotonic - latency.
// * every other type: host_monotonic - latency (no device time in those protocols).
//
// The CAN sensor's bytes (a dive log's RAW_<NAME>, hil-tests/README.md) are candump log lines,
// `(sec.usec) IFACE ID#DATA\n` (candump_log.h), one line per frame, the time stamp being the
// kernel's receive time (CLOCK_REALTIME); device threads feed frames with feed_frame().
//
// Threads: a decoder belongs to one thread; counters() is a snapshot for that thread (the
// device sources copy it into their health record).

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "nav/daemon/config/config.h"
#include "nav/daemon/queue/measurements.h"
#include "nav/drivers/transports/can_bus.h"

namespace nav::daemon {

struct SensorDecoderCounters {
  std::uint64_t bytes = 0;          ///< bytes fed (CAN: data bytes of the frames)
  std::uint64_t messages = 0;       ///< protocol records decoded (ensembles, lines, frames)
  std::uint64_t measurements = 0;   ///< measurements emitted
  std::uint64_t decode_errors = 0;  ///< codec checksum failures + malformed + out of range
  std::uint64_t out_of_range = 0;   ///< of which records with a value outside its range (the
                                    ///< record is still used; e.g. PD0 leader fields left empty)
  std::uint64_t dropped_bytes = 0;  ///< bytes the codec discarded (resync, bad records)
  std::uint64_t invalid = 0;  ///< records without a usable value: invalid bottom track, no echo,
                              ///< sensor status invalid, depth conversion rejected
  std::uint64_t unsupported_frame = 0;  ///< DVL records not in the instrument frame
  std::uint64_t unused = 0;  ///< well-formed records this sensor does not turn into measurements
  std::uint64_t device_clock = 0;  ///< measurements dated by the device clock mapping
};

struct SensorDecoderOptions {
  /// Accepted clock-mapping samples before a device clock dates measurements (>= 2).
  std::size_t min_clock_samples = 5;
};

class SensorDecoder {
 public:
  virtual ~SensorDecoder() = default;
  /// Decodes one read of the device (any chunking: records may span reads) received at these
  /// host times; appends complete measurements (sensor_index and host times set) to `out`.
  virtual void feed(std::span<const std::uint8_t> bytes, std::int64_t host_realtime_us,
                    std::int64_t host_monotonic_us, std::vector<Measurement>& out) = 0;
  /// One CAN frame from a CanBus (dvl_can only; other types count it as a decode error).
  virtual void feed_frame(const drivers::CanFrame& frame, std::vector<Measurement>& out);
  virtual SensorDecoderCounters counters() const = 0;
  const std::string& sensor_name() const { return name_; }

 protected:
  explicit SensorDecoder(std::string name) : name_(std::move(name)) {}
  std::uint64_t misrouted_frames_ = 0;

 private:
  std::string name_;
};

/// True for the types that produce bytes or frames (everything but cameras).
bool has_sensor_decoder(SensorType type);

/// The decoder of `sensor` (measurements carry `sensor_index`). Throws std::invalid_argument
/// for camera types (their frames are ImageEvents, not bytes).
std::unique_ptr<SensorDecoder> make_sensor_decoder(const SensorConfig& sensor,
                                                   std::uint16_t sensor_index,
                                                   const SensorDecoderOptions& options = {});

/// The candump log line (with '\n') a CAN sensor's raw bytes carry for `frame` on `interface`;
/// the time stamp is the frame's kernel receive time, else its host CLOCK_REALTIME.
std::string can_frame_log_line(const drivers::CanFrame& frame, const std::string& interface);

}  // namespace nav::daemon
