// In-memory ByteStream (tests and replay): chunks and errors are returned in the order pushed.

#include <algorithm>
#include <cstring>

#include "nav/drivers/transports/byte_stream.h"

namespace nav::drivers {

MemoryByteStream::MemoryByteStream(std::string name) : name_(std::move(name)) {}

void MemoryByteStream::push(std::span<const uint8_t> chunk, const HostTime& received) {
  if (chunk.empty()) return;  // an empty chunk would read as "0 bytes, ok": never produce it
  {
    std::lock_guard lock(mutex_);
    items_.push_back(Item{{chunk.begin(), chunk.end()}, 0, received, IoStatus::Ok()});
  }
  ready_.notify_one();
}

void MemoryByteStream::push_error(IoStatus error) {
  {
    std::lock_guard lock(mutex_);
    items_.push_back(Item{{}, 0, {}, std::move(error)});
  }
  ready_.notify_one();
}

std::vector<uint8_t> MemoryByteStream::written() const {
  std::lock_guard lock(mutex_);
  return written_;
}

ReadResult MemoryByteStream::read(std::span<uint8_t> buffer, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [this] { return !items_.empty(); })) {
    return {IoStatus::Error(IoCode::kTimeout, name_, "read: no data within timeout"), 0, {}};
  }
  Item& item = items_.front();
  if (!item.error.ok()) {
    ReadResult result{item.error, 0, {}};
    items_.pop_front();
    return result;
  }
  const std::size_t n = std::min(buffer.size(), item.bytes.size() - item.consumed);
  if (n > 0) std::memcpy(buffer.data(), item.bytes.data() + item.consumed, n);
  item.consumed += n;
  ReadResult result{IoStatus::Ok(), n, item.received};
  if (item.consumed == item.bytes.size()) items_.pop_front();
  return result;
}

IoStatus MemoryByteStream::write(std::span<const uint8_t> bytes, std::chrono::milliseconds) {
  std::lock_guard lock(mutex_);
  written_.insert(written_.end(), bytes.begin(), bytes.end());
  return IoStatus::Ok();
}

}  // namespace nav::drivers
