#pragma once
// Byte-stream transport interface (LCM's transport table / ArduPilot AP_HAL::UARTDriver idea,
// without globals): serial sensors (DVL PD0/PD6, NMEA heading, Paroscientific, altimeters) are
// read through this interface, so the same driver code runs on a termios port (SerialPort), on a
// replayed recording or on the in-memory stream below.
//
// Threading contract: one ByteStream is used by ONE driver thread; read() and write() may block
// for at most their timeout. Implementations are not required to be thread-safe unless they say
// so (MemoryByteStream is: a test thread may push() while the driver thread reads).

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "nav/drivers/time/timestamps.h"
#include "nav/drivers/transports/io_status.h"

namespace nav::drivers {

/// Result of one read: `bytes` bytes were copied to the caller's buffer at host time `received`
/// (taken right after the kernel returned them). On error `bytes` is 0 and `status` says why;
/// kTimeout means nothing arrived, kDisconnected that the device vanished (it may come back).
struct ReadResult {
  IoStatus status;
  std::size_t bytes = 0;
  HostTime received;
};

class ByteStream {
 public:
  virtual ~ByteStream() = default;
  /// Waits at most `timeout` for at least one byte, then copies what is available (up to
  /// buffer.size()). Never blocks longer than `timeout` (plus scheduling jitter).
  virtual ReadResult read(std::span<uint8_t> buffer, std::chrono::milliseconds timeout) = 0;
  /// Writes all of `bytes` (commands for polled sensors) within `timeout`, or fails.
  virtual IoStatus write(std::span<const uint8_t> bytes, std::chrono::milliseconds timeout) = 0;
  /// Device path or name, for messages.
  virtual const std::string& name() const = 0;
};

/// In-memory ByteStream for tests and replay: the producer pushes chunks (each read returns at
/// most one chunk, so chunking is reproduced exactly) or errors; writes are recorded.
/// Thread-safe: push()/push_error()/written() may be called from any thread.
class MemoryByteStream final : public ByteStream {
 public:
  explicit MemoryByteStream(std::string name = "memory");

  /// Queues one chunk; `received` is the host time reported when it is read.
  void push(std::span<const uint8_t> chunk, const HostTime& received);
  /// Queues an error returned by the read that reaches it (e.g. kDisconnected).
  void push_error(IoStatus error);
  /// Everything written so far.
  std::vector<uint8_t> written() const;

  ReadResult read(std::span<uint8_t> buffer, std::chrono::milliseconds timeout) override;
  IoStatus write(std::span<const uint8_t> bytes, std::chrono::milliseconds timeout) override;
  const std::string& name() const override { return name_; }

 private:
  struct Item {
    std::vector<uint8_t> bytes;
    std::size_t consumed = 0;
    HostTime received;
    IoStatus error;
  };
  std::string name_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Item> items_;
  std::vector<uint8_t> written_;
};

}  // namespace nav::drivers
