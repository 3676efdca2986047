#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace canalid::drivers {

/// Overwrites `bytes` with OpenSSL's OPENSSL_cleanse (a wipe the compiler cannot drop as a dead
/// store).
void WipeBytes(std::span<uint8_t> bytes) noexcept;

/// Bytes of a secret (a command key): move-only, wiped with WipeBytes when destroyed, assigned
/// over or Wipe()d. Sized once at construction and never grown, so no reallocation leaves an
/// unwiped copy on the heap; a move hands the buffer over (the source is left empty).
class SecretBytes final {
 public:
  SecretBytes() = default;
  explicit SecretBytes(std::size_t size) : bytes_(size) {}
  explicit SecretBytes(std::span<const uint8_t> bytes) : bytes_(bytes.begin(), bytes.end()) {}
  ~SecretBytes() { Wipe(); }
  SecretBytes(SecretBytes&& other) noexcept : bytes_(std::move(other.bytes_)) {}
  SecretBytes& operator=(SecretBytes&& other) noexcept {
    if (this != &other) {
      Wipe();
      bytes_ = std::move(other.bytes_);
    }
    return *this;
  }
  SecretBytes(const SecretBytes&) = delete;
  SecretBytes& operator=(const SecretBytes&) = delete;

  /// Wipes the bytes and leaves this empty.
  void Wipe() noexcept {
    WipeBytes(bytes_);
    bytes_.clear();
  }
  std::span<const uint8_t> span() const { return bytes_; }
  std::span<uint8_t> mutable_span() { return bytes_; }
  std::size_t size() const { return bytes_.size(); }
  bool empty() const { return bytes_.empty(); }

 private:
  std::vector<uint8_t> bytes_;
};

}  // namespace canalid::drivers
