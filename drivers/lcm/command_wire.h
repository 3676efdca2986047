#pragma once
#include <cstddef>
#include <cstdint>
#include <span>

#include "drivers/auth/command_auth.h"

namespace canalid::drivers {

/// Largest LCM encoding of a canalid.command_t the daemon accepts (bytes): the 8-byte fingerprint,
/// utime and counter (8 each), sender (4 + 64 + 1), kind (1), reach (4 + 64 + 1), argument
/// (4 + 1024 + 1), hmac_size (4) and a 32-byte MAC. Strings are LCM-encoded as an int32 length
/// that counts a terminating NUL, then the bytes and the NUL.
inline constexpr std::size_t kMaxCommandMessageBytes =
    8 + 8 + 8 + (4 + drivers::kMaxCommandSenderBytes + 1) + 1 +
    (4 + drivers::kMaxCommandReachBytes + 1) + (4 + drivers::kMaxCommandArgumentBytes + 1) + 4 + 32;
static_assert(kMaxCommandMessageBytes == 1228);

/// True when `data` is a canalid.command_t that lcm-gen's decoder can take without a large
/// allocation: at most kMaxCommandMessageBytes long, the right fingerprint, each string's length
/// in [1, its maximum + 1] and within the bytes left, ending in its NUL, hmac_size exactly 32 and
/// the data ending right after the MAC. Reads `data` only: never allocates, never throws.
///
/// Why: lcm-gen's C++ decode resizes `hmac` to `hmac_size` before checking that the bytes are
/// there, so one 60-byte message with hmac_size = 0x7fffffff allocated and zeroed 2 GiB before
/// any authentication (about 1 s of stalled loop per message); a string length of 0 or below
/// makes it throw. The channel's messages are checked here first and only then decoded.
bool CommandWireIsBounded(std::span<const uint8_t> data) noexcept;

}  // namespace canalid::drivers
