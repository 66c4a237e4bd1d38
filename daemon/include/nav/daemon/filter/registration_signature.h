#pragma once
// Optional signing of registration_t (config lcm.registration_signing; docs/formats.md
// "Signed registrations"), after MAVLink 2 message signing: an answerer holding the shared key
// sets signer_id and signature_time_us and puts HMAC-SHA256(key, encode(message with signature
// all zero)) into `signature`; the timestamp is covered by the MAC. navd accepts a signed answer
// only when the MAC matches (OpenSSL CRYPTO_memcmp: constant time), the signing time is within
// `window_us` of its own CLOCK_REALTIME and strictly later than the last accepted one of the
// same signer_id (a recording replayed, even within the window, is stale).
//
// The key file holds the key as hex text (`openssl rand -hex 32`, 16 to 64 bytes, surrounding
// white space ignored) and must be a regular file owned by the process's effective uid with no
// group or other permission bits (mode 0600 or 0400); anything else is refused with an error
// naming the file and its mode.

#include <cstdint>
#include <map>
#include <navlcm/registration_t.hpp>
#include <string>
#include <vector>

namespace nav::daemon {

using SigningKey = std::vector<std::uint8_t>;

/// Reads and checks a key file (contract above); throws std::runtime_error naming the file
/// (and its mode or the reason) otherwise.
SigningKey load_signing_key(const std::string& path);
/// Hex text (even length, [0-9a-fA-F], 16..64 bytes) to bytes; throws std::invalid_argument.
SigningKey signing_key_from_hex(const std::string& hex);

/// HMAC-SHA256 over the encoding of `message` with its signature zeroed.
std::vector<std::uint8_t> registration_mac(const navlcm::registration_t& message,
                                           const SigningKey& key);
/// Answerers: fills signer_id, signature_time_us and signature (the last field set).
void sign_registration(navlcm::registration_t& message, const SigningKey& key,
                       std::int32_t signer_id, std::int64_t time_us);

enum class SignatureVerdict { kValid, kUnsigned, kBadSignature, kStale };
const char* to_string(SignatureVerdict verdict);

/// navd's check of signed answers (one thread: the LCM listener).
class SignatureChecker {
 public:
  /// `window_us` > 0: how far the signing time may be from navd's clock, either way.
  SignatureChecker(SigningKey key, std::int64_t window_us);
  /// kUnsigned: signature_time_us == 0 or an all-zero signature; kBadSignature: the MAC does
  /// not match; kStale: outside the window or not after the signer's last valid one. Only a
  /// kValid answer advances its signer's last time.
  SignatureVerdict check(const navlcm::registration_t& message, std::int64_t now_realtime_us);

 private:
  SigningKey key_;
  std::int64_t window_us_;
  std::map<std::int32_t, std::int64_t> last_time_us_;  ///< per signer_id
};

}  // namespace nav::daemon
