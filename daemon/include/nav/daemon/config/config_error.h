#pragma once
// The error every configuration check throws (config.h): the key path and the reason, so that a
// bad file stops start-up with a message naming where and what.

#include <stdexcept>
#include <string>

namespace nav::daemon {

/// A configuration error: `key_path()` is the YAML path ("sensors[2].transport.baud", "" for the
/// document root), `reason()` what is wrong; what() = "<source>: <key_path>: <reason>".
class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& source, std::string key_path, std::string reason);
  const std::string& key_path() const { return key_path_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string key_path_;
  std::string reason_;
};

}  // namespace nav::daemon
