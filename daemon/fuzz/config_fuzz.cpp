// libFuzzer target for navd's YAML config loader (config/README.md), the operator's input:
// parse_config() on arbitrary text must either return a config or throw ConfigError (its
// contract: errors name the key path and the reason); any other exception, crash or sanitizer
// report is a finding. Seeded with config/*.yaml (scripts/fuzz).
#include <cstdint>
#include <cstdlib>
#include <string>

#include "nav/daemon/config/config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  try {
    const nav::daemon::NavdConfig config = nav::daemon::parse_config(text, "<fuzz>", "/nonexistent");
    if (config.sensors.empty()) std::abort();  // "required, at least one"
  } catch (const nav::daemon::ConfigError&) {
  }
  return 0;
}
