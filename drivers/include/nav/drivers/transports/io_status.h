#pragma once
// Errors as values for every device transport (docs/architecture.md "Conventions"): what failed,
// on which device, and the errno text when the kernel reported one. Transports never throw.

#include <string>
#include <utility>

namespace nav::drivers {

enum class IoCode {
  kOk = 0,
  kTimeout,          ///< nothing arrived / could be sent within the caller's timeout
  kDisconnected,     ///< the device vanished (EIO, ENXIO, POLLHUP, ENODEV); may come back
  kInvalidArgument,  ///< bad options or a malformed request; nothing was done
  kBusy,             ///< another process holds the device (TIOCEXCL / flock / EBUSY)
  kUnsupported,      ///< the kernel or device lacks the feature (e.g. no PF_CAN)
  kSystemError,      ///< any other failing system or library call
};

const char* to_string(IoCode code);

class [[nodiscard]] IoStatus {
 public:
  IoStatus() = default;
  static IoStatus Ok() { return {}; }
  /// `device` is the path/name of the device, `what` the failed operation; `errno_value` 0 when
  /// the failure did not come from the kernel.
  static IoStatus Error(IoCode code, std::string device, std::string what, int errno_value = 0);
  /// Maps an errno from a failed call to the matching IoCode (EIO/ENXIO/ENODEV -> kDisconnected,
  /// EBUSY/EWOULDBLOCK -> kBusy, EAFNOSUPPORT -> kUnsupported, ...).
  static IoStatus FromErrno(int errno_value, std::string device, std::string what);

  bool ok() const { return code_ == IoCode::kOk; }
  IoCode code() const { return code_; }
  int errno_value() const { return errno_; }
  const std::string& device() const { return device_; }
  /// "<device>: <what>: <strerror> (<code>)".
  const std::string& message() const { return message_; }

 private:
  IoCode code_ = IoCode::kOk;
  int errno_ = 0;
  std::string device_;
  std::string message_;
};

}  // namespace nav::drivers
