#pragma once
// One pseudo-terminal standing in for a sensor's serial port (hardware-in-the-loop playback,
// hil-tests/README.md "Playing a dive back"): the player writes the sensor's recorded bytes into
// the master side; navd opens the slave through a stable symlink (like socat's
// `pty,raw,echo=0,link=PATH`), so a config can name the link before the pty exists.
//
// The player keeps no slave descriptor open, so it can tell whether a reader is attached
// (Linux reports POLLHUP on the master while no process has the slave open; socat's
// `wait-slave` relies on the same). A pty resets its termios when the last slave descriptor
// closes, so the reader must put the line in raw mode itself (navd's serial driver does).
// Writes never block: bytes the reader has no room for are dropped and counted.
//
// Threads: one thread uses a PtyLink at a time.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace nav::hil {

class PtyLink {
 public:
  /// Opens a pty pair (openpty), puts it in raw mode and points `link_path` at the slave
  /// (replacing an existing symlink there). Throws std::runtime_error naming the path and
  /// the failed call.
  explicit PtyLink(std::filesystem::path link_path);
  ~PtyLink();
  PtyLink(const PtyLink&) = delete;
  PtyLink& operator=(const PtyLink&) = delete;

  const std::filesystem::path& link_path() const { return link_path_; }
  const std::string& slave_path() const { return slave_path_; }

  /// Whether a process has the slave side open now.
  bool reader_attached() const;

  /// Writes `bytes` without blocking; returns how many were written (fewer when the reader is
  /// gone or has not read the pty's buffer).
  std::size_t write(std::span<const std::uint8_t> bytes);

 private:
  std::filesystem::path link_path_;
  std::string slave_path_;
  int master_ = -1;
};

}  // namespace nav::hil
