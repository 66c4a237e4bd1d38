#pragma once
// The measurement types (sensor_measurements.h) both ways (core/serialization/archive.h): a
// measurement is its alternative's index (u8) and then that alternative's fields, so a filter
// holding measurements before its initialisation checkpoints them exactly.

#include <cstdint>
#include <string>
#include <utility>
#include <variant>

#include "nav/core/navigation/sensor_measurements.h"
#include "nav/core/serialization/archive.h"

namespace nav::core {

template <class Archive>
void serialize(Archive& ar, MeasurementTime& t) {
  ar(t.validity_us, "validity_us");
  ar(t.host_monotonic_us, "host_monotonic_us");
  ar(t.host_realtime_us, "host_realtime_us");
  ar(t.sensor_index, "sensor_index");
}
template <class Archive>
void serialize(Archive& ar, DvlVelocity& m) {
  ar(m.time, "time");
  ar(m.v_sensor_mps, "DVL velocity");
}
template <class Archive>
void serialize(Archive& ar, Attitude& m) {
  ar(m.time, "time");
  ar(m.roll_rad, "roll");
  ar(m.pitch_rad, "pitch");
  ar(m.heading_rad, "heading");
  ar(m.has_roll_pitch, "has_roll_pitch");
  ar(m.has_heading, "has_heading");
}
template <class Archive>
void serialize(Archive& ar, AngularRate& m) {
  ar(m.time, "time");
  ar(m.omega_sensor_radps, "angular rate");
  ar(m.has_axis, "has_axis");
}
template <class Archive>
void serialize(Archive& ar, Depth& m) {
  ar(m.time, "time");
  ar(m.depth_m, "depth");
}
template <class Archive>
void serialize(Archive& ar, Altitude& m) {
  ar(m.time, "time");
  ar(m.altitude_m, "altitude");
}
template <class Archive>
void serialize(Archive& ar, ImageEvent& m) {
  ar(m.time, "time");
  ar(m.frame_id, "frame_id");
}

namespace serialization_detail {
template <std::size_t... I>
Measurement measurement_of_kind(std::size_t kind, std::index_sequence<I...>) {
  Measurement m;
  ((kind == I ? (void)m.template emplace<I>() : void()), ...);
  return m;
}
}  // namespace serialization_detail

/// The alternative's index (u8), then the alternative.
template <class Archive>
void serialize(Archive& ar, Measurement& m) {
  constexpr std::size_t kKinds = std::variant_size_v<Measurement>;
  auto kind = static_cast<std::uint8_t>(m.index());
  ar(kind, "measurement kind");
  if (!ar.check(kind < kKinds, "measurement kind " + std::to_string(kind) + " unknown")) return;
  if constexpr (Archive::kReading) {
    m = serialization_detail::measurement_of_kind(kind, std::make_index_sequence<kKinds>{});
  }
  std::visit([&ar](auto& x) { serialize(ar, x); }, m);
}

}  // namespace nav::core
