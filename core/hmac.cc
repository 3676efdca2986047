#include "core/hmac.h"

#include <algorithm>

namespace canalid::core {

HmacSha256::HmacSha256(std::span<const uint8_t> key) {
  std::array<uint8_t, Sha256::kBlockBytes> k0{};
  if (key.size() > Sha256::kBlockBytes) {
    const Sha256Digest hashed = Sha256::Hash(key);
    std::copy(hashed.begin(), hashed.end(), k0.begin());
  } else {
    std::copy(key.begin(), key.end(), k0.begin());
  }
  for (std::size_t i = 0; i < k0.size(); ++i) {
    inner_pad_[i] = static_cast<uint8_t>(k0[i] ^ 0x36);
    outer_pad_[i] = static_cast<uint8_t>(k0[i] ^ 0x5c);
  }
  inner_.Update(inner_pad_);
}

Sha256Digest HmacSha256::Finish() {
  const Sha256Digest inner_digest = inner_.Finish();
  Sha256 outer;
  outer.Update(outer_pad_);
  outer.Update(inner_digest);
  inner_.Reset();
  inner_.Update(inner_pad_);
  return outer.Finish();
}

Sha256Digest HmacSha256::Mac(std::span<const uint8_t> key, std::span<const uint8_t> message) {
  HmacSha256 hmac(key);
  hmac.Update(message);
  return hmac.Finish();
}

bool ConstantTimeEqual(std::span<const uint8_t> a, std::span<const uint8_t> b) {
  if (a.size() != b.size()) return false;
  // Accumulate every difference instead of returning at the first one; volatile keeps the
  // compiler from turning the loop back into an early exit.
  volatile uint8_t difference = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    difference = static_cast<uint8_t>(difference | (a[i] ^ b[i]));
  }
  return difference == 0;
}

}  // namespace canalid::core
