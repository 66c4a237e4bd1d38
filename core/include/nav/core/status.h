#pragma once
// Results instead of crashes (docs/architecture.md "Conventions"): every core operation that can
// reject its input returns a Status naming what was wrong and where; the state is left unchanged on
// error.

#include <string>
#include <utility>

namespace nav::core {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,      // NaN/Inf, wrong size, out-of-range value
  kNotPositiveDefinite,  // a noise/information matrix that is not SPD
  kUnknownState,         // a state id that is not (or no longer) in the filter
  kNumericalFailure,     // factorisation failed, solver diverged
  kOutOfRange,           // e.g. pitch at the Euler singularity
};

class [[nodiscard]] Status {
 public:
  Status() = default;
  static Status Ok() { return {}; }
  static Status Error(StatusCode code, std::string message) {
    Status s;
    s.code_ = code;
    s.message_ = std::move(message);
    return s;
  }
  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  std::string to_string() const;

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

const char* to_string(StatusCode code);

}  // namespace nav::core
