#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace canalid::drivers {

/// The answer to a GET (or HEAD) of one target.
struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  /// Cache-Control: assets may be cached, live data not.
  std::string cache_control = "no-store";
};

/// Answers a GET of `target` (the request target as sent: path and query).  Runs on the server's
/// io_context thread; must not throw (an exception becomes a 500, counted).
using HttpGetHandler = std::function<HttpResponse(std::string_view target)>;

/// What a WebSocket client is sent first, on connecting (a snapshot of the state).
using WebSocketGreeting = std::function<std::shared_ptr<const std::string>()>;

struct HttpServerLimits {
  /// HTTP and WebSocket connections at once; beyond, a connection is accepted and closed at once.
  int max_connections = 64;
  /// The request line and headers of one request (bytes); beyond, 431 and the connection closes.
  std::size_t max_header_bytes = 8192;
  /// An HTTP connection with no whole request for this long is closed (s).
  double idle_timeout_s = 30.0;
  /// Messages waiting to be sent to one WebSocket client (bytes); a client that does not read
  /// (or reads too slowly) is disconnected when its queue would exceed this, so memory stays
  /// bounded at max_connections times this plus the message each is being sent (not counted:
  /// a first message larger than the limit is taken).
  std::size_t max_websocket_queue_bytes = std::size_t{8} << 20;
  /// The path on which WebSocket upgrades are accepted.
  std::string websocket_path = "/ws";
  /// Names a request's Host header may give besides IP addresses (DNS rebinding: a page of
  /// another site whose name resolves to this address must not read it); empty: any name.
  std::vector<std::string> allowed_hosts;
};

/// What the server has done since it started.
struct HttpServerStats {
  std::int64_t connections_accepted = 0;
  std::int64_t connections_refused = 0;  ///< over max_connections
  std::int64_t requests = 0;             ///< HTTP requests answered (any status)
  std::int64_t bad_requests = 0;         ///< refused: 400, 403, 405, 413, 431, an upgrade elsewhere
  std::int64_t handler_failures = 0;     ///< the handler threw: answered 500
  std::int64_t websocket_opened = 0;
  std::int64_t websocket_dropped_slow = 0;  ///< disconnected: queue over the limit
  std::int64_t websocket_messages = 0;      ///< messages queued to clients
  int open_connections = 0;                 ///< HTTP and WebSocket
  int websocket_clients = 0;
  std::size_t websocket_queued_bytes = 0;  ///< waiting in every client's queue now
};

struct HttpServerState;

/// A read-only HTTP/1.1 server with WebSocket broadcast (Boost.Beast) on the caller's
/// io_context, single-threaded: GET and HEAD go to the handler, other methods get 405, a request
/// with a body 413, headers over the limit 431, anything unparsable 400, a Host that is neither an
/// IP address nor an allowed name 403, a WebSocket upgrade from a page of another origin (its
/// Origin header not naming the Host) 403; upgrades
/// on websocket_path become WebSocket clients that are sent the greeting and then every
/// Broadcast.  Messages from clients are read and discarded (pings and closes are answered).
class HttpServer final {
 public:
  HttpServer(boost::asio::io_context& io, HttpServerLimits limits, HttpGetHandler get,
             WebSocketGreeting greeting);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// Binds host:port (port 0: a free one) and starts accepting; returns the port bound.
  /// @throws std::runtime_error "cannot listen on HOST:PORT: ..." when it cannot.
  int Listen(const std::string& host, int port);

  /// Queues `text` to every WebSocket client (one shared copy).
  void Broadcast(const std::shared_ptr<const std::string>& text);

  /// Stops accepting and closes every connection.
  void Stop();

  HttpServerStats stats() const;

 private:
  boost::asio::io_context& io_;
  std::shared_ptr<HttpServerState> state_;
};

}  // namespace canalid::drivers
