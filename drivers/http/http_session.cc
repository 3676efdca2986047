#include <algorithm>
#include <cctype>
#include <chrono>
#include <exception>

#include "drivers/http/http_connections.h"

namespace canalid::drivers {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;

// The host name of a Host header or an origin's authority: without the port and brackets,
// lower case.
std::string HostName(std::string_view authority) {
  std::string_view host = authority;
  if (!host.empty() && host.front() == '[') {
    host = host.substr(
        1, host.find(']') == std::string_view::npos ? host.size() - 1 : host.find(']') - 1);
  } else if (const std::size_t colon = host.find(':');
             colon != std::string_view::npos &&
             host.find(':', colon + 1) == std::string_view::npos) {
    host = host.substr(0, colon);
  }
  std::string name(host);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

bool IsIpAddress(const std::string& host) {
  boost::system::error_code error;
  boost::asio::ip::make_address(host, error);
  return !error;
}

std::string_view View(beast::string_view text) { return {text.data(), text.size()}; }

// Lower case, for comparing authorities.
std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

}  // namespace

HttpSession::HttpSession(boost::asio::ip::tcp::socket socket,
                         std::shared_ptr<HttpServerState> state)
    : stream_(std::move(socket)), state_(std::move(state)) {
  ++state_->stats.open_connections;
}

HttpSession::~HttpSession() { --state_->stats.open_connections; }

void HttpSession::Start() { Read(); }

void HttpSession::Close() {
  if (handed_over_) return;
  beast::error_code ignored;
  stream_.socket().shutdown(boost::asio::ip::tcp::socket::shutdown_both, ignored);
  stream_.close();
}

void HttpSession::Read() {
  parser_.emplace();
  parser_->header_limit(static_cast<std::uint32_t>(state_->limits.max_header_bytes));
  parser_->body_limit(0);
  stream_.expires_after(Seconds(state_->limits.idle_timeout_s));
  http::async_read(
      stream_, buffer_, *parser_,
      [self = shared_from_this()](beast::error_code error, std::size_t) { self->OnRead(error); });
}

void HttpSession::OnRead(beast::error_code error) {
  if (state_->stopped) return;
  if (error == http::error::end_of_stream || error == beast::error::timeout ||
      error == boost::asio::error::operation_aborted ||
      error == boost::asio::error::connection_reset || error == boost::asio::error::eof) {
    Close();
    return;
  }
  if (error == http::error::header_limit) {
    Refuse(http::status::request_header_fields_too_large,
           "request headers over " + std::to_string(state_->limits.max_header_bytes) + " bytes\n");
    return;
  }
  if (error == http::error::body_limit) {
    Refuse(http::status::payload_too_large, "this server is read-only: no request body\n");
    return;
  }
  if (error) {
    Refuse(http::status::bad_request, "malformed request: " + error.message() + "\n");
    return;
  }
  Answer();
}

void HttpSession::Refuse(http::status status, std::string text) {
  ++state_->stats.bad_requests;
  response_ = {};
  response_.version(11);
  response_.result(status);
  response_.set(http::field::content_type, "text/plain; charset=utf-8");
  response_.set(http::field::connection, "close");
  response_.body() = std::move(text);
  response_.prepare_payload();
  Write(false);
}

void HttpSession::Answer() {
  const http::request<http::empty_body>& request = parser_->get();
  const std::string target(request.target());
  const std::string host = HostName(View(request[http::field::host]));
  const auto& allowed = state_->limits.allowed_hosts;
  if (!allowed.empty() && !IsIpAddress(host) &&
      std::find(allowed.begin(), allowed.end(), host) == allowed.end()) {
    Refuse(http::status::forbidden, "Host '" + host + "' is not served here\n");
    return;
  }
  if (beast::websocket::is_upgrade(request)) {
    // A browser names the page's origin; a page of another site (cross-site WebSocket
    // hijacking) is refused.  Clients that are not browsers send no Origin.
    const std::string_view origin = View(request[http::field::origin]);
    const std::size_t scheme = origin.find("://");
    if (!origin.empty() &&
        (scheme == std::string_view::npos ||
         Lower(origin.substr(scheme + 3)) != Lower(View(request[http::field::host])))) {
      Refuse(http::status::forbidden,
             "WebSocket from origin '" + std::string(origin) + "' refused: not this server's\n");
      return;
    }
    if (target != state_->limits.websocket_path) {
      Refuse(http::status::not_found, "no WebSocket at " + target + "\n");
      return;
    }
    stream_.expires_never();
    handed_over_ = true;
    auto session = std::make_shared<WebSocketSession>(std::move(stream_), state_);
    state_->Track(session);
    session->Start(parser_->get());
    return;
  }
  if (request.method() != http::verb::get && request.method() != http::verb::head) {
    ++state_->stats.bad_requests;
    response_ = {};
    response_.version(request.version());
    response_.result(http::status::method_not_allowed);
    response_.set(http::field::allow, "GET, HEAD");
    response_.set(http::field::content_type, "text/plain; charset=utf-8");
    response_.body() = "read-only: GET and HEAD only\n";
    response_.keep_alive(request.keep_alive());
    response_.prepare_payload();
    Write(request.keep_alive());
    return;
  }
  HttpResponse answer;
  try {
    answer = state_->get(target);
  } catch (const std::exception& e) {
    ++state_->stats.handler_failures;
    answer = HttpResponse{500, "text/plain; charset=utf-8", std::string("error: ") + e.what(),
                          "no-store"};
  }
  if (answer.status >= 400 && answer.status != 404 && answer.status != 500) {
    ++state_->stats.bad_requests;
  }
  response_ = {};
  response_.version(request.version());
  response_.result(static_cast<unsigned>(answer.status));
  response_.set(http::field::server, "canalid");
  response_.set(http::field::content_type, answer.content_type);
  response_.set(http::field::cache_control, answer.cache_control);
  response_.set("X-Content-Type-Options", "nosniff");
  response_.keep_alive(request.keep_alive());
  response_.body() = std::move(answer.body);
  response_.prepare_payload();
  if (request.method() == http::verb::head) {
    const auto length = response_.body().size();
    response_.body().clear();
    response_.content_length(length);
  }
  Write(request.keep_alive());
}

void HttpSession::Write(bool keep_alive) {
  ++state_->stats.requests;
  stream_.expires_after(Seconds(state_->limits.idle_timeout_s));
  http::async_write(stream_, response_,
                    [self = shared_from_this(), keep_alive](beast::error_code error, std::size_t) {
                      if (error || !keep_alive || self->state_->stopped) {
                        self->Close();
                        return;
                      }
                      self->Read();
                    });
}

}  // namespace canalid::drivers
