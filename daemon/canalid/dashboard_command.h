#pragma once
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace canalid::cli {

/// Everything `canalid dashboard` takes from the command line.
struct DashboardCommandOptions {
  std::string lcm_url;
  std::string listen = "127.0.0.1:8080";
  std::string log;
  double speed = 1.0;
  std::vector<std::string> configs;
  std::vector<std::string> allow_hosts;
  double history_hours = 2.0;
  int max_points = 7200;
  int max_connections = 64;
  int max_client_queue_kib = 8192;
  double update_period_s = 0.25;
};

/// Registers `dashboard` on the app; `exit_code` receives the result when it runs.
void AddDashboardCommand(CLI::App& app, DashboardCommandOptions& options, int& exit_code);

}  // namespace canalid::cli
