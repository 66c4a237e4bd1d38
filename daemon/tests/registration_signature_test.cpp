// Signed registrations (registration_signature.h): the MAC equals HMAC-SHA256 computed by the
// openssl command line tool over the same bytes (an independent implementation of RFC 2104);
// a changed field, a replayed (not increasing) or out-of-window time and an unsigned answer are
// refused; a key file readable by others is refused naming the file and its mode.
#include "nav/daemon/filter/registration_signature.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace nav::daemon {
namespace {

namespace fs = std::filesystem;
const std::string kKeyHex = "00112233445566778899aabbccddeeff0123456789abcdef0011223344556677";
constexpr std::int64_t kNowUs = 1'700'000'000'000'000;
constexpr std::int64_t kWindowUs = 2'000'000;

navlcm::registration_t answer() {
  navlcm::registration_t r{};
  r.utime = kNowUs;
  r.frame_id_i = 4;
  r.frame_id_j = 9;
  r.success = true;
  for (int k = 0; k < 25; k += 6) r.covariance[k] = 1e-4;
  r.measurement[4] = 0.3;
  r.run_id = 77;
  r.sequence = 5;
  return r;
}

std::string hex(const std::vector<std::uint8_t>& bytes) {
  std::string out;
  char two[3];
  for (std::uint8_t b : bytes) {
    std::snprintf(two, sizeof two, "%02x", b);
    out += two;
  }
  return out;
}

TEST(RegistrationSignature, MacEqualsOpensslCommandLineHmac) {
  const SigningKey key = signing_key_from_hex(kKeyHex);
  navlcm::registration_t r = answer();
  sign_registration(r, key, 3, kNowUs);
  navlcm::registration_t zeroed = r;
  std::fill(std::begin(zeroed.signature), std::end(zeroed.signature), 0);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(zeroed.getEncodedSize()));
  ASSERT_GT(zeroed.encode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  const fs::path file = fs::temp_directory_path() / ("reg_sig_" + std::to_string(::getpid()));
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  const std::string command =
      "openssl dgst -sha256 -mac HMAC -macopt hexkey:" + kKeyHex + " -r " + file.string();
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char line[256] = {};
  ASSERT_NE(std::fgets(line, sizeof line, pipe), nullptr) << command;
  ::pclose(pipe);
  fs::remove(file);
  const std::vector<std::uint8_t> mac(std::begin(r.signature), std::end(r.signature));
  EXPECT_EQ(std::string(line).substr(0, 64), hex(mac));
}

TEST(RegistrationSignature, TamperedReplayedStaleAndUnsignedAnswersAreRefused) {
  const SigningKey key = signing_key_from_hex(kKeyHex);
  SignatureChecker checker(key, kWindowUs);
  navlcm::registration_t unsigned_answer = answer();
  EXPECT_EQ(checker.check(unsigned_answer, kNowUs), SignatureVerdict::kUnsigned);
  navlcm::registration_t r = answer();
  sign_registration(r, key, 1, kNowUs - 1000);
  navlcm::registration_t tampered = r;
  tampered.measurement[4] = 0.31;
  EXPECT_EQ(checker.check(tampered, kNowUs), SignatureVerdict::kBadSignature);
  navlcm::registration_t other_key = answer();
  sign_registration(other_key, signing_key_from_hex(std::string(64, 'a')), 1, kNowUs);
  EXPECT_EQ(checker.check(other_key, kNowUs), SignatureVerdict::kBadSignature);
  EXPECT_EQ(checker.check(r, kNowUs), SignatureVerdict::kValid);
  EXPECT_EQ(checker.check(r, kNowUs), SignatureVerdict::kStale);  // replayed within the window
  navlcm::registration_t old = answer();
  sign_registration(old, key, 2, kNowUs - kWindowUs - 1);  // another signer, too old
  EXPECT_EQ(checker.check(old, kNowUs), SignatureVerdict::kStale);
  navlcm::registration_t future = answer();
  sign_registration(future, key, 2, kNowUs + kWindowUs + 1);
  EXPECT_EQ(checker.check(future, kNowUs), SignatureVerdict::kStale);
  navlcm::registration_t next = answer();
  sign_registration(next, key, 1, kNowUs - 999);  // signer 1 later than its last: valid
  EXPECT_EQ(checker.check(next, kNowUs), SignatureVerdict::kValid);
  navlcm::registration_t signer2 = answer();
  sign_registration(signer2, key, 2, kNowUs - 5000);  // signers are independent
  EXPECT_EQ(checker.check(signer2, kNowUs), SignatureVerdict::kValid);
}

TEST(RegistrationSignature, KeyFileReadableByOthersIsRefusedNamingFileAndMode) {
  const fs::path file = fs::temp_directory_path() / ("reg_key_" + std::to_string(::getpid()));
  std::ofstream(file) << kKeyHex << "\n";
  ASSERT_EQ(::chmod(file.c_str(), 0644), 0);
  try {
    load_signing_key(file.string());
    ADD_FAILURE() << "a 0644 key file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0644"), std::string::npos) << e.what();
  }
  ASSERT_EQ(::chmod(file.c_str(), 0400), 0);
  EXPECT_EQ(load_signing_key(file.string()), signing_key_from_hex(kKeyHex));
  ASSERT_EQ(::chmod(file.c_str(), 0600), 0);
  std::ofstream(file) << "not hex\n";
  EXPECT_THROW(load_signing_key(file.string()), std::runtime_error);
  fs::remove(file);
  EXPECT_THROW(load_signing_key(file.string()), std::runtime_error);  // missing
  EXPECT_THROW(signing_key_from_hex("abc"), std::invalid_argument);
}

}  // namespace
}  // namespace nav::daemon
