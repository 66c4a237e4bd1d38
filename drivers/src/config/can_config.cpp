// YAML loader of CAN signal tables; schema in can_config.h.
#include "nav/drivers/config/can_config.h"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <sstream>

namespace nav::drivers {
namespace {

/// Error at a key path; the source name is prefixed by the caller.
struct PathError {
  std::string message;
};

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
  throw PathError{path + ": " + reason};
}

void check_keys(const YAML::Node& map, const std::string& path,
                std::initializer_list<std::string_view> allowed) {
  for (const auto& kv : map) {
    const std::string key = kv.first.Scalar();
    bool ok = false;
    for (std::string_view a : allowed) ok = ok || key == a;
    if (!ok) fail(path + "." + key, "unknown key");
  }
}

const YAML::Node scalar_at(const YAML::Node& map, const std::string& key, const std::string& path,
                           bool required) {
  const YAML::Node node = map[key];
  if (!node) {
    if (required) fail(path + "." + key, "missing");
    return node;
  }
  if (!node.IsScalar()) fail(path + "." + key, "must be a scalar");
  return node;
}

/// Integer scalar: decimal or 0x hex, optional sign; within [lo, hi].
int64_t parse_int(const YAML::Node& node, const std::string& path, int64_t lo, int64_t hi) {
  const std::string& text = node.Scalar();
  std::string_view s = text;
  bool negative = false;
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) {
    negative = s[0] == '-';
    s.remove_prefix(1);
  }
  int base = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    base = 16;
    s.remove_prefix(2);
  }
  const std::string digits(s);
  char* end = nullptr;
  errno = 0;
  const unsigned long long magnitude = std::strtoull(digits.c_str(), &end, base);
  if (digits.empty() || end != digits.c_str() + digits.size() || digits[0] == '-' ||
      digits[0] == '+' || digits[0] == ' ') {
    fail(path, "\"" + text + "\" is not an integer");
  }
  const bool too_big =
      errno == ERANGE ||
      magnitude >
          static_cast<unsigned long long>(std::numeric_limits<int64_t>::max()) + (negative ? 1 : 0);
  if (too_big) fail(path, "\"" + text + "\" is out of range");
  const int64_t v =
      negative ? static_cast<int64_t>(0 - magnitude) : static_cast<int64_t>(magnitude);
  if (v < lo || v > hi) {
    fail(path, text + " is not in " + std::to_string(lo) + ".." + std::to_string(hi));
  }
  return v;
}

double parse_double(const YAML::Node& node, const std::string& path) {
  double v = 0.0;
  if (!YAML::convert<double>::decode(node, v)) {
    fail(path, "\"" + node.Scalar() + "\" is not a number");
  }
  return v;
}

bool parse_bool(const YAML::Node& node, const std::string& path) {
  bool v = false;
  if (!YAML::convert<bool>::decode(node, v)) {
    fail(path, "\"" + node.Scalar() + "\" is not true/false");
  }
  return v;
}

CanByteOrder parse_byte_order(const YAML::Node& node, const std::string& path) {
  const std::string& s = node.Scalar();
  if (s == "intel" || s == "little_endian") return CanByteOrder::kIntel;
  if (s == "motorola" || s == "big_endian") return CanByteOrder::kMotorola;
  fail(path, "\"" + s + "\" is not one of intel, little_endian, motorola, big_endian");
}

