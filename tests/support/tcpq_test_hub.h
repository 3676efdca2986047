#pragma once
// A minimal LCM tcpq hub for tests (Debian's liblcm-bin ships none): a TCP server on 127.0.0.1
// that speaks the client side of liblcm's lcm_tcpq.c. The client sends MAGIC_CLIENT and its
// version, the hub answers MAGIC_SERVER and its version; then SUBSCRIBE (2) frames come from the
// client and PUBLISH (1) frames go either way: u32 type | u32 channel length | channel
// [| u32 data length | data], all big-endian. It does not route: a test reads and writes frames.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/system/errno_text.h"

namespace canalid::testing {

inline constexpr uint32_t kMagicServer = 0x287617fa;
inline constexpr uint32_t kMagicClient = 0x287617fb;
inline constexpr uint32_t kPublish = 1;
inline constexpr uint32_t kSubscribe = 2;
inline constexpr int kHubWaitMs = 10000;  // bounded waits: far above what loopback needs

inline bool SendAll(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::send(fd, p, size, MSG_NOSIGNAL);
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}
inline bool RecvAll(int fd, void* data, std::size_t size) {
  auto* p = static_cast<uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::recv(fd, p, size, 0);
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}
inline bool SendU32(int fd, uint32_t v) {
  const uint32_t n = htonl(v);
  return SendAll(fd, &n, 4);
}
inline bool RecvU32(int fd, uint32_t& v) {
  uint32_t n = 0;
  if (!RecvAll(fd, &n, 4)) return false;
  v = ntohl(n);
  return true;
}

// One hub on 127.0.0.1 (an ephemeral port); each Accept serves one client connection.
class TcpqTestHub {
 public:
  TcpqTestHub() {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    if (listen_fd_ < 0 || ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), length) != 0 ||
        ::listen(listen_fd_, 4) != 0 ||
        ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
      ADD_FAILURE() << "test hub: " << canalid::core::ErrnoText(errno);
      return;
    }
    port_ = ntohs(address.sin_port);
  }
  ~TcpqTestHub() {
    if (listen_fd_ >= 0) ::close(listen_fd_);
  }
  std::string url() const { return "tcpq://127.0.0.1:" + std::to_string(port_); }
  void StopListening() {
    ::close(listen_fd_);
    listen_fd_ = -1;
  }

  // Accepts a client and answers its handshake; -1 when none came within kHubWaitMs.
  int Accept() {
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, kHubWaitMs) != 1) return -1;
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) return -1;
    timeval timeout{kHubWaitMs / 1000, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    uint32_t magic = 0, version = 0;
    if (!RecvU32(fd, magic) || magic != kMagicClient || !RecvU32(fd, version) ||
        !SendU32(fd, kMagicServer) || !SendU32(fd, version)) {
      ::close(fd);
      return -1;
    }
    return fd;
  }
  // The channel of the next SUBSCRIBE frame from the client (PUBLISH frames before it are read
  // and dropped), or "" on anything else.
  static std::string ReadSubscribe(int fd) {
    for (int frames = 0; frames < 1000; ++frames) {
      uint32_t type = 0, length = 0;
      if (!RecvU32(fd, type) || !RecvU32(fd, length) || length > 1000) return "";
      std::string channel(length, '\0');
      if (!RecvAll(fd, channel.data(), length)) return "";
      if (type == kSubscribe) return channel;
      uint32_t data_length = 0;
      if (type != kPublish || !RecvU32(fd, data_length) || data_length > (16u << 20)) return "";
      std::vector<uint8_t> data(data_length);
      if (!RecvAll(fd, data.data(), data_length)) return "";
    }
    return "";
  }
  // The next frame from the client: its type, channel and (for PUBLISH) data. False on a read
  // error or timeout, or a frame larger than 16 MB.
  static bool ReadFrame(int fd, uint32_t& type, std::string& channel, std::vector<uint8_t>& data) {
    uint32_t length = 0;
    if (!RecvU32(fd, type) || !RecvU32(fd, length) || length > 1000) return false;
    channel.assign(length, '\0');
    if (!RecvAll(fd, channel.data(), length)) return false;
    data.clear();
    if (type != kPublish) return true;
    uint32_t data_length = 0;
    if (!RecvU32(fd, data_length) || data_length > (16u << 20)) return false;
    data.resize(data_length);
    return RecvAll(fd, data.data(), data_length);
  }
  static bool Publish(int fd, const std::string& channel, const std::vector<uint8_t>& data) {
    return SendU32(fd, kPublish) && SendU32(fd, static_cast<uint32_t>(channel.size())) &&
           SendAll(fd, channel.data(), channel.size()) &&
           SendU32(fd, static_cast<uint32_t>(data.size())) && SendAll(fd, data.data(), data.size());
  }

 private:
  int listen_fd_ = -1;
  int port_ = 0;
};

}  // namespace canalid::testing
