#pragma once
// The connections of HttpServer (http_server.h): one HTTP session per accepted socket, which
// becomes a WebSocket session on an upgrade.  Internal to drivers/http.
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/http/http_server.h"

namespace canalid::drivers {

/// A connection the server can close when it stops.
class HttpConnection {
 public:
  virtual ~HttpConnection() = default;
  virtual void Close() = 0;
};

class WebSocketSession;

/// What the server and its connections share (one thread: no locks).
struct HttpServerState {
  HttpServerLimits limits;
  HttpGetHandler get;
  WebSocketGreeting greeting;
  HttpServerStats stats;
  bool stopped = false;
  std::optional<boost::asio::ip::tcp::acceptor> acceptor;
  std::vector<std::weak_ptr<HttpConnection>> connections;
  std::vector<std::weak_ptr<WebSocketSession>> websockets;

  /// Remembers `connection` for Stop (dropping the entries of closed ones).
  void Track(const std::shared_ptr<HttpConnection>& connection);
};

/// Reads requests one after another on a keep-alive connection and answers them.
class HttpSession final : public HttpConnection, public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(boost::asio::ip::tcp::socket socket, std::shared_ptr<HttpServerState> state);
  ~HttpSession() override;
  HttpSession(const HttpSession&) = delete;
  HttpSession& operator=(const HttpSession&) = delete;
  void Start();
  void Close() override;

 private:
  void Read();
  void OnRead(boost::beast::error_code error);
  void Answer();
  void Refuse(boost::beast::http::status status, std::string text);
  void Write(bool keep_alive);

  boost::beast::tcp_stream stream_;
  std::shared_ptr<HttpServerState> state_;
  boost::beast::flat_buffer buffer_;
  std::optional<boost::beast::http::request_parser<boost::beast::http::empty_body>> parser_;
  boost::beast::http::response<boost::beast::http::string_body> response_;
  bool handed_over_ = false;  ///< the socket went to a WebSocketSession
};

/// One WebSocket client: sent the greeting, then every broadcast, in order.
class WebSocketSession final : public HttpConnection,
                               public std::enable_shared_from_this<WebSocketSession> {
 public:
  WebSocketSession(boost::beast::tcp_stream stream, std::shared_ptr<HttpServerState> state);
  ~WebSocketSession() override;
  WebSocketSession(const WebSocketSession&) = delete;
  WebSocketSession& operator=(const WebSocketSession&) = delete;
  void Start(const boost::beast::http::request<boost::beast::http::empty_body>& request);
  void Send(std::shared_ptr<const std::string> text);
  void Close() override;

 private:
  void ReadAndDiscard();
  void WriteNext();

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  std::shared_ptr<HttpServerState> state_;
  boost::beast::flat_buffer incoming_;
  std::deque<std::shared_ptr<const std::string>> queue_;
  std::size_t queued_bytes_ = 0;
  bool open_ = false;
  bool writing_ = false;
  bool closed_ = false;
};

}  // namespace canalid::drivers
