#pragma once
// Field encodings of WriteArchive and ReadArchive (the rules are stated in archive.h, which
// includes this file; do not include it directly).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "nav/core/serialization/archive.h"

namespace nav::core {

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

}  // namespace nav::core
