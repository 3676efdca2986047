#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/results/results_image.h"

namespace canalid::drivers {

struct ResultsServerOptions {
  std::string host = "127.0.0.1";  ///< address to bind ("0.0.0.0" / "::" for every interface)
  std::string port = "1503";       ///< "0" picks a free port (tests)
  int max_clients = 64;            ///< connections beyond are accepted and closed at once
  /// A frame must arrive whole within this time of its first byte (s, > 0).
  double frame_timeout_s = 1.0;
  /// A connection with no request for this long is closed (s, > 0): connections a SCADA left
  /// behind (its restart, a network break) do not hold the max_clients slots.
  double idle_timeout_s = 60.0;
};

/// Why host:port cannot be bound now (a probe socket, closed at once); empty when it can.
std::string ResultsListenProblem(const std::string& host, const std::string& port);

/// What the server has done since it started (monotonic, read from any thread).
struct ResultsServerCounters {
  std::int64_t requests = 0;        ///< requests answered (with data or an exception)
  std::int64_t refused_writes = 0;  ///< write requests answered with exception 1
  std::int64_t clients_accepted = 0;
  std::int64_t clients_refused = 0;  ///< over max_clients
  /// Closed by the server: a malformed frame, a frame not whole in time, replies not read, idle.
  std::int64_t clients_dropped = 0;
  std::int64_t clients_connected = 0;
};

/// The results register map (core/results) served read-only over Modbus TCP on its own thread:
/// libmodbus binds the socket and encodes the replies; the thread reads frames itself from
/// non-blocking sockets, so that no master can hold it.  Functions 3 and 4 read the image (the
/// same words for both); every write function (5, 6, 15, 16, 22, 23) gets exception 1 (illegal
/// function), as does any other function; a count outside 1..125 gets exception 3, an address
/// past the image exception 2.  A master is dropped when its frame is malformed (MBAP protocol id
/// not 0, length outside 2..254, a function code with the exception bit), not whole within
/// frame_timeout_s, when it does not read its
/// replies (a reply that does not fit its socket's send buffer at once), or after idle_timeout_s
/// without a request.  A connection is answered at most 16 frames in a row before the others get
/// their turn.  The owner updates the image through Update(), which holds the image's lock
/// for the update only; a request copies the words it asks for under the lock and replies after
/// releasing it.
class ResultsServer final {
 public:
  /// Binds and listens.  @throws std::runtime_error naming the address and the system error.
  ResultsServer(core::ResultsImage image, ResultsServerOptions options);
  ~ResultsServer();  ///< stops the thread, closes every connection
  ResultsServer(const ResultsServer&) = delete;
  ResultsServer& operator=(const ResultsServer&) = delete;

  /// The TCP port bound.
  int port() const { return port_; }

  /// Runs `update(core::ResultsImage&)` under the image's lock.  No allocation of its own.
  template <class Function>
  void Update(Function&& update) {
    const std::lock_guard<std::mutex> lock(mutex_);
    update(image_);
  }

  ResultsServerCounters counters() const;

 private:
  struct Connections;
  struct Client;
  void Serve();
  /// Reads what `client` sent; false when the connection must be closed.
  bool Receive(Client& client, double now_s);
  /// Answers the whole frame in client.frame; false when the connection must be closed.
  bool Answer(Client& client);

  core::ResultsImage image_;
  ResultsServerOptions options_;
  mutable std::mutex mutex_;
  std::unique_ptr<Connections> connections_;
  int port_ = 0;
  int stop_fd_ = -1;  ///< eventfd: written by the destructor to wake the thread
  std::atomic<bool> stop_{false};
  std::atomic<std::int64_t> requests_{0}, refused_writes_{0}, clients_accepted_{0},
      clients_refused_{0}, clients_dropped_{0}, clients_connected_{0};
  std::thread thread_;
};

}  // namespace canalid::drivers
