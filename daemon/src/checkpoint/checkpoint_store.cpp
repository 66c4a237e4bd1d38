// Checkpoint files on disk: atomic write (temp, fsync, rename, fsync dir), rotation, loading the
// newest valid one. See nav/daemon/checkpoint/checkpoint.h.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "nav/daemon/checkpoint/checkpoint.h"

namespace nav::daemon {
namespace fs = std::filesystem;
namespace {

constexpr std::string_view kPrefix = "checkpoint-";
constexpr std::string_view kSuffix = ".ckpt";
constexpr std::string_view kTempPrefix = ".checkpoint-";
constexpr std::string_view kTempSuffix = ".ckpt.tmp";

/// Sequence of a final checkpoint file name, nullopt for any other name.
std::optional<std::uint64_t> parse_name(const std::string& name) {
  if (name.size() != kPrefix.size() + 20 + kSuffix.size()) return std::nullopt;
  if (name.rfind(kPrefix, 0) != 0 || !name.ends_with(kSuffix)) return std::nullopt;
  std::uint64_t value = 0;
  for (std::size_t i = kPrefix.size(); i < kPrefix.size() + 20; ++i) {
    if (name[i] < '0' || name[i] > '9') return std::nullopt;
    value = value * 10 + static_cast<std::uint64_t>(name[i] - '0');
  }
  return value;
}

std::string errno_text(const std::string& what, const fs::path& path) {
  return what + " " + path.string() + ": " + std::strerror(errno);
}

/// Writes all bytes to a new file and fsyncs it; returns "" or the error.
std::string write_synced(const fs::path& path, std::span<const std::uint8_t> bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
  if (fd < 0) return errno_text("open", path);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const std::string error = errno_text("write", path);
      ::close(fd);
      return error;
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    const std::string error = errno_text("fsync", path);
    ::close(fd);
    return error;
  }
  if (::close(fd) != 0) return errno_text("close", path);
  return "";
}

std::string fsync_dir(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return errno_text("open directory", dir);
  const int rc = ::fsync(fd);
  const std::string error = rc != 0 ? errno_text("fsync directory", dir) : "";
  ::close(fd);
  return error;
}

std::vector<std::uint8_t> read_file(const fs::path& path, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot open";
    return {};
  }
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

fs::path checkpoint_path(const fs::path& dir, std::uint64_t sequence) {
  char digits[21];
  std::snprintf(digits, sizeof(digits), "%020llu", static_cast<unsigned long long>(sequence));
  return dir / (std::string(kPrefix) + digits + std::string(kSuffix));
}

std::vector<std::uint64_t> list_checkpoints(const fs::path& dir) {
  std::vector<std::uint64_t> out;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (const auto seq = parse_name(entry.path().filename().string())) out.push_back(*seq);
  }
  std::sort(out.begin(), out.end());
  return out;
}

LoadResult load_newest_valid(const fs::path& dir) { return load_newest_valid(dir, nullptr); }

LoadResult load_newest_valid(const fs::path& dir, const CheckpointAcceptor& accept) {
  LoadResult result;
  const std::vector<std::uint64_t> sequences = list_checkpoints(dir);
  for (auto it = sequences.rbegin(); it != sequences.rend(); ++it) {
    const fs::path path = checkpoint_path(dir, *it);
    std::string reason;
    const std::vector<std::uint8_t> bytes = read_file(path, &reason);
    std::optional<Checkpoint> checkpoint;
    if (reason.empty()) checkpoint = decode_checkpoint(bytes, &reason);
    if (checkpoint && checkpoint->sequence != *it) {
      reason = "sequence " + std::to_string(checkpoint->sequence) + " does not match the name";
      checkpoint.reset();
    }
    if (checkpoint) checkpoint->path = path;
    if (checkpoint && accept) {
      reason = accept(*checkpoint);
      if (!reason.empty()) checkpoint.reset();
    }
    if (checkpoint) {
      result.checkpoint = std::move(checkpoint);
      return result;
    }
    result.skipped.push_back({path, reason});
  }
  return result;
}

CheckpointWriter::CheckpointWriter(fs::path dir, int keep) : dir_(std::move(dir)), keep_(keep) {
  if (keep_ < 1) throw std::invalid_argument("CheckpointWriter: keep must be >= 1");
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_)) {
    throw std::runtime_error("checkpoint directory " + dir_.string() + ": " +
                             (ec ? ec.message() : "not a directory"));
  }
  for (const fs::directory_entry& entry : fs::directory_iterator(dir_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kTempPrefix, 0) == 0 && name.ends_with(kTempSuffix))
      fs::remove(entry.path(), ec);
  }
}

WriteResult CheckpointWriter::write(std::uint32_t payload_version,
                                    std::span<const std::uint8_t> payload) {
  WriteResult result;
  const std::vector<std::uint64_t> existing = list_checkpoints(dir_);
  result.sequence = existing.empty() ? 1 : existing.back() + 1;
  const fs::path final_path = checkpoint_path(dir_, result.sequence);
  const fs::path temp_path =
      dir_ / (std::string(kTempPrefix) + final_path.filename().string().substr(kPrefix.size(), 20) +
              std::string(kTempSuffix));
  result.error =
      write_synced(temp_path, encode_checkpoint(payload_version, result.sequence, payload));
  if (result.error.empty() && std::rename(temp_path.c_str(), final_path.c_str()) != 0) {
    result.error = errno_text("rename to " + final_path.string() + " from", temp_path);
  }
  if (!result.error.empty()) {
    std::error_code ec;
    fs::remove(temp_path, ec);
    return result;
  }
  result.error = fsync_dir(dir_);
  result.ok = result.error.empty();
  result.path = final_path;
  // Rotation: the newest `keep` stay (the one just written, fsynced, is the newest).
  std::vector<std::uint64_t> all = list_checkpoints(dir_);
  for (std::size_t i = 0; i + static_cast<std::size_t>(keep_) < all.size(); ++i) {
    std::error_code ec;
    fs::remove(checkpoint_path(dir_, all[i]), ec);
  }
  return result;
}

}  // namespace nav::daemon
