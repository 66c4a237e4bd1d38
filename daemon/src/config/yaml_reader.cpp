// Typed, path-aware YAML reads for the navd config: see yaml_reader.h.
#include "yaml_reader.h"

#include <cmath>
#include <sstream>

namespace nav::daemon::detail {
namespace {

const char* kind_name(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Sequence:
      return "a sequence";
    case YAML::NodeType::Scalar:
      return "a scalar";
    case YAML::NodeType::Null:
      return "null";
    default:
      return "undefined";
  }
}

std::string number_text(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

}  // namespace

std::string range_text(double lo, double hi) {
  std::string text = "[";
  text += number_text(lo);
  text += ", ";
  text += number_text(hi);
  text += "]";
  return text;
}

void YamlReader::fail(const std::string& reason) const {
  throw ConfigError(*source_, path_, reason);
}

std::string YamlReader::child_path(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

void YamlReader::expect_map(std::initializer_list<std::string_view> allowed) const {
  if (!node_.IsMap()) fail(std::string("expected a mapping, got ") + kind_name(node_));
  for (const auto& entry : node_) {
    if (!entry.first.IsScalar()) fail("mapping keys must be scalars");
    const std::string key = entry.first.Scalar();
    bool known = false;
    std::string list;
    for (std::string_view name : allowed) {
      known = known || key == name;
      if (!list.empty()) list += ", ";
      list += name;
    }
    if (!known) throw ConfigError(*source_, child_path(key), "unknown key (allowed: " + list + ")");
  }
}

bool YamlReader::has(std::string_view key) const {
  return node_.IsMap() && node_[std::string(key)].IsDefined();
}

YamlReader YamlReader::at(std::string_view key) const {
  if (!has(key)) throw ConfigError(*source_, child_path(key), "missing required key");
  return YamlReader(node_[std::string(key)], child_path(key), source_);
}

std::vector<YamlReader> YamlReader::elements() const {
  if (!node_.IsSequence()) fail(std::string("expected a sequence, got ") + kind_name(node_));
  std::vector<YamlReader> out;
  for (std::size_t i = 0; i < node_.size(); ++i) {
    out.emplace_back(node_[i], path_ + "[" + std::to_string(i) + "]", source_);
  }
  return out;
}

std::string YamlReader::as_string() const {
  if (!node_.IsScalar()) fail(std::string("expected a string, got ") + kind_name(node_));
  return node_.Scalar();
}

double YamlReader::as_double() const {
  if (!node_.IsScalar()) fail(std::string("expected a number, got ") + kind_name(node_));
  double v = 0.0;
  if (!YAML::convert<double>::decode(node_, v))
    fail("expected a number, got '" + node_.Scalar() + "'");
  if (!std::isfinite(v)) fail("'" + node_.Scalar() + "' is not finite");
  return v;
}

long long YamlReader::as_int() const {
  if (!node_.IsScalar()) fail(std::string("expected an integer, got ") + kind_name(node_));
  long long v = 0;
  if (!YAML::convert<long long>::decode(node_, v)) {
    fail("expected an integer, got '" + node_.Scalar() + "'");
  }
  return v;
}

bool YamlReader::as_bool() const {
  if (!node_.IsScalar()) fail(std::string("expected true or false, got ") + kind_name(node_));
  bool v = false;
  if (!YAML::convert<bool>::decode(node_, v))
    fail("expected true or false, got '" + node_.Scalar() + "'");
  return v;
}

void YamlReader::read(std::string_view key, std::string& out, bool required) const {
  if (!has(key) && !required) return;
  const YamlReader child = at(key);
  out = child.as_string();
  if (out.empty()) child.fail("must not be empty");
}

void YamlReader::read(std::string_view key, double& out, double lo, double hi,
                      bool required) const {
  if (!has(key) && !required) return;
  const YamlReader child = at(key);
  const double v = child.as_double();
  if (v < lo || v > hi) child.fail(number_text(v) + " is not in " + range_text(lo, hi));
  out = v;
}

void YamlReader::read(std::string_view key, int& out, int lo, int hi, bool required) const {
  if (!has(key) && !required) return;
  const YamlReader child = at(key);
  const long long v = child.as_int();
  if (v < lo || v > hi) {
    child.fail(std::to_string(v) + " is not in [" + std::to_string(lo) + ", " + std::to_string(hi) +
               "]");
  }
  out = static_cast<int>(v);
}

}  // namespace nav::daemon::detail
