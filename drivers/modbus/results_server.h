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
};

/// What the server has done since it started (monotonic, read from any thread).
struct ResultsServerCounters {
  std::int64_t requests = 0;        ///< requests answered (with data or an exception)
  std::int64_t refused_writes = 0;  ///< write requests answered with exception 1
  std::int64_t clients_accepted = 0;
  std::int64_t clients_refused = 0;  ///< over max_clients
  std::int64_t clients_dropped = 0;  ///< closed for a malformed frame or a failed send
  std::int64_t clients_connected = 0;
};

/// The results register map (core/results) served read-only over Modbus TCP by libmodbus on its
/// own thread: functions 3 and 4 read the image (the same words for both); every write function
/// (5, 6, 15, 16, 22, 23) is refused with exception 1 (illegal function), coils and discrete
/// inputs do not exist (exception 2), as do addresses past the image.  The owner updates the image
/// through Update(), which holds the lock for the update only; a request copies the words it asks
/// for under the lock and replies after releasing it, so a slow client never holds it.  A client
/// that does not read its replies is dropped after a 1 s send timeout; a frame that stops
/// mid-way, after 100 ms (libmodbus's byte timeout).
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
  void Serve();

  core::ResultsImage image_;
  ResultsServerOptions options_;
  mutable std::mutex mutex_;
  std::unique_ptr<Connections> connections_;
  int port_ = 0;
  int stop_fd_ = -1;  ///< eventfd: written by the destructor to wake the thread
  std::atomic<std::int64_t> requests_{0}, refused_writes_{0}, clients_accepted_{0},
      clients_refused_{0}, clients_dropped_{0}, clients_connected_{0};
  std::thread thread_;
};

}  // namespace canalid::drivers
