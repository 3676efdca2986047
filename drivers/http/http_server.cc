#include "drivers/http/http_server.h"

#include <algorithm>
#include <stdexcept>

#include "drivers/http/http_connections.h"

namespace canalid::drivers {
namespace {

namespace asio = boost::asio;

void Accept(const std::shared_ptr<HttpServerState>& state, asio::io_context& io);

// Accepting again after a failure (out of descriptors): a pause, so the loop does not spin.
void AcceptLater(const std::shared_ptr<HttpServerState>& state, asio::io_context& io) {
  auto timer = std::make_shared<asio::steady_timer>(io, std::chrono::milliseconds(100));
  timer->async_wait([state, &io, timer](const boost::system::error_code&) {
    if (!state->stopped) Accept(state, io);
  });
}

void Accept(const std::shared_ptr<HttpServerState>& state, asio::io_context& io) {
  state->acceptor->async_accept(
      [state, &io](const boost::system::error_code& error, asio::ip::tcp::socket s) {
        if (state->stopped) return;
        if (error) {
          AcceptLater(state, io);
          return;
        }
        if (state->stats.open_connections >= state->limits.max_connections) {
          ++state->stats.connections_refused;
          boost::system::error_code ignored;
          s.close(ignored);
        } else {
          ++state->stats.connections_accepted;
          auto session = std::make_shared<HttpSession>(std::move(s), state);
          state->Track(session);
          session->Start();
        }
        Accept(state, io);
      });
}

}  // namespace

void HttpServerState::Track(const std::shared_ptr<HttpConnection>& connection) {
  std::erase_if(connections, [](const std::weak_ptr<HttpConnection>& c) { return c.expired(); });
  connections.push_back(connection);
}

HttpServer::HttpServer(asio::io_context& io, HttpServerLimits limits, HttpGetHandler get,
                       WebSocketGreeting greeting)
    : io_(io), state_(std::make_shared<HttpServerState>()) {
  state_->limits = std::move(limits);
  state_->get = std::move(get);
  state_->greeting = std::move(greeting);
}

HttpServer::~HttpServer() { Stop(); }

int HttpServer::Listen(const std::string& host, int port) {
  const std::string where = host + ":" + std::to_string(port);
  try {
    const asio::ip::tcp::endpoint endpoint(asio::ip::make_address(host),
                                           static_cast<unsigned short>(port));
    asio::ip::tcp::acceptor acceptor(io_);
    acceptor.open(endpoint.protocol());
    acceptor.set_option(asio::socket_base::reuse_address(true));
    acceptor.bind(endpoint);
    acceptor.listen(asio::socket_base::max_listen_connections);
    state_->acceptor.emplace(std::move(acceptor));
  } catch (const boost::system::system_error& e) {
    throw std::runtime_error("cannot listen on " + where + ": " + e.code().message());
  }
  Accept(state_, io_);
  return state_->acceptor->local_endpoint().port();
}

void HttpServer::Broadcast(const std::shared_ptr<const std::string>& text) {
  std::erase_if(state_->websockets,
                [](const std::weak_ptr<WebSocketSession>& w) { return w.expired(); });
  // Send may close a slow client, which only marks it: the list is not changed while walked.
  for (const auto& weak : state_->websockets) {
    if (auto session = weak.lock()) session->Send(text);
  }
}

void HttpServer::Stop() {
  if (state_->stopped) return;
  state_->stopped = true;
  if (state_->acceptor) {
    boost::system::error_code ignored;
    state_->acceptor->close(ignored);
  }
  const auto connections = state_->connections;
  for (const auto& weak : connections) {
    if (auto connection = weak.lock()) connection->Close();
  }
}

HttpServerStats HttpServer::stats() const { return state_->stats; }

}  // namespace canalid::drivers
