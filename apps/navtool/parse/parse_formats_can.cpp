// `navtool parse --format can LOG --can-config TABLE.yaml`: decodes a candump text log
// (drivers/codecs/candump_log.h: `candump -l`/`-L` log lines and the ASCII screen format)
// with a CAN signal table (drivers/config/can_config.h) and prints one JSON object per decoded
// message per line:
//   {"time_unix_s": log time stamp, "interface": "can0", "id": "0x200", "extended": false,
//    "name": "dvl_velocity", "multiplexer": 2 (multiplexed messages only),
//    "sensor_time_s": time-of-validity signal (or that of the time_from message) or null,
//    "time_of_validity_unix_s": that sensor time mapped onto the log's clock or null,
//    "signals": {"v_x_mps": 1.2345, "heading_deg": 12.3, "v_y_mps": null, ...}}
// Signal values are SI; angles (rad, rad/s) are shown in degrees at this display edge with
// `_deg`/`_degps` names (a `_rad`/`_radps` suffix is replaced). Invalid or out-of-range values
// are null. Sensor time counters are mapped with one ClockMapping per message (lower envelope
// of the log time stamps, counter period from the signal's length and unit).
//
// Summary counters: bytes of the log; records = decoded messages; lines that are not frames
// are malformed/unsupported with their bytes dropped; frames of unknown id or remote frames
// are unsupported, frames of the wrong length malformed, and their line bytes dropped;
// out_of_range counts messages with a value outside its [min, max].
#include <cmath>
#include <istream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <ostream>
#include <vector>

#include "nav/drivers/codecs/can_signals.h"
#include "nav/drivers/codecs/candump_log.h"
#include "nav/drivers/config/can_config.h"
#include "nav/drivers/time/clock_mapping.h"
#include "navtool/commands.h"
#include "navtool/parse/parse_formats.h"

namespace nav::tool {
namespace {

using nlohmann::json;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

/// Display value rounded to 1e-9 of its unit.
json num(double v) { return json(std::round(v * 1e9) / 1e9); }

bool ends_with(const std::string& s, std::string_view suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix.data(), suffix.size()) == 0;
}

/// Display name and factor of a signal: angles in degrees with _deg / _degps names.
std::pair<std::string, double> display_of(const drivers::CanSignalSpec& s) {
  const auto unit = drivers::can_unit_to_si(s.unit);
  const std::string_view si = unit ? unit->si_unit : std::string_view{};
  if (si == "rad") {
    const std::string base =
        ends_with(s.name, "_rad") ? s.name.substr(0, s.name.size() - 4) : s.name;
    return {base + "_deg", kRadToDeg};
  }
  if (si == "rad/s") {
    const std::string base =
        ends_with(s.name, "_radps") ? s.name.substr(0, s.name.size() - 6) : s.name;
    return {base + "_degps", kRadToDeg};
  }
  return {s.name, 1.0};
}

std::string hex_id(uint32_t id, bool extended) {
  char buf[16];
  std::snprintf(buf, sizeof buf, extended ? "0x%08X" : "0x%03X", id);
  return buf;
}

/// Clock mappings of the messages that carry a time-of-validity counter.
class SensorClocks {
 public:
  explicit SensorClocks(const std::vector<drivers::CanMessageSpec>& messages) {
    for (const auto& m : messages) {
      for (const auto& s : m.signals) {
        if (!s.time_of_validity) continue;
        drivers::ClockMappingOptions o;
        o.sensor_modulus_us = drivers::can_time_signal_modulus_us(s).value_or(0);
        o.sensor_resolution_us = drivers::can_time_signal_resolution_us(s);
        // Short counters (e.g. 16-bit ms: 65 s) need a threshold below half their period.
        if (o.sensor_modulus_us > 0) {
          o.jump_threshold_us = std::min(o.jump_threshold_us, o.sensor_modulus_us / 4);
        }
        if (o.validate().empty()) {
          clocks_.emplace(&m, std::make_unique<drivers::ClockMapping>(o));
        }
      }
    }
  }
  /// Host (log) time of the message's sensor time, after adding it as a sample; a message
  /// dated by another (time_from) goes through that one's mapping without adding a sample.
  std::optional<int64_t> map(const drivers::CanDecodedMessage& msg,
                             const drivers::CanSignalDecoder& decoder) {
    if (!msg.time.sensor_time_us) return std::nullopt;
    const bool linked = !msg.spec->time_from.empty();
    auto it = clocks_.find(linked ? decoder.find(msg.spec->time_from) : msg.spec);
    if (it == clocks_.end()) return std::nullopt;
    drivers::ClockMapping& clock = *it->second;
    int64_t sensor_us = *msg.time.sensor_time_us;
    const int64_t modulus = clock.options().sensor_modulus_us;
    if (modulus > 0) sensor_us = ((sensor_us % modulus) + modulus) % modulus;
    if (!linked) clock.update(sensor_us, msg.time.host.realtime_us);
    return clock.to_host_us(sensor_us);
  }

