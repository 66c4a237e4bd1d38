// systemd notification wrapper: see nav/daemon/system/sd_notify.h.
#include "nav/daemon/system/sd_notify.h"

#include <systemd/sd-daemon.h>

#include <cstdint>
#include <cstdlib>

namespace nav::daemon {

SdNotifier::SdNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  enabled_ = socket != nullptr && socket[0] != '\0';
  std::uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0 && usec > 0) {
    watchdog_timeout_ = std::chrono::microseconds(static_cast<std::int64_t>(usec));
  }
}

std::optional<std::chrono::microseconds> SdNotifier::watchdog_period() const {
  if (!watchdog_timeout_) return std::nullopt;
  return *watchdog_timeout_ / 2;
}

bool SdNotifier::send(const std::string& state) const {
  if (!enabled_) return false;
  return sd_notify(0, state.c_str()) > 0;
}

bool SdNotifier::ready() const { return send("READY=1"); }
bool SdNotifier::watchdog() const { return send("WATCHDOG=1"); }
bool SdNotifier::stopping() const { return send("STOPPING=1"); }

bool SdNotifier::status(std::string_view line) const {
  return send("STATUS=" + sanitize_status_line(line));
}

bool SdNotifier::ready_with_status(std::string_view line) const {
  return send("READY=1\nSTATUS=" + sanitize_status_line(line));
}

std::string sanitize_status_line(std::string_view line) {
  std::string out(line);
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  }
  return out;
}

}  // namespace nav::daemon
