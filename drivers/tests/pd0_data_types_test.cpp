// Tests of PD0 ensembles with many data types. The header's count is one byte, so an ensemble
// may carry up to 255 types (WinRiver II appends one navigation type 0x2022 per GPS fix); the
// decoder must decode every such checksum-valid ensemble, locate the types through the offset
// table, check every offset against the ensemble length and skip (and count) the IDs it does
// not decode. Ensembles are built by encode_pd0 with extra raw types.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "nav/drivers/codecs/pd0.h"
#include "pd0_test_support.h"

namespace nav::drivers {
namespace {

using namespace pd0_test;

/// IDs of the WorkHorse manual's PD0 table that the decoder skips (profiles); any other
/// skipped ID counts as unknown.
bool is_profile_id(uint16_t id) { return id >= 0x0100 && id <= 0x0500 && (id & 0xFF) == 0; }

/// `count` extra data types cycling through profiles, WinRiver navigation 0x2022, IDs no
/// manual lists (0xBEEF, 0x7F7F: a false header ID inside the ensemble) and repeats of the
/// decoded leaders; bodies of 0..max_body bytes with a byte pattern that differs per type.
std::vector<Pd0RawDataType> extra_types(std::size_t count, std::size_t max_body) {
  const uint16_t ids[] = {0x0100, 0x0200, 0x0300, 0x0400, 0x0500, 0x2022,
                          0x2022, 0x2101, 0xBEEF, 0x7F7F, 0x0000, 0x0080};
  std::vector<Pd0RawDataType> types(count);
  for (std::size_t k = 0; k < count; ++k) {
    types[k].id = ids[k % std::size(ids)];
    types[k].body.resize(k % (max_body + 1));
    for (std::size_t i = 0; i < types[k].body.size(); ++i) types[k].body[i] = uint8_t(k * 31 + i);
  }
  return types;
}

std::vector<uint16_t> ids_of(const std::vector<Pd0RawDataType>& types) {
  std::vector<uint16_t> ids;
  for (const auto& t : types) ids.push_back(t.id);
  return ids;
}

uint16_t le16_at(const std::vector<uint8_t>& bytes, std::size_t i) {
  return uint16_t(bytes[i] | (bytes[i + 1] << 8));
}

TEST(Pd0DataTypes, EncoderWritesExtraTypesAfterTheDecodedOnesInOrder) {
  const auto extra = extra_types(5, 4);  // bodies of 0, 1, 2, 3, 4 bytes
  const std::vector<uint8_t> bytes = encode_pd0(sample_ensemble(), extra);
  const std::size_t table_end = 6 + 2 * 8;
  const std::size_t n = table_end + 59 + 65 + 85 + (2 + 0) + (2 + 1) + (2 + 2) + (2 + 3) + (2 + 4);
  ASSERT_EQ(bytes.size(), n + 2);
  EXPECT_EQ(le16_at(bytes, 2), n);
  EXPECT_EQ(bytes[5], 8);
  const std::size_t expected_offsets[8] = {
      table_end,           table_end + 59,      table_end + 59 + 65, table_end + 209,
      table_end + 209 + 2, table_end + 209 + 5, table_end + 209 + 9, table_end + 209 + 14};
  const uint16_t expected_ids[8] = {0x0000, 0x0080, 0x0600, 0x0100, 0x0200, 0x0300, 0x0400, 0x0500};
  for (std::size_t k = 0; k < 8; ++k) {
    const std::size_t offset = le16_at(bytes, 6 + 2 * k);
    EXPECT_EQ(offset, expected_offsets[k]) << "type " << k;
    EXPECT_EQ(le16_at(bytes, offset), expected_ids[k]) << "type " << k;
  }
  const std::size_t last = expected_offsets[7];  // ID 0x0500 then the 4 body bytes 4*31 + i
  EXPECT_EQ(bytes[last + 2], uint8_t(124));
  EXPECT_EQ(bytes[last + 5], uint8_t(127));
  uint32_t sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += bytes[i];
  EXPECT_EQ(le16_at(bytes, n), sum & 0xFFFF);
}

TEST(Pd0DataTypes, EncoderRejectsWhatPd0CannotCarry) {
  const Pd0Ensemble with_bt = sample_ensemble();
  EXPECT_NO_THROW(encode_pd0(with_bt, extra_types(252, 0)));  // 255 types
  EXPECT_THROW(encode_pd0(with_bt, extra_types(253, 0)), std::invalid_argument);
  std::vector<Pd0RawDataType> huge(1);
  huge[0].body.resize(65535);  // N past the 16-bit byte count
  EXPECT_THROW(encode_pd0(with_bt, huge), std::invalid_argument);
  Pd0Ensemble no_bt = sample_ensemble();
  no_bt.bottom_track.reset();
  const std::vector<Pd0RawDataType> bt_id = {{0x0600, {1, 2, 3}}};
  EXPECT_THROW(encode_pd0(no_bt, bt_id), std::invalid_argument);
  EXPECT_NO_THROW(encode_pd0(with_bt, bt_id));  // a repeat, skipped after the real one
}

/// Skipped types the decoder must count for `extra`: all of them, and those that are neither a
/// profile nor a (repeated) leader or bottom-track ID.
std::pair<uint64_t, uint64_t> expected_skipped(const std::vector<Pd0RawDataType>& extra) {
  uint64_t unknown = 0;
  for (const auto& t : extra) {
    if (!is_profile_id(t.id) && t.id != 0x0000 && t.id != 0x0080 && t.id != 0x0600) ++unknown;
  }
  return {extra.size(), unknown};
}

TEST(Pd0DataTypes, EnsemblesWith35And68And255TypesAreDecoded) {
  for (const std::size_t types : {35u, 68u, 255u}) {
    SCOPED_TRACE(testing::Message() << types << " data types");
    const auto extra = extra_types(types - 3, 40);
    const std::vector<uint8_t> garbage = {0x7F, 0x7F, 0x01, 0x02, 0x7F};
    std::vector<uint8_t> stream = garbage;
    append(stream, encode_pd0(sample_ensemble(1), extra));
    append(stream, garbage);
    append(stream, encode_pd0(sample_ensemble(2), extra));
    ASSERT_EQ(stream[garbage.size() + 5], uint8_t(types));

    Pd0Decoder decoder;
    const auto out = decode_all(stream, decoder);
    ASSERT_EQ(out.size(), 2u);
    for (uint32_t k = 0; k < 2; ++k) {
      expect_same(out[k], sample_ensemble(k + 1));
      EXPECT_EQ(out[k].skipped_type_ids, ids_of(extra));
    }
    const DecodeStats& s = decoder.stats();
    EXPECT_EQ(s.records, 2u);
    EXPECT_EQ(s.checksum_failures, 0u);
    EXPECT_EQ(s.unsupported, 0u);
    EXPECT_EQ(s.dropped_bytes, 2 * garbage.size());  // the garbage and nothing else
    EXPECT_EQ(decoder.buffered_bytes(), 0u);
    const auto [total, unknown] = expected_skipped(extra);
    EXPECT_EQ(decoder.skipped_types().total, 2 * total);
    EXPECT_EQ(decoder.skipped_types().unknown, 2 * unknown);
    EXPECT_GT(unknown, 0u);
  }
}

TEST(Pd0DataTypes, ManyTypesSplitAtEveryByteGiveIdenticalOutput) {
  std::vector<uint8_t> stream = {0x7F};
  append(stream, encode_pd0(sample_ensemble(1), extra_types(252, 3)));
  append(stream, encode_pd0(sample_ensemble(2), extra_types(65, 8)));
  expect_split_invariant(stream);
  Pd0Decoder decoder;
  EXPECT_EQ(decode_all(stream, decoder).size(), 2u);
  EXPECT_EQ(decoder.stats().dropped_bytes, 1u);
}

/// Sets the k-th offset of an encoded ensemble and repairs the checksum.
void set_offset(std::vector<uint8_t>& bytes, std::size_t k, std::size_t offset) {
  bytes[6 + 2 * k] = uint8_t(offset & 0xFF);
  bytes[7 + 2 * k] = uint8_t(offset >> 8);
  fix_checksum(bytes);
}

TEST(Pd0DataTypes, OffsetsAreStillCheckedAgainstTheEnsembleLength) {
  const std::vector<uint8_t> good = encode_pd0(sample_ensemble(1), extra_types(252, 3));
  const std::size_t n = good.size() - 2;
  struct Case {
    std::size_t type;
    std::size_t offset;
    bool unparsable;  ///< parse_pd0_ensemble rejects it too (it accepts any offset order)
    const char* what;
  };
  const Case cases[] = {
      {254, n - 1, true, "last offset leaves no room for its ID"},
      {200, n + 10, true, "offset past N"},
      {200, le16_at(good, 6 + 2 * 199), true, "offset equal to the previous one"},
      {100, std::size_t(le16_at(good, 6 + 2 * 99) - 1), false, "offset below the previous one"}};
  for (const Case& c : cases) {
    std::vector<uint8_t> bad = good;
    set_offset(bad, c.type, c.offset);
    Pd0Ensemble e;
    int rejected = 0;
    if (c.unparsable) {
      EXPECT_EQ(parse_pd0_ensemble(bad, e, rejected), Pd0ParseError::kMalformed) << c.what;
    }
    std::vector<uint8_t> stream = bad;
    append(stream, encode_pd0(sample_ensemble(2), extra_types(252, 3)));
    Pd0Decoder decoder;
    const auto out = decode_all(stream, decoder);
    ASSERT_EQ(out.size(), 1u) << c.what;
    EXPECT_EQ(out[0].ensemble_number, 2u) << c.what;
    EXPECT_GE(decoder.stats().malformed, 1u) << c.what;
    EXPECT_EQ(decoder.stats().dropped_bytes, bad.size()) << c.what;
  }
  std::vector<uint8_t> no_types = good;  // a count of 0 cannot hold the fixed leader
  no_types[5] = 0;
  fix_checksum(no_types);
  Pd0Decoder decoder;
  EXPECT_TRUE(decode_all(no_types, decoder).empty());
  EXPECT_GE(decoder.stats().malformed, 1u);
  EXPECT_EQ(decoder.stats().dropped_bytes, no_types.size());
}

TEST(Pd0DataTypes, BufferStaysBoundedByTheLargestEnsemble) {
  const std::vector<uint8_t> bytes = encode_pd0(sample_ensemble(7), extra_types(252, 40));
  for (const std::size_t bound : {bytes.size(), bytes.size() - 1}) {
    Pd0DecoderOptions options;
    options.max_ensemble_bytes = bound;
    Pd0Decoder decoder(options);
    std::vector<Pd0Ensemble> out;
    for (uint8_t b : bytes) {
      decoder.feed({&b, 1}, kHost, out);
      ASSERT_LE(decoder.buffered_bytes(), bound);
    }
    // An ensemble larger than the bound is a false header: rejected, not waited for.
    EXPECT_EQ(out.size(), bound == bytes.size() ? 1u : 0u) << "bound " << bound;
    EXPECT_EQ(
        decoder.stats().dropped_bytes + decoder.buffered_bytes() + (out.empty() ? 0 : bytes.size()),
        bytes.size());
  }
}

}  // namespace
}  // namespace nav::drivers
