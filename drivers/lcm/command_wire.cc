#include "drivers/lcm/command_wire.h"

#include "canalid/command_t.hpp"

namespace canalid::drivers {
namespace {

// Reads big-endian integers from a span, failing (instead of reading past the end) when the bytes
// run out.
class WireReader {
 public:
  explicit WireReader(std::span<const uint8_t> data) : data_(data) {}
  std::size_t left() const { return data_.size() - pos_; }
  bool Skip(std::size_t n) {
    if (n > left()) return false;
    pos_ += n;
    return true;
  }
  bool U64(uint64_t& value) {
    if (left() < 8) return false;
    value = 0;
    for (int i = 0; i < 8; ++i) value = (value << 8) | data_[pos_++];
    return true;
  }
  bool I32(int32_t& value) {
    if (left() < 4) return false;
    uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) bits = (bits << 8) | data_[pos_++];
    value = static_cast<int32_t>(bits);
    return true;
  }
  // An LCM string: int32 length counting the NUL, then the bytes and the NUL.
  bool String(std::size_t max_bytes) {
    int32_t length = 0;
    if (!I32(length)) return false;
    if (length < 1 || static_cast<std::size_t>(length) > max_bytes + 1) return false;
    const auto n = static_cast<std::size_t>(length);
    if (n > left() || data_[pos_ + n - 1] != 0) return false;
    pos_ += n;
    return true;
  }

 private:
  std::span<const uint8_t> data_;
  std::size_t pos_ = 0;
};

}  // namespace

bool CommandWireIsBounded(std::span<const uint8_t> data) noexcept {
  if (data.size() > kMaxCommandMessageBytes) return false;
  WireReader r(data);
  uint64_t fingerprint = 0;
  int32_t hmac_size = 0;
  // Fields in command_t.lcm order.
  return r.U64(fingerprint) &&
         fingerprint == static_cast<uint64_t>(canalid::command_t::getHash()) &&
         r.Skip(8) &&                                    // utime
         r.Skip(8) &&                                    // counter
         r.String(drivers::kMaxCommandSenderBytes) &&    // sender
         r.Skip(1) &&                                    // kind
         r.String(drivers::kMaxCommandReachBytes) &&     // reach
         r.String(drivers::kMaxCommandArgumentBytes) &&  // argument
         r.I32(hmac_size) && hmac_size == static_cast<int32_t>(sizeof(drivers::Sha256Digest)) &&
         r.Skip(sizeof(drivers::Sha256Digest)) && r.left() == 0;
}

}  // namespace canalid::drivers
