#pragma once
// Little-endian byte encoding for map checkpoints (no file I/O: bytes in memory only).
//
// ByteWriter appends fixed-width little-endian integers and IEEE-754 doubles (bit patterns, so
// a round trip is bit-identical, NaN payloads and signed zeros included). ByteReader reads them
// back with a length check before every read: running past the end is a Status naming the
// field, its offset in the whole payload and how many bytes were missing, never a read out of
// bounds. Offsets are reported relative to `base_offset`, the reader's position in the payload
// it was cut from (a section's start in the container), so errors point into the file.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "nav/core/status.h"

namespace nav::core {

class ByteWriter {
 public:
  void u8(std::uint8_t v) { bytes_.push_back(v); }
  void u32(std::uint32_t v) { put(v, 4); }
  void u64(std::uint64_t v) { put(v, 8); }
  void i64(std::int64_t v) { put(static_cast<std::uint64_t>(v), 8); }
  void f64(double v);
  /// rows, cols as u32, then the entries column-major.
  void matrix(const Eigen::Ref<const Eigen::MatrixXd>& m);
  /// Entries only, column-major (the caller writes/knows the shape).
  void values(const Eigen::Ref<const Eigen::MatrixXd>& m);
  void bytes(std::span<const std::uint8_t> b);

  const std::vector<std::uint8_t>& data() const { return bytes_; }
  std::vector<std::uint8_t> take() { return std::move(bytes_); }

 private:
  void put(std::uint64_t v, int n);
  std::vector<std::uint8_t> bytes_;
};

class ByteReader {
 public:
  /// `what` names the payload in errors ("ESDF section"); base_offset as in the file comment.
  ByteReader(std::span<const std::uint8_t> bytes, std::string what, std::size_t base_offset = 0);

  Status u8(std::uint8_t* v, const char* field);
  Status u32(std::uint32_t* v, const char* field);
  Status u64(std::uint64_t* v, const char* field);
  Status i64(std::int64_t* v, const char* field);
  /// The next n bytes as a view into the input (no copy).
  Status raw(std::span<const std::uint8_t>* out, std::size_t n, const char* field);
  /// Also rejects NaN/Inf (every double in a map is finite).
  Status f64(double* v, const char* field);
  /// A matrix written by ByteWriter::matrix whose shape must be rows x cols, or 0 x 0 when
  /// allow_empty. Entries must be finite.
  Status matrix(Eigen::MatrixXd* m, Eigen::Index rows, Eigen::Index cols, bool allow_empty,
                const char* field);
  /// rows x cols finite values written by ByteWriter::values into *m (already sized).
  template <class M>
  Status values(M* m, const char* field);

  /// Checks that `count` items of at least `min_item_bytes` each can still follow, before the
  /// caller allocates for them (a corrupt count must not make us reserve gigabytes).
  Status check_count(std::uint64_t count, std::size_t min_item_bytes, const char* field) const;

  std::size_t remaining() const { return bytes_.size() - pos_; }
  /// Position in the whole payload (base_offset + bytes consumed).
  std::size_t offset() const { return base_ + pos_; }
  /// kInvalidArgument unless every byte was consumed.
  Status expect_end() const;
  /// An error at the current offset: "<what>: <message> at offset <n>".
  Status error(const std::string& message) const;

 private:
  Status need(std::size_t n, const char* field) const;
  std::uint64_t get(int n);

  std::span<const std::uint8_t> bytes_;
  std::string what_;
  std::size_t base_;
  std::size_t pos_ = 0;
};

template <class M>
Status ByteReader::values(M* m, const char* field) {
  const std::size_t n = static_cast<std::size_t>(m->size());
  if (Status s = need(8 * n, field); !s.ok()) return s;
  for (Eigen::Index c = 0; c < m->cols(); ++c) {
    for (Eigen::Index r = 0; r < m->rows(); ++r) {
      if (Status s = f64(&(*m)(r, c), field); !s.ok()) return s;
    }
  }
  return Status::Ok();
}

}  // namespace nav::core
