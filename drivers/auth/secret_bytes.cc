#include "drivers/auth/secret_bytes.h"

#include <openssl/crypto.h>

namespace canalid::drivers {

void WipeBytes(std::span<uint8_t> bytes) noexcept {
  if (!bytes.empty()) OPENSSL_cleanse(bytes.data(), bytes.size());
}

}  // namespace canalid::drivers
