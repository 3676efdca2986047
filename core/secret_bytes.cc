#include "core/secret_bytes.h"

#include <openssl/crypto.h>

namespace canalid::core {

void WipeBytes(std::span<uint8_t> bytes) noexcept {
  if (!bytes.empty()) OPENSSL_cleanse(bytes.data(), bytes.size());
}

}  // namespace canalid::core
