// candump text logs: log (-l/-L) and ASCII (with -t a/d/A time stamps) lines, remote, extended,
// FD/error frames counted as unsupported, garbage counted, streams split at every byte.

#include "nav/drivers/codecs/candump_log.h"

#include <gtest/gtest.h>

#include <random>
#include <string>

namespace nav::drivers {
namespace {

std::vector<CanLogFrame> decode_all(const std::string& text, CandumpLogDecoder& d,
                                    size_t chunk = 4096) {
  std::vector<CanLogFrame> out;
  const auto* p = reinterpret_cast<const uint8_t*>(text.data());
  for (size_t i = 0; i < text.size(); i += chunk) {
    d.feed({p + i, std::min(chunk, text.size() - i)}, HostTime{7, 8}, out);
  }
  d.finish(HostTime{7, 8}, out);
  return out;
}

CanLogFrame parse_ok(const std::string& line) {
  CanLogFrame f;
  bool has_time = false;
  EXPECT_EQ(parse_candump_line(line, f, has_time), CandumpLineResult::kFrame) << line;
  return f;
}

CandumpLineResult result_of(const std::string& line) {
  CanLogFrame f;
  bool has_time = false;
  return parse_candump_line(line, f, has_time);
}

TEST(CandumpLog, LogFormatStandardExtendedRemote) {
  CanLogFrame f = parse_ok("(1699999999.123456) can0 123#DEADBEEF");
  EXPECT_EQ(f.id, 0x123u);
  EXPECT_FALSE(f.extended);
  EXPECT_EQ(f.dlc, 4);
  EXPECT_EQ(f.data[0], 0xDE);
  EXPECT_EQ(f.data[3], 0xEF);
  EXPECT_EQ(f.time.realtime_us, 1'699'999'999'123'456);
  EXPECT_STREQ(f.interface_name.data(), "can0");

  f = parse_ok("(1.5) vcan1 18FF1001#0011223344556677");
  EXPECT_EQ(f.id, 0x18FF1001u);
  EXPECT_TRUE(f.extended);
  EXPECT_EQ(f.dlc, 8);
  EXPECT_EQ(f.data[7], 0x77);
  EXPECT_EQ(f.time.realtime_us, 1'500'000);

  f = parse_ok("(0.000001) can0 7FF#R");
  EXPECT_TRUE(f.remote);
  EXPECT_EQ(f.payload().size(), 0u);
  EXPECT_EQ(parse_ok("(0.000001) can0 7FF#R3").dlc, 3);
  EXPECT_EQ(parse_ok("(0.1) can0 001#").dlc, 0);
  EXPECT_EQ(parse_ok("(0.1) can0 001#11.22.33").dlc, 3);            // cansend's dotted form
  EXPECT_EQ(parse_ok("(0.1) can0 001#1122334455667788_C").dlc, 8);  // len8_dlc suffix
}

TEST(CandumpLog, AsciiFormatsWithAndWithoutTimestamps) {
  CanLogFrame f = parse_ok("  can0  123   [4]  DE AD BE EF");
  EXPECT_EQ(f.id, 0x123u);
  EXPECT_EQ(f.dlc, 4);
  EXPECT_EQ(f.data[1], 0xAD);
  f = parse_ok(" (1699999999.123456)  can0  18FF1001   [2]  01 02");
  EXPECT_TRUE(f.extended);
  EXPECT_EQ(f.time.realtime_us, 1'699'999'999'123'456);
  f = parse_ok(" (000.000123)  can0  123   [0] ");
  EXPECT_EQ(f.time.realtime_us, 123);
  f = parse_ok(" (2023-11-14 22:13:20.500000)  can0  123   [1]  FF");
  EXPECT_EQ(f.time.realtime_us, 1'700'000'000'500'000);  // 2023-11-14T22:13:20Z
  f = parse_ok("  can0  123   [3]  remote request");
  EXPECT_TRUE(f.remote);
  EXPECT_EQ(f.dlc, 3);
  parse_ok("  can0  123   [2]  41 42   'AB'");  // candump -a
}

TEST(CandumpLog, UnsupportedAndMalformedLines) {
  EXPECT_EQ(result_of("(0.1) can0 123##1DEADBEEF"), CandumpLineResult::kUnsupported);  // FD
  EXPECT_EQ(result_of("(0.1) can0 20000004#0000000000000000"),
            CandumpLineResult::kUnsupported);  // error frame
  EXPECT_EQ(result_of("  can0  123  [08]  01 02 03 04 05 06 07 08"),
            CandumpLineResult::kUnsupported);  // FD in ASCII
  EXPECT_EQ(result_of(""), CandumpLineResult::kBlank);
  EXPECT_EQ(result_of("   \r"), CandumpLineResult::kBlank);
  for (const char* bad :
       {"(0.1) can0 800#00", "(0.1) can0 1234#00", "(0.1) can0 123#0", "(0.1) can0 123#0G",
        "(0.1) can0 123#001122334455667788", "(0.1 can0 123#00", "(x.1) can0 123#00", "(0.1) can0",
        "(0.1) can0 123#R9", "  can0  123   [4]  DE AD BE", "  can0  123   [9]  DE",
        "  can0  123   [2]  DE AD BE", "hello world", "(0.1) can0 123#00 extra",
        "(2023-13-14 22:13:20.5) can0 123#00"}) {
    EXPECT_EQ(result_of(bad), CandumpLineResult::kMalformed) << bad;
  }
}

const std::string kLog =
    "(1700000000.000100) can0 200#1027D8F07B00F1C9\n"
    "garbage line\n"
    "(1700000000.000200) can0 18FF1001#8CA0FB2E0237C04D\n"
    "(1700000000.000300) can0 123##1DEADBEEF\n"
    "\n"
    " (1700000000.000400)  can0  202   [6]  02 6E B2 00 09 C8\n"
    "(1700000000.000500) can0 201#R\n"
    "(1700000000.000600) can0 201#0011";  // no final newline

TEST(CandumpLog, StreamCountsEveryLine) {
  CandumpLogDecoder d;
  const auto frames = decode_all(kLog, d);
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames[0].id, 0x200u);
  EXPECT_EQ(frames[2].id, 0x202u);
  EXPECT_EQ(frames[4].time.realtime_us, 1'700'000'000'000'600);
  EXPECT_EQ(frames[0].line_bytes, 46u);  // 45 characters and the newline
  EXPECT_EQ(frames[4].line_bytes, 33u);  // the last line has no newline
  const DecodeStats& s = d.stats();
  EXPECT_EQ(s.records, 5u);
  EXPECT_EQ(s.malformed, 1u);
  EXPECT_EQ(s.unsupported, 1u);
  EXPECT_EQ(s.bytes, kLog.size());
  EXPECT_EQ(s.dropped_bytes, std::string("garbage line\n").size() +
                                 std::string("(1700000000.000300) can0 123##1DEADBEEF\n").size());
}

TEST(CandumpLog, SplitAtEveryByteGivesIdenticalOutput) {
  CandumpLogDecoder whole;
  const auto expected = decode_all(kLog, whole);
  for (size_t chunk = 1; chunk <= kLog.size(); ++chunk) {
    CandumpLogDecoder d;
    const auto frames = decode_all(kLog, d, chunk);
    ASSERT_EQ(frames.size(), expected.size()) << "chunk " << chunk;
    for (size_t i = 0; i < frames.size(); ++i) {
      EXPECT_EQ(format_candump_log_line(frames[i]), format_candump_log_line(expected[i]));
    }
    EXPECT_EQ(d.stats().to_json(), whole.stats().to_json()) << "chunk " << chunk;
  }
}

TEST(CandumpLog, OverlongLinesAreDroppedAndCounted) {
  const std::string text = std::string(2000, 'A') + "\n(0.1) can0 123#00\n";
  CandumpLogDecoder d;
  const auto frames = decode_all(text, d, 100);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(d.stats().malformed, 1u);
  EXPECT_EQ(d.stats().dropped_bytes, 2001u);
}

TEST(CandumpLog, FormatParseRoundTrip) {
  std::mt19937_64 rng(9);
  for (int i = 0; i < 2000; ++i) {
    CanLogFrame f;
    f.extended = rng() % 2;
    f.id = static_cast<uint32_t>(rng() % (f.extended ? 0x20000000u : 0x800u));
    f.remote = rng() % 8 == 0;
    f.dlc = static_cast<uint8_t>(rng() % 9);
    if (!f.remote) {
      for (int k = 0; k < f.dlc; ++k) f.data[k] = static_cast<uint8_t>(rng());
    }
    f.time.realtime_us = static_cast<int64_t>(rng() % 4'000'000'000'000'000ull);
    const std::string line = format_candump_log_line(f);
    const CanLogFrame g = parse_ok(line);
    EXPECT_EQ(g.id, f.id) << line;
    EXPECT_EQ(g.extended, f.extended);
    EXPECT_EQ(g.remote, f.remote);
    EXPECT_EQ(g.dlc, f.dlc) << line;
    EXPECT_EQ(g.data, f.data);
    EXPECT_EQ(g.time.realtime_us, f.time.realtime_us);
  }
}

TEST(CandumpLog, RandomBytesNeverCrash) {
  std::mt19937_64 rng(10);
  std::string text;
  for (int i = 0; i < 20000; ++i) {
    const char alphabet[] = "0123456789ABCDEF#(). R[]\n\n-:_can";
    text += alphabet[rng() % (sizeof alphabet - 1)];
  }
  CandumpLogDecoder d;
  decode_all(text, d, 37);
  const DecodeStats& s = d.stats();
  EXPECT_EQ(s.bytes, text.size());
  EXPECT_LE(s.dropped_bytes, s.bytes);
  EXPECT_GT(s.malformed, 0u);
}

}  // namespace
}  // namespace nav::drivers
