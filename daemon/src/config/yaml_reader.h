#pragma once
// Internal to nav_daemon: a YAML node paired with its key path, with typed, range-checked reads
// that throw ConfigError("<source>", "<path>", "<reason>"). Used by the config loaders.

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "nav/daemon/config/config.h"

namespace nav::daemon::detail {

class YamlReader {
 public:
  YamlReader(YAML::Node node, std::string path, const std::string* source)
      : node_(std::move(node)), path_(std::move(path)), source_(source) {}

  const std::string& path() const { return path_; }
  const YAML::Node& node() const { return node_; }
  [[noreturn]] void fail(const std::string& reason) const;
  /// Path of a child key ("filter" + "latency_window_ms" -> "filter.latency_window_ms").
  std::string child_path(std::string_view key) const;

  /// Requires a mapping whose keys are all in `allowed` (unknown key -> error naming it).
  void expect_map(std::initializer_list<std::string_view> allowed) const;
  bool has(std::string_view key) const;
  /// The child node (must exist: "missing required key").
  YamlReader at(std::string_view key) const;
  /// Sequence elements with paths "<path>[i]"; errors if not a sequence.
  std::vector<YamlReader> elements() const;

  std::string as_string() const;
  double as_double() const;  ///< finite
  long long as_int() const;
  bool as_bool() const;

  // Optional keys keep `out` when absent; required ones fail when absent.
  void read(std::string_view key, std::string& out, bool required = false) const;
  void read(std::string_view key, double& out, double lo, double hi, bool required = false) const;
  void read(std::string_view key, int& out, int lo, int hi, bool required = false) const;
  /// Maps one of `names` (index i) onto `values[i]`.
  template <typename E>
  void read_enum(std::string_view key, E& out,
                 std::initializer_list<std::pair<std::string_view, E>> names) const {
    if (!has(key)) return;
    const YamlReader child = at(key);
    const std::string text = child.as_string();
    std::string allowed;
    for (const auto& [name, value] : names) {
      if (text == name) {
        out = value;
        return;
      }
      if (!allowed.empty()) allowed += ", ";
      allowed += name;
    }
    child.fail("'" + text + "' is not one of: " + allowed);
  }

 private:
  YAML::Node node_;
  std::string path_;
  const std::string* source_;
};

/// Error message text of a value range: "[lo, hi]".
std::string range_text(double lo, double hi);

}  // namespace nav::daemon::detail
