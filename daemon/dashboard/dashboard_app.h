#pragma once
#include <utility>  // before Boost.Asio under GCC 12 and C++20 (docs/design.md)

#include <boost/asio.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/dashboard/dashboard_json.h"
#include "daemon/dashboard/dashboard_store.h"
#include "daemon/dashboard/log_playback.h"
#include "drivers/http/http_server.h"
#include "drivers/lcm/bus_watch.h"
#include "drivers/lcm/lcm_bus.h"

namespace canalid::dashboard {

struct DashboardOptions {
  std::string lcm_url;                    ///< "" : LCM's default; ignored when log_path is set
  std::string log_path;                   ///< play this LCM log instead of listening to the bus
  double speed = 1.0;                     ///< of the log: 1 real time, 0 as fast as possible
  std::vector<std::string> config_paths;  ///< daemon configurations: layouts before CONFIG comes
  std::string host = "127.0.0.1";
  int port = 8080;
  double update_period_s = 0.25;       ///< WebSocket updates
  std::size_t snapshot_points = 2000;  ///< per series, in a snapshot (thinned evenly)
  StoreLimits limits;
  drivers::HttpServerLimits http;
  /// Where the dashboard says what it does (start, the bus lost and back, the log's end).
  std::function<void(const std::string&)> log;
};

/// `canalid dashboard`: the store fed from the bus (or a log), served over HTTP with a WebSocket
/// for the page, on one Asio loop.  Destroy it only once that loop has stopped (its timers'
/// handlers hold `this`).  Routes: / (the page), /assets/* (embedded), /ws, /api,
/// /api/state, /api/snapshot, /api/series/ID, /metrics.
class DashboardApp final {
 public:
  /// Reads the configurations and opens the bus or the log.  @throws std::runtime_error naming
  /// the file or URL.
  DashboardApp(boost::asio::io_context& io, DashboardOptions options);
  ~DashboardApp();
  DashboardApp(const DashboardApp&) = delete;
  DashboardApp& operator=(const DashboardApp&) = delete;

  /// Listens and starts; returns the port bound.  @throws std::runtime_error when it cannot.
  int Start();
  void Stop();

  /// The answer to GET `target` (also used by tests, without a socket).
  drivers::HttpResponse Get(std::string_view target);

  const DashboardStore& store() const { return store_; }

 private:
  std::int64_t NowUtime() const;
  void Tick();
  void OnLogMessage(std::string_view channel, std::span<const std::uint8_t> data);

  boost::asio::io_context& io_;
  DashboardOptions options_;
  DashboardStore store_;
  DeltaWriter deltas_;
  std::unique_ptr<drivers::LcmBus> bus_;
  std::unique_ptr<drivers::BusWatch> bus_watch_;
  std::unique_ptr<LogPlayback> playback_;
  drivers::HttpServer server_;
  boost::asio::steady_timer tick_;
  bool stopping_ = false;
};

}  // namespace canalid::dashboard
