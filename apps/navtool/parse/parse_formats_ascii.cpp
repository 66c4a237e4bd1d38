// `navtool parse` formats for the ASCII heading/attitude, gyro, pressure and altimeter codecs:
// "nmea" (HDT, iXblue PHTRO/PIXSE), "kvh" (DSP-3000 rate output), "paro" (Digiquartz replies in
// psi) and "altimeter" (Tritech PA500 "ddd.ddm"), each with the codec's default options. One
// JSON object per decoded record per line; angles in degrees at this display edge (`_deg`
// names), null for absent values.
#include <cmath>
#include <istream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <ostream>
#include <variant>
#include <vector>

#include "nav/drivers/codecs/altimeter.h"
#include "nav/drivers/codecs/kvh.h"
#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "navtool/parse/parse_formats.h"

namespace nav::tool {
namespace {

using nlohmann::json;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

/// Display value rounded to 1e-9 of its unit (finer than any of these protocols' resolution).
json num(double v, double scale = 1.0) { return json(std::round(v * scale * 1e9) / 1e9); }
json opt(const std::optional<double>& v, double scale = 1.0) {
  return v ? num(*v, scale) : json(nullptr);
}

/// Runs `Decoder` over the stream, printing `to_json(record)` per record, adding its stats.
template <typename Decoder, typename Record, typename ToJson>
void run_decoder(Decoder decoder, std::istream& in, std::ostream& records,
                 drivers::DecodeStats& stats, ToJson to_json) {
  decode_stream<Record>(in, decoder,
                        [&](const Record& r) { records << to_json(r).dump() << '\n'; });
  stats += decoder.stats();
}

json nmea_to_json(const drivers::NmeaRecord& record) {
  struct ToJson {
    json operator()(const drivers::NmeaHeading& r) const {
      return {{"sentence", drivers::to_string(r.sentence)},
              {"talker", std::string(r.talker.data(), 2)},
              {"heading_deg", num(r.heading_rad, kRadToDeg)}};
    }
    json operator()(const drivers::NmeaAttitude& r) const {
      return {{"sentence", drivers::to_string(r.sentence)},
              {"roll_deg", num(r.roll_rad, kRadToDeg)},
              {"pitch_deg", num(r.pitch_rad, kRadToDeg)}};
    }
    json operator()(const drivers::NmeaPosition& r) const {
      return {{"sentence", "PIXSE,POSITI"},
              {"latitude_deg", num(r.latitude_rad, kRadToDeg)},
              {"longitude_deg", num(r.longitude_rad, kRadToDeg)},
              {"altitude_m", opt(r.altitude_m)}};
    }
    json operator()(const drivers::NmeaVelocity& r) const {
      return {{"sentence", "PIXSE,SPEED_"},
              {"v_ned_mps", {num(r.v_ned_mps[0]), num(r.v_ned_mps[1]), num(r.v_ned_mps[2])}}};
    }
    json operator()(const drivers::NmeaAttitudeStd& r) const {
      return {{"sentence", "PIXSE,STDHRP"},
              {"heading_std_deg", num(r.heading_std_rad, kRadToDeg)},
              {"roll_std_deg", num(r.roll_std_rad, kRadToDeg)},
              {"pitch_std_deg", num(r.pitch_std_rad, kRadToDeg)}};
    }
    json operator()(const drivers::NmeaPositionStd& r) const {
      return {{"sentence", "PIXSE,STDPOS"},
              {"north_std_m", num(r.north_std_m)},
              {"east_std_m", num(r.east_std_m)},
              {"altitude_std_m", num(r.altitude_std_m)}};
    }
    json operator()(const drivers::NmeaVelocityStd& r) const {
      return {{"sentence", "PIXSE,STDSPD"},
              {"v_ned_std_mps",
               {num(r.v_ned_std_mps[0]), num(r.v_ned_std_mps[1]), num(r.v_ned_std_mps[2])}}};
    }
    json operator()(const drivers::NmeaStatus& r) const {
      return {{"sentence", drivers::to_string(r.sentence)}, {"status_word", r.word}};
    }
  };
  return std::visit(ToJson{}, record);
}

const char* to_string(drivers::AltimeterStatus status) {
  switch (status) {
    case drivers::AltimeterStatus::kValid:
      return "valid";
    case drivers::AltimeterStatus::kNoEcho:
      return "no_echo";
    case drivers::AltimeterStatus::kOutOfRange:
      return "out_of_range";
  }
  return "?";
}

void run_nmea(std::istream& in, std::ostream& records, drivers::DecodeStats& stats,
              const ParseOptions&) {
  run_decoder<drivers::NmeaDecoder, drivers::NmeaRecord>(drivers::NmeaDecoder{}, in, records, stats,
                                                         nmea_to_json);
}

void run_kvh(std::istream& in, std::ostream& records, drivers::DecodeStats& stats,
             const ParseOptions&) {
  run_decoder<drivers::KvhDecoder, drivers::KvhRecord>(
      drivers::KvhDecoder{}, in, records, stats, [](const drivers::KvhRecord& r) {
        return json{{"sensor_valid", r.sensor_valid},
                    {"rate_deg_per_s", opt(r.rate_radps, kRadToDeg)},
                    {"angle_deg", opt(r.angle_rad, kRadToDeg)}};
      });
}

void run_paro(std::istream& in, std::ostream& records, drivers::DecodeStats& stats,
              const ParseOptions&) {
  run_decoder<drivers::ParoDecoder, drivers::ParoRecord>(
      drivers::ParoDecoder{}, in, records, stats, [](const drivers::ParoRecord& r) {
        return json{{"destination_id", r.destination_id},
                    {"source_id", r.source_id},
                    {"pressure_pa", num(r.pressure_pa)}};
      });
}

void run_altimeter(std::istream& in, std::ostream& records, drivers::DecodeStats& stats,
                   const ParseOptions&) {
  run_decoder<drivers::AltimeterDecoder, drivers::AltimeterRecord>(
      drivers::AltimeterDecoder{}, in, records, stats, [](const drivers::AltimeterRecord& r) {
        return json{{"status", to_string(r.status)},
                    {"range_m", opt(r.range_m)},
                    {"raw_value_m", num(r.raw_value_m)},
                    {"pressure_pa", opt(r.pressure_pa)}};
      });
}

const ParseFormatRegistration kNmea{
    "nmea", ParseFormat{"NMEA 0183 heading/attitude: $--HDT, iXblue $PHTRO and $PIXSE", run_nmea}};
const ParseFormatRegistration kKvh{
    "kvh", ParseFormat{"KVH DSP-3000 ASCII rate output (deg/s, status flag)", run_kvh}};
const ParseFormatRegistration kParo{
    "paro", ParseFormat{"Paroscientific Digiquartz replies *DDSS<value> in psi", run_paro}};
const ParseFormatRegistration kAltimeter{
    "altimeter", ParseFormat{"altimeter range lines ddd.ddm (Tritech PA500 form)", run_altimeter}};

}  // namespace
}  // namespace nav::tool