CanSignalSpec parse_signal(const YAML::Node& node, const std::string& path) {
  if (!node.IsMap()) fail(path, "must be a map");
  check_keys(node, path,
             {"name", "start_bit", "length", "byte_order", "signed", "scale", "offset", "unit",
              "min", "max", "invalid", "multiplexer_value", "time_of_validity"});
  CanSignalSpec s;
  s.name = scalar_at(node, "name", path, true).Scalar();
  s.start_bit = static_cast<uint32_t>(
      parse_int(scalar_at(node, "start_bit", path, true), path + ".start_bit", 0, 63));
  s.length = static_cast<uint32_t>(
      parse_int(scalar_at(node, "length", path, true), path + ".length", 1, 64));
  s.byte_order = parse_byte_order(scalar_at(node, "byte_order", path, true), path + ".byte_order");
  if (auto n = scalar_at(node, "signed", path, false))
    s.is_signed = parse_bool(n, path + ".signed");
  if (auto n = scalar_at(node, "scale", path, false)) s.scale = parse_double(n, path + ".scale");
  if (auto n = scalar_at(node, "offset", path, false)) s.offset = parse_double(n, path + ".offset");
  if (auto n = scalar_at(node, "unit", path, false)) s.unit = n.Scalar();
  if (auto n = scalar_at(node, "min", path, false)) s.min = parse_double(n, path + ".min");
  if (auto n = scalar_at(node, "max", path, false)) s.max = parse_double(n, path + ".max");
  if (s.min == 0.0 && s.max == 0.0) {
    // DBC writes [0|0] for "no range"; a table transcribed from a .dbc keeps that meaning.
    s.min.reset();
    s.max.reset();
  }
  if (auto n = scalar_at(node, "invalid", path, false)) {
    const int64_t v = parse_int(n, path + ".invalid", std::numeric_limits<int64_t>::min(),
                                std::numeric_limits<int64_t>::max());
    if (v < 0 && !s.is_signed) fail(path + ".invalid", "negative for an unsigned signal");
    // A negative pattern of a signed signal is its two's complement in `length` bits.
    const uint64_t mask = s.length >= 64 ? ~uint64_t{0} : (uint64_t{1} << s.length) - 1;
    const auto bits = static_cast<uint64_t>(v);
    if (v < 0) {
      const int64_t lowest =
          s.length >= 64 ? std::numeric_limits<int64_t>::min() : -(int64_t{1} << (s.length - 1));
      if (v < lowest) fail(path + ".invalid", n.Scalar() + " does not fit");
      s.invalid_raw = bits & mask;
    } else {
      s.invalid_raw = bits;  // range checked by validate_can_messages
    }
  }
  if (auto n = scalar_at(node, "multiplexer_value", path, false)) {
    s.multiplexer_value = static_cast<uint64_t>(
        parse_int(n, path + ".multiplexer_value", 0, std::numeric_limits<int64_t>::max()));
  }
  if (auto n = scalar_at(node, "time_of_validity", path, false)) {
    s.time_of_validity = parse_bool(n, path + ".time_of_validity");
  }
  return s;
}

CanMessageSpec parse_message(const YAML::Node& node, const std::string& path) {
  if (!node.IsMap()) fail(path, "must be a map");
  check_keys(
      node, path,
      {"name", "id", "extended", "dlc", "multiplexer", "signals", "time_from", "time_match"});
  CanMessageSpec m;
  m.name = scalar_at(node, "name", path, true).Scalar();
  m.id = static_cast<uint32_t>(
      parse_int(scalar_at(node, "id", path, true), path + ".id", 0, 0xFFFFFFFF));
  if (auto n = scalar_at(node, "extended", path, false)) {
    m.extended = parse_bool(n, path + ".extended");
  }
  m.dlc = static_cast<uint8_t>(parse_int(scalar_at(node, "dlc", path, true), path + ".dlc", 0, 8));
  if (auto n = scalar_at(node, "multiplexer", path, false)) m.multiplexer = n.Scalar();
  if (auto n = scalar_at(node, "time_from", path, false)) m.time_from = n.Scalar();
  if (auto n = scalar_at(node, "time_match", path, false)) m.time_match = n.Scalar();
  const YAML::Node signals = node["signals"];
  if (!signals) fail(path + ".signals", "missing");
  if (!signals.IsSequence()) fail(path + ".signals", "must be a list");
  for (size_t i = 0; i < signals.size(); ++i) {
    m.signals.push_back(parse_signal(signals[i], path + ".signals[" + std::to_string(i) + "]"));
  }
  return m;
}

}  // namespace

CanConfig parse_can_config(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    std::ostringstream msg;
    msg << source << ": YAML syntax error at line " << e.mark.line + 1 << ", column "
        << e.mark.column + 1 << ": " << e.msg;
    throw CanConfigError(msg.str());
  }
  CanConfig config;
  try {
    if (!root.IsMap()) fail("(top level)", "must be a map with a \"messages\" list");
    check_keys(root, "(top level)", {"messages"});
    const YAML::Node messages = root["messages"];
    if (!messages) fail("messages", "missing");
    if (!messages.IsSequence()) fail("messages", "must be a list");
    for (size_t i = 0; i < messages.size(); ++i) {
      config.messages.push_back(parse_message(messages[i], "messages[" + std::to_string(i) + "]"));
    }
  } catch (const PathError& e) {
    throw CanConfigError(source + ": " + e.message);
  } catch (const YAML::Exception& e) {
    throw CanConfigError(source + ": " + e.what());
  }
  if (std::string err = validate_can_messages(config.messages); !err.empty()) {
    throw CanConfigError(source + ": " + err);
  }
  return config;
}

CanConfig load_can_config_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CanConfigError(path + ": cannot open the CAN config file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw CanConfigError(path + ": read error");
  return parse_can_config(text.str(), path);
}

}  // namespace nav::drivers
