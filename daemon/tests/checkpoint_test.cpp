// Checkpoints: the file format (its CRC-32s: core/serialization/crc32.h), atomic write +
// rotation, and loading the newest valid checkpoint past truncated, bit-flipped, mis-named files
// and leftover temp files.
#include "nav/daemon/checkpoint/checkpoint.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <numeric>
#include <string>
#include <string_view>


namespace nav::daemon {
namespace {
namespace fs = std::filesystem;

std::span<const std::uint8_t> bytes_of(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

std::vector<std::uint8_t> payload(std::size_t n, std::uint8_t seed) {
  std::vector<std::uint8_t> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(seed + 31 * i);
  return out;
}

std::vector<std::uint8_t> read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

void write_all(const fs::path& p, std::span<const std::uint8_t> bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

class CheckpointDir : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/navd-checkpoint-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST(CheckpointFormat, RoundTripAndHeaderLayout) {
  const auto data = payload(100, 9);
  const auto bytes = encode_checkpoint(7, 42, data);
  ASSERT_EQ(bytes.size(), kCheckpointHeaderBytes + 100);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 8), "NAVDCKPT");
  EXPECT_EQ(bytes[24], 100);  // payload length, little-endian
  std::string reason;
  const auto decoded = decode_checkpoint(bytes, &reason);
  ASSERT_TRUE(decoded.has_value()) << reason;
  EXPECT_EQ(decoded->payload_version, 7u);
  EXPECT_EQ(decoded->sequence, 42u);
  EXPECT_EQ(decoded->payload, data);
  const auto empty = decode_checkpoint(encode_checkpoint(1, 1, {}), &reason);
  ASSERT_TRUE(empty.has_value());
  EXPECT_TRUE(empty->payload.empty());
}

TEST(CheckpointFormat, EveryTruncationIsRejected) {
  const auto bytes = encode_checkpoint(1, 5, payload(64, 1));
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    std::string reason;
    EXPECT_FALSE(decode_checkpoint(std::span(bytes).first(n), &reason).has_value()) << n;
    EXPECT_NE(reason.find("truncated"), std::string::npos) << n << ": " << reason;
  }
  auto longer = bytes;
  longer.push_back(0);
  std::string reason;
  EXPECT_FALSE(decode_checkpoint(longer, &reason).has_value());
  EXPECT_EQ(reason, "1 trailing bytes after 104");
}

TEST(CheckpointFormat, EveryFlippedBitIsRejected) {
  const auto bytes = encode_checkpoint(1, 5, payload(48, 2));
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      auto corrupt = bytes;
      corrupt[i] ^= static_cast<std::uint8_t>(1u << bit);
      std::string reason;
      EXPECT_FALSE(decode_checkpoint(corrupt, &reason).has_value()) << i << ":" << bit;
      EXPECT_FALSE(reason.empty());
    }
  }
}

TEST_F(CheckpointDir, WriteLoadAndRotation) {
  CheckpointWriter writer(dir_, 3);
  EXPECT_FALSE(load_newest_valid(dir_).checkpoint.has_value());
  for (std::uint8_t i = 1; i <= 5; ++i) {
    const WriteResult r = writer.write(2, payload(10 * i, i));
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_EQ(r.sequence, i);
    EXPECT_EQ(r.path, checkpoint_path(dir_, i));
  }
  EXPECT_EQ(list_checkpoints(dir_), (std::vector<std::uint64_t>{3, 4, 5}));
  const LoadResult loaded = load_newest_valid(dir_);
  ASSERT_TRUE(loaded.checkpoint.has_value());
  EXPECT_TRUE(loaded.skipped.empty());
  EXPECT_EQ(loaded.checkpoint->sequence, 5u);
  EXPECT_EQ(loaded.checkpoint->payload_version, 2u);
  EXPECT_EQ(loaded.checkpoint->payload, payload(50, 5));
  // Only checkpoint files, no temp files, remain.
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++files;
  EXPECT_EQ(files, 3);
}

TEST_F(CheckpointDir, TruncatedNewestFallsBackToPreviousAtManyOffsets) {
  CheckpointWriter writer(dir_, 5);
  ASSERT_TRUE(writer.write(1, payload(200, 1)).ok);
  const WriteResult newest = writer.write(1, payload(200, 2));
  ASSERT_TRUE(newest.ok);
  const auto good = read_all(newest.path);
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{20}, std::size_t{39},
                        std::size_t{40}, std::size_t{41}, std::size_t{120}, good.size() - 1}) {
    write_all(newest.path, std::span(good).first(n));
    const LoadResult r = load_newest_valid(dir_);
    ASSERT_TRUE(r.checkpoint.has_value()) << n;
    EXPECT_EQ(r.checkpoint->sequence, 1u) << n;
    EXPECT_EQ(r.checkpoint->payload, payload(200, 1));
    ASSERT_EQ(r.skipped.size(), 1u);
    EXPECT_EQ(r.skipped[0].path, newest.path);
    EXPECT_NE(r.skipped[0].reason.find("truncated"), std::string::npos) << r.skipped[0].reason;
  }
}

