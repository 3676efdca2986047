#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace canalid::core {

/// SHA-256 digest: 32 bytes, most significant byte of H0 first (FIPS 180-4 section 6.2.2).
using Sha256Digest = std::array<uint8_t, 32>;

/// SHA-256 (FIPS 180-4): the message is padded with 0x80, zeros and its length in bits as a
/// 64-bit big-endian integer to a multiple of 64 bytes, and each 64-byte block is compressed
/// into the eight 32-bit words H0..H7 with 64 rounds of
///   T1 = h + Sigma1(e) + Ch(e, f, g) + K_t + W_t,  T2 = Sigma0(a) + Maj(a, b, c).
/// Incremental: Update any number of times, then Finish once. Pure, never allocates, not
/// thread-safe. Messages up to 2^61 - 1 bytes.
class Sha256 final {
 public:
  static constexpr std::size_t kBlockBytes = 64;
  static constexpr std::size_t kDigestBytes = 32;

  Sha256();
  /// Appends `data` to the message. @pre Finish has not been called.
  void Update(std::span<const uint8_t> data);
  /// Pads the message and returns its digest; the object must be reset (Reset) to hash again.
  Sha256Digest Finish();
  /// Starts a new message.
  void Reset();

  /// The digest of `data` in one call.
  static Sha256Digest Hash(std::span<const uint8_t> data);

 private:
  void Compress(const uint8_t* block);

  std::array<uint32_t, 8> state_;
  std::array<uint8_t, kBlockBytes> buffer_;
  std::size_t buffered_ = 0;  // bytes waiting in buffer_
  uint64_t total_bytes_ = 0;  // message length so far
};

}  // namespace canalid::core
