#include "daemon/canalidd/key_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace canalid::daemon {
namespace {

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& why) {
  throw std::runtime_error("command key file " + path.string() + ": " + why);
}

int HexValue(uint8_t c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

std::vector<uint8_t> ReadKeyFile(const std::filesystem::path& path) {
  // Open first and check the opened file (fstat), so the checked file is the one read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) Fail(path, std::string("cannot open: ") + std::strerror(errno));
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) Fail(path, std::string("cannot stat: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) Fail(path, "is not a regular file");
  const unsigned mode = st.st_mode & 07777;
  if ((mode & (S_IRGRP | S_IWGRP | S_IROTH | S_IWOTH)) != 0) {
    char octal[8];
    std::snprintf(octal, sizeof octal, "%04o", mode);
    Fail(path, std::string("mode ") + octal +
                   " lets group or others read or write it; run chmod 600 " + path.string() +
                   " (owner: the service user)");
  }
  std::vector<uint8_t> bytes;
  uint8_t chunk[4096];
  for (;;) {
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0) {
      if (errno == EINTR) continue;
      Fail(path, std::string("cannot read: ") + std::strerror(errno));
    }
    if (n == 0) break;
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  if (bytes.empty())
    Fail(path, "is empty; write a key, e.g. openssl rand -hex 32 > " + path.string());

  std::size_t end = bytes.size();
  while (end > 0 && (bytes[end - 1] == '\n' || bytes[end - 1] == '\r' || bytes[end - 1] == ' ' ||
                     bytes[end - 1] == '\t')) {
    --end;
  }
  bool hex = end > 0 && end % 2 == 0;
  for (std::size_t i = 0; hex && i < end; ++i) hex = HexValue(bytes[i]) >= 0;
  std::vector<uint8_t> key;
  if (hex) {
    key.reserve(end / 2);
    for (std::size_t i = 0; i < end; i += 2) {
      key.push_back(static_cast<uint8_t>(HexValue(bytes[i]) * 16 + HexValue(bytes[i + 1])));
    }
  } else {
    key = std::move(bytes);
  }
  if (key.size() < kMinCommandKeyBytes) {
    Fail(path, "key is " + std::to_string(key.size()) + " bytes; at least " +
                   std::to_string(kMinCommandKeyBytes) + " are needed (32 advised)");
  }
  return key;
}

}  // namespace canalid::daemon