TEST_F(CheckpointDir, FlippedBytesAreReportedAndSkipped) {
  CheckpointWriter writer(dir_, 5);
  ASSERT_TRUE(writer.write(1, payload(64, 1)).ok);
  const WriteResult second = writer.write(1, payload(64, 2));
  const WriteResult third = writer.write(1, payload(64, 3));
  auto bytes = read_all(third.path);
  bytes[kCheckpointHeaderBytes + 10] ^= 0x01;  // payload
  write_all(third.path, bytes);
  bytes = read_all(second.path);
  bytes[30] ^= 0x80;  // header (payload CRC field)
  write_all(second.path, bytes);
  const LoadResult r = load_newest_valid(dir_);
  ASSERT_TRUE(r.checkpoint.has_value());
  EXPECT_EQ(r.checkpoint->sequence, 1u);
  ASSERT_EQ(r.skipped.size(), 2u);
  EXPECT_EQ(r.skipped[0].path, third.path);
  EXPECT_EQ(r.skipped[0].reason, "payload CRC-32 mismatch");
  EXPECT_EQ(r.skipped[1].path, second.path);
  EXPECT_EQ(r.skipped[1].reason, "header CRC-32 mismatch");
}

TEST_F(CheckpointDir, AllCorruptGivesNoCheckpointButReportsEach) {
  CheckpointWriter writer(dir_, 5);
  ASSERT_TRUE(writer.write(1, payload(8, 1)).ok);
  ASSERT_TRUE(writer.write(1, payload(8, 2)).ok);
  for (std::uint64_t s : {1u, 2u}) write_all(checkpoint_path(dir_, s), bytes_of("garbage"));
  const LoadResult r = load_newest_valid(dir_);
  EXPECT_FALSE(r.checkpoint.has_value());
  EXPECT_EQ(r.skipped.size(), 2u);
}

TEST_F(CheckpointDir, RenamedFileWithWrongSequenceIsSkipped) {
  CheckpointWriter writer(dir_, 5);
  const WriteResult first = writer.write(1, payload(8, 1));
  fs::copy_file(first.path, checkpoint_path(dir_, 9));
  const LoadResult r = load_newest_valid(dir_);
  ASSERT_TRUE(r.checkpoint.has_value());
  EXPECT_EQ(r.checkpoint->sequence, 1u);
  ASSERT_EQ(r.skipped.size(), 1u);
  EXPECT_NE(r.skipped[0].reason.find("does not match the name"), std::string::npos);
}

TEST_F(CheckpointDir, LeftoverTempFilesAreIgnoredThenRemoved) {
  {
    CheckpointWriter writer(dir_, 3);
    ASSERT_TRUE(writer.write(1, payload(16, 1)).ok);
  }
  // A crash between write and rename leaves a temp file, possibly complete, possibly partial.
  const fs::path temp = dir_ / ".checkpoint-00000000000000000002.ckpt.tmp";
  write_all(temp, encode_checkpoint(1, 2, payload(16, 2)));
  write_all(dir_ / "notes.txt", bytes_of("not a checkpoint"));
  LoadResult r = load_newest_valid(dir_);
  ASSERT_TRUE(r.checkpoint.has_value());
  EXPECT_EQ(r.checkpoint->sequence, 1u);
  EXPECT_TRUE(r.skipped.empty());
  CheckpointWriter restarted(dir_, 3);
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_TRUE(fs::exists(dir_ / "notes.txt"));  // only our temp files are removed
  const WriteResult next = restarted.write(1, payload(16, 3));
  ASSERT_TRUE(next.ok) << next.error;
  EXPECT_EQ(next.sequence, 2u);
  r = load_newest_valid(dir_);
  EXPECT_EQ(r.checkpoint->payload, payload(16, 3));
}

TEST_F(CheckpointDir, WriteErrorsAreReportedWithThePath) {
  CheckpointWriter writer(dir_ / "sub", 2);
  ASSERT_TRUE(fs::is_directory(dir_ / "sub"));
  fs::remove_all(dir_ / "sub");
  const WriteResult r = writer.write(1, payload(4, 1));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find((dir_ / "sub").string()), std::string::npos) << r.error;
  EXPECT_THROW(CheckpointWriter(dir_ / "x", 0), std::invalid_argument);
  write_all(dir_ / "file", bytes_of("x"));
  EXPECT_THROW(CheckpointWriter(dir_ / "file", 1), std::runtime_error);
}

TEST_F(CheckpointDir, MissingDirectoryLoadsNothing) {
  const LoadResult r = load_newest_valid(dir_ / "does-not-exist");
  EXPECT_FALSE(r.checkpoint.has_value());
  EXPECT_TRUE(r.skipped.empty());
}

}  // namespace
}  // namespace nav::daemon
