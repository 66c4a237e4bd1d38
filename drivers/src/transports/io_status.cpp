// Errors as values for device transports: errno classification and message formatting.

#include "nav/drivers/transports/io_status.h"

#include <cerrno>
#include <cstring>

namespace nav::drivers {

const char* to_string(IoCode code) {
  switch (code) {
    case IoCode::kOk:
      return "ok";
    case IoCode::kTimeout:
      return "timeout";
    case IoCode::kDisconnected:
      return "disconnected";
    case IoCode::kInvalidArgument:
      return "invalid argument";
    case IoCode::kBusy:
      return "busy";
    case IoCode::kUnsupported:
      return "unsupported";
    case IoCode::kSystemError:
      return "system error";
  }
  return "unknown";
}

IoStatus IoStatus::Error(IoCode code, std::string device, std::string what, int errno_value) {
  IoStatus s;
  s.code_ = code;
  s.errno_ = errno_value;
  s.device_ = std::move(device);
  s.message_ = s.device_ + ": " + what;
  if (errno_value != 0) {
    s.message_ += ": ";
    s.message_ += std::strerror(errno_value);
  }
  s.message_ += " (";
  s.message_ += to_string(code);
  s.message_ += ")";
  return s;
}

IoStatus IoStatus::FromErrno(int errno_value, std::string device, std::string what) {
  IoCode code = IoCode::kSystemError;
  switch (errno_value) {
    case EIO:
    case ENXIO:
    case ENODEV:
    case ENOENT:
    case EPIPE:
    case ECONNRESET:
    case ENETDOWN:
      code = IoCode::kDisconnected;
      break;
    case EBUSY:
    case EWOULDBLOCK:
      code = IoCode::kBusy;
      break;
    case EAFNOSUPPORT:
    case EPROTONOSUPPORT:
    case ENOTSUP:
      code = IoCode::kUnsupported;
      break;
    case EINVAL:
      code = IoCode::kInvalidArgument;
      break;
    case ETIMEDOUT:
      code = IoCode::kTimeout;
      break;
    default:
      break;
  }
  return Error(code, std::move(device), std::move(what), errno_value);
}

}  // namespace nav::drivers
