#pragma once
// A bounded FIFO of outgoing frames for one WebSocket client. When full, push() drops the
// OLDEST frame and counts it: a slow or stalled client loses history, never the newest state,
// and never makes the producer (the LCM thread) wait or grow memory without bound.
// Not thread-safe on its own: TopsideServer guards all queues with its clients mutex.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>

namespace nav::daemon::topside {

/// One frame to send: text (JSON) or binary, its bytes shared between clients.
struct OutgoingFrame {
  std::shared_ptr<const std::string> payload;
  bool binary = false;
};

class ClientQueue {
 public:
  explicit ClientQueue(std::size_t capacity) : capacity_(capacity) {
    if (capacity == 0) throw std::invalid_argument("ClientQueue: capacity must be at least 1");
  }

  /// Appends `frame`; if the queue held `capacity` frames, the oldest is dropped first.
  void push(OutgoingFrame frame) {
    if (frames_.size() == capacity_) {
      frames_.pop_front();
      ++dropped_;
    }
    frames_.push_back(std::move(frame));
  }

  bool has_frames() const { return !frames_.empty(); }
  std::size_t queued() const { return frames_.size(); }  ///< frames waiting
  bool full() const { return frames_.size() == capacity_; }
  std::uint64_t dropped() const { return dropped_; }

  /// Removes and returns the oldest frame; precondition: has_frames().
  OutgoingFrame pop() {
    OutgoingFrame f = std::move(frames_.front());
    frames_.pop_front();
    return f;
  }

 private:
  std::size_t capacity_;
  std::deque<OutgoingFrame> frames_;
  std::uint64_t dropped_ = 0;
};

}  // namespace nav::daemon::topside
