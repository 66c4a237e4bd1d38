#pragma once
// Map checkpoints: an opaque payload (the serialised filter state) written atomically and
// checksummed, so that a dive resumes from the newest intact checkpoint after a crash or power
// loss, and a corrupt or truncated file is reported and the previous one used.
//
// File `checkpoint-<sequence, 20 digits>.ckpt`, little-endian:
//   offset  0  magic "NAVDCKPT" (8 bytes)
//           8  u32 format version (kCheckpointFormatVersion)
//          12  u32 payload version (the caller's schema version of the blob)
//          16  u64 sequence (equals the one in the file name)
//          24  u64 payload length in bytes
//          32  u32 CRC-32 of the payload
//          36  u32 CRC-32 of bytes 0..35 (the header)
//          40  payload
// Atomic write (POSIX rename semantics): write `.checkpoint-<seq>.ckpt.tmp` in the same
// directory, fsync it, rename onto the final name, fsync the directory. A crash leaves either
// the old set of checkpoints or the new one plus, at worst, a temp file that loading ignores and
// the next CheckpointWriter removes.
//
// Threads: one writer per directory (the checkpoint thread); loading is read-only.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace nav::daemon {

inline constexpr std::uint32_t kCheckpointFormatVersion = 1;
inline constexpr std::size_t kCheckpointHeaderBytes = 40;

/// The bytes of a checkpoint file (header + payload).
std::vector<std::uint8_t> encode_checkpoint(std::uint32_t payload_version, std::uint64_t sequence,
                                            std::span<const std::uint8_t> payload);

struct Checkpoint {
  std::filesystem::path path;
  std::uint64_t sequence = 0;
  std::uint32_t payload_version = 0;
  std::vector<std::uint8_t> payload;
};

/// Checks magic, format version, header CRC, length and payload CRC of file bytes. Returns the
/// checkpoint, or nullopt with `reason` set ("truncated: 57 of 72 bytes", "payload CRC-32
/// mismatch", ...).
std::optional<Checkpoint> decode_checkpoint(std::span<const std::uint8_t> bytes,
                                            std::string* reason);

struct SkippedCheckpoint {
  std::filesystem::path path;
  std::string reason;
};

struct LoadResult {
  std::optional<Checkpoint> checkpoint;    ///< newest valid one, if any
  std::vector<SkippedCheckpoint> skipped;  ///< newer files that failed verification, newest first
};

/// Newest checkpoint in `dir` (by sequence) whose header, length and checksums verify; every
/// newer corrupt or truncated one is listed in `skipped`. Temp files and other names are ignored.
/// A missing or empty directory gives an empty result.
LoadResult load_newest_valid(const std::filesystem::path& dir);

/// Says whether a verified checkpoint's payload can be resumed: "" to take it, else the reason
/// (e.g. the payload's own decode error); the loader then skips it like a corrupt file.
using CheckpointAcceptor = std::function<std::string(const Checkpoint&)>;
/// Same, also skipping verified checkpoints that `accept` refuses (the reason is recorded).
LoadResult load_newest_valid(const std::filesystem::path& dir, const CheckpointAcceptor& accept);

/// Sequence numbers of the checkpoint files in `dir` (by name), ascending.
std::vector<std::uint64_t> list_checkpoints(const std::filesystem::path& dir);
std::filesystem::path checkpoint_path(const std::filesystem::path& dir, std::uint64_t sequence);

struct WriteResult {
  bool ok = false;
  std::filesystem::path path;  ///< the final file when ok
  std::uint64_t sequence = 0;
  std::string error;  ///< what failed and where ("fsync /x/.checkpoint-...: EIO")
};

class CheckpointWriter {
 public:
  /// `keep` >= 1 newest checkpoints are kept. Creates `dir` if needed and removes temp files
  /// left by an interrupted write. Throws std::runtime_error when the directory is unusable.
  CheckpointWriter(std::filesystem::path dir, int keep);

  /// Writes the next checkpoint (sequence = newest on disk + 1) atomically, then deletes all but
  /// the newest `keep`. Errors are returned, not thrown.
  WriteResult write(std::uint32_t payload_version, std::span<const std::uint8_t> payload);

  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  int keep_;
};

}  // namespace nav::daemon
