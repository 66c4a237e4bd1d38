// Two-way archives (serialization/archive.h): one serialize function per type writes and reads
// the same fields; every kind of field round-trips bit-identically, every truncation and every
// out-of-range or malformed value is refused naming the field, and a corrupt count cannot make
// the reader allocate beyond the bytes present. The measurement variant and the filter's
// records (navigation/nav_filter_serialization.h) round-trip alternative by alternative.
#include "nav/core/serialization/archive.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/navigation/nav_filter_serialization.h"

namespace nav::core {
namespace {

using Bytes = std::vector<std::uint8_t>;

struct Inner {
  std::optional<double> maybe;
  std::string text;
  template <class Archive>
  void serialize(Archive& ar) {
    ar(maybe, "maybe");
    ar(text, "text");
  }
};

struct Everything {
  bool flag = false;
  int small = 0;
  std::int64_t wide = 0;
  std::uint16_t narrow = 0;
  std::uint64_t big = 0;
  double value = 0.0;
  Eigen::Matrix<double, 2, 3> block = Eigen::Matrix<double, 2, 3>::Zero();
  std::array<bool, 3> axes{};
  std::vector<Inner> items;
};

template <class Archive>
void serialize(Archive& ar, Everything& e) {
  ar(e.flag, "flag");
  ar(e.small, "small");
  ar(e.wide, "wide");
  ar(e.narrow, "narrow");
  ar(e.big, "big");
  ar(e.value, "value");
  ar(e.block, "block");
  ar(e.axes, "axes");
  ar(e.items, "items");
}

Everything sample() {
  Everything e;
  e.flag = true;
  e.small = -7;
  e.wide = std::numeric_limits<std::int64_t>::min();
  e.narrow = 65535;
  e.big = std::numeric_limits<std::uint64_t>::max();
  e.value = -0.0;
  e.block << 1.0, -2.5, 1e-300, std::nextafter(1.0, 2.0), 3.0, -4.0;
  e.axes = {true, false, true};
  e.items = {Inner{std::nullopt, ""}, Inner{0.1, "two words"}};
  return e;
}

Status read(const Bytes& bytes, Everything* out) {
  ReadArchive ar(bytes, "test payload", 100);
  ar(*out, "everything");
  return ar.finish();
}

TEST(Archive, EveryFieldKindRoundTripsBitIdentically) {
  const Everything e = sample();
  const Bytes bytes = to_bytes(e);
  // bool 1 + int 8 + i64 8 + u16 4 + u64 8 + f64 8 + 6 f64 + 3 bools + count 4 + items.
  const std::size_t items = (1 + 4) + (1 + 8 + 4 + 9);
  EXPECT_EQ(bytes.size(), 1 + 8 + 8 + 4 + 8 + 8 + 48 + 3 + 4 + items);
  Everything back;
  ASSERT_TRUE(read(bytes, &back).ok());
  EXPECT_EQ(to_bytes(back), bytes);
  EXPECT_TRUE(std::signbit(back.value));
  EXPECT_EQ(back.block, e.block);
  EXPECT_EQ(back.items[1].text, "two words");
  EXPECT_FALSE(back.items[0].maybe.has_value());
  EXPECT_EQ(back.narrow, 65535);
}

TEST(Archive, EveryTruncationAndTrailingByteIsRefused) {
  const Bytes bytes = to_bytes(sample());
  for (std::size_t len = 0; len < bytes.size(); ++len) {
    Everything back;
    const Status s = read(Bytes(bytes.begin(), bytes.begin() + static_cast<long>(len)), &back);
    ASSERT_FALSE(s.ok()) << "truncated to " << len;
    EXPECT_NE(s.message().find("test payload"), std::string::npos) << s.message();
  }
  Bytes longer = bytes;
  longer.push_back(0);
  Everything back;
  EXPECT_NE(read(longer, &back).message().find("trailing"), std::string::npos);
}

TEST(Archive, OutOfRangeAndMalformedValuesNameTheField) {
  Bytes bytes = to_bytes(sample());
  Everything back;
  Bytes bad = bytes;
  bad[0] = 2;  // flag
  Status s = read(bad, &back);
  EXPECT_NE(s.message().find("flag is not 0/1 at offset 101"), std::string::npos) << s.message();
  bad = bytes;
  bad[1 + 8 + 8 + 2] = 1;  // narrow = 65535 + 65536
  s = read(bad, &back);
  EXPECT_NE(s.message().find("narrow 131071 out of range"), std::string::npos) << s.message();
  bad = bytes;
  bad[1 + 4] = 0x01;  // small: bit 32 of a sign-extended -7, no longer an int
  s = read(bad, &back);
  EXPECT_NE(s.message().find("small"), std::string::npos) << s.message();
  // A count of 2^32 - 1 items runs out of bytes instead of allocating for them.
  bad = bytes;
  const std::size_t count_at = 1 + 8 + 8 + 4 + 8 + 8 + 48 + 3;
  for (std::size_t k = 0; k < 4; ++k) bad[count_at + k] = 0xFF;
  s = read(bad, &back);
  EXPECT_FALSE(s.ok());
  EXPECT_LE(back.items.size(), bytes.size());
}

TEST(Archive, CheckRecordsTheFirstErrorAndWriterIgnoresIt) {
  const Bytes bytes = to_bytes(sample());
  ReadArchive ar(bytes, "test payload");
  Everything back;
  ar(back, "everything");
  EXPECT_FALSE(ar.check(false, "semantic check failed"));
  EXPECT_FALSE(ar.check(false, "second"));
  EXPECT_NE(ar.finish().message().find("semantic check failed"), std::string::npos);
  WriteArchive w;
  EXPECT_TRUE(w.check(false, "ignored"));
}

template <class T>
Bytes round_trip(const T& value) {
  const Bytes bytes = to_bytes(value);
  T back{};
  ReadArchive ar(bytes, "record");
  ar(back, "record");
  EXPECT_TRUE(ar.finish().ok()) << ar.finish().message();
  return to_bytes(back);
}

TEST(Archive, EveryMeasurementKindRoundTrips) {
  const MeasurementTime t{123, -4, 5'000'000'000'000, 7};
  Attitude att{t, 0.1, -0.2, 3.1, false, true};
  AngularRate rate{t, {0.1, 0.2, 0.3}, {false, false, true}};
  const std::vector<Measurement> all = {DvlVelocity{t, {1.0, -2.0, 0.5}}, att, rate,
                                        Depth{t, 3800.25}, Altitude{t, 2.5}, ImageEvent{t, 42}};
  ASSERT_EQ(all.size(), std::variant_size_v<Measurement>);
  for (const Measurement& m : all) {
    const Bytes bytes = to_bytes(m);
    EXPECT_EQ(round_trip(m), bytes) << "kind " << m.index();
    Measurement back;
    ReadArchive ar(bytes, "m");
    ar(back, "m");
    ASSERT_TRUE(ar.finish().ok());
    EXPECT_EQ(back.index(), m.index());
    EXPECT_EQ(time_of(back).host_realtime_us, 5'000'000'000'000);
  }
  Bytes unknown = to_bytes(all[0]);
  unknown[0] = 9;
  Measurement back;
  ReadArchive ar(unknown, "m");
  ar(back, "m");
  EXPECT_NE(ar.finish().message().find("measurement kind 9 unknown"), std::string::npos);
}

TEST(Archive, FilterRecordsRoundTrip) {
  LinkRecord link;
  link.t_us = 99;
  link.frame_i = 3;
  link.frame_j = 8;
  link.state_i = 2;
  link.outcome = LinkOutcome::kGated;
  link.z << 0.1, 0.2, 0.3, 0.4, 0.5;
  EXPECT_EQ(round_trip(link), to_bytes(link));
  ImageRecord image;
  image.robot_mean.setLinSpaced(12, -1.0, 1.0);
  image.initial_bound.setIdentity();
  EXPECT_EQ(round_trip(image), to_bytes(image));
  NavFilterCounters counters;
  counters.links_gated = 17;
  counters.max_cg_relative_residual = 0.25;
  EXPECT_EQ(round_trip(counters), to_bytes(counters));
  Bytes bad = to_bytes(link);
  bad[8 * 5] = 4;  // the outcome byte after t_us, frame_i, frame_j, state_i, state_j
  LinkRecord back;
  ReadArchive ar(bad, "link");
  ar(back, "link");
  EXPECT_NE(ar.finish().message().find("link outcome 4 unknown"), std::string::npos)
      << ar.finish().message();
}

}  // namespace
}  // namespace nav::core
