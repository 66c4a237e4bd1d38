// Sensor faults of the HIL player: byte transforms through the drivers' own codecs; see
// player_faults.h.
#include "nav/hil/player_faults.h"

#include <cmath>

#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "nav/drivers/codecs/pd0.h"

namespace nav::hil {
namespace {

/// Water density x gravity for the depth spike (hydrostatic approximation, player_faults.h).
constexpr double kPascalPerMetre = 1025.0 * 9.80665;

/// splitmix64 (Steele, Lea, Flood 2014): one well-mixed 64-bit value per state increment.
std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::vector<std::uint8_t> to_bytes(const std::string& s) { return {s.begin(), s.end()}; }

}  // namespace

const char* to_string(FaultKind kind) {
  switch (kind) {
    case FaultKind::kDrop:
      return "drop";
    case FaultKind::kGarbage:
      return "garbage";
    case FaultKind::kHeadingStuck:
      return "heading_stuck";
    case FaultKind::kDepthSpike:
      return "depth_spike";
    case FaultKind::kUnplug:
      return "unplug";
    case FaultKind::kCameraVanish:
      return "camera_vanish";
  }
  return "?";
}

std::string PlayerFault::validate() const {
  if (sensor.empty()) return std::string(to_string(kind)) + " fault: no sensor";
  if (!(from_s >= 0.0 && to_s > from_s)) {
    return std::string(to_string(kind)) + " fault on " + sensor + ": window [" +
           std::to_string(from_s) + ", " + std::to_string(to_s) + ") s is empty or negative";
  }
  if ((kind == FaultKind::kGarbage || kind == FaultKind::kDepthSpike) && !(value > 0.0)) {
    return std::string(to_string(kind)) + " fault on " + sensor + ": value must be > 0";
  }
  return {};
}

std::optional<std::vector<std::uint8_t>> pd0_with_garbage_velocity(
    std::span<const std::uint8_t> ensemble, double max_mps, std::uint64_t seed) {
  if (ensemble.size() < 8 || ensemble[0] != 0x7F || ensemble[1] != 0x7F) return std::nullopt;
  const std::size_t length = ensemble[2] | (std::size_t{ensemble[3]} << 8);  // without checksum
  if (length + 2 != ensemble.size()) return std::nullopt;
  drivers::Pd0Ensemble e;
  int out_of_range = 0;
  const drivers::Pd0ParseError error = drivers::parse_pd0_ensemble(ensemble, e, out_of_range);
  if ((error != drivers::Pd0ParseError::kNone && error != drivers::Pd0ParseError::kOutOfRange) ||
      !e.bottom_track) {
    return std::nullopt;
  }
  std::uint64_t state = seed;
  for (std::optional<double>& v : e.bottom_track->velocity_mps) {
    const double unit = static_cast<double>(splitmix64(state) >> 11) * 0x1.0p-53;  // [0, 1)
    v = std::round((2.0 * unit - 1.0) * max_mps * 1e3) * 1e-3;                     // mm/s
  }
  return drivers::encode_pd0(e);
}

std::optional<std::vector<std::uint8_t>> nmea_with_heading(std::span<const std::uint8_t> bytes,
                                                           double heading_rad) {
  drivers::NmeaDecoder decoder;
  std::vector<drivers::NmeaRecord> records;
  decoder.feed(bytes, drivers::HostTime{}, records);
  if (records.size() != 1) return std::nullopt;
  auto* heading = std::get_if<drivers::NmeaHeading>(&records.front());
  if (heading == nullptr) return std::nullopt;
  heading->heading_rad = std::remainder(heading_rad, 2.0 * M_PI);
  return to_bytes(drivers::encode_nmea(*heading));
}

std::optional<std::vector<std::uint8_t>> paro_with_depth_offset(std::span<const std::uint8_t> bytes,
                                                                double depth_offset_m) {
  drivers::ParoDecoder decoder;
  std::vector<drivers::ParoRecord> records;
  decoder.feed(bytes, drivers::HostTime{}, records);
  if (records.size() != 1) return std::nullopt;
  drivers::ParoRecord r = records.front();
  r.pressure_pa += depth_offset_m * kPascalPerMetre;
  return to_bytes(drivers::encode_paro_reply(r));
}

std::vector<std::uint8_t> apply_fault(const PlayerFault& fault, std::span<const std::uint8_t> bytes,
                                      std::int64_t count) {
  std::optional<std::vector<std::uint8_t>> changed;
  switch (fault.kind) {
    case FaultKind::kDrop:
    case FaultKind::kUnplug:
    case FaultKind::kCameraVanish:
      return {};
    case FaultKind::kGarbage:
      changed = pd0_with_garbage_velocity(bytes, fault.value, static_cast<std::uint64_t>(count));
      break;
    case FaultKind::kHeadingStuck:
      changed = nmea_with_heading(bytes, fault.value);
      break;
    case FaultKind::kDepthSpike:
      changed = paro_with_depth_offset(bytes, count % 2 == 0 ? fault.value : -fault.value);
      break;
  }
  return changed ? std::move(*changed) : std::vector<std::uint8_t>(bytes.begin(), bytes.end());
}

}  // namespace nav::hil
