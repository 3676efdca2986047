#include "drivers/auth/hmac.h"

#include <openssl/crypto.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>

#include <climits>
#include <stdexcept>
#include <string>

namespace canalid::drivers {
namespace {

// "<what> failed: <each entry of OpenSSL's error queue>", emptying the queue.
std::string OpenSslFailure(const std::string& what) {
  std::string message = what + " failed";
  int entries = 0;
  for (unsigned long code = ERR_get_error(); code != 0; code = ERR_get_error()) {
    char text[256];
    ERR_error_string_n(code, text, sizeof text);
    message += entries++ == 0 ? ": " : "; ";
    message += text;
  }
  if (entries == 0) message += " (OpenSSL queued no error)";
  return message;
}

}  // namespace

Sha256Digest HmacSha256::Mac(std::span<const uint8_t> key, std::span<const uint8_t> message) {
  if (key.size() > static_cast<std::size_t>(INT_MAX)) {
    throw std::invalid_argument("HMAC-SHA256 key of " + std::to_string(key.size()) +
                                " bytes is longer than OpenSSL accepts (INT_MAX)");
  }
  // An empty span may have a null data(); give OpenSSL a valid pointer with length 0 instead, so
  // the empty key never depends on how OpenSSL treats a null key.
  static constexpr unsigned char kNoKey = 0;
  const unsigned char* key_bytes = key.empty() ? &kNoKey : key.data();
  Sha256Digest tag{};
  unsigned int tag_bytes = 0;
  if (HMAC(EVP_sha256(), key_bytes, static_cast<int>(key.size()), message.data(), message.size(),
           tag.data(), &tag_bytes) == nullptr) {
    throw std::runtime_error(OpenSslFailure("HMAC-SHA256 (OpenSSL HMAC)"));
  }
  if (tag_bytes != tag.size()) {
    throw std::runtime_error("HMAC-SHA256 (OpenSSL HMAC) gave " + std::to_string(tag_bytes) +
                             " bytes instead of " + std::to_string(tag.size()));
  }
  return tag;
}

bool ConstantTimeEqual(std::span<const uint8_t> a, std::span<const uint8_t> b) {
  if (a.size() != b.size()) return false;
  return CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

}  // namespace canalid::drivers
