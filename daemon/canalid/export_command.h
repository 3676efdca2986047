#pragma once
#include <string>

namespace CLI {
class App;
}

namespace canalid::cli {

/// Everything `canalid export` takes from the command line.
struct ExportOptions {
  std::string log;
  std::string out;
  std::string config;  ///< instead of the configuration recorded in the log
  std::string reach;   ///< only this reach; empty: all
  std::string prefix;  ///< the daemon's LCM channel prefix; empty: from the log
};

/// Registers `export` on the app; `exit_code` receives the result when it runs.
void AddExportCommand(CLI::App& app, ExportOptions& options, int& exit_code);

}  // namespace canalid::cli
