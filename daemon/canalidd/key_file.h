#pragma once
#include <cstdint>
#include <filesystem>
#include <string>

#include "drivers/auth/secret_bytes.h"

namespace canalid::daemon {

/// Size of the command key (bytes): HMAC-SHA256's hash length, as RFC 2104 advises.
inline constexpr std::size_t kCommandKeyBytes = 32;

/// The key file format, for messages and docs.
inline constexpr const char* kKeyFileFormat =
    "exactly 64 hex digits (0-9, a-f, A-F: a 32-byte key), optionally followed by one newline";

/// Reads the shared command key from `path` (canalidd at start and --check-config, and
/// canalid-command: one function, so a file the check accepts is one the daemon accepts).
/// Format: kKeyFileFormat, i.e. what `openssl rand -hex 32 > FILE` writes. Nothing else is taken
/// (no raw keys, no other lengths: a 16-character password is refused, not read as 8 bytes).
/// Refused, with a std::runtime_error that names the path, the format and the fix, when: the file
/// cannot be opened or is not a regular file (a directory; a symlink is followed to its target,
/// which must pass the same checks); its mode lets group or others read or write it (it must be
/// like 0600 or 0400, owned by the service user); it is empty, too short or too long, holds a
/// character that is not a hex digit, or anything after the key but one newline.
/// The file's bytes and the key are wiped (OPENSSL_cleanse) from every buffer this used; the
/// returned key is wiped when it is destroyed.
drivers::SecretBytes ReadKeyFile(const std::filesystem::path& path);

}  // namespace canalid::daemon
