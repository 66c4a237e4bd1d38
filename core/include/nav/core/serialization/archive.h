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

namespace archive_detail {
template <class T>
struct IsVector : std::false_type {};
template <class T, class A>
struct IsVector<std::vector<T, A>> : std::true_type {};
template <class T>
struct IsArray : std::false_type {};
template <class T, std::size_t N>
struct IsArray<std::array<T, N>> : std::true_type {};
template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <class T>
concept FixedEigen = std::is_base_of_v<Eigen::MatrixBase<T>, T> &&
                     T::RowsAtCompileTime != Eigen::Dynamic &&
                     T::ColsAtCompileTime != Eigen::Dynamic;
template <class T, class Archive>
concept HasMember = requires(T& t, Archive& ar) { t.serialize(ar); };
template <class T, class Archive>
concept HasFree = requires(T& t, Archive& ar) { serialize(ar, t); };
}  // namespace archive_detail

template <class T>
void WriteArchive::write(T& value) {
  using namespace archive_detail;
  if constexpr (std::is_same_v<T, bool>) {
    w_.u8(value ? 1 : 0);
  } else if constexpr (std::is_integral_v<T> && std::is_signed_v<T>) {
    w_.i64(static_cast<std::int64_t>(value));
  } else if constexpr (std::is_integral_v<T> && sizeof(T) == 1) {
    w_.u8(static_cast<std::uint8_t>(value));
  } else if constexpr (std::is_integral_v<T> && sizeof(T) <= 4) {
    w_.u32(static_cast<std::uint32_t>(value));
  } else if constexpr (std::is_integral_v<T>) {
    w_.u64(static_cast<std::uint64_t>(value));
  } else if constexpr (std::is_same_v<T, double>) {
    w_.f64(value);
  } else if constexpr (FixedEigen<T>) {
    w_.values(value);
  } else if constexpr (std::is_same_v<T, std::string>) {
    w_.u32(static_cast<std::uint32_t>(value.size()));
    w_.bytes(std::span(reinterpret_cast<const std::uint8_t*>(value.data()), value.size()));
  } else if constexpr (IsArray<T>::value) {
    for (auto& item : value) write(item);
  } else if constexpr (IsVector<T>::value) {
    w_.u32(static_cast<std::uint32_t>(value.size()));
    for (auto& item : value) write(item);
  } else if constexpr (IsOptional<T>::value) {
    w_.u8(value ? 1 : 0);
    if (value) write(*value);
  } else if constexpr (HasMember<T, WriteArchive>) {
    value.serialize(*this);
  } else {
    static_assert(HasFree<T, WriteArchive>, "no serialize(Archive&, T&) for this type");
    serialize(*this, value);
  }
}

template <class T>
void ReadArchive::read(T& value, const char* field) {
  using namespace archive_detail;
  if constexpr (std::is_same_v<T, bool>) {
    std::uint8_t b = 0;
    if ((status_ = r_.u8(&b, field)).ok() && check(b <= 1, std::string(field) + " is not 0/1")) {
      value = b == 1;
    }
  } else if constexpr (std::is_integral_v<T> && std::is_signed_v<T>) {
    std::int64_t v = 0;
    if ((status_ = r_.i64(&v, field)).ok() &&
        check(v >= std::numeric_limits<T>::min() && v <= std::numeric_limits<T>::max(),
              std::string(field) + " " + std::to_string(v) + " out of range")) {
      value = static_cast<T>(v);
    }
  } else if constexpr (std::is_integral_v<T> && sizeof(T) == 1) {
    std::uint8_t v = 0;
    if ((status_ = r_.u8(&v, field)).ok()) value = static_cast<T>(v);
  } else if constexpr (std::is_integral_v<T> && sizeof(T) <= 4) {
    std::uint32_t v = 0;
    if ((status_ = r_.u32(&v, field)).ok() &&
        check(v <= std::numeric_limits<T>::max(),
              std::string(field) + " " + std::to_string(v) + " out of range")) {
      value = static_cast<T>(v);
    }
  } else if constexpr (std::is_integral_v<T>) {
    std::uint64_t v = 0;
    if ((status_ = r_.u64(&v, field)).ok() &&
        check(v <= std::numeric_limits<T>::max(),
              std::string(field) + " " + std::to_string(v) + " out of range")) {
      value = static_cast<T>(v);
    }
  } else if constexpr (std::is_same_v<T, double>) {
    status_ = r_.f64(&value, field);
  } else if constexpr (FixedEigen<T>) {
    status_ = r_.values(&value, field);
  } else if constexpr (std::is_same_v<T, std::string>) {
    std::uint32_t n = 0;
    std::span<const std::uint8_t> text;
    if ((status_ = r_.u32(&n, field)).ok() && (status_ = r_.raw(&text, n, field)).ok()) {
      value.assign(text.begin(), text.end());
    }
  } else if constexpr (IsArray<T>::value) {
    for (auto& item : value) read(item, field);
  } else if constexpr (IsVector<T>::value) {
    std::uint32_t n = 0;
    if (!(status_ = r_.u32(&n, field)).ok()) return;
    value.clear();
    for (std::uint32_t k = 0; k < n && status_.ok(); ++k) read(value.emplace_back(), field);
  } else if constexpr (IsOptional<T>::value) {
    bool present = false;
    read(present, field);
    if (!status_.ok()) return;
    value.reset();
    if (present) read(value.emplace(), field);
  } else if constexpr (HasMember<T, ReadArchive>) {
    value.serialize(*this);
  } else {
    static_assert(HasFree<T, ReadArchive>, "no serialize(Archive&, T&) for this type");
    serialize(*this, value);
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
