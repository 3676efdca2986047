#pragma once
// Loopback TCP ports for tests that start a server of their own as a child process.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>

namespace canalid::testing {

/// The address 127.0.0.1:port.
inline sockaddr_in LoopbackAddress(int port) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  return addr;
}

/// A TCP socket listening on 127.0.0.1 at a free port, and that port; fd -1 on error.  The caller
/// closes it.
struct LoopbackListener {
  int fd = -1;
  int port = 0;
};
inline LoopbackListener ListenOnLoopback() {
  LoopbackListener l{socket(AF_INET, SOCK_STREAM, 0), 0};
  sockaddr_in addr = LoopbackAddress(0);
  socklen_t len = sizeof addr;
  if (l.fd < 0 || bind(l.fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      listen(l.fd, 1) != 0 || getsockname(l.fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    if (l.fd >= 0) close(l.fd);
    return {};
  }
  l.port = ntohs(addr.sin_port);
  return l;
}

/// A TCP port on 127.0.0.1 that was free a moment ago (listened on and released), 0 on error.
inline int FreeLoopbackPort() {
  const LoopbackListener l = ListenOnLoopback();
  if (l.fd >= 0) close(l.fd);
  return l.port;
}

/// A socket connected to 127.0.0.1:port, -1 when the connection is refused.  The caller closes it.
inline int ConnectLoopback(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  const sockaddr_in addr = LoopbackAddress(port);
  if (fd >= 0 && connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0) return fd;
  if (fd >= 0) close(fd);
  return -1;
}

/// Whether a connection to 127.0.0.1:port is accepted now.
inline bool AcceptsOnLoopback(int port) {
  const int fd = ConnectLoopback(port);
  if (fd >= 0) close(fd);
  return fd >= 0;
}

}  // namespace canalid::testing
