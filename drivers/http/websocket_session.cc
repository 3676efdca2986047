#include "drivers/http/http_connections.h"

namespace canalid::drivers {
namespace {

namespace beast = boost::beast;
namespace websocket = beast::websocket;

// Messages from a client are not used; a larger one closes the connection.
constexpr std::size_t kMaxIncomingBytes = 4096;

}  // namespace

WebSocketSession::WebSocketSession(beast::tcp_stream stream, std::shared_ptr<HttpServerState> state)
    : ws_(std::move(stream)), state_(std::move(state)) {
  ++state_->stats.open_connections;
}

WebSocketSession::~WebSocketSession() {
  --state_->stats.open_connections;
  if (open_) --state_->stats.websocket_clients;
  state_->stats.websocket_queued_bytes -= queued_bytes_;
}

// Beast answers the upgrade from `request` when async_accept is called; it does not keep it.
void WebSocketSession::Start(const beast::http::request<beast::http::empty_body>& request) {
  ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
  ws_.read_message_max(kMaxIncomingBytes);
  ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& response) {
    response.set(beast::http::field::server, "canalid");
  }));
  ws_.async_accept(request, [self = shared_from_this()](beast::error_code error) {
    if (error || self->state_->stopped) {
      self->Close();
      return;
    }
    self->open_ = true;
    ++self->state_->stats.websocket_opened;
    ++self->state_->stats.websocket_clients;
    self->state_->websockets.push_back(self);
    if (self->state_->greeting) self->Send(self->state_->greeting());
    self->ReadAndDiscard();
  });
}

void WebSocketSession::ReadAndDiscard() {
  ws_.async_read(incoming_, [self = shared_from_this()](beast::error_code error, std::size_t) {
    if (error) {
      self->Close();
      return;
    }
    self->incoming_.consume(self->incoming_.size());
    self->ReadAndDiscard();
  });
}

void WebSocketSession::Send(std::shared_ptr<const std::string> text) {
  if (closed_ || !open_ || !text) return;
  // The message being written does not count (a snapshot may be larger than the limit, and a
  // page on a slow link is still writing it when the next update comes), so a client holds at
  // most the limit plus the message in flight.
  const std::size_t in_flight = writing_ ? queue_.front()->size() : 0;
  if (queued_bytes_ - in_flight + text->size() > state_->limits.max_websocket_queue_bytes &&
      queue_.size() > (writing_ ? 1U : 0U)) {
    ++state_->stats.websocket_dropped_slow;
    Close();
    return;
  }
  queued_bytes_ += text->size();
  state_->stats.websocket_queued_bytes += text->size();
  ++state_->stats.websocket_messages;
  queue_.push_back(std::move(text));
  if (!writing_) WriteNext();
}

void WebSocketSession::WriteNext() {
  if (queue_.empty() || closed_) {
    writing_ = false;
    return;
  }
  writing_ = true;
  ws_.text(true);
  ws_.async_write(boost::asio::buffer(*queue_.front()),
                  [self = shared_from_this()](beast::error_code error, std::size_t) {
                    if (error) {
                      self->writing_ = false;
                      self->Close();
                      return;
                    }
                    const std::size_t size = self->queue_.front()->size();
                    self->queued_bytes_ -= size;
                    self->state_->stats.websocket_queued_bytes -= size;
                    self->queue_.pop_front();
                    self->WriteNext();
                  });
}

// Closes the socket at once (no closing handshake: a client that does not read would never
// finish it); pending operations end with an error and release the session.
void WebSocketSession::Close() {
  if (closed_) return;
  closed_ = true;
  beast::error_code ignored;
  beast::get_lowest_layer(ws_).socket().shutdown(boost::asio::ip::tcp::socket::shutdown_both,
                                                 ignored);
  beast::get_lowest_layer(ws_).close();
}

}  // namespace canalid::drivers
