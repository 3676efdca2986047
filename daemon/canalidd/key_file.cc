#include "daemon/canalidd/key_file.h"

#include "core/system/errno_text.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace canalid::daemon {
namespace {

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& why) {
  throw std::runtime_error("command key file " + path.string() + ": " + why +
                           "; the file must hold " + kKeyFileFormat +
                           ", e.g. (umask 077; openssl rand -hex 32 > " + path.string() + ")");
}

int HexValue(uint8_t c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// The file's bytes, wiped when it goes out of scope (also when a refusal throws).
struct FileBuffer {
  static constexpr std::size_t kHexDigits = 2 * kCommandKeyBytes;
  std::array<uint8_t, kHexDigits + 2> bytes{};  // one more than the longest accepted file
  std::size_t size = 0;
  ~FileBuffer() { drivers::WipeBytes(bytes); }
};

}  // namespace

drivers::SecretBytes ReadKeyFile(const std::filesystem::path& path) {
  // Open first and check the opened file (fstat), so the checked file is the one read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) Fail(path, std::string("cannot open: ") + core::ErrnoText(errno));
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) Fail(path, std::string("cannot stat: ") + core::ErrnoText(errno));
  if (!S_ISREG(st.st_mode)) Fail(path, "is not a regular file");
  const unsigned mode = st.st_mode & 07777;
  if ((mode & (S_IRGRP | S_IWGRP | S_IROTH | S_IWOTH)) != 0) {
    char octal[8];
    std::snprintf(octal, sizeof octal, "%04o", mode);
    Fail(path, std::string("mode ") + octal +
                   " lets group or others read or write it; run chmod 600 " + path.string() +
                   " (owner: the service user)");
  }
  // Read at most one byte more than the longest valid file, so a long file is refused unread.
  FileBuffer file;
  while (file.size < file.bytes.size()) {
    const ssize_t n = ::read(fd, file.bytes.data() + file.size, file.bytes.size() - file.size);
    if (n < 0) {
      if (errno == EINTR) continue;
      Fail(path, std::string("cannot read: ") + core::ErrnoText(errno));
    }
    if (n == 0) break;
    file.size += static_cast<std::size_t>(n);
  }
  if (file.size == 0) Fail(path, "is empty");
  std::size_t digits = file.size;
  if (file.bytes[digits - 1] == '\n') --digits;
  for (std::size_t i = 0; i < digits; ++i) {
    if (HexValue(file.bytes[i]) < 0) {
      // The position only: the content is secret.
      Fail(path, "byte " + std::to_string(i + 1) + " is not a hex digit");
    }
  }
  if (digits != FileBuffer::kHexDigits) {
    Fail(path, file.size == file.bytes.size()
                   ? std::string("is longer than a key (more than 64 hex digits)")
                   : std::to_string(digits) + " hex digits instead of " +
                         std::to_string(FileBuffer::kHexDigits));
  }
  drivers::SecretBytes key(kCommandKeyBytes);
  const std::span<uint8_t> out = key.mutable_span();
  for (std::size_t i = 0; i < kCommandKeyBytes; ++i) {
    out[i] =
        static_cast<uint8_t>(HexValue(file.bytes[2 * i]) * 16 + HexValue(file.bytes[2 * i + 1]));
  }
  return key;
}

}  // namespace canalid::daemon
