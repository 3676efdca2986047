#pragma once
// Blocking HTTP and WebSocket clients for tests of the dashboard's server, every wait bounded
// (socket receive timeouts), on 127.0.0.1.
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <memory>
#include <string>

#include "tests/support/loopback_port.h"

namespace canalid::testing {

/// Sets a receive and send timeout on a socket, so a blocking read or write gives up.
inline void SetSocketTimeouts(int fd, double seconds) {
  timeval tv{};
  tv.tv_sec = static_cast<time_t>(seconds);
  tv.tv_usec = static_cast<suseconds_t>((seconds - static_cast<double>(tv.tv_sec)) * 1e6);
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
}

/// Everything the server sends after `request` until it closes the connection or `timeout_s`
/// passes with nothing more ("" when the connection is refused).
inline std::string RawExchange(int port, const std::string& request, double timeout_s = 10.0) {
  const int fd = ConnectLoopback(port);
  if (fd < 0) return "";
  SetSocketTimeouts(fd, timeout_s);
  std::size_t sent = 0;
  while (sent < request.size()) {
    const ssize_t n = send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) break;
    sent += static_cast<std::size_t>(n);
  }
  std::string reply;
  char buffer[65536];
  for (;;) {
    const ssize_t n = recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    reply.append(buffer, static_cast<std::size_t>(n));
  }
  close(fd);
  return reply;
}

/// GET `target` with Connection: close; the whole reply (status line, headers, body).
inline std::string HttpGet(int port, const std::string& target, double timeout_s = 10.0) {
  return RawExchange(port,
                     "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n",
                     timeout_s);
}

/// The body of an HTTP reply ("" when it has none).
inline std::string HttpBody(const std::string& reply) {
  const std::size_t at = reply.find("\r\n\r\n");
  return at == std::string::npos ? "" : reply.substr(at + 4);
}

/// The status code of an HTTP reply (0 when it is not one).
inline int HttpStatus(const std::string& reply) {
  if (reply.rfind("HTTP/1.1 ", 0) != 0 || reply.size() < 12) return 0;
  return std::stoi(reply.substr(9, 3));
}

/// A WebSocket client with bounded waits (the socket's receive timeout).
class WebSocketClient {
 public:
  /// Connects and upgrades on `path`; false (with `error`) when it cannot.
  bool Connect(int port, const std::string& path, std::string* error, double timeout_s = 10.0) {
    try {
      ws_ = std::make_unique<Stream>(io_);
      ws_->next_layer().connect(
          {boost::asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
      SetSocketTimeouts(ws_->next_layer().native_handle(), timeout_s);
      ws_->handshake("127.0.0.1:" + std::to_string(port), path);
      return true;
    } catch (const std::exception& e) {
      *error = e.what();
      return false;
    }
  }
  /// The next message; false when none comes in time or the connection is gone.
  bool Read(std::string* text) {
    try {
      boost::beast::flat_buffer buffer;
      ws_->read(buffer);
      *text = boost::beast::buffers_to_string(buffer.data());
      return true;
    } catch (const std::exception&) {
      return false;
    }
  }
  /// Sends one text message; false when the connection is gone.
  bool Write(const std::string& text) {
    try {
      ws_->text(true);
      ws_->write(boost::asio::buffer(text));
      return true;
    } catch (const std::exception&) {
      return false;
    }
  }
  void Close() {
    boost::system::error_code ignored;
    if (ws_) ws_->next_layer().close(ignored);
  }

 private:
  using Stream = boost::beast::websocket::stream<boost::asio::ip::tcp::socket>;
  boost::asio::io_context io_;
  std::unique_ptr<Stream> ws_;
};

/// The upgrade request a WebSocket client sends first (RFC 6455's example key).
inline std::string WebSocketUpgradeRequest(const std::string& path) {
  return "GET " + path +
         " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
}

}  // namespace canalid::testing
