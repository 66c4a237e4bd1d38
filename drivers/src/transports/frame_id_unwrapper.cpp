// Frame counter unwrapping for camera streams (GigE Vision 1.x 16-bit block ids that skip 0,
// 64-bit extended ids, 32-bit V4L2 sequence numbers); see camera.h.

#include <algorithm>

#include "nav/drivers/transports/camera.h"

namespace nav::drivers {

FrameIdUnwrapper::FrameIdUnwrapper(int bits, bool zero_reserved)
    : bits_(std::clamp(bits, 1, 64)), zero_reserved_(zero_reserved) {
  const uint64_t values = bits_ == 64 ? 0 : (uint64_t{1} << bits_);  // 0 means 2^64
  period_ = values - (zero_reserved_ ? 1 : 0);  // 2^64 - 1 wraps correctly from 0
}

uint64_t FrameIdUnwrapper::ordinal(uint64_t raw) const {
  const uint64_t mask = bits_ == 64 ? ~uint64_t{0} : (uint64_t{1} << bits_) - 1;
  raw &= mask;
  if (zero_reserved_) return raw == 0 ? 0 : raw - 1;  // a stray 0 is treated like 1
  return raw;
}

FrameIdUnwrapper::Update FrameIdUnwrapper::update(uint64_t raw_id) {
  const uint64_t o = ordinal(raw_id);
  Update u;
  if (!started_) {
    started_ = true;
    last_ordinal_ = o;
    last_id_ = o + (zero_reserved_ ? 1 : 0);
    u.id = last_id_;
    return u;
  }
  // Forward distance modulo the period (period_ == 0 means modulo 2^64: plain wrap-around).
  uint64_t delta = o - last_ordinal_;
  if (period_ != 0) delta = o >= last_ordinal_ ? o - last_ordinal_ : period_ - (last_ordinal_ - o);
  const uint64_t half = period_ == 0 ? (uint64_t{1} << 63) : period_ / 2;
  last_ordinal_ = o;
  if (delta == 0) {
    u.duplicate = true;
  } else if (delta > half) {
    u.restarted = true;  // counter went backwards: count from here, nothing known lost
    ++last_id_;
  } else {
    u.lost = delta - 1;
    last_id_ += delta;
  }
  u.id = last_id_;
  return u;
}

}  // namespace nav::drivers
