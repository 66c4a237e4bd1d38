// HMAC-SHA256 signing of registration_t: see registration_signature.h.
#include "nav/daemon/filter/registration_signature.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace nav::daemon {
namespace {

constexpr std::size_t kMacBytes = 32;  // SHA-256

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string octal_mode(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof text, "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

}  // namespace

SigningKey signing_key_from_hex(const std::string& hex) {
  if (hex.size() % 2 != 0 || hex.size() < 32 || hex.size() > 128) {
    throw std::invalid_argument("signing key: " + std::to_string(hex.size()) +
                                " hex digits; expected an even number from 32 to 128 "
                                "(16 to 64 bytes, e.g. `openssl rand -hex 32`)");
  }
  SigningKey key(hex.size() / 2);
  for (std::size_t k = 0; k < key.size(); ++k) {
    const int hi = hex_value(hex[2 * k]), lo = hex_value(hex[2 * k + 1]);
    if (hi < 0 || lo < 0) {
      throw std::invalid_argument("signing key: character " + std::to_string(2 * k + (hi < 0 ? 0 : 1)) +
                                  " is not a hex digit");
    }
    key[k] = static_cast<std::uint8_t>(16 * hi + lo);
  }
  return key;
}

SigningKey load_signing_key(const std::string& path) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0) {
    throw std::runtime_error("signing key file " + path + ": cannot stat it");
  }
  if (!S_ISREG(st.st_mode)) throw std::runtime_error("signing key file " + path + ": not a file");
  if (st.st_uid != ::geteuid() || (st.st_mode & 077) != 0) {
    throw std::runtime_error("signing key file " + path + " has mode " + octal_mode(st.st_mode) +
                             " and owner uid " + std::to_string(st.st_uid) +
                             ": it must be readable by navd's user only (owner uid " +
                             std::to_string(::geteuid()) + ", mode 0600 or 0400)");
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error("signing key file " + path + ": cannot read it");
  std::string hex = text.str();
  hex.erase(std::remove_if(hex.begin(), hex.end(), [](unsigned char c) { return std::isspace(c); }),
            hex.end());
  try {
    return signing_key_from_hex(hex);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("signing key file " + path + ": " + e.what());
  }
}

std::vector<std::uint8_t> registration_mac(const navlcm::registration_t& message,
                                           const SigningKey& key) {
  navlcm::registration_t zeroed = message;
  std::fill(std::begin(zeroed.signature), std::end(zeroed.signature), 0);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(zeroed.getEncodedSize()));
  if (zeroed.encode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) {
    throw std::runtime_error("registration_mac: registration_t does not encode");
  }
  std::vector<std::uint8_t> mac(kMacBytes);
  unsigned int length = 0;
  if (HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), bytes.data(), bytes.size(),
           mac.data(), &length) == nullptr ||
      length != kMacBytes) {
    throw std::runtime_error("registration_mac: OpenSSL HMAC-SHA256 failed");
  }
  return mac;
}

void sign_registration(navlcm::registration_t& message, const SigningKey& key,
                       std::int32_t signer_id, std::int64_t time_us) {
  message.signer_id = signer_id;
  message.signature_time_us = time_us;
  const std::vector<std::uint8_t> mac = registration_mac(message, key);
  std::copy(mac.begin(), mac.end(), std::begin(message.signature));
}

const char* to_string(SignatureVerdict verdict) {
  switch (verdict) {
    case SignatureVerdict::kValid: return "valid";
    case SignatureVerdict::kUnsigned: return "unsigned";
    case SignatureVerdict::kBadSignature: return "bad signature";
    case SignatureVerdict::kStale: return "stale signature";
  }
  return "?";
}

SignatureChecker::SignatureChecker(SigningKey key, std::int64_t window_us)
    : key_(std::move(key)), window_us_(window_us) {
  if (key_.empty()) throw std::invalid_argument("SignatureChecker: empty key");
  if (window_us_ <= 0) throw std::invalid_argument("SignatureChecker: window must be > 0");
}

SignatureVerdict SignatureChecker::check(const navlcm::registration_t& message,
                                         std::int64_t now_realtime_us) {
  const bool zero_mac = std::all_of(std::begin(message.signature), std::end(message.signature),
                                    [](std::uint8_t b) { return b == 0; });
  if (message.signature_time_us == 0 || zero_mac) return SignatureVerdict::kUnsigned;
  const std::vector<std::uint8_t> mac = registration_mac(message, key_);
  if (CRYPTO_memcmp(mac.data(), message.signature, kMacBytes) != 0) {
    return SignatureVerdict::kBadSignature;
  }
  const std::int64_t t = message.signature_time_us;
  // |now - t| > window without overflow for any int64 t.
  if (t < now_realtime_us - window_us_ || t > now_realtime_us + window_us_) {
    return SignatureVerdict::kStale;
  }
  const auto last = last_time_us_.find(message.signer_id);
  if (last != last_time_us_.end() && t <= last->second) return SignatureVerdict::kStale;
  last_time_us_[message.signer_id] = t;
  return SignatureVerdict::kValid;
}

}  // namespace nav::daemon