 private:
  std::map<const drivers::CanMessageSpec*, std::unique_ptr<drivers::ClockMapping>> clocks_;
};

json message_to_json(const drivers::CanDecodedMessage& msg, const drivers::CanLogFrame& frame,
                     const std::optional<int64_t>& time_of_validity_us) {
  json j;
  j["time_unix_s"] = num(static_cast<double>(frame.time.realtime_us) / 1e6);
  j["interface"] = std::string(frame.interface_name.data());
  j["id"] = hex_id(msg.id, msg.extended);
  j["extended"] = msg.extended;
  j["name"] = msg.spec->name;
  if (msg.multiplexer_value) j["multiplexer"] = *msg.multiplexer_value;
  j["sensor_time_s"] = msg.time.sensor_time_us
                           ? num(static_cast<double>(*msg.time.sensor_time_us) / 1e6)
                           : json(nullptr);
  j["time_of_validity_unix_s"] =
      time_of_validity_us ? num(static_cast<double>(*time_of_validity_us) / 1e6) : json(nullptr);
  json signals = json::object();
  for (const drivers::CanSignalValue& v : msg.signals) {
    const auto [name, factor] = display_of(*v.spec);
    signals[name] = v.value_si ? num(*v.value_si * factor) : json(nullptr);
  }
  j["signals"] = std::move(signals);
  return j;
}

void run_can(std::istream& in, std::ostream& records, drivers::DecodeStats& stats,
             const ParseOptions& options) {
  if (options.can_config_path.empty()) {
    throw CommandError("parse --format can: --can-config FILE (CAN signal table) is required");
  }
  drivers::CanConfig config;
  try {
    config = drivers::load_can_config_file(options.can_config_path);
  } catch (const drivers::CanConfigError& e) {
    throw CommandError(std::string("parse --format can: ") + e.what());
  }
  drivers::CanSignalDecoder decoder(config.messages);
  SensorClocks clocks(decoder.messages());
  drivers::CandumpLogDecoder log;
  drivers::DecodeStats frames;  // frame-level counters beyond the signal decoder's
  std::vector<drivers::CanLogFrame> out;
  drivers::CanDecodedMessage msg;
  auto handle = [&](const drivers::CanLogFrame& f) {
    if (f.remote) {
      ++frames.unsupported;
      frames.dropped_bytes += f.line_bytes;
      return;
    }
    const drivers::Timestamps time{f.time, std::nullopt};
    if (!decoder.decode(f.id, f.extended, f.payload(), time, msg)) {
      frames.dropped_bytes += f.line_bytes;
      return;
    }
    records << message_to_json(msg, f, clocks.map(msg, decoder)).dump() << '\n';
  };
  decode_stream<drivers::CanLogFrame>(in, log, handle);
  log.finish(drivers::HostTime{}, out);
  for (const auto& f : out) handle(f);

  const drivers::DecodeStats& l = log.stats();
  const drivers::DecodeStats& d = decoder.stats();
  drivers::DecodeStats total;
  total.records = d.records;
  total.bytes = l.bytes;
  total.dropped_bytes = l.dropped_bytes + frames.dropped_bytes;
  total.malformed = l.malformed + d.malformed;
  total.unsupported = l.unsupported + d.unsupported + frames.unsupported;
  total.out_of_range = d.out_of_range;
  stats += total;
}

const ParseFormatRegistration kCan{
    "can",
    ParseFormat{"candump log (-l/-L or ASCII) decoded with --can-config signal table", run_can}};

}  // namespace
}  // namespace nav::tool
