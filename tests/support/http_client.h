#pragma once
// HTTP and WebSocket clients for tests of the dashboard's server, on 127.0.0.1, every wait
// bounded (socket timeouts for the raw HTTP exchange; run_for for the WebSocket client).
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

/// A WebSocket client whose every wait is bounded: each operation runs asynchronously on the
/// client's own io_context for at most the timeout given to Connect, then is cancelled (Asio's
/// blocking operations poll past a socket's receive timeout, so that cannot bound them).  After
/// a timeout or an error the connection is closed and every later call returns false.
class WebSocketClient {
 public:
  /// Connects and upgrades on `path`; false (with `error`) when it cannot.
  bool Connect(int port, const std::string& path, std::string* error, double timeout_s = 10.0) {
    timeout_ = std::chrono::milliseconds(static_cast<int>(timeout_s * 1000));
    ws_ = std::make_unique<Stream>(io_);
    boost::system::error_code code;
    const boost::asio::ip::tcp::endpoint endpoint(boost::asio::ip::make_address("127.0.0.1"),
                                                  static_cast<unsigned short>(port));
    bool ok = Run([&](auto done) { ws_->next_layer().async_connect(endpoint, done); }, code);
    if (ok) {
      ok = Run(
          [&](auto done) { ws_->async_handshake("127.0.0.1:" + std::to_string(port), path, done); },
          code);
    }
    if (!ok) *error = code ? code.message() : "timed out";
    return ok;
  }
  /// The next message; false when none comes in time or the connection is gone.
  bool Read(std::string* text) {
    boost::beast::flat_buffer buffer;
    boost::system::error_code code;
    if (!ws_ || !Run([&](auto done) { ws_->async_read(buffer, done); }, code)) return false;
    *text = boost::beast::buffers_to_string(buffer.data());
    return true;
  }
  /// Sends one text message; false when the connection is gone.
  bool Write(const std::string& text) {
    boost::system::error_code code;
    if (!ws_) return false;
    ws_->text(true);
    return Run([&](auto done) { ws_->async_write(boost::asio::buffer(text), done); }, code);
  }
  void Close() {
    boost::system::error_code ignored;
    if (ws_) ws_->next_layer().close(ignored);
  }

 private:
  using Stream = boost::beast::websocket::stream<boost::asio::ip::tcp::socket>;

  // Starts `start(handler)` and runs it for at most the timeout; true when it completed without
  // error.  On a timeout or an error the socket is closed (the operation then ends, aborted).
  template <class Start>
  bool Run(Start start, boost::system::error_code& code) {
    bool finished = false;
    start([&](const boost::system::error_code& e, auto&&...) {
      code = e;
      finished = true;
    });
    io_.restart();
    io_.run_for(timeout_);
    if (finished && !code) return true;
    Close();
    io_.restart();
    io_.run_for(std::chrono::seconds(5));  // the aborted operation completes
    ws_.reset();
    return false;
  }

  boost::asio::io_context io_;
  std::unique_ptr<Stream> ws_;
  std::chrono::milliseconds timeout_{10000};
};

/// The upgrade request a WebSocket client sends first (RFC 6455's example key).
inline std::string WebSocketUpgradeRequest(const std::string& path) {
  return "GET " + path +
         " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
}

}  // namespace canalid::testing
