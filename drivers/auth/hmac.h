#pragma once
#include <array>
#include <cstdint>
#include <span>

namespace canalid::drivers {

/// An HMAC-SHA256 tag: 32 bytes (the SHA-256 digest size).
using Sha256Digest = std::array<uint8_t, 32>;

/// HMAC-SHA256 (RFC 2104 with SHA-256) and the constant-time tag compare, both from OpenSSL's
/// libcrypto; this file only gives them the project's names and turns OpenSSL's failures into
/// exceptions. The RFC 4231 vectors are in tests/drivers/hmac_test.cc.
class HmacSha256 final {
 public:
  HmacSha256() = delete;

  /// The MAC of `message` under `key`. The key may be empty (RFC 2104 allows it; callers decide
  /// their own minimum); a key longer than 64 bytes is hashed first, as RFC 2104 says.
  /// Thread-safe. @throws std::invalid_argument when the key is longer than INT_MAX bytes;
  ///   std::runtime_error with OpenSSL's error queue when OpenSSL fails.
  static Sha256Digest Mac(std::span<const uint8_t> key, std::span<const uint8_t> message);
};

/// True when a and b have the same length and bytes. The lengths are compared first (a tag's
/// length is no secret); the bytes with OpenSSL's CRYPTO_memcmp, whose time depends only on the
/// length, never on where the first difference is, so a MAC check does not leak how many leading
/// bytes of a forgery were right.
bool ConstantTimeEqual(std::span<const uint8_t> a, std::span<const uint8_t> b);

}  // namespace canalid::drivers
