#include "nav/core/status.h"

namespace nav::core {

const char* to_string(StatusCode code) {
  switch (code) {
    case StatusCode::kOk: return "ok";
    case StatusCode::kInvalidArgument: return "invalid argument";
    case StatusCode::kNotPositiveDefinite: return "not positive definite";
    case StatusCode::kUnknownState: return "unknown state";
    case StatusCode::kNumericalFailure: return "numerical failure";
    case StatusCode::kOutOfRange: return "out of range";
  }
  return "unknown status";
}

std::string Status::to_string() const {
  if (ok()) return "ok";
  return std::string(nav::core::to_string(code_)) + ": " + message_;
}

}  // namespace nav::core
