#pragma once
#include <cstdint>
#include <span>

#include "core/sha256.h"

namespace canalid::core {

/// HMAC-SHA256 (RFC 2104 with SHA-256, B = 64, L = 32):
///   HMAC(K, m) = H((K0 ^ opad) || H((K0 ^ ipad) || m)),  ipad = 0x36..., opad = 0x5c...,
/// where K0 is K padded with zeros to 64 bytes, or H(K) padded when K is longer than 64 bytes.
/// Incremental like Sha256; pure, never allocates. The key may be empty (RFC 2104 allows it;
/// callers decide their own minimum).
class HmacSha256 final {
 public:
  explicit HmacSha256(std::span<const uint8_t> key);
  void Update(std::span<const uint8_t> data) { inner_.Update(data); }
  /// The MAC of everything given to Update since construction or the last Finish; the object is
  /// ready for a new message with the same key afterwards.
  Sha256Digest Finish();

  /// The MAC of `message` under `key` in one call.
  static Sha256Digest Mac(std::span<const uint8_t> key, std::span<const uint8_t> message);

 private:
  std::array<uint8_t, Sha256::kBlockBytes> inner_pad_;  // K0 ^ ipad
  std::array<uint8_t, Sha256::kBlockBytes> outer_pad_;  // K0 ^ opad
  Sha256 inner_;
};

/// True when a and b have the same length and bytes. The time taken depends only on the
/// lengths, never on where the first difference is, so a MAC check does not leak how many
/// leading bytes of a forgery were right.
bool ConstantTimeEqual(std::span<const uint8_t> a, std::span<const uint8_t> b);

}  // namespace canalid::core
