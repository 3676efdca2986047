// The dashboard's HTTP/WebSocket server (drivers/http) against raw sockets and Beast's client:
// what it answers, what it refuses, and that a client that does not read cannot grow its memory.
#include "drivers/http/http_server.h"

#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <future>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/http_client.h"

namespace canalid::drivers {
namespace {

using canalid::testing::ConnectLoopback;
using canalid::testing::HttpBody;
using canalid::testing::HttpGet;
using canalid::testing::HttpStatus;
using canalid::testing::RawExchange;
using canalid::testing::SetSocketTimeouts;
using canalid::testing::WebSocketClient;
using canalid::testing::WebSocketUpgradeRequest;

// A server on its own thread, answering "/hello" and greeting WebSocket clients with "hi".
class ServerFixture : public ::testing::Test {
 protected:
  void StartServer(const HttpServerLimits& limits = {}) {
    server_ = std::make_unique<HttpServer>(
        io_, limits,
        [](std::string_view target) {
          if (target == "/hello") return HttpResponse{200, "text/plain", "hello\n", "no-store"};
          if (target == "/throw") throw std::runtime_error("handler failed");
          return HttpResponse{404, "text/plain", "no\n", "no-store"};
        },
        [] { return std::make_shared<const std::string>("hi"); });
    port_ = server_->Listen("127.0.0.1", 0);
    work_.emplace(io_.get_executor());
    thread_ = std::thread([this] { io_.run(); });
  }
  void TearDown() override {
    if (server_) OnIo([this] { server_->Stop(); });
    work_.reset();
    if (thread_.joinable()) thread_.join();
  }
  // Runs `f` on the server's thread and waits for it (bounded).
  template <class F>
  auto OnIo(F f) -> decltype(f()) {
    auto task = std::make_shared<std::packaged_task<decltype(f())()>>(std::move(f));
    auto result = task->get_future();
    boost::asio::post(io_, [task] { (*task)(); });
    if (result.wait_for(std::chrono::seconds(10)) != std::future_status::ready) {
      std::cerr << "the server's thread did not run a task within 10 s\n";
      std::abort();  // bounded: a hung server ends the test instead of stalling the suite
    }
    return result.get();
  }
  HttpServerStats Stats() {
    return OnIo([this] { return server_->stats(); });
  }
  void Broadcast(const std::string& text) {
    OnIo([this, text] { server_->Broadcast(std::make_shared<const std::string>(text)); });
  }
  // Waits (at most 10 s) until `done(stats)` holds.  The check runs on the server's own
  // thread, between its other handlers (a 2 ms timer paces it there), and the test thread blocks
  // on a future: no sleep, and the stats are read where they are written.
  bool WaitForStats(std::function<bool(const HttpServerStats&)> done) {
    auto wait = std::make_shared<StatsWait>(std::move(done), io_);
    auto reached = wait->reached.get_future();
    boost::asio::post(io_, [this, wait] { Check(*server_, wait); });
    const bool ok = reached.wait_for(std::chrono::seconds(10)) == std::future_status::ready;
    OnIo([wait] {
      wait->over = true;
      wait->timer.cancel();
    });
    return ok;
  }

  struct StatsWait {
    StatsWait(std::function<bool(const HttpServerStats&)> d, boost::asio::io_context& io)
        : done(std::move(d)), timer(io) {}
    std::function<bool(const HttpServerStats&)> done;
    std::promise<void> reached;
    boost::asio::steady_timer timer;
    bool over = false;  ///< on the server's thread only
  };
  static void Check(HttpServer& server, const std::shared_ptr<StatsWait>& wait) {
    if (wait->over) return;
    if (wait->done(server.stats())) {
      wait->over = true;
      wait->reached.set_value();
      return;
    }
    wait->timer.expires_after(std::chrono::milliseconds(2));
    wait->timer.async_wait(
        [&server, wait](const boost::system::error_code&) { Check(server, wait); });
  }

