#pragma once
#include <cstdint>
#include <optional>
#include <string>

namespace CLI {
class App;
}

namespace canalid::cli {

/// Everything `canalid replay` takes from the command line.
struct ReplayOptions {
  std::string log;
  std::string config;  ///< instead of the configuration recorded in the log
  std::string reach;
  std::string prefix;  ///< the daemon's LCM channel prefix; empty: from the log
  std::optional<double> from_s, to_s;
  std::int64_t snapshot_every = 0;
  bool json = false;
};

/// Registers `replay` on the app; `exit_code` receives the result when it runs.
void AddReplayCommand(CLI::App& app, ReplayOptions& options, int& exit_code);

}  // namespace canalid::cli
