#pragma once
// Internal helpers shared by the PD0/PD6 decoders and encoders: little-endian access, the
// PD0 data type IDs and field sizes ("WorkHorse Commands and Output Data Format", PD0 Output
// Format, Tables "Fixed Leader", "Variable Leader", "Bottom-Track Data"), and civil-time
// conversion for the instrument's real-time clock (UTC, no leap seconds).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace nav::drivers::pd0_wire {

constexpr uint8_t kHeaderId = 0x7F;  ///< header ID and data source ID bytes
constexpr uint16_t kFixedLeaderId = 0x0000;
constexpr uint16_t kVariableLeaderId = 0x0080;
constexpr uint16_t kBottomTrackId = 0x0600;
constexpr std::size_t kHeaderFixedBytes = 6;  ///< IDs, byte count, spare, number of types
constexpr std::size_t kChecksumBytes = 2;
constexpr std::size_t kMaxDataTypes = 255;  ///< the header's count is one byte

// Sizes written by the encoder (WorkHorse firmware 16.x and later).
constexpr std::size_t kFixedLeaderBytes = 59;
constexpr std::size_t kVariableLeaderBytes = 65;
constexpr std::size_t kBottomTrackBytes = 85;
// Shortest data types the decoder accepts (the fields it needs are present).
constexpr std::size_t kFixedLeaderMinBytes = 34;     ///< through "bin 1 distance"
constexpr std::size_t kVariableLeaderMinBytes = 28;  ///< through "temperature"
constexpr std::size_t kVariablePressureBytes = 52;   ///< carries "pressure" (bytes 49-52)
constexpr std::size_t kVariableY2kBytes = 65;        ///< carries the Y2K RTC (bytes 58-65)
constexpr std::size_t kBottomTrackMinBytes = 44;     ///< through "BT percent good"
constexpr std::size_t kBottomTrackMsbBytes = 81;     ///< carries "BT range MSB" (78-81)

constexpr int16_t kInvalidVelocity = -32768;

inline uint16_t le16(const uint8_t* p) { return uint16_t(p[0] | (uint16_t(p[1]) << 8)); }
inline int16_t le16s(const uint8_t* p) { return int16_t(le16(p)); }
inline uint32_t le32(const uint8_t* p) {
  return uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16) | (uint32_t(p[3]) << 24);
}
inline void put16(uint8_t* p, uint16_t v) {
  p[0] = uint8_t(v & 0xFF);
  p[1] = uint8_t(v >> 8);
}
inline void put32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = uint8_t((v >> (8 * i)) & 0xFF);
}

/// Broken-down UTC time as the RTC reports it.
struct CivilTime {
  int year = 0;  ///< full year, e.g. 2017
  int month = 0;
  int day = 0;
  int hour = 0;
  int minute = 0;
  int second = 0;
  int hundredths = 0;
};

/// Microseconds since 1970-01-01T00:00Z, or empty when a field is out of its calendar range.
std::optional<int64_t> civil_to_unix_us(const CivilTime& t);
/// Inverse of civil_to_unix_us (truncated to hundredths of a second).
CivilTime unix_us_to_civil(int64_t time_us);

}  // namespace nav::drivers::pd0_wire
