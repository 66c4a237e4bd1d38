#pragma once
// systemd service notification (sd_notify(3)) for navd running as Type=notify: READY=1 once the
// filter runs, WATCHDOG=1 from the filter loop (at half the WatchdogSec interval), STATUS= with a
// one-line health summary, STOPPING=1 on shutdown. A thin wrapper over libsystemd.
//
// Outside systemd (no NOTIFY_SOCKET) every call is a no-op returning false, so the same binary
// runs from a shell. Thread-safe: sd_notify(3) only sends one datagram per call.

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

namespace nav::daemon {

class SdNotifier {
 public:
  /// Reads the environment once (NOTIFY_SOCKET, WATCHDOG_USEC, WATCHDOG_PID) through
  /// sd_watchdog_enabled(3); the environment is left untouched for child processes.
  SdNotifier();

  /// True when NOTIFY_SOCKET is set (the service manager listens).
  bool enabled() const { return enabled_; }
  /// The watchdog timeout WatchdogSec (WATCHDOG_USEC) if the watchdog is enabled for this PID.
  std::optional<std::chrono::microseconds> watchdog_timeout() const { return watchdog_timeout_; }
  /// Period at which WATCHDOG=1 should be sent: half the timeout (sd_watchdog_enabled(3)
  /// recommendation), or nullopt when the watchdog is disabled.
  std::optional<std::chrono::microseconds> watchdog_period() const;

  /// Each returns true when the datagram was sent, false when disabled or sending failed.
  bool ready() const;                        ///< "READY=1"
  bool watchdog() const;                     ///< "WATCHDOG=1"
  bool status(std::string_view line) const;  ///< "STATUS=<line>" (newlines replaced by ' ')
  bool stopping() const;                     ///< "STOPPING=1"
  bool ready_with_status(std::string_view line) const;  ///< "READY=1\nSTATUS=<line>"

  /// Sends an arbitrary newline-separated assignment list (sd_notify(3) state string).
  bool send(const std::string& state) const;

 private:
  bool enabled_ = false;
  std::optional<std::chrono::microseconds> watchdog_timeout_;
};

/// STATUS values are one line: control characters (newline included) become spaces.
std::string sanitize_status_line(std::string_view line);

}  // namespace nav::daemon
