#pragma once
// The checkpoint thread: the filter thread hands it a serialised snapshot of
// the map (core/serialization + the daemon's own sections) and goes on; this thread writes it
// atomically with CheckpointWriter (temp, fsync, rename, fsync dir; rotation to `keep`).
//
// Threads: offer() is called by the filter thread only and never waits for disk: it moves the
// payload into a one-slot mailbox under a mutex held for a pointer swap. If the previous offer
// has not been written yet it is replaced (a newer map supersedes it) and counted in
// `superseded`, so a slow disk costs checkpoint frequency, never filter time or memory beyond
// two payloads. stop() (any thread, once) writes what is still pending — the shutdown
// checkpoint — and joins. Write errors are counted and kept (last_error) and the thread keeps
// going: the next period tries again.

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "nav/daemon/checkpoint/checkpoint.h"

namespace nav::daemon {

struct CheckpointWorkerStats {
  std::uint64_t offered = 0;     ///< payloads handed in
  std::uint64_t written = 0;     ///< checkpoint files written
  std::uint64_t failed = 0;      ///< writes that failed (last_error says why)
  std::uint64_t superseded = 0;  ///< replaced by a newer offer before being written
  std::uint64_t last_sequence = 0;
  std::uint64_t last_bytes = 0;
  double last_write_ms = 0.0;  ///< wall time of the last write (incl. fsyncs)
  std::string last_error;
};

class CheckpointWorker {
 public:
  /// Starts the thread. Throws std::runtime_error when `dir` is unusable (CheckpointWriter).
  CheckpointWorker(std::filesystem::path dir, int keep);
  ~CheckpointWorker();  ///< stop()
  CheckpointWorker(const CheckpointWorker&) = delete;
  CheckpointWorker& operator=(const CheckpointWorker&) = delete;

  /// Hands over a payload (moved from; the filter's buffer comes back empty). Never blocks on
  /// I/O. Returns false after stop().
  bool offer(std::uint32_t payload_version, std::vector<std::uint8_t>&& payload);
  /// Writes the pending payload if any, then stops the thread. Idempotent.
  void stop();
  /// Blocks until every payload offered so far has been written or has failed (tests, and
  /// the shutdown checkpoint before exit).
  void flush();

  CheckpointWorkerStats stats() const;
  const std::filesystem::path& dir() const { return writer_.dir(); }

 private:
  struct Pending {
    std::uint32_t version = 0;
    std::vector<std::uint8_t> payload;
  };
  void run();
  void write(Pending& job);

  CheckpointWriter writer_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable idle_;
  std::optional<Pending> pending_;
  bool writing_ = false;
  bool stopping_ = false;
  CheckpointWorkerStats stats_;
  std::thread thread_;
};

}  // namespace nav::daemon
