// Little-endian, length-checked byte encoding (see nav/core/serialization/byte_io.h).
#include "nav/core/serialization/byte_io.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <utility>

namespace nav::core {

void ByteWriter::put(std::uint64_t v, int n) {
  for (int i = 0; i < n; ++i) bytes_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void ByteWriter::bytes(std::span<const std::uint8_t> b) {
  // resize + copy: GCC 12 -O3 misreports vector::insert of a span (-Wstringop-overflow).
  const std::size_t at = bytes_.size();
  bytes_.resize(at + b.size());
  if (!b.empty()) std::memcpy(bytes_.data() + at, b.data(), b.size());
}

void ByteWriter::f64(double v) { put(std::bit_cast<std::uint64_t>(v), 8); }

void ByteWriter::matrix(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  u32(static_cast<std::uint32_t>(m.rows()));
  u32(static_cast<std::uint32_t>(m.cols()));
  values(m);
}

void ByteWriter::values(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  for (Eigen::Index c = 0; c < m.cols(); ++c) {
    for (Eigen::Index r = 0; r < m.rows(); ++r) f64(m(r, c));
  }
}

ByteReader::ByteReader(std::span<const std::uint8_t> bytes, std::string what,
                       std::size_t base_offset)
    : bytes_(bytes), what_(std::move(what)), base_(base_offset) {}

Status ByteReader::error(const std::string& message) const {
  return Status::Error(StatusCode::kInvalidArgument,
                       what_ + ": " + message + " at offset " + std::to_string(offset()));
}

Status ByteReader::need(std::size_t n, const char* field) const {
  if (remaining() >= n) return Status::Ok();
  return error(std::string("truncated reading ") + field + " (needs " + std::to_string(n) +
               " bytes, " + std::to_string(remaining()) + " left)");
}

Status ByteReader::check_count(std::uint64_t count, std::size_t min_item_bytes,
                               const char* field) const {
  if (min_item_bytes == 0 || count <= remaining() / min_item_bytes) return Status::Ok();
  return error(std::string(field) + " " + std::to_string(count) + " cannot fit in the " +
               std::to_string(remaining()) + " bytes left");
}

std::uint64_t ByteReader::get(int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i)
    v |= std::uint64_t{bytes_[pos_ + static_cast<std::size_t>(i)]} << (8 * i);
  pos_ += static_cast<std::size_t>(n);
  return v;
}

Status ByteReader::u8(std::uint8_t* v, const char* field) {
  if (Status s = need(1, field); !s.ok()) return s;
  *v = static_cast<std::uint8_t>(get(1));
  return Status::Ok();
}

Status ByteReader::u32(std::uint32_t* v, const char* field) {
  if (Status s = need(4, field); !s.ok()) return s;
  *v = static_cast<std::uint32_t>(get(4));
  return Status::Ok();
}

Status ByteReader::u64(std::uint64_t* v, const char* field) {
  if (Status s = need(8, field); !s.ok()) return s;
  *v = get(8);
  return Status::Ok();
}

Status ByteReader::i64(std::int64_t* v, const char* field) {
  if (Status s = need(8, field); !s.ok()) return s;
  *v = static_cast<std::int64_t>(get(8));
  return Status::Ok();
}

Status ByteReader::raw(std::span<const std::uint8_t>* out, std::size_t n, const char* field) {
  if (Status s = need(n, field); !s.ok()) return s;
  *out = bytes_.subspan(pos_, n);
  pos_ += n;
  return Status::Ok();
}

Status ByteReader::f64(double* v, const char* field) {
  if (Status s = need(8, field); !s.ok()) return s;
  const std::size_t at = offset();
  const double x = std::bit_cast<double>(get(8));
  if (!std::isfinite(x)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         what_ + ": " + field + " is not finite at offset " + std::to_string(at));
  }
  *v = x;
  return Status::Ok();
}

Status ByteReader::matrix(Eigen::MatrixXd* m, Eigen::Index rows, Eigen::Index cols,
                          bool allow_empty, const char* field) {
  const std::size_t at = offset();
  std::uint32_t r = 0, c = 0;
  if (Status s = u32(&r, field); !s.ok()) return s;
  if (Status s = u32(&c, field); !s.ok()) return s;
  const bool empty = r == 0 && c == 0;
  if (!(r == rows && c == cols) && !(allow_empty && empty)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         what_ + ": " + field + " is " + std::to_string(r) + "x" +
                             std::to_string(c) + ", expected " + std::to_string(rows) + "x" +
                             std::to_string(cols) + (allow_empty ? " or 0x0" : "") + " at offset " +
                             std::to_string(at));
  }
  if (Status s = need(8 * static_cast<std::size_t>(r) * c, field); !s.ok()) return s;
  Eigen::MatrixXd out(r, c);
  if (Status s = values(&out, field); !s.ok()) return s;
  *m = std::move(out);
  return Status::Ok();
}

Status ByteReader::expect_end() const {
  if (remaining() == 0) return Status::Ok();
  return error(std::to_string(remaining()) + " unexpected trailing bytes");
}

}  // namespace nav::core
