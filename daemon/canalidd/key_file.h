#pragma once
#include <cstdint>
#include <filesystem>
#include <vector>

namespace canalid::daemon {

/// Smallest key ReadKeyFile accepts (bytes). RFC 2104 advises at least the hash length (32);
/// 16 is the floor below which a key is refused as a mistake.
inline constexpr std::size_t kMinCommandKeyBytes = 16;

/// Reads the shared command key from `path`.
/// Format: if the whole file, without trailing whitespace, is an even number of hex digits
/// (0-9, a-f, A-F), it is decoded as hex (e.g. the output of `openssl rand -hex 32`); otherwise
/// the file's bytes are the key as they are (raw).
/// Refused, with a std::runtime_error that names the path and the fix, when: the file cannot be
/// opened or is not a regular file; its mode lets group or others read or write it (it must be
/// like 0600 or 0400, owned by the service user); it is empty; the key is shorter than
/// kMinCommandKeyBytes.
std::vector<uint8_t> ReadKeyFile(const std::filesystem::path& path);

}  // namespace canalid::daemon