  boost::asio::io_context io_;
  std::optional<boost::asio::executor_work_guard<boost::asio::io_context::executor_type>> work_;
  std::unique_ptr<HttpServer> server_;
  std::thread thread_;
  int port_ = 0;
};

TEST_F(ServerFixture, AnswersGetAndHeadAndNamesWhatItRefuses) {
  StartServer();
  const std::string get = HttpGet(port_, "/hello");
  EXPECT_EQ(HttpStatus(get), 200) << get;
  EXPECT_EQ(HttpBody(get), "hello\n");
  EXPECT_NE(get.find("Content-Length: 6"), std::string::npos) << get;
  EXPECT_NE(get.find("X-Content-Type-Options: nosniff"), std::string::npos) << get;

  const std::string head =
      RawExchange(port_, "HEAD /hello HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(HttpStatus(head), 200) << head;
  EXPECT_NE(head.find("Content-Length: 6"), std::string::npos) << head;
  EXPECT_EQ(HttpBody(head), "");

  EXPECT_EQ(HttpStatus(HttpGet(port_, "/elsewhere")), 404);
  const std::string failed = HttpGet(port_, "/throw");
  EXPECT_EQ(HttpStatus(failed), 500);
  EXPECT_NE(HttpBody(failed).find("handler failed"), std::string::npos);

  const std::string post = RawExchange(
      port_, "POST /hello HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(HttpStatus(post), 405) << post;
  EXPECT_NE(post.find("Allow: GET, HEAD"), std::string::npos) << post;

  const std::string body =
      RawExchange(port_, "GET /hello HTTP/1.1\r\nHost: x\r\nContent-Length: 5\r\n\r\nhello");
  EXPECT_EQ(HttpStatus(body), 413) << body;

  const std::string big_header =
      RawExchange(port_, "GET /hello HTTP/1.1\r\nHost: x\r\nX-Padding: " + std::string(10000, 'a') +
                             "\r\n\r\n");
  EXPECT_EQ(HttpStatus(big_header), 431) << big_header;

  const std::string garbage = RawExchange(port_, "\x01\x02 not http at all\r\n\r\n");
  EXPECT_EQ(HttpStatus(garbage), 400) << garbage;

  const std::string wrong_ws = RawExchange(port_, WebSocketUpgradeRequest("/elsewhere"));
  EXPECT_EQ(HttpStatus(wrong_ws), 404) << wrong_ws;

  const HttpServerStats stats = Stats();
  EXPECT_EQ(stats.handler_failures, 1);
  EXPECT_EQ(stats.bad_requests, 5);  // 405, 413, 431, 400, and the upgrade elsewhere
}

TEST_F(ServerFixture, KeepAliveServesRequestsOneAfterAnother) {
  StartServer();
  const std::string one = "GET /hello HTTP/1.1\r\nHost: x\r\n\r\n";
  const std::string reply =
      RawExchange(port_, one + one + "GET /hello HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  std::size_t count = 0;
  for (std::size_t at = reply.find("HTTP/1.1 200"); at != std::string::npos;
       at = reply.find("HTTP/1.1 200", at + 1)) {
    ++count;
  }
  EXPECT_EQ(count, 3U) << reply;
}

TEST_F(ServerFixture, ConnectionsOverTheLimitAreClosedAtOnce) {
  HttpServerLimits limits;
  limits.max_connections = 3;
  StartServer(limits);
  std::vector<int> held;
  held.reserve(3);
  for (int i = 0; i < 3; ++i) held.push_back(ConnectLoopback(port_));
  ASSERT_TRUE(WaitForStats([](const HttpServerStats& s) { return s.open_connections == 3; }));
  const int extra = ConnectLoopback(port_);
  ASSERT_GE(extra, 0);
  SetSocketTimeouts(extra, 10.0);
  char c = 0;
  EXPECT_EQ(recv(extra, &c, 1, 0), 0) << "the connection over the limit is closed";
  close(extra);
  EXPECT_EQ(Stats().connections_refused, 1);
  for (const int fd : held) close(fd);
  ASSERT_TRUE(WaitForStats([](const HttpServerStats& s) { return s.open_connections == 0; }));
  EXPECT_EQ(HttpStatus(HttpGet(port_, "/hello")), 200) << "slots are given back";
}

TEST_F(ServerFixture, IdleConnectionsAreClosed) {
  HttpServerLimits limits;
  limits.idle_timeout_s = 0.3;
  StartServer(limits);
  const int fd = ConnectLoopback(port_);
  ASSERT_GE(fd, 0);
  SetSocketTimeouts(fd, 10.0);
  const auto start = std::chrono::steady_clock::now();
  char c = 0;
  EXPECT_EQ(recv(fd, &c, 1, 0), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  close(fd);
}

TEST_F(ServerFixture, FiftyWebSocketClientsGetTheGreetingAndEveryBroadcastInOrder) {
  StartServer();
  std::vector<WebSocketClient> clients(50);
  for (auto& client : clients) {
    std::string error;
    ASSERT_TRUE(client.Connect(port_, "/ws", &error)) << error;
    std::string text;
    ASSERT_TRUE(client.Read(&text));
    EXPECT_EQ(text, "hi");
  }
  ASSERT_TRUE(WaitForStats([](const HttpServerStats& s) { return s.websocket_clients == 50; }));
  for (int i = 0; i < 5; ++i) Broadcast("update " + std::to_string(i));
  for (auto& client : clients) {
    for (int i = 0; i < 5; ++i) {
      std::string text;
      ASSERT_TRUE(client.Read(&text));
      EXPECT_EQ(text, "update " + std::to_string(i));
    }
  }
  for (auto& client : clients) client.Close();
  ASSERT_TRUE(WaitForStats([](const HttpServerStats& s) { return s.websocket_clients == 0; }));
}

// A client that upgrades and then never reads: once the kernel's buffers are full its queue
// grows to the limit and it is disconnected; the queued bytes never exceed the limit, and a
// client that reads gets every message meanwhile.
TEST_F(ServerFixture, AClientThatNeverReadsIsDroppedAtItsQueueLimit) {
  HttpServerLimits limits;
  limits.max_websocket_queue_bytes = 4 << 20;
  StartServer(limits);
  const int silent = ConnectLoopback(port_);
  ASSERT_GE(silent, 0);
  const int small_buffer = 4096;
  setsockopt(silent, SOL_SOCKET, SO_RCVBUF, &small_buffer, sizeof small_buffer);
  const std::string upgrade = WebSocketUpgradeRequest("/ws");
  ASSERT_EQ(send(silent, upgrade.data(), upgrade.size(), MSG_NOSIGNAL),
            static_cast<ssize_t>(upgrade.size()));
  WebSocketClient reader;
  std::string error;
  ASSERT_TRUE(reader.Connect(port_, "/ws", &error)) << error;
  std::string text;
  ASSERT_TRUE(reader.Read(&text));
  ASSERT_TRUE(WaitForStats([](const HttpServerStats& s) { return s.websocket_clients == 2; }));

  const std::string message(std::size_t{256} * 1024, 'x');
  std::size_t most_queued = 0;
  int sent = 0;
  for (; sent < 200 && Stats().websocket_dropped_slow == 0; ++sent) {
    Broadcast(message);
    for (int k = 0; k < 1 && reader.Read(&text); ++k) EXPECT_EQ(text.size(), message.size());
    most_queued = std::max(most_queued, Stats().websocket_queued_bytes);
  }
  const HttpServerStats stats = Stats();
  EXPECT_EQ(stats.websocket_dropped_slow, 1) << "after " << sent << " messages";
  // The limit, plus the message being written (not counted against it).
  EXPECT_LE(most_queued, limits.max_websocket_queue_bytes + message.size());
  ASSERT_TRUE(WaitForStats([](const HttpServerStats& s) { return s.websocket_clients == 1; }));
  Broadcast("still here");
  ASSERT_TRUE(reader.Read(&text));
  EXPECT_EQ(text, "still here");
  close(silent);
}

// DNS rebinding and cross-site WebSocket hijacking: a Host that is a name not allowed, and an
// upgrade from a page of another origin, are refused; IP addresses, allowed names and clients
// without an Origin (not browsers) are served.
TEST_F(ServerFixture, RefusesOtherHostsAndCrossOriginWebSockets) {
  HttpServerLimits limits;
  limits.allowed_hosts = {"localhost", "canalid.plant.example"};
  StartServer(limits);
  const auto get_with_host = [&](const std::string& host) {
    return HttpStatus(RawExchange(
        port_, "GET /hello HTTP/1.1\r\nHost: " + host + "\r\nConnection: close\r\n\r\n"));
  };
  const std::string here = "127.0.0.1:" + std::to_string(port_);
  EXPECT_EQ(get_with_host(here), 200);
  EXPECT_EQ(get_with_host("[::1]:" + std::to_string(port_)), 200);
  EXPECT_EQ(get_with_host("localhost:" + std::to_string(port_)), 200);
  EXPECT_EQ(get_with_host("Canalid.Plant.Example"), 200);
  EXPECT_EQ(get_with_host("evil.example:" + std::to_string(port_)), 403);
  EXPECT_EQ(get_with_host("127.0.0.1.evil.example"), 403);
  const auto upgrade_from = [&](const std::string& origin) {
    std::string request = WebSocketUpgradeRequest("/ws");
    request.replace(request.find("Host: 127.0.0.1"), std::string("Host: 127.0.0.1").size(),
                    "Host: " + here);
    if (!origin.empty()) request.insert(request.size() - 2, "Origin: " + origin + "\r\n");
    const int fd = ConnectLoopback(port_);
    SetSocketTimeouts(fd, 10.0);
    send(fd, request.data(), request.size(), MSG_NOSIGNAL);
    char reply[512] = {};
    const ssize_t n = recv(fd, reply, sizeof reply - 1, 0);
    close(fd);
    return n > 12 ? std::stoi(std::string(reply + 9, 3)) : 0;
  };
  EXPECT_EQ(upgrade_from("http://" + here), 101);
  EXPECT_EQ(upgrade_from(""), 101);
  EXPECT_EQ(upgrade_from("http://evil.example"), 403);
  EXPECT_EQ(upgrade_from("null"), 403);
}

TEST_F(ServerFixture, ListenNamesTheAddressItCannotBind) {
  StartServer();
  boost::asio::io_context other_io;
  HttpServer other(
      other_io, {}, [](std::string_view) { return HttpResponse{}; }, nullptr);
  try {
    other.Listen("127.0.0.1", port_);
    FAIL() << "bound a busy port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot listen on 127.0.0.1:" + std::to_string(port_)),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(other.Listen("not-an-address", 0), std::runtime_error);
}

}  // namespace
}  // namespace canalid::drivers
