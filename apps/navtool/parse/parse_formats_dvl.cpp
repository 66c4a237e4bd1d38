// `navtool parse` formats for the Teledyne RDI DVL codecs: "pd0" (binary ensembles) and "pd6"
// (ASCII lines). One JSON object per decoded record per line; angles in degrees at this
// display edge (`_deg` names), null for absent or invalid values.
#include <cmath>
#include <istream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <ostream>
#include <vector>

#include "nav/drivers/codecs/pd0.h"
#include "nav/drivers/codecs/pd6.h"
#include "navtool/parse/parse_formats.h"

namespace nav::tool {
namespace {

using nlohmann::json;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

/// Display value rounded to 1e-6 of its unit (finer than any field's wire resolution), so that
/// e.g. 2.92 deg prints as 2.92 rather than 2.9199999999999995.
json opt(const std::optional<double>& v, double scale = 1.0) {
  return v ? json(std::round(*v * scale * 1e6) / 1e6) : json(nullptr);
}

json opt_time_s(const std::optional<int64_t>& time_us) {
  return time_us ? json(double(*time_us) / 1e6) : json(nullptr);
}

template <std::size_t N>
json opt_array(const std::array<std::optional<double>, N>& values) {
  json a = json::array();
  for (const auto& v : values) a.push_back(opt(v));
  return a;
}

/// The decoder's counters with an incomplete record left at the end of the file counted as
/// dropped bytes and one malformed record (a truncated recording).
drivers::DecodeStats end_of_stream(drivers::DecodeStats stats, std::size_t buffered_bytes) {
  if (buffered_bytes > 0) {
    stats.dropped_bytes += buffered_bytes;
    ++stats.malformed;
  }
  return stats;
}

json pd0_to_json(const drivers::Pd0Ensemble& e) {
  json j;
  j["ensemble"] = e.ensemble_number;
  j["time_unix_s"] = opt_time_s(e.time.sensor_time_us);
  j["heading_deg"] = opt(e.heading_rad, kRadToDeg);
  j["pitch_deg"] = opt(e.pitch_rad, kRadToDeg);
  j["roll_deg"] = opt(e.roll_rad, kRadToDeg);
  j["temperature_c"] = opt(e.temperature_c);
  j["salinity_ppt"] = opt(e.salinity_ppt);
  j["sound_speed_mps"] = opt(e.sound_speed_mps);
  j["depth_m"] = opt(e.depth_m);
  j["pressure_dbar"] = opt(e.pressure_dbar);
  j["bit_result"] = e.bit_result;
  j["coord_frame"] = drivers::to_string(e.coord_frame());
  j["num_beams"] = e.fixed.num_beams;
  j["num_cells"] = e.fixed.num_cells;
  // Always 4 values (null when invalid or when the ensemble has no bottom-track type).
  const drivers::Pd0BottomTrack bt = e.bottom_track.value_or(drivers::Pd0BottomTrack{});
  j["has_bottom_track"] = e.bottom_track.has_value();
  j["bt_velocity_mps"] = opt_array(bt.velocity_mps);
  j["bt_range_m"] = opt_array(bt.range_m);
  j["skipped_types"] = e.skipped_type_ids;
  return j;
}

void run_pd0(std::istream& in, std::ostream& records, drivers::DecodeStats& stats,
             const ParseOptions&) {
  drivers::Pd0Decoder decoder;
  decode_stream<drivers::Pd0Ensemble>(in, decoder, [&](const drivers::Pd0Ensemble& e) {
    records << pd0_to_json(e).dump() << '\n';
  });
  stats += end_of_stream(decoder.stats(), decoder.buffered_bytes());
}

json pd6_to_json(const drivers::Pd6Record& r) {
  json j;
  j["type"] = drivers::pd6_line_name(r);
  j["time_unix_s"] = opt_time_s(r.time.sensor_time_us);
  if (const auto* a = std::get_if<drivers::Pd6Attitude>(&r.value)) {
    j["pitch_deg"] = opt(a->pitch_rad, kRadToDeg);
    j["roll_deg"] = opt(a->roll_rad, kRadToDeg);
    j["heading_deg"] = opt(a->heading_rad, kRadToDeg);
  } else if (const auto* t = std::get_if<drivers::Pd6TimingScaling>(&r.value)) {
    j["salinity_ppt"] = opt(t->salinity_ppt);
    j["temperature_c"] = opt(t->temperature_c);
    j["depth_m"] = opt(t->depth_m);
    j["sound_speed_mps"] = opt(t->sound_speed_mps);
    j["bit_result"] = t->bit_result;
  } else if (const auto* v = std::get_if<drivers::Pd6Velocity>(&r.value)) {
    j["velocity_mps"] = opt_array(v->velocity_mps);
    j["valid"] = v->valid;
  } else if (const auto* d = std::get_if<drivers::Pd6Distance>(&r.value)) {
    j["distance_enu_m"] = opt_array(d->distance_enu_m);
    j["range_m"] = opt(d->range_m);
    j["time_since_valid_s"] = opt(d->time_since_valid_s);
  }
  return j;
}

void run_pd6(std::istream& in, std::ostream& records, drivers::DecodeStats& stats,
             const ParseOptions&) {
  drivers::Pd6Decoder decoder;
  decode_stream<drivers::Pd6Record>(
      in, decoder, [&](const drivers::Pd6Record& r) { records << pd6_to_json(r).dump() << '\n'; });
  stats += end_of_stream(decoder.stats(), decoder.buffered_bytes());
}

const ParseFormatRegistration kPd0{
    "pd0", ParseFormat{"Teledyne RDI PD0 binary ensembles (leaders, bottom track)", run_pd0}};
const ParseFormatRegistration kPd6{
    "pd6",
    ParseFormat{"Teledyne RDI PD6 ASCII lines (:SA :TS :WI/BI :WS/BS :WE/BE :WD/BD)", run_pd6}};

}  // namespace
}  // namespace nav::tool
