#pragma once
// Two-way archives: each checkpointed type has ONE function that serves writing and reading,
// in the manner of GTSAM's serialize(Archive&) (boost::serialization):
//   template <class Archive> void serialize(Archive& ar, T& value) { ar(value.a, "a"); ... }
// WriteArchive appends the fields with ByteWriter; ReadArchive reads them back with ByteReader
// into the same fields, in the same order, so writer and reader cannot disagree.
//
// Encoding (little-endian, byte_io.h): bool as one byte 0/1; signed integers as i64; unsigned
// ones by width: 1 byte as u8, up to 4 bytes as u32, wider as u64 (range-checked against the
// field's type on reading); double as its
// IEEE-754 bit pattern (finite on reading); fixed-size Eigen matrices as their values
// column-major; std::array as its elements; std::vector as a u32 count then the elements (read one by one, so a corrupt
// count runs out of bytes instead of allocating); std::optional as a presence byte then the
// value; std::string as a u32 length then the bytes. A type T with a member
// `template <class A> void serialize(A&)` or a free `serialize(A&, T&)` nests.
//
// Reading errors are sticky: the first one (named field, offset in the payload) is kept in
// status() and every later read is skipped; ar.check(condition, message) adds a semantic check
// (an index out of range) to the reader and is a no-op on the writer.

#include <Eigen/Core>
#include <array>
#include <concepts>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "nav/core/serialization/byte_io.h"
#include "nav/core/status.h"

namespace nav::core {

class WriteArchive {
 public:
  static constexpr bool kReading = false;

  template <class T>
  void operator()(T& value, const char* /*field*/) {
    write(value);
  }
  /// A dynamic matrix with its shape (rows, cols as u32, then values).
  void matrix(Eigen::MatrixXd& m, Eigen::Index, Eigen::Index, bool, const char*) {
    w_.matrix(m);
  }
  /// The values of an already-sized dynamic matrix or vector (no shape).
  template <class M>
  void values(M& m, const char*) {
    w_.values(m);
  }
  /// Reader only: `count` items of at least min_item_bytes each must still fit.
  bool check_count(std::uint64_t, std::size_t, const char*) { return true; }
  /// Opaque bytes (their length is a field written before them).
  void raw(std::span<const std::uint8_t>& bytes, std::size_t, const char*) { w_.bytes(bytes); }
  /// Bytes written so far.
  std::size_t offset() const { return w_.data().size(); }
  const std::vector<std::uint8_t>& data() const { return w_.data(); }
  bool check(bool, const std::string&) { return true; }
  bool ok() const { return true; }
  Status status() const { return Status::Ok(); }
  std::vector<std::uint8_t> take() { return w_.take(); }

 private:
  template <class T>
  void write(T& value);
  ByteWriter w_;
};

class ReadArchive {
 public:
  static constexpr bool kReading = true;

  ReadArchive(std::span<const std::uint8_t> bytes, std::string what, std::size_t base_offset = 0)
      : r_(bytes, std::move(what), base_offset) {}

  template <class T>
  void operator()(T& value, const char* field) {
    if (status_.ok()) read(value, field);
  }
  /// A dynamic matrix of shape rows x cols (or 0 x 0 when allow_empty).
  void matrix(Eigen::MatrixXd& m, Eigen::Index rows, Eigen::Index cols, bool allow_empty,
              const char* field) {
    if (status_.ok()) status_ = r_.matrix(&m, rows, cols, allow_empty, field);
  }
  /// The values of an already-sized dynamic matrix or vector (no shape); entries finite.
  template <class M>
  void values(M& m, const char* field) {
    if (status_.ok()) status_ = r_.values(&m, field);
  }
  /// `count` items of at least min_item_bytes each must still fit (before allocating them).
  bool check_count(std::uint64_t count, std::size_t min_item_bytes, const char* field) {
    if (status_.ok()) status_ = r_.check_count(count, min_item_bytes, field);
    return status_.ok();
  }
  /// The next n bytes as a view into the input (no copy).
  void raw(std::span<const std::uint8_t>& bytes, std::size_t n, const char* field) {
    if (status_.ok()) status_ = r_.raw(&bytes, n, field);
  }
  /// Position in the whole payload (base_offset + bytes consumed).
  std::size_t offset() const { return r_.offset(); }
  std::size_t remaining() const { return r_.remaining(); }
  /// Records `message` as the error (at the current offset) unless `condition`.
  bool check(bool condition, const std::string& message) {
    if (status_.ok() && !condition) status_ = r_.error(message);
    return status_.ok() && condition;
  }
  bool ok() const { return status_.ok(); }
  /// The first error, or an error if bytes are left over; Ok when everything was consumed.
  Status finish() const { return status_.ok() ? r_.expect_end() : status_; }
  Status status() const { return status_; }

 private:
  template <class T>
  void read(T& value, const char* field);
  ByteReader r_;
  Status status_ = Status::Ok();
};

/// A std::size_t stored as u64 on every platform (its width differs between 32- and 64-bit
/// targets; the layouts must not), range-checked on reading.
template <class Archive>
void serialize_size(Archive& ar, std::size_t& value, const char* field) {
  auto wide = static_cast<std::uint64_t>(value);
  ar(wide, field);
  if (ar.check(wide <= std::numeric_limits<std::size_t>::max(),
               std::string(field) + " " + std::to_string(wide) + " out of range")) {
    value = static_cast<std::size_t>(wide);
  }
}

/// The bytes of `value` (its serialize function on a WriteArchive).
template <class T>
std::vector<std::uint8_t> to_bytes(const T& value) {
  WriteArchive ar;
  ar(const_cast<T&>(value), "value");  // writing only reads the fields
  return ar.take();
}

}  // namespace nav::core

#include "nav/core/serialization/archive_impl.h"  // IWYU pragma: export
