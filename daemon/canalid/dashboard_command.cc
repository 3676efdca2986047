#include "daemon/canalid/dashboard_command.h"

#include <CLI/CLI.hpp>
#include <cctype>
#include <csignal>
#include <iostream>
#include <limits>

#include "daemon/canalid/cli.h"
#include "daemon/canalid/input_error.h"
#include "daemon/config/daemon_config.h"
#include "daemon/dashboard/dashboard_app.h"

namespace canalid::cli {
namespace {

int RunDashboard(const DashboardCommandOptions& options) {
  const auto listen = config::ParseListenAddress(options.listen);
  if (!listen) {
    throw InputError("--listen '" + options.listen +
                     "': expected HOST:PORT (an IPv4 or IPv6 address, port 0..65535)");
  }
  dashboard::DashboardOptions settings;
  settings.lcm_url = options.lcm_url;
  settings.log_path = options.log;
  settings.speed = options.speed;
  settings.config_paths = options.configs;
  settings.host = listen->host;
  settings.port = listen->port;
  settings.update_period_s = options.update_period_s;
  settings.limits.history_s = options.history_hours * 3600.0;
  settings.limits.max_points = static_cast<std::size_t>(options.max_points);
  settings.http.max_connections = options.max_connections;
  // IP addresses and localhost always; a name only when the operator gives it.
  settings.http.allowed_hosts = {"localhost"};
  for (const std::string& host : options.allow_hosts) {
    std::string name = host;
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    settings.http.allowed_hosts.push_back(name);
  }
  settings.http.max_websocket_queue_bytes =
      static_cast<std::size_t>(options.max_client_queue_kib) * 1024;
  settings.log = [](const std::string& text) {
    std::cerr << "canalid dashboard: " << text << "\n";
  };

  boost::asio::io_context io;
  std::unique_ptr<dashboard::DashboardApp> app;
  try {
    app = std::make_unique<dashboard::DashboardApp>(io, settings);
  } catch (const std::exception& e) {
    throw InputError(e.what());
  }
  int port = 0;
  try {
    port = app->Start();
  } catch (const std::exception& e) {
    throw InputError(e.what());
  }
  const std::string host =
      listen->host.find(':') != std::string::npos ? "[" + listen->host + "]" : listen->host;
  std::cout << "canalid dashboard: serving http://" << host << ":" << port << "/ ("
            << (options.log.empty() ? "LCM " + (options.lcm_url.empty() ? std::string("default URL")
                                                                        : options.lcm_url)
                                    : "log " + options.log)
            << ")" << std::endl;
  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& error, int) {
    if (error) return;
    std::cerr << "canalid dashboard: stopping\n";
    app->Stop();
  });
  io.run();
  return kExitOk;
}

}  // namespace

void AddDashboardCommand(CLI::App& app, DashboardCommandOptions& options, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "dashboard", "Serve a live web page, JSON and Prometheus metrics of canalidd's LCM messages");
  cmd->footer(
      "Read-only: listens to every canalidd on the bus (any channel prefix: one site each), or\n"
      "plays a log, and serves the page at http://HOST:PORT/ (levels with the safety band, flows,\n"
      "the actuator, the experiment, every online model's parameters with +-2 sigma, health),\n"
      "/api/... (JSON) and /metrics (Prometheus). Binds to loopback unless told otherwise; put it\n"
      "behind a reverse proxy with TLS and authentication for a control-room network\n"
      "(docs/dashboard.md). The page needs no internet (dygraphs is built in).\n"
      "Examples:\n"
      "  canalid dashboard\n"
      "  canalid dashboard --lcm-url 'udpm://239.255.76.67:7667?ttl=0' --listen 0.0.0.0:8080\n"
      "  canalid dashboard --log run.lcmlog --speed 60");
  cmd->add_option("--lcm-url", options.lcm_url,
                  "LCM URL to listen on (default: LCM's default, $LCM_DEFAULT_URL)");
  cmd->add_option("--listen", options.listen, "HOST:PORT to serve on (port 0: a free one)")
      ->capture_default_str();
  cmd->add_option("--log", options.log, "Play this LCM log instead of listening to the bus")
      ->check(CLI::ExistingFile);
  cmd->add_option("--speed", options.speed,
                  "Pace of --log: 1 as logged, 60 a minute per second, 0 as fast as possible")
      ->check(FiniteIn(0.0, 1e6))
      ->capture_default_str();
  cmd->add_option("--config", options.configs,
                  "canalidd configuration(s): reaches and safety bands before the daemon's CONFIG "
                  "message is seen (it is published when canalidd starts)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--allow-host", options.allow_hosts,
                  "A host name the page may be reached by (e.g. the reverse proxy's); IP addresses "
                  "and localhost always may. Other Host headers get 403 (DNS rebinding)");
  cmd->add_option("--history-hours", options.history_hours, "Hours of points kept per series")
      ->check(FiniteIn(0.0, 24.0 * 365.0, true))
      ->capture_default_str();
  cmd->add_option("--max-points", options.max_points, "Points kept per series, at most")
      ->check(CLI::Range(10, 1000000))
      ->capture_default_str();
  cmd->add_option("--max-connections", options.max_connections,
                  "HTTP and WebSocket connections at once")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  cmd->add_option("--max-client-queue-kib", options.max_client_queue_kib,
                  "Updates waiting for one page, at most (KiB); a page that does not read them "
                  "is disconnected")
      ->check(CLI::Range(64, 1048576))
      ->capture_default_str();
  cmd->add_option("--update-period", options.update_period_s, "Seconds between page updates")
      ->check(FiniteIn(0.05, 60.0))
      ->capture_default_str();
  cmd->callback([&options, &exit_code] {
    if (options.log.empty() && options.speed != 1.0) {
      throw InputError("--speed is for --log: the bus is live");
    }
    exit_code = RunDashboard(options);
  });
}

}  // namespace canalid::cli
